//! glTF images, decoded under the size limit and sampled where the mesh's vertices sit.
//! Fovea has no texture sampling in its shading passes yet: a base colour (or occlusion) map
//! is read at each vertex's UV and carried as a vertex colour, so detail finer than the mesh
//! is lost (stated in `docs/scenes.md`).

use glam::Vec2;

use crate::scene::limits::MAX_TEXTURE_EDGE;

pub struct Texture {
    width: u32,
    height: u32,
    /// Linear RGBA (sRGB decoded when the map holds colour).
    texels: Vec<[f32; 4]>,
}

pub fn decode(bytes: &[u8], srgb: bool) -> Result<Texture, String> {
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    let mut reader = reader;
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
    let to_linear = |c: u8| {
        let v = f32::from(c) / 255.0;
        if srgb {
            crate::optics::color::srgb_to_linear(v)
        } else {
            v
        }
    };
    let texels = img
        .pixels()
        .map(|p| {
            [
                to_linear(p[0]),
                to_linear(p[1]),
                to_linear(p[2]),
                f32::from(p[3]) / 255.0,
            ]
        })
        .collect();
    Ok(Texture {
        width,
        height,
        texels,
    })
}

impl Texture {
    /// Bilinear sample with repeat wrapping (glTF's default sampler); NaN UVs read texel 0.
    pub fn sample(&self, uv: Vec2) -> [f32; 4] {
        let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
        let x = uv.x.rem_euclid(1.0) * self.width as f32 - 0.5;
        let y = uv.y.rem_euclid(1.0) * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (tx, ty) = (x - x0, y - y0);
        let at = |xi: f32, yi: f32| {
            let xi = (xi as i64).rem_euclid(i64::from(self.width)) as usize;
            let yi = (yi as i64).rem_euclid(i64::from(self.height)) as usize;
            self.texels[yi * self.width as usize + xi]
        };
        let (a, b, c, d) = (
            at(x0, y0),
            at(x0 + 1.0, y0),
            at(x0, y0 + 1.0),
            at(x0 + 1.0, y0 + 1.0),
        );
        std::array::from_fn(|k| {
            (a[k] * (1.0 - tx) + b[k] * tx) * (1.0 - ty) + (c[k] * (1.0 - tx) + d[k] * tx) * ty
        })
    }

    /// The mean of the map (what a per-material factor becomes when only the factor is used).
    pub fn mean(&self) -> [f32; 4] {
        let n = self.texels.len().max(1) as f32;
        let mut sum = [0.0f32; 4];
        for t in &self.texels {
            for k in 0..4 {
                sum[k] += t[k];
            }
        }
        sum.map(|s| s / n)
    }
}
