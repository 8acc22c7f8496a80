//! The renderer's side of radiosity: starting (or joining) a scene's solve, and uploading its
//! newest snapshot as the per-vertex irradiance buffer.

use super::pass::gbuffer::GiVertex;
use super::scene_gpu::SceneGpu;
use crate::scene::{Plan, Scene};

/// Starts (or joins) the scene's radiosity solve when its plan asks for one.
pub(super) fn start_radiosity(scene: &Scene) -> Option<crate::radiosity::RadiosityHandle> {
    if !Plan::of(scene, 1, 1).radiosity {
        return None;
    }
    let options = crate::radiosity::Options {
        stop_fraction: scene.file.radiosity.map_or(0.001, |r| r.stop_fraction),
        sun: crate::scene::plan::radiosity_sun(scene),
        ..Default::default()
    };
    match crate::radiosity::RadiosityHandle::start(
        scene.name(),
        scene.radiosity_surfaces(),
        options,
    ) {
        Ok(h) => Some(h),
        Err(e) => {
            tracing::warn!(scene = scene.name(), error = %e, "radiosity unavailable; direct light only");
            None
        }
    }
}

/// Uploads the solve's newest snapshot if it is newer than the one on the GPU.
pub(super) fn upload_radiosity(queue: &wgpu::Queue, sg: &mut SceneGpu) {
    let Some(handle) = &sg.radiosity else { return };
    if handle.version() <= sg.gi_version {
        return;
    }
    let Some(snap) = handle.latest() else { return };
    let data: Vec<GiVertex> = snap
        .direct
        .iter()
        .zip(&snap.indirect)
        .map(|(d, i)| GiVertex {
            direct: *d,
            indirect: *i,
        })
        .collect();
    if data.len() == sg.scene.mesh.positions.len() {
        queue.write_buffer(&sg.mesh.gi, 0, bytemuck::cast_slice(&data));
    } else {
        tracing::error!(
            scene = sg.scene.name(),
            "radiosity output does not match the mesh; ignored"
        );
    }
    sg.gi_version = snap.version;
    sg.gi = Some(snap.progress());
}
