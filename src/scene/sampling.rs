//! How a texture is read: glTF samplers' wrap modes (per axis) and magnification filter. The
//! G-buffer pass reads each map through a GPU sampler with its pair of wrap modes (folding
//! coordinates in the shader instead left seams along triangle edges on the software adapter);
//! a nearest-magnified texture is enlarged without filtering when it is uploaded, so it stays
//! blocky however far it is magnified.

/// Outside [0, 1] along one axis: glTF's `REPEAT`, `CLAMP_TO_EDGE`, `MIRRORED_REPEAT`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Wrap {
    #[default]
    Repeat = 0,
    Clamp = 1,
    Mirror = 2,
}

impl From<::gltf::texture::WrappingMode> for Wrap {
    fn from(w: ::gltf::texture::WrappingMode) -> Wrap {
        match w {
            ::gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
            ::gltf::texture::WrappingMode::ClampToEdge => Wrap::Clamp,
            ::gltf::texture::WrappingMode::MirroredRepeat => Wrap::Mirror,
        }
    }
}

/// A texture's sampler, as far as Fovea honours it (minification is always trilinear).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Sampling {
    /// u (glTF `wrapS`) and v (`wrapT`).
    pub wrap: [Wrap; 2],
    /// glTF `magFilter` `NEAREST`: texels stay square when magnified.
    pub nearest: bool,
}

impl Sampling {
    /// The code the shader reads: u's mode in bits 0–1, v's in bits 2–3.
    pub fn code(&self) -> u32 {
        self.wrap[0] as u32 | (self.wrap[1] as u32) << 2
    }

    pub fn of_gltf(s: &::gltf::texture::Sampler) -> Sampling {
        Sampling {
            wrap: [s.wrap_s().into(), s.wrap_t().into()],
            nearest: s.mag_filter() == Some(::gltf::texture::MagFilter::Nearest),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_pack_u_then_v() {
        let s = Sampling {
            wrap: [Wrap::Mirror, Wrap::Clamp],
            nearest: false,
        };
        assert_eq!(s.code(), 2 | 1 << 2);
        assert_eq!(Sampling::default().code(), 0);
    }
}
