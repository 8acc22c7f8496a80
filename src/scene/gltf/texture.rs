//! glTF images, decoded under the size limit. Base colour maps go to the GPU as they are
//! (sampled, filtered and mip-mapped in the G-buffer pass); metallic-roughness and emissive
//! maps contribute their mean to the material's factors.

use crate::scene::limits::MAX_TEXTURE_EDGE;
use crate::scene::TextureImage;

pub fn decode(bytes: &[u8]) -> Result<TextureImage, String> {
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_EDGE);
    limits.max_image_height = Some(MAX_TEXTURE_EDGE);
    limits.max_alloc = Some(u64::from(MAX_TEXTURE_EDGE) * u64::from(MAX_TEXTURE_EDGE) * 8);
    reader.limits(limits);
    let img = reader
        .decode()
        .map_err(|e| format!("{e} (textures up to {MAX_TEXTURE_EDGE}×{MAX_TEXTURE_EDGE})"))?
        .into_rgba8();
    let (width, height) = img.dimensions();
    Ok(TextureImage {
        width,
        height,
        rgba: img.into_raw(),
    })
}

/// The mean of a map, linear (`srgb`: the bytes are sRGB-encoded colour).
pub fn mean(t: &TextureImage, srgb: bool) -> [f32; 4] {
    let n = (t.rgba.len() / 4).max(1) as f32;
    let mut sum = [0.0f32; 4];
    for p in t.rgba.chunks_exact(4) {
        for k in 0..4 {
            let v = f32::from(p[k]) / 255.0;
            sum[k] += if srgb && k < 3 {
                crate::optics::color::srgb_to_linear(v)
            } else {
                v
            };
        }
    }
    sum.map(|s| s / n)
}
