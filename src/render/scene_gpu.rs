//! A scene on the GPU: its mesh, materials, photon map (when something is translucent) and
//! radiosity solve (when its plan asks for one), and the resources every stream of it binds.

use super::gi::start_radiosity;
use super::graph::{GraphError, Pipelines, Resources};
use super::pass::gbuffer::{self, MeshBuffers};
use super::pass::photons::{PhotonMap, PhotonPass};
use super::pass::shadow::ShadowMap;
use crate::radiosity::{Progress, RadiosityHandle};
use crate::scene::Scene;

pub struct SceneGpu {
    pub scene: Scene,
    pub mesh: MeshBuffers,
    /// The kinds of material it has (`materials::KIND_*`), for the shading pipeline.
    pub kinds: u32,
    pub photons: Option<PhotonMap>,
    /// The key and punctual lights' shadow maps (`shadow.depth`, `shadow.atlas` in `resources`),
    /// when the plan has shadows.
    pub shadow: Option<ShadowMap>,
    /// `materials.scene` (every translucent material marked subsurface, for the G-buffer and
    /// the photon map), `scene.reach`, and `photons.nodes` with its texels (stand-ins without
    /// photons).
    pub resources: Resources,
    /// The scene's radiosity solve, when its plan asks for one, and the snapshot uploaded.
    pub radiosity: Option<RadiosityHandle>,
    pub gi: Option<Progress>,
    pub gi_version: u64,
}

impl SceneGpu {
    pub fn upload(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        pipelines: &mut Pipelines,
        photon_pass: &PhotonPass,
        scene: Scene,
    ) -> Result<SceneGpu, GraphError> {
        fits_the_device(&scene, &device.limits())?;
        let mesh = gbuffer::upload(device, &scene);
        let gpu_materials = super::materials::gpu_materials(&scene, None);
        let materials = super::materials::upload(device, "materials.scene", &gpu_materials);
        // The shadow maps first: the photon pass tests its photons against the key light's.
        let mut maps = Resources::default();
        let shadow = if crate::scene::Plan::of(&scene, 1, 1).shadows {
            let tiles = super::lights::shadow_tiles(&scene).len();
            Some(ShadowMap::new(device, pipelines, tiles)?)
        } else {
            None
        };
        for name in ["shadow.depth", "shadow.atlas"] {
            let map = shadow
                .as_ref()
                .and_then(|m| m.resources.get_texture(name).map(|(t, _)| t.clone()));
            // Bound in place of a map the scene has none of (the shader is told not to look).
            let map = map.unwrap_or_else(|| {
                super::gpu::texture_2d(
                    device,
                    "shadow.none",
                    (1, 1),
                    wgpu::TextureFormat::R32Float,
                    wgpu::TextureUsages::TEXTURE_BINDING,
                )
            });
            maps.texture(name, map);
        }
        // The photons test the key light's map and carry the extra lights' light.
        maps.buffer("materials.scene", materials.clone());
        maps.buffer("lights.scene", super::lights::upload(device, &scene));
        let tile_views = super::lights::upload_tile_views(device, queue, &scene);
        maps.texture("shadow.tile_views", tile_views);
        let photons = if scene.has_translucency() {
            Some(photon_pass.create_map(device, pipelines, &maps)?)
        } else {
            None
        };
        let mut resources = Resources::default();
        resources.extend(&maps);
        resources.buffer(
            "scene.reach",
            super::materials::upload_reach(device, &scene),
        );
        let nodes = match photons.as_ref().and_then(PhotonMap::nodes) {
            Some(nodes) => nodes.clone(),
            // Bound in place of the pyramid when the scene has none.
            None => device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("photons.none"),
                size: 48,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            }),
        };
        resources.buffer("photons.nodes", nodes);
        let texels = match photons.as_ref().and_then(PhotonMap::node_texels) {
            Some(t) => t.clone(),
            None => super::gpu::texture_2d(
                device,
                "photons.none",
                (1, 1),
                wgpu::TextureFormat::Rgba32Float,
                wgpu::TextureUsages::TEXTURE_BINDING,
            ),
        };
        resources.texture("photons.node_texels", texels);
        let (textures, linear_maps, samplers) = super::textures::upload(device, queue, &scene);
        resources.texture_array("materials.textures", textures);
        resources.texture_array("materials.linear_maps", linear_maps);
        for (name, sampler) in super::textures::SAMPLERS.into_iter().zip(samplers) {
            resources.sampler(name, sampler);
        }
        tracing::info!(scene = %scene.name(), triangles = scene.mesh.triangle_count(), translucent = scene.has_translucency(), "scene loaded");
        let radiosity = start_radiosity(&scene);
        Ok(SceneGpu {
            kinds: super::materials::kinds(&gpu_materials),
            scene,
            mesh,
            photons,
            shadow,
            resources,
            radiosity,
            gi: None,
            gi_version: 0,
        })
    }
}

/// Whether the scene's largest buffers fit the device: a scene within the scene-file limits
/// fits wgpu's default limits (a test checks), but an adapter may offer less, and wgpu would
/// panic on the buffer rather than say so.
pub fn fits_the_device(scene: &Scene, limits: &wgpu::Limits) -> Result<(), GraphError> {
    let vertices = scene.mesh.positions.len() as u64;
    let needs = [
        (
            "vertices",
            vertices * std::mem::size_of::<gbuffer::Vertex>() as u64,
        ),
        (
            "radiosity",
            vertices * std::mem::size_of::<gbuffer::GiVertex>() as u64,
        ),
        ("indices", scene.mesh.indices.len() as u64 * 4),
    ];
    for (what, bytes) in needs {
        if bytes > limits.max_buffer_size {
            return Err(GraphError::TooLarge(what, bytes, limits.max_buffer_size));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::limits::{MAX_TRIANGLES, MAX_VERTICES};

    #[test]
    fn scenes_within_the_file_limits_fit_the_limits_we_ask_the_device_for() {
        let limits = wgpu::Limits::default();
        let vertex = std::mem::size_of::<gbuffer::Vertex>() as u64;
        assert!(MAX_VERTICES as u64 * vertex <= limits.max_buffer_size);
        assert!(MAX_TRIANGLES as u64 * 12 <= limits.max_buffer_size);
        let scene = Scene::builtin(crate::scene::DEFAULT_SCENE).unwrap();
        assert!(fits_the_device(&scene, &limits).is_ok());
        let small = wgpu::Limits {
            max_buffer_size: 1024,
            ..limits
        };
        let err = fits_the_device(&scene, &small).unwrap_err().to_string();
        assert!(err.contains("1024"), "{err}");
    }
}
