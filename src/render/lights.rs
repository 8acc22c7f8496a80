//! Extra punctual lights on the GPU: the Rust twin of `struct PunctualLight` in
//! `shaders/common.wgsl`, uploaded once per scene as `lights.scene`, and the cameras of their
//! shadow maps: a spot light gets one perspective tile of the shadow atlas, a point light six
//! (a cube, one 90° tile per axis direction).

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

use crate::optics::lights::Punctual;
use crate::render::pass::shadow::{ATLAS_TILES, TILE};
use crate::scene::{LightSpec, Scene};

/// Cube faces in tile order: +X, −X, +Y, −Y, +Z, −Z (`cube_face` in `shaders/common.wgsl`).
const CUBE: [Vec3; 6] = [
    Vec3::X,
    Vec3::NEG_X,
    Vec3::Y,
    Vec3::NEG_Y,
    Vec3::Z,
    Vec3::NEG_Z,
];

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug, Default, PartialEq)]
pub struct GpuLight {
    /// xyz: position (point, spot) or unit vector towards the light (directional); w: kind.
    pub position_kind: [f32; 4],
    /// rgb: colour × intensity; w: range (0: none).
    pub color_range: [f32; 4],
    /// xyz: spot axis (away from the light); w: cos of the outer angle.
    pub axis_cos_outer: [f32; 4],
    /// x: cos of the inner angle.
    pub cone: [f32; 4],
    /// x: first shadow tile, −1 for none (a spot uses one, a point light six in `CUBE` order;
    /// their cameras are in `shadow.tile_views`); y: a texel's size per unit of distance from
    /// the light (sets the bias and normal offset); z: tile side; w: tiles per atlas row.
    pub shadow: [f32; 4],
}

/// The cameras of one light's shadow tiles.
#[derive(Debug, Clone, PartialEq)]
pub struct LightViews {
    /// World → clip, one per tile.
    pub view_projs: Vec<Mat4>,
    pub position: Vec3,
    /// A texel's size per unit of distance from the light, at the tile's centre.
    pub texel: f32,
}

/// The index of the cube face (`CUBE` order) that sees direction `d` from a point light: the
/// axis of `d`'s largest component. CPU twin of `cube_face` in `shaders/common.wgsl`.
pub fn cube_face(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        usize::from(d.x < 0.0)
    } else if a.y >= a.z {
        2 + usize::from(d.y < 0.0)
    } else {
        4 + usize::from(d.z < 0.0)
    }
}

/// Near and far planes that hold the whole scene seen from `pos`.
fn depth_range(scene: &Scene, pos: Vec3) -> (f32, f32) {
    let (lo, hi) = scene.mesh.bounds();
    let far = (0..8)
        .map(|k| {
            let corner = Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            corner.distance(pos)
        })
        .fold(0.0f32, f32::max)
        * 1.01;
    let near = ((hi - lo).length() * 1e-3).max(1e-4);
    (near, far.max(near * 2.0))
}

/// A perspective camera at `pos` looking along `axis`, `fov` radians wide.
fn look(pos: Vec3, axis: Vec3, fov: f32, (near, far): (f32, f32)) -> Mat4 {
    let up = if axis.y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    Mat4::perspective_rh(fov, 1.0, near, far) * Mat4::look_at_rh(pos, pos + axis, up)
}

/// The shadow cameras of a spot light (one tile along its axis, as wide as its outer cone) or a
/// point light (six 90° tiles); `None` for a directional light (the key light's map serves it).
pub fn light_views(scene: &Scene, l: &LightSpec) -> Option<LightViews> {
    let (position, view_projs, fov) = match *l {
        LightSpec::Spot {
            position,
            direction,
            outer_deg,
            ..
        } => {
            let pos = Vec3::from(position);
            let axis = Vec3::from(direction).normalize_or(Vec3::NEG_Y);
            let fov = (2.0 * outer_deg).clamp(1.0, 170.0).to_radians();
            (
                pos,
                vec![look(pos, axis, fov, depth_range(scene, pos))],
                fov,
            )
        }
        LightSpec::Point { position, .. } => {
            let pos = Vec3::from(position);
            let range = depth_range(scene, pos);
            let fov = std::f32::consts::FRAC_PI_2;
            (pos, CUBE.map(|a| look(pos, a, fov, range)).to_vec(), fov)
        }
        LightSpec::Directional { .. } => return None,
    };
    Some(LightViews {
        view_projs,
        position,
        texel: 2.0 * (fov * 0.5).tan() / TILE as f32,
    })
}

/// The scene's shadowed lights in tile order, with the first tile of each: a light gets all of
/// its tiles or none, in the scene's order, while the atlas has room.
pub fn shadowed_lights(scene: &Scene) -> Vec<(usize, usize, LightViews)> {
    let mut next = 0;
    let mut out = Vec::new();
    for (i, l) in scene.file.lights.iter().enumerate() {
        if let Some(v) = light_views(scene, l) {
            if next + v.view_projs.len() <= ATLAS_TILES {
                let first = next;
                next += v.view_projs.len();
                out.push((i, first, v));
            }
        }
    }
    out
}

/// Every shadow tile in atlas order: (view-projection, the light's position).
pub fn shadow_tiles(scene: &Scene) -> Vec<(Mat4, Vec3)> {
    shadowed_lights(scene)
        .into_iter()
        .flat_map(|(_, _, v)| v.view_projs.into_iter().map(move |m| (m, v.position)))
        .collect()
}

pub fn gpu_light(l: &LightSpec) -> GpuLight {
    let p = Punctual::of(l);
    GpuLight {
        position_kind: p.at.extend(p.kind as f32).to_array(),
        color_range: p.radiance.extend(p.range).to_array(),
        axis_cos_outer: p.axis.extend(p.cos_outer).to_array(),
        cone: [p.cos_inner, 0.0, 0.0, 0.0],
        shadow: [-1.0, 0.0, 0.0, 0.0],
    }
}

/// The scene's extra lights (one unused entry when it has none: storage buffers cannot be
/// empty).
pub fn upload(device: &wgpu::Device, scene: &Scene) -> wgpu::Buffer {
    let mut lights: Vec<GpuLight> = scene.file.lights.iter().map(gpu_light).collect();
    let columns = crate::render::pass::shadow::atlas_columns(shadow_tiles(scene).len());
    for (i, first, v) in shadowed_lights(scene) {
        lights[i].shadow = [first as f32, v.texel, TILE as f32, columns as f32];
    }
    if lights.is_empty() {
        lights.push(GpuLight::default());
    }
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("lights.scene"),
        contents: bytemuck::cast_slice(&lights),
        usage: wgpu::BufferUsages::STORAGE,
    })
}

/// Every shadow tile's world → clip matrix, one row of four rgba32float texels (its columns)
/// per tile in atlas order (`shadow.tile_views`). A texture rather than a field of each light:
/// the cube face differs from pixel to pixel, and a software adapter fetches texels for a whole
/// SIMD row at once where it reads a matrix picked per lane from a buffer one lane at a time
/// (gallery's extra lights cost 545 ms of a 710 ms opaque shading pass so, 640x480, lavapipe).
pub fn upload_tile_views(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    scene: &Scene,
) -> wgpu::Texture {
    let tiles = shadow_tiles(scene);
    let mut texels: Vec<[[f32; 4]; 4]> = tiles.iter().map(|(m, _)| m.to_cols_array_2d()).collect();
    if texels.is_empty() {
        texels.push([[0.0; 4]; 4]);
    }
    device.create_texture_with_data(
        queue,
        &wgpu::TextureDescriptor {
            label: Some("shadow.tile_views"),
            size: wgpu::Extent3d {
                width: 4,
                height: texels.len() as u32,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        bytemuck::cast_slice(&texels),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every direction lands inside the tile of the face `cube_face` picks, in front of it.
    #[test]
    fn each_direction_projects_inside_the_face_it_picks() {
        let scene = Scene::builtin("bunny").expect("built-in scene");
        let pos = Vec3::new(0.1, 0.3, -0.2);
        let light = LightSpec::Point {
            position: pos.into(),
            color: [1.0; 3],
            intensity: 1.0,
            range: None,
        };
        let views = light_views(&scene, &light).expect("a point light has views");
        assert_eq!(views.view_projs.len(), 6);
        let mut seen = [0; 6];
        let mut s = 12345u64;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        for k in 0..20_000 {
            // Random directions, and the exact diagonals and axes (ties between faces).
            let d = match k {
                0..=7 => Vec3::new(
                    if k & 1 == 0 { 1.0 } else { -1.0 },
                    if k & 2 == 0 { 1.0 } else { -1.0 },
                    if k & 4 == 0 { 1.0 } else { -1.0 },
                ),
                8..=13 => CUBE[k - 8],
                _ => Vec3::new(next(), next(), next()),
            };
            if d.length() < 1e-3 {
                continue;
            }
            let face = cube_face(d);
            seen[face] += 1;
            let p = views.view_projs[face] * (pos + d.normalize() * 0.05).extend(1.0);
            assert!(p.w > 0.0, "{d} behind face {face}");
            let ndc = p.truncate() / p.w;
            assert!(
                ndc.x.abs() <= 1.0 + 1e-4 && ndc.y.abs() <= 1.0 + 1e-4,
                "{d} outside face {face}: {ndc}"
            );
        }
        assert!(seen.iter().all(|&n| n > 2000), "faces picked {seen:?}");
    }
}
