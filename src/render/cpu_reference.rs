//! A CPU rasteriser for opaque scenes: the same camera, the same shading (Lambert + GGX,
//! `optics::specular::surface`, and the ambient sky) with each vertex's material, pixel
//! centres sampled, perspective-correct normals, no shadows. Slow and simple on purpose; tests
//! hold the GPU image (rendered with shadows off) to it.

use glam::{Vec3, Vec4, Vec4Swizzles};

use crate::optics::color::{linear_to_srgb8, srgb8_to_linear};
use crate::optics::specular;
use crate::scene::Scene;

/// The reference image: sRGB RGBA8 like the GPU's, plus which pixels the mesh covers.
pub struct ReferenceImage {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    pub covered: Vec<bool>,
}

pub fn render_reference(
    scene: &Scene,
    width: u32,
    height: u32,
    to_light: Option<Vec3>,
) -> ReferenceImage {
    let g = rasterise(scene, width, height);
    shade(scene, &g, width, height, to_light)
}

/// Per-pixel depth (infinite where nothing covers it), normal and material.
struct GBuffer {
    depth: Vec<f32>,
    normal: Vec<Vec3>,
    material: Vec<u32>,
}

/// Rasterises every front-facing triangle the way the GPU's rules do (pixel centres,
/// perspective-correct normals, nearest depth wins).
fn rasterise(scene: &Scene, width: u32, height: u32) -> GBuffer {
    let n = (width * height) as usize;
    let mut depth = vec![f32::INFINITY; n];
    let mut normal = vec![Vec3::ZERO; n];
    let mut material = vec![0u32; n];
    let view_proj = scene.file.camera.view_proj(width, height);
    let mesh = &scene.mesh;
    let clip: Vec<Vec4> = mesh
        .positions
        .iter()
        .map(|p| view_proj * p.extend(1.0))
        .collect();
    let (wf, hf) = (width as f32, height as f32);
    for tri in mesh.indices.chunks_exact(3) {
        let idx = [tri[0], tri[1], tri[2]].map(|i| i as usize);
        let c = idx.map(|i| clip[i]);
        if c.iter().any(|v| v.w <= 1e-6) {
            continue; // behind the eye; the shipped scenes keep meshes in front of the camera
        }
        // Window coordinates: x right, y down, pixel centres at +0.5.
        let s = c.map(|v| {
            let ndc = v.xyz() / v.w;
            Vec3::new((ndc.x * 0.5 + 0.5) * wf, (0.5 - ndc.y * 0.5) * hf, ndc.z)
        });
        let area = edge(s[0], s[1], s[2]);
        // Counter-clockwise in NDC is clockwise with y flipped: front faces have area < 0 here.
        if area >= 0.0 {
            continue;
        }
        let lo = s.iter().fold(Vec3::splat(f32::MAX), |a, v| a.min(*v));
        let hi = s.iter().fold(Vec3::splat(f32::MIN), |a, v| a.max(*v));
        let x0 = (lo.x - 0.5).ceil().max(0.0) as u32;
        let y0 = (lo.y - 0.5).ceil().max(0.0) as u32;
        let x1 = ((hi.x - 0.5).floor().min(wf - 1.0)).max(-1.0);
        let y1 = ((hi.y - 0.5).floor().min(hf - 1.0)).max(-1.0);
        if x1 < 0.0 || y1 < 0.0 {
            continue;
        }
        for y in y0..=y1 as u32 {
            for x in x0..=x1 as u32 {
                let p = Vec3::new(x as f32 + 0.5, y as f32 + 0.5, 0.0);
                let b = [
                    edge(s[1], s[2], p) / area,
                    edge(s[2], s[0], p) / area,
                    edge(s[0], s[1], p) / area,
                ];
                if b.iter().any(|&v| v < 0.0) {
                    continue;
                }
                let z = b[0] * s[0].z + b[1] * s[1].z + b[2] * s[2].z;
                let k = (y * width + x) as usize;
                if z >= depth[k] || !(0.0..=1.0).contains(&z) {
                    continue;
                }
                depth[k] = z;
                // Perspective-correct: weight by 1/w, as the GPU interpolates varyings.
                let pw = [b[0] / c[0].w, b[1] / c[1].w, b[2] / c[2].w];
                let sum = pw[0] + pw[1] + pw[2];
                material[k] = mesh.material[idx[0]];
                normal[k] = (mesh.normals[idx[0]] * pw[0]
                    + mesh.normals[idx[1]] * pw[1]
                    + mesh.normals[idx[2]] * pw[2])
                    / sum;
            }
        }
    }
    GBuffer {
        depth,
        normal,
        material,
    }
}

/// Shading of the covered pixels (key light and ambient, no shadows); the background elsewhere.
fn shade(
    scene: &Scene,
    g: &GBuffer,
    width: u32,
    height: u32,
    to_light: Option<Vec3>,
) -> ReferenceImage {
    let n = (width * height) as usize;
    let light = &scene.file.light;
    let l = to_light
        .and_then(|l| l.try_normalize())
        .unwrap_or(Vec3::from(light.to_light))
        .as_dvec3();
    let radiance = (Vec3::from(light.color) * light.intensity).as_dvec3();
    let ambient = f64::from(scene.file.ambient);
    let camera = &scene.file.camera;
    let inv = camera.view_proj(width, height).inverse();
    let eye = Vec3::from(camera.eye);
    let background = scene.file.background_srgb;
    let mut rgba = Vec::with_capacity(n * 4);
    let mut covered = Vec::with_capacity(n);
    for k in 0..n {
        let id = g.material[k] as usize;
        let (Some(surface), true) = (scene.materials[id].1.surface(), g.depth[k].is_finite())
        else {
            // Round-trip so the reference background is exactly what an sRGB clear produces.
            let bg = background.map(|b| linear_to_srgb8(srgb8_to_linear(b)));
            rgba.extend_from_slice(&[bg[0], bg[1], bg[2], 255]);
            covered.push(false);
            continue;
        };
        let (x, y) = (
            (k as u32 % width) as f32 + 0.5,
            (k as u32 / width) as f32 + 0.5,
        );
        let ndc = Vec4::new(
            x / width as f32 * 2.0 - 1.0,
            1.0 - y / height as f32 * 2.0,
            1.0,
            1.0,
        );
        let far = inv * ndc;
        let v = -(far.xyz() / far.w - eye).normalize().as_dvec3();
        let nrm = g.normal[k].try_normalize().unwrap_or(Vec3::ZERO).as_dvec3();
        let h = (l + v).normalize();
        let albedo = scene.materials[id].1.albedo();
        let alpha = specular::alpha(surface.roughness);
        let table = &surface.lobe;
        let c: [f64; 3] = std::array::from_fn(|c| {
            let diffuse = albedo[c] * (1.0 - surface.metallic);
            let f0 = surface.f0[c];
            let lit = specular::surface(
                diffuse,
                f0,
                alpha,
                table,
                nrm.dot(l),
                nrm.dot(v),
                nrm.dot(h),
                v.dot(h),
            );
            let e_o = specular::lobe_albedo(table, f0, nrm.dot(v));
            let e_avg = specular::lobe_average(table, f0);
            radiance[c] * (lit + ambient * (diffuse * (1.0 - e_o) * (1.0 - e_avg) + e_o))
        });
        rgba.extend_from_slice(&[
            linear_to_srgb8(c[0] as f32),
            linear_to_srgb8(c[1] as f32),
            linear_to_srgb8(c[2] as f32),
            255,
        ]);
        covered.push(true);
    }
    ReferenceImage {
        width,
        height,
        rgba,
        covered,
    }
}

fn edge(a: Vec3, b: Vec3, p: Vec3) -> f32 {
    (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x)
}
