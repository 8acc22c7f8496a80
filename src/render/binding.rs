//! The bindings a pass declares: each resource's name and the WGSL form it is bound as.

use wgpu::{TextureFormat, TextureViewDimension};

use super::gpu;

/// How a pass uses a bound resource; each maps to one WGSL declaration form.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// `var<uniform>`.
    Uniform,
    /// `var<uniform>` selected per dispatch by a dynamic offset; `size` bytes are visible.
    DynamicUniform { size: u64 },
    /// `var<storage, read>`.
    Read,
    /// `var<storage, read_write>`: the pass writes it (and may read it).
    ReadWrite,
    /// `texture_2d<f32>` read with `textureLoad` (never filtered).
    Texture,
    /// `texture_2d_array<f32>` sampled with filtering (material textures).
    TextureArray,
    /// `texture_2d_array<f32>` of 32-bit floats read with `textureLoad` (pyramid layers).
    Layers,
    /// `texture_2d<u32>` read with `textureLoad`.
    UintTexture,
    /// `texture_storage_2d<r32uint, write>`: the pass writes it.
    WriteUint,
    /// A filtering `sampler`.
    Sampler,
}

impl Access {
    /// Whether a pass with this binding writes the resource.
    pub fn writes(self) -> bool {
        matches!(self, Access::ReadWrite | Access::WriteUint)
    }

    /// The bind group layout entry at binding number `i`.
    pub fn layout_entry(self, i: u32) -> wgpu::BindGroupLayoutEntry {
        match self {
            Access::Uniform => gpu::uniform(i, false),
            Access::DynamicUniform { .. } => gpu::uniform(i, true),
            Access::Read => gpu::storage_buffer(i, true),
            Access::ReadWrite => gpu::storage_buffer(i, false),
            Access::Texture => gpu::texture(i, gpu::FLOAT),
            Access::TextureArray => gpu::texture_array(i),
            Access::Layers => gpu::layers(i),
            Access::UintTexture => gpu::texture(i, wgpu::TextureSampleType::Uint),
            Access::WriteUint => {
                gpu::write_storage(i, TextureFormat::R32Uint, TextureViewDimension::D2)
            }
            Access::Sampler => gpu::sampler(i),
        }
    }
}

/// One binding of a pass: the resource (or port) name and how it is used.
#[derive(Debug, Clone, Copy)]
pub struct Binding {
    pub name: &'static str,
    pub access: Access,
}

pub const fn uniform(name: &'static str) -> Binding {
    Binding {
        name,
        access: Access::Uniform,
    }
}
pub const fn dynamic_uniform(name: &'static str, size: u64) -> Binding {
    Binding {
        name,
        access: Access::DynamicUniform { size },
    }
}
pub const fn read(name: &'static str) -> Binding {
    Binding {
        name,
        access: Access::Read,
    }
}
pub const fn write(name: &'static str) -> Binding {
    Binding {
        name,
        access: Access::ReadWrite,
    }
}
pub const fn texture(name: &'static str) -> Binding {
    Binding {
        name,
        access: Access::Texture,
    }
}
pub const fn texture_array(name: &'static str) -> Binding {
    Binding {
        name,
        access: Access::TextureArray,
    }
}
pub const fn layers(name: &'static str) -> Binding {
    Binding {
        name,
        access: Access::Layers,
    }
}
pub const fn uint_texture(name: &'static str) -> Binding {
    Binding {
        name,
        access: Access::UintTexture,
    }
}
pub const fn write_uint(name: &'static str) -> Binding {
    Binding {
        name,
        access: Access::WriteUint,
    }
}
pub const fn sampler(name: &'static str) -> Binding {
    Binding {
        name,
        access: Access::Sampler,
    }
}
