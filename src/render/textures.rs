//! A scene's textures on the GPU: its base colour maps in one sRGB texture array and its normal
//! maps in a linear one (every image resized to the largest one's square, at most `MAX_SIDE`,
//! with a full mip chain made here), and a trilinear sampler for each pair of wrap modes (u, v)
//! glTF can ask for; the G-buffer pass reads each map through its own (`scene::sampling`).

use wgpu::util::DeviceExt;

use crate::scene::sampling::Wrap;
use crate::scene::{Scene, TextureImage};

/// Largest layer side: larger images are scaled down to it.
pub const MAX_SIDE: u32 = 2048;

/// Layer texels per texel, at least, of a texture magnified with glTF's `NEAREST`.
pub const NEAREST_ENLARGE: u32 = 64;

/// The samplers' resource names in the order of [`SAMPLER_MODES`].
pub const SAMPLERS: [&str; 9] = [
    "materials.sampler",
    "materials.sampler_cr",
    "materials.sampler_mr",
    "materials.sampler_rc",
    "materials.sampler_cc",
    "materials.sampler_mc",
    "materials.sampler_rm",
    "materials.sampler_cm",
    "materials.sampler_mm",
];

/// (u, v) wrap modes of each sampler, u varying fastest: the order of the codes 0, 1, 2, 4, …,
/// 10 that `sample_map` in shaders/gbuffer.wgsl switches on.
pub const SAMPLER_MODES: [(Wrap, Wrap); 9] = {
    use Wrap::*;
    [
        (Repeat, Repeat),
        (Clamp, Repeat),
        (Mirror, Repeat),
        (Repeat, Clamp),
        (Clamp, Clamp),
        (Mirror, Clamp),
        (Repeat, Mirror),
        (Clamp, Mirror),
        (Mirror, Mirror),
    ]
};

/// The base colour array (sRGB), the normal map array (linear) and their samplers (in the
/// order of [`SAMPLERS`]).
pub fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &Scene,
) -> (wgpu::Texture, wgpu::Texture, Vec<wgpu::Sampler>) {
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
    let address = |w: Wrap| match w {
        Wrap::Repeat => wgpu::AddressMode::Repeat,
        Wrap::Clamp => wgpu::AddressMode::ClampToEdge,
        Wrap::Mirror => wgpu::AddressMode::MirrorRepeat,
    };
    let samplers = SAMPLER_MODES
        .iter()
        .map(|&(u, v)| sampler(device, address(u), address(v)))
        .collect();
    (base, normals, samplers)
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
        sampling: Default::default(),
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
    // A nearest-magnified image gets at least NEAREST_ENLARGE layer texels per texel, so the
    // filtered edge between two of its texels is a sliver however far it is magnified.
    let side = images
        .iter()
        .filter(|t| t.sampling.nearest)
        .map(|t| {
            (t.width.max(t.height).saturating_mul(NEAREST_ENLARGE))
                .min(MAX_SIDE)
                .next_power_of_two()
        })
        .fold(side, u32::max)
        .min(MAX_SIDE);
    let levels = side.ilog2() + 1;
    // Layer-major, then mip level: the order `create_texture_with_data` expects.
    let mut data = Vec::new();
    for img in &images {
        let mut level = image::RgbaImage::from_raw(img.width, img.height, img.rgba.clone())
            .unwrap_or_else(|| image::RgbaImage::from_pixel(1, 1, image::Rgba([255; 4])));
        // A nearest-magnified texture is enlarged without filtering, so its texels stay square
        // at the layer's resolution (glTF magFilter NEAREST); shrinking always filters.
        let enlarge = if img.sampling.nearest && img.width.max(img.height) < side {
            image::imageops::FilterType::Nearest
        } else {
            image::imageops::FilterType::Triangle
        };
        level = image::imageops::resize(&level, side, side, enlarge);
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

fn sampler(device: &wgpu::Device, u: wgpu::AddressMode, v: wgpu::AddressMode) -> wgpu::Sampler {
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("materials.sampler"),
        address_mode_u: u,
        address_mode_v: v,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        anisotropy_clamp: 8,
        ..Default::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::sampling::Sampling;

    #[test]
    fn each_sampler_sits_where_its_code_points() {
        // sample_map's switch: code c reads SAMPLERS[index], codes 0,1,2,4,5,6,8,9,10.
        for (index, &(u, v)) in SAMPLER_MODES.iter().enumerate() {
            let code = Sampling {
                wrap: [u, v],
                nearest: false,
            }
            .code();
            assert_eq!(code as usize, index / 3 * 4 + index % 3, "{u:?} {v:?}");
        }
    }
}
