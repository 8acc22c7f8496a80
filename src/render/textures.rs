//! A scene's textures on the GPU: its base colour maps in one sRGB texture array and its normal
//! maps in a linear one (every image resized to the largest one's square, at most `MAX_SIDE`,
//! with a full mip chain made here), and a trilinear, repeating sampler; the G-buffer pass
//! reads them.

use wgpu::util::DeviceExt;

use crate::scene::{Scene, TextureImage};

/// Largest layer side: larger images are scaled down to it.
pub const MAX_SIDE: u32 = 2048;

/// The base colour array (sRGB), the normal map array (linear) and their sampler.
pub fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &Scene,
) -> (wgpu::Texture, wgpu::Texture, wgpu::Sampler) {
    let base = array(
        device,
        queue,
        &scene.textures,
        wgpu::TextureFormat::Rgba8UnormSrgb,
    );
    let normals = array(
        device,
        queue,
        &scene.linear_maps,
        wgpu::TextureFormat::Rgba8Unorm,
    );
    (base, normals, sampler(device))
}

/// One texture array of `images` (a single white texel when there are none).
fn array(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    images: &[TextureImage],
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    let white = TextureImage {
        width: 1,
        height: 1,
        rgba: vec![255; 4],
    };
    let images: Vec<&TextureImage> = if images.is_empty() {
        vec![&white]
    } else {
        images.iter().collect()
    };
    let side = images
        .iter()
        .map(|t| t.width.max(t.height))
        .max()
        .unwrap_or(1)
        .clamp(1, MAX_SIDE)
        .next_power_of_two()
        .min(MAX_SIDE);
    let levels = side.ilog2() + 1;
    // Layer-major, then mip level: the order `create_texture_with_data` expects.
    let mut data = Vec::new();
    for img in &images {
        let mut level = image::RgbaImage::from_raw(img.width, img.height, img.rgba.clone())
            .unwrap_or_else(|| image::RgbaImage::from_pixel(1, 1, image::Rgba([255; 4])));
        level = image::imageops::resize(&level, side, side, image::imageops::FilterType::Triangle);
        for l in 0..levels {
            let s = (side >> l).max(1);
            if l > 0 {
                level =
                    image::imageops::resize(&level, s, s, image::imageops::FilterType::Triangle);
            }
            data.extend_from_slice(level.as_raw());
        }
    }
    device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some("materials.textures"),
            size: wgpu::Extent3d {
                width: side,
                height: side,
                depth_or_array_layers: images.len() as u32,
            },
            mip_level_count: levels,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &data,
    )
}

fn sampler(device: &wgpu::Device) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("materials.sampler"),
        address_mode_u: wgpu::AddressMode::Repeat,
        address_mode_v: wgpu::AddressMode::Repeat,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        anisotropy_clamp: 8,
        ..Default::default()
    })
}
