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
        sampling: Default::default(),
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

/// Where a map reads its texture coordinates: a `TEXCOORD_n` set and the affine transform of
/// `KHR_texture_transform` (identity without it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UvMap {
    pub set: u32,
    /// Rows of the 2×3 matrix: u' = m[0]·(u, v, 1), v' = m[1]·(u, v, 1).
    pub m: [[f32; 3]; 2],
}

impl UvMap {
    pub const IDENTITY: [[f32; 3]; 2] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    /// A texture reference's coordinates: `tex_coord` and its `KHR_texture_transform` object,
    /// if any. The extension's matrix is translation · rotation · scale; the rotation turns
    /// (u, v) by −θ in the texture's frame (u' = cos θ·u + sin θ·v, v' = −sin θ·u + cos θ·v),
    /// which is the direction the extension's own example needs (offset (0, 1), θ = π/2, scale
    /// ½ reads the image's lower-left quadrant). Malformed or non-finite values leave the
    /// identity and a note.
    pub fn of(tex_coord: u32, ext: Option<&serde_json::Value>, notes: &mut Vec<String>) -> UvMap {
        let mut map = UvMap {
            set: tex_coord,
            m: Self::IDENTITY,
        };
        let Some(t) = ext else { return map };
        let pair = |key: &str, default: [f32; 2]| -> Option<[f32; 2]> {
            match t.get(key) {
                None => Some(default),
                Some(v) => {
                    let a = v.as_array().filter(|a| a.len() == 2)?;
                    let x = a[0].as_f64()? as f32;
                    let y = a[1].as_f64()? as f32;
                    (x.is_finite() && y.is_finite()).then_some([x, y])
                }
            }
        };
        let rotation = match t.get("rotation") {
            None => Some(0.0f32),
            Some(v) => v.as_f64().map(|r| r as f32).filter(|r| r.is_finite()),
        };
        let set = match t.get("texCoord") {
            None => Some(tex_coord),
            Some(v) => v.as_u64().and_then(|s| u32::try_from(s).ok()),
        };
        match (
            pair("offset", [0.0; 2]),
            rotation,
            pair("scale", [1.0; 2]),
            set,
        ) {
            (Some([ox, oy]), Some(r), Some([sx, sy]), Some(set)) => {
                let (s, c) = r.sin_cos();
                map.set = set;
                map.m = [[c * sx, s * sy, ox], [-s * sx, c * sy, oy]];
            }
            _ => notes.push(format!(
                "KHR_texture_transform {t}: not a valid transform, ignored"
            )),
        }
        map
    }

    pub fn apply(&self, [u, v]: [f32; 2]) -> [f32; 2] {
        let [a, b] = self.m;
        [a[0] * u + a[1] * v + a[2], b[0] * u + b[1] * v + b[2]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(json: serde_json::Value) -> (UvMap, Vec<String>) {
        let mut notes = Vec::new();
        (UvMap::of(0, Some(&json), &mut notes), notes)
    }

    #[test]
    fn the_extensions_example_reads_the_lower_left_quadrant_turned() {
        let (m, notes) =
            map(serde_json::json!({"offset": [0, 1], "rotation": 1.5707964, "scale": [0.5, 0.5]}));
        assert!(notes.is_empty());
        // The unit square's corners land on the lower-left quadrant (u ≤ ½, v ≥ ½), turned:
        // the source's top edge (v = 0) runs down its left side.
        let close =
            |a: [f32; 2], b: [f32; 2]| (a[0] - b[0]).abs() < 1e-6 && (a[1] - b[1]).abs() < 1e-6;
        assert!(close(m.apply([0.0, 0.0]), [0.0, 1.0]));
        assert!(close(m.apply([1.0, 0.0]), [0.0, 0.5]));
        assert!(close(m.apply([0.0, 1.0]), [0.5, 1.0]));
        assert!(close(m.apply([1.0, 1.0]), [0.5, 0.5]));
    }

    #[test]
    fn defaults_overrides_and_bad_values() {
        let (m, _) = map(serde_json::json!({}));
        assert_eq!(m.m, UvMap::IDENTITY);
        let (m, _) = map(serde_json::json!({"offset": [0, 1], "scale": [1, -1], "texCoord": 1}));
        assert_eq!(m.set, 1);
        assert_eq!(m.apply([0.25, 0.25]), [0.25, 0.75]);
        for bad in [
            serde_json::json!({"scale": [1]}),
            serde_json::json!({"rotation": "x"}),
            serde_json::json!({"offset": [1e39, 0]}),
            serde_json::json!({"texCoord": -1}),
        ] {
            let (m, notes) = map(bad);
            assert_eq!((m.set, m.m), (0, UvMap::IDENTITY));
            assert_eq!(notes.len(), 1);
        }
    }
}
