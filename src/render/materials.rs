//! Materials on the GPU: the Rust twin of `struct Material` in `shaders/common.wgsl`.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::optics::specular::{self, ALBEDO_TABLE};
use crate::scene::{Material, Plan, Scene};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug, Default)]
pub struct GpuMaterial {
    pub kind: u32,
    pub subsurface: u32,
    pub eta: f32,
    pub double_sided: u32,
    pub albedo: [f32; 4],
    pub sigma_tr: [f32; 4],
    pub z_r: [f32; 4],
    pub z_v: [f32; 4],
    pub alpha: [f32; 4],
    /// GGX α, metallic, dielectric F0, base colour texture layer (−1: none).
    pub surface: [f32; 4],
    /// Normal map layer (−1: none), its scale, occlusion map layer (−1: none), its strength.
    pub maps: [f32; 4],
    /// Wrap codes (`scene::sampling::Sampling::code`) of the base colour, normal and
    /// occlusion maps.
    pub wrap: [u32; 4],
    /// The lobe's directional-albedo table, two (A, B) entries per vec4.
    pub lobe: [[f32; 4]; ALBEDO_TABLE / 2],
    /// xy: the table's hemisphere averages (`specular::lobe_average_split`); zw unused.
    pub lobe_average: [f32; 4],
}

/// The interface half of a material: its α, metallic, F0 and lobe table (zeros for emitters).
fn interface(m: &Material) -> (u32, [f32; 4], [[f32; 4]; ALBEDO_TABLE / 2], [f32; 4]) {
    let Some(s) = m.surface() else {
        return (0, [0.0; 4], [[0.0; 4]; ALBEDO_TABLE / 2], [0.0; 4]);
    };
    let alpha = specular::alpha(s.roughness);
    let table = &s.lobe;
    let lobe = std::array::from_fn(|k| {
        let (a, b) = (table[2 * k], table[2 * k + 1]);
        [a[0] as f32, a[1] as f32, b[0] as f32, b[1] as f32]
    });
    let surface = [alpha as f32, s.metallic as f32, s.dielectric_f0 as f32, 0.0];
    let [a, b] = specular::lobe_average_split(table);
    let average = [a as f32, b as f32, 0.0, 0.0];
    (u32::from(s.double_sided), surface, lobe, average)
}

/// The scene's materials; `subsurface` says which translucent ones get the subsurface rungs
/// (all translucent ones when `plan` is `None`, as for the photon map).
pub fn gpu_materials(scene: &Scene, plan: Option<&Plan>) -> Vec<GpuMaterial> {
    scene
        .materials
        .iter()
        .enumerate()
        .map(|(id, (_, m))| {
            let albedo = m.albedo();
            let rgba = |v: [f64; 3]| [v[0] as f32, v[1] as f32, v[2] as f32, 0.0];
            let (double_sided, mut surface, lobe, lobe_average) = interface(m);
            // The base colour texture's layer, −1 for none.
            surface[3] = scene
                .material_textures
                .get(id)
                .copied()
                .flatten()
                .map_or(-1.0, |layer| layer as f32);
            let (normal, scale) = scene
                .material_normal_maps
                .get(id)
                .copied()
                .flatten()
                .map_or((-1.0, 1.0), |(layer, k)| (layer as f32, k));
            let (occlusion, strength) = scene
                .material_occlusion_maps
                .get(id)
                .copied()
                .flatten()
                .map_or((-1.0, 0.0), |(layer, k)| (layer as f32, k));
            let maps = [normal, scale, occlusion, strength];
            let code = |images: &[crate::scene::TextureImage], layer: f32| {
                (layer >= 0.0)
                    .then(|| images.get(layer as usize))
                    .flatten()
                    .map_or(0, |t| t.sampling.code())
            };
            let wrap = [
                code(&scene.textures, surface[3]),
                code(&scene.linear_maps, normal),
                code(&scene.linear_maps, occlusion),
                0,
            ];
            match m {
                Material::Opaque { .. } => GpuMaterial {
                    albedo: rgba(albedo),
                    eta: 1.0,
                    double_sided,
                    surface,
                    maps,
                    wrap,
                    lobe,
                    lobe_average,
                    ..Default::default()
                },
                Material::Translucent { eta, dipole, .. } => GpuMaterial {
                    kind: 1,
                    subsurface: plan.map(|p| p.subsurface(id)).unwrap_or(true) as u32,
                    eta: *eta as f32,
                    double_sided,
                    surface,
                    maps,
                    wrap,
                    lobe,
                    lobe_average,
                    albedo: rgba(albedo),
                    sigma_tr: rgba(dipole.map(|d| d.sigma_tr)),
                    z_r: rgba(dipole.map(|d| d.z_r)),
                    z_v: rgba(dipole.map(|d| d.z_v)),
                    alpha: rgba(dipole.map(|d| d.albedo)),
                },
                // Shaded as its own exitance, carried in the albedo slot.
                Material::Emitter { emission } => GpuMaterial {
                    kind: 2,
                    albedo: rgba(*emission),
                    eta: 1.0,
                    ..Default::default()
                },
            }
        })
        .collect()
}

/// Bits of the kinds of material a scene has (`SCENE_KINDS` in the shading shader): bit
/// `1 << kind` per `GpuMaterial::kind` value.
pub const KIND_OPAQUE: u32 = 1;
pub const KIND_TRANSLUCENT: u32 = 2;
pub const KIND_EMITTER: u32 = 4;

/// The kinds of material in `materials`, as `KIND_*` bits: shading compiles out the others.
/// Taken from the materials the shader reads, so the two cannot disagree.
pub fn kinds(materials: &[GpuMaterial]) -> u32 {
    materials.iter().fold(0, |all, m| all | 1 << m.kind)
}

pub fn upload(device: &wgpu::Device, label: &str, materials: &[GpuMaterial]) -> wgpu::Buffer {
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(materials),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    })
}

/// Each material's subsurface reach in mm, as vec4s (x used), for the screen-space rung.
pub fn upload_reach(device: &wgpu::Device, scene: &Scene) -> wgpu::Buffer {
    let reach: Vec<[f32; 4]> = scene
        .materials
        .iter()
        .map(|(_, m)| [m.reach_mm() as f32, 0.0, 0.0, 0.0])
        .collect();
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("materials.reach"),
        contents: bytemuck::cast_slice(&reach),
        usage: wgpu::BufferUsages::STORAGE,
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn gpu_material_matches_the_wgsl_struct_size() {
        assert_eq!(
            std::mem::size_of::<super::GpuMaterial>(),
            // Header, eight vec4 fields, the lobe table's eight vec4s, the lobe's averages.
            16 + 8 * 16 + 8 * 16 + 16
        );
    }

    #[test]
    fn a_scene_names_the_kinds_of_material_it_has_and_no_others() {
        use super::{kinds, KIND_EMITTER, KIND_OPAQUE, KIND_TRANSLUCENT};
        let of = |name| {
            let scene = crate::scene::Scene::builtin(name).expect("builtin scene");
            kinds(&super::gpu_materials(&scene, None))
        };
        assert_eq!(of("opaque"), KIND_OPAQUE);
        // One translucent bunny on the background, no floor.
        assert_eq!(of("bunny-marble"), KIND_TRANSLUCENT);
        assert_eq!(of("cornell"), KIND_OPAQUE | KIND_TRANSLUCENT | KIND_EMITTER);
        // Each bit is the one `GpuMaterial::kind` value the shader tests it against.
        for (kind, bit) in [KIND_OPAQUE, KIND_TRANSLUCENT, KIND_EMITTER]
            .iter()
            .enumerate()
        {
            assert_eq!(*bit, 1 << kind);
        }
    }
}
