//! A scene file made into a `Scene`: every value checked, every object's mesh loaded (built
//! in, or a file beside the scene inside its folder), transformed and appended to the one
//! combined mesh, glTF materials and lights merged in.

use std::path::Path;

use glam::{Mat4, Quat, Vec3};

use super::folder::Folder;
use super::gltf::{self, Imported};
use super::limits::{read_limited, MAX_TRIANGLES, MAX_VERTICES};
use super::{
    parse_ply, Material, Mesh, Placed, RadiosityMode, RadiositySpec, RawMesh, Scene, SceneError,
    SceneFile, BUILTIN_MESHES,
};

/// Most materials a scene may have: the G-buffer stores id + 1 in 8 bits.
pub const MAX_MATERIALS: usize = 254;

/// Where a scene file's relative paths lead: its folder and its own directory in it. `None`
/// for built-in scenes and JSON given inline, which may name built-in meshes only.
pub type Location<'a> = Option<(&'a Folder, &'a Path)>;

/// An object's geometry before placement.
pub enum Loaded {
    Plain(RawMesh),
    Gltf(Imported),
}

pub fn build(json: &str, at: Location) -> Result<Scene, SceneError> {
    build_with(json, at, None)
}

/// `build`, with one mesh already loaded (by the name objects use for it).
pub fn build_with(
    json: &str,
    at: Location,
    mut preloaded: Option<(String, Loaded)>,
) -> Result<Scene, SceneError> {
    let mut file: SceneFile = serde_json::from_str(json).map_err(|source| SceneError::Json {
        scene: "<json>".into(),
        source,
    })?;
    let scene = file.name.clone();
    let invalid = |message: String| SceneError::Invalid {
        scene: scene.clone(),
        message,
    };
    check_file(&mut file).map_err(&invalid)?;
    let mut materials = Vec::new();
    for (name, spec) in &file.materials {
        let m =
            Material::from_spec(spec).map_err(|e| invalid(format!("material {name:?}: {e}")))?;
        materials.push((name.clone(), m));
    }
    let mut lights = file.lights.clone();
    let mut textures = Vec::new();
    let mut material_textures: Vec<Option<u32>> = Vec::new();
    let mut linear_maps = Vec::new();
    let mut material_normal_maps: Vec<Option<(u32, f32)>> = Vec::new();
    let mut material_occlusion_maps: Vec<Option<(u32, f32)>> = Vec::new();
    let mut notes = Vec::new();
    let mut mesh = Mesh::default();
    let mut placed = Vec::new();
    for (i, object) in file.objects.iter().enumerate() {
        if !(object.scale.is_finite() && object.scale > 0.0)
            || !Vec3::from(object.translate).is_finite()
            || !object.rotate_y_deg.is_finite()
        {
            return Err(invalid(format!(
                "object {i}: scale must be > 0 and the transform finite"
            )));
        }
        let transform = Mat4::from_scale_rotation_translation(
            Vec3::splat(object.scale),
            Quat::from_rotation_y(object.rotate_y_deg.to_radians()),
            Vec3::from(object.translate),
        );
        let named = |materials: &[(String, Material)]| {
            materials
                .iter()
                .position(|(n, _)| *n == object.material)
                .ok_or_else(|| {
                    invalid(format!(
                        "object {i} uses material {:?}, which the scene does not define",
                        object.material
                    ))
                })
        };
        let mut quad = None;
        let loaded = match object.mesh.as_str() {
            "plane" => Loaded::Plain(plane()),
            "quad" => {
                let corners = object
                    .corners
                    .map(|c| c.map(Vec3::from))
                    .ok_or_else(|| invalid(format!("object {i}: a quad needs its four corners")))?;
                let (cells, depth) =
                    quad_lattice(&corners, file.radiosity.as_ref()).ok_or_else(|| {
                        invalid(format!(
                            "object {i}: quad corners must be finite and form a parallelogram"
                        ))
                    })?;
                // Checked before the lattice is built: a fine grid at depth 6 would otherwise
                // allocate hundreds of megabytes before the scene's vertex limit is looked at.
                let [lu, lv] = crate::radiosity::lattice(cells, depth);
                let points = (u64::from(lu) + 1) * (u64::from(lv) + 1);
                if mesh.positions.len() as u64 + points > MAX_VERTICES as u64 {
                    return Err(invalid(format!(
                        "object {i}: its radiosity lattice ({lu}x{lv} cells: {cells:?} patches \
                         halved {depth} times) needs {points} vertices, and the scene may have \
                         {MAX_VERTICES}; raise radiosity.patch_size or lower max_depth"
                    )));
                }
                quad = Some((corners.map(|p| transform.transform_point3(p)), cells, depth));
                Loaded::Plain(lattice_mesh(
                    &corners,
                    crate::radiosity::lattice(cells, depth),
                ))
            }
            name => match preloaded.take_if(|(n, _)| n == name) {
                Some((_, loaded)) => loaded,
                None => load_mesh(&scene, name, at)?,
            },
        };
        match loaded {
            Loaded::Plain(raw) => {
                let material = named(&materials)?;
                if raw.dropped_degenerate > 0 {
                    notes.push(format!(
                        "{}: {} degenerate faces dropped",
                        object.mesh, raw.dropped_degenerate
                    ));
                }
                let positions = raw
                    .positions
                    .iter()
                    .map(|p| transform.transform_point3(*p))
                    .collect();
                let part = Mesh::with_smooth_normals(positions, raw.indices);
                append(
                    &mut mesh,
                    &mut placed,
                    part,
                    material,
                    &materials,
                    file.mm_per_unit,
                    quad,
                );
            }
            Loaded::Gltf(imported) => {
                // The file's own materials, named after it, unless the object overrides them.
                let own = if object.material.is_empty() {
                    let base = materials.len();
                    let first_texture = textures.len() as u32;
                    textures.extend(imported.textures.iter().cloned());
                    material_textures.resize(base, None);
                    let first_normal = linear_maps.len() as u32;
                    linear_maps.extend(imported.linear_maps.iter().cloned());
                    material_normal_maps.resize(base, None);
                    material_occlusion_maps.resize(base, None);
                    let shift = |n: &Option<(usize, f32)>| {
                        n.map(|(layer, k)| (first_normal + layer as u32, k))
                    };
                    material_normal_maps.extend(imported.material_normal_maps.iter().map(shift));
                    material_occlusion_maps
                        .extend(imported.material_occlusion_maps.iter().map(shift));
                    for ((name, spec), tex) in
                        imported.materials.iter().zip(&imported.material_textures)
                    {
                        let m = Material::from_spec(spec).map_err(|e| {
                            invalid(format!("{} material {name:?}: {e}", object.mesh))
                        })?;
                        materials.push((format!("{}#{name}", object.mesh), m));
                        material_textures.push(tex.map(|t| first_texture + t as u32));
                    }
                    Some(base)
                } else {
                    None
                };
                let fixed = if own.is_none() {
                    Some(named(&materials)?)
                } else {
                    None
                };
                for part in imported.parts {
                    let material = own.map_or(fixed.unwrap_or(0), |base| base + part.material);
                    let positions: Vec<Vec3> = part
                        .mesh
                        .positions
                        .iter()
                        .map(|p| transform.transform_point3(*p))
                        .collect();
                    let mut m = match part.normals {
                        Some(n) => {
                            let turn = Quat::from_rotation_y(object.rotate_y_deg.to_radians());
                            Mesh::with_normals(
                                positions,
                                n.into_iter().map(|n| turn * n).collect(),
                                part.mesh.indices,
                            )
                        }
                        None => Mesh::with_smooth_normals(positions, part.mesh.indices),
                    };
                    if let Some(t) = part.tint {
                        m.tint = t;
                    }
                    if let Some(uv) = part.uv {
                        m.uv = uv;
                    }
                    if let Some(t) = part.tangents {
                        let turn = Quat::from_rotation_y(object.rotate_y_deg.to_radians());
                        m.tangent = t
                            .into_iter()
                            .map(|t| {
                                let v = turn * Vec3::new(t[0], t[1], t[2]);
                                [v.x, v.y, v.z, t[3]]
                            })
                            .collect();
                    }
                    append(
                        &mut mesh,
                        &mut placed,
                        m,
                        material,
                        &materials,
                        file.mm_per_unit,
                        None,
                    );
                }
                for l in imported.lights {
                    lights.push(l.transformed(transform));
                }
                notes.extend(
                    imported
                        .notes
                        .into_iter()
                        .map(|n| format!("{}: {n}", object.mesh)),
                );
            }
        }
        if mesh.positions.len() > MAX_VERTICES || mesh.triangle_count() as usize > MAX_TRIANGLES {
            return Err(invalid(format!(
                "the scene is over the limits ({MAX_VERTICES} vertices, {MAX_TRIANGLES} triangles)"
            )));
        }
    }
    if materials.len() > MAX_MATERIALS {
        return Err(invalid(format!(
            "{} materials; a scene may have at most {MAX_MATERIALS}",
            materials.len()
        )));
    }
    if lights.len() > super::file::MAX_LIGHTS {
        notes.push(format!(
            "{} lights; the first {} are used",
            lights.len(),
            super::file::MAX_LIGHTS
        ));
        lights.truncate(super::file::MAX_LIGHTS);
    }
    for l in &lights {
        l.validate().map_err(&invalid)?;
    }
    file.lights = lights;
    material_textures.resize(materials.len(), None);
    material_normal_maps.resize(materials.len(), None);
    material_occlusion_maps.resize(materials.len(), None);
    Ok(Scene {
        file,
        mesh,
        materials,
        placed,
        notes,
        textures,
        material_textures,
        linear_maps,
        material_normal_maps,
        material_occlusion_maps,
    })
}

/// The scene-wide values: camera, ambient, units, key light, radiosity, objects present.
fn check_file(file: &mut SceneFile) -> Result<(), String> {
    file.camera.validate()?;
    if !(0.0..=1.0).contains(&file.ambient) {
        return Err(format!("ambient {} must lie in [0, 1]", file.ambient));
    }
    if !(file.mm_per_unit.is_finite() && file.mm_per_unit > 0.0) {
        return Err(format!(
            "mm_per_unit {} must be finite and > 0",
            file.mm_per_unit
        ));
    }
    let to_light = Vec3::from(file.light.to_light)
        .try_normalize()
        .ok_or("light.to_light must be a non-zero finite vector")?;
    file.light.to_light = to_light.into();
    let light_ok = file.light.color.iter().all(|c| c.is_finite() && *c >= 0.0)
        && file.light.intensity.is_finite()
        && file.light.intensity >= 0.0
        && file.light.orbit_deg_per_s.is_finite();
    if !light_ok {
        return Err("light colour and intensity must be finite and ≥ 0".into());
    }
    if file.objects.is_empty() {
        return Err("a scene needs at least one object".into());
    }
    if let Some(r) = &file.radiosity {
        if !r.patch_size.is_none_or(|p| p.is_finite() && p > 0.0)
            || r.max_depth > 6
            || !(r.stop_fraction > 0.0 && r.stop_fraction < 1.0)
        {
            return Err(
                "radiosity: patch_size must be > 0, max_depth ≤ 6 and stop_fraction in (0, 1)"
                    .into(),
            );
        }
    }
    Ok(())
}

fn append(
    mesh: &mut Mesh,
    placed: &mut Vec<super::Placed>,
    part: Mesh,
    material: usize,
    materials: &[(String, Material)],
    mm_per_unit: f64,
    quad: Option<([Vec3; 4], [u32; 2], u32)>,
) {
    // The cheap translucency rung shades with normals blurred over the light's reach.
    let reach_units = (materials[material].1.reach_mm() / mm_per_unit) as f32;
    placed.push(Placed {
        material: material as u32,
        first_vertex: mesh.positions.len() as u32,
        vertex_count: part.positions.len() as u32,
        first_index: mesh.indices.len() as u32,
        index_count: part.indices.len() as u32,
        quad,
    });
    mesh.append(part.with_blurred_normals(reach_units), material as u32);
}

/// An object's mesh by name: built in, or a file in the scene's folder.
fn load_mesh(scene: &str, name: &str, at: Location) -> Result<Loaded, SceneError> {
    let mesh_err = |message: String| SceneError::MeshFile {
        scene: scene.to_string(),
        mesh: name.to_string(),
        message,
    };
    if let Some((_, bytes)) = BUILTIN_MESHES.iter().find(|(n, _)| *n == name) {
        return parse_ply(bytes)
            .map(Loaded::Plain)
            .map_err(|e| mesh_err(e.to_string()));
    }
    let Some((folder, base)) = at else {
        return Err(SceneError::UnknownMesh {
            scene: scene.to_string(),
            mesh: name.to_string(),
        });
    };
    let path = folder
        .resolve(base, name)
        .map_err(|e| mesh_err(e.to_string()))?;
    load_model(&path, folder).map_err(mesh_err)
}

/// A mesh or glTF file by its extension.
pub fn load_model(path: &Path, folder: &Folder) -> Result<Loaded, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match ext.as_str() {
        "gltf" | "glb" => gltf::import(path, folder)
            .map(Loaded::Gltf)
            .map_err(|e| e.to_string()),
        "ply" | "obj" => {
            let bytes = read_limited(path).map_err(|e| e.to_string())?;
            if ext == "ply" {
                parse_ply(&bytes)
                    .map(Loaded::Plain)
                    .map_err(|e| e.to_string())
            } else {
                super::obj::parse_obj(&bytes)
                    .map(Loaded::Plain)
                    .map_err(|e| e.to_string())
            }
        }
        _ => Err(format!(
            "unknown file type {ext:?} (Fovea reads .gltf, .glb, .ply and .obj)"
        )),
    }
}

/// A unit square in XZ centred on the origin, facing +Y (two counter-clockwise triangles).
fn plane() -> RawMesh {
    let positions = vec![
        Vec3::new(-0.5, 0.0, -0.5),
        Vec3::new(-0.5, 0.0, 0.5),
        Vec3::new(0.5, 0.0, 0.5),
        Vec3::new(0.5, 0.0, -0.5),
    ];
    RawMesh {
        positions,
        indices: vec![0, 1, 2, 0, 2, 3],
        dropped_degenerate: 0,
    }
}

/// Patches per side and subdivision depth for a quad: patches no larger than the scene's
/// `radiosity.patch_size` (one patch without radiosity settings). `None` if not a parallelogram.
fn quad_lattice(c: &[Vec3; 4], spec: Option<&RadiositySpec>) -> Option<([u32; 2], u32)> {
    let (u, v) = (c[1] - c[0], c[3] - c[0]);
    let closes = (c[0] + u + v - c[2]).length() <= 1e-4 * (u.length() + v.length());
    if !(c.iter().all(|p| p.is_finite()) && closes && u.cross(v).length() > 0.0) {
        return None;
    }
    Some(match spec {
        Some(r) if r.mode != RadiosityMode::Off => {
            let size = r.patch_size.unwrap_or_else(|| {
                u.length().max(v.length()) / crate::scene::file::DEFAULT_PATCHES as f32
            });
            let n = |len: f32| ((len / size).ceil() as u32).clamp(1, 64);
            ([n(u.length()), n(v.length())], r.max_depth)
        }
        _ => ([1, 1], 0),
    })
}

/// A parallelogram as a grid of `lattice[0] × lattice[1]` cells, row by row from corner 0
/// (the order the radiosity solver writes its per-vertex output in).
fn lattice_mesh(c: &[Vec3; 4], lattice: [u32; 2]) -> RawMesh {
    let [lu, lv] = lattice;
    let mut positions = Vec::with_capacity(((lu + 1) * (lv + 1)) as usize);
    for j in 0..=lv {
        for i in 0..=lu {
            positions.push(
                c[0] + (c[1] - c[0]) * (i as f32 / lu as f32)
                    + (c[3] - c[0]) * (j as f32 / lv as f32),
            );
        }
    }
    let mut indices = Vec::with_capacity((lu * lv * 6) as usize);
    let at = |i: u32, j: u32| j * (lu + 1) + i;
    for j in 0..lv {
        for i in 0..lu {
            indices.extend([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            indices.extend([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    RawMesh {
        positions,
        indices,
        dropped_degenerate: 0,
    }
}
