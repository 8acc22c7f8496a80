//! Radiosity on triangle meshes, as glTF files bring them: emitting meshes (a lamp), scale
//! invariance in a glTF's metres, and the boundary of an open mesh (a wall's joint).

mod common;

use common::radiosity::{grid_mesh, opposed_rectangles, quad, serial};
use fovea::radiosity::{Solver, Surface};
use glam::Vec3;

/// A square of side `side` centred over `base` at height `side` above it, facing down
/// (X × Z = −Y), as a triangle mesh of n × n cells shooting 16 triangles at a time: a glTF lamp.
fn emitting_mesh(n: u32, emission: f32, side: f32, base: Vec3) -> Surface {
    let corner = base + Vec3::new(-0.5, 1.0, -0.5) * side;
    match grid_mesh(corner, Vec3::X * side, Vec3::Z * side, n, 0.8) {
        Surface::Mesh {
            positions,
            normals,
            indices,
            reflectance,
            ..
        } => Surface::Mesh {
            positions,
            normals,
            indices,
            reflectance,
            emission: Vec3::splat(emission),
            triangles_per_patch: 16,
        },
        quad => quad,
    }
}

#[test]
fn an_emitting_mesh_lights_as_an_emitting_quad_does_at_any_scale() {
    // glTF lamps are meshes: the same squares as `two_opposed_squares…`, the emitter as 32
    // triangles, give the receiver ρ·F·M too, in a glTF's metres as in a scene file's
    // centimetres. Before meshes could emit, this scene had no emitter at all.
    let exact = opposed_rectangles(1.0, 1.0, 1.0);
    let (rho, m) = (0.5f32, 2.0f32);
    // Cornell's lamp (6 cm, 19.95 cm up) in metres, as the glTF has it, in cm, and at 1.
    for (side, height) in [(0.06f32, 0.1395f32), (6.0, 13.95), (1.0, 2.325)] {
        let base = Vec3::new(0.0, height, 0.0);
        let corner = base + Vec3::new(-0.5, 0.0, -0.5) * side;
        let surfaces = vec![
            emitting_mesh(4, m, side, base),
            quad(corner, Vec3::Z * side, Vec3::X * side, 8, 0, rho, 0.0),
        ];
        let mut solver = Solver::new(&surfaces, serial()).unwrap();
        let emitted = solver.stats().emitted / f64::from(side * side);
        assert!((emitted - f64::from(m)).abs() < 1e-4, "emitted {emitted}");
        while solver.step().is_some_and(|s| s.patch < 2) {}
        let b: f32 = (2..66).map(|p| solver.patch_radiosity(p).x).sum::<f32>() / 64.0;
        let expected = f64::from(rho * m) * exact;
        assert!(
            (f64::from(b) - expected).abs() < 0.02 * expected,
            "side {side}: receiver radiosity {b} vs closed form {expected}"
        );
        // The lamp reflects nothing of what comes back (its reflectance 0.8 is ignored).
        for p in 0..2 {
            assert_eq!(solver.patch_radiosity(p), Vec3::ZERO, "lamp patch {p}");
        }
    }
}

#[test]
fn the_cornell_box_glbs_lamp_does_not_light_itself() {
    // The lamp of assets/models/cornell-box.glb in the glTF's metres: its own triangles took
    // a whole shot's worth of factor (points coplanar with it were sampled on its plane, where
    // rounding decided whether they saw it), so the factors summed to 1.24 and every shot was
    // scaled down to 55%: the glTF box rendered at half the light of the scene file's.
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models");
    let folder = fovea::scene::Folder::open(&dir).unwrap();
    let scene = fovea::scene::Scene::load(&dir.join("cornell-box.glb"), &folder).unwrap();
    let surfaces = scene.radiosity_surfaces();
    let mut solver = Solver::new(&surfaces, serial()).unwrap();
    // The lamp's two patches hold all the unshot power: they shoot first.
    let lamp: Vec<usize> = (0..2)
        .filter_map(|_| solver.step())
        .map(|s| s.patch)
        .collect();
    assert_eq!(lamp.len(), 2);
    for p in lamp {
        let factors = solver.patch_factors(p);
        let own: f32 = factors.iter().filter(|f| f.0 == p).map(|f| f.2).sum();
        let sum: f32 = factors.iter().map(|f| f.2).sum();
        assert!(
            own == 0.0 && sum <= 1.0,
            "lamp patch {p}: own {own}, all {sum}"
        );
    }
}

#[test]
fn a_mesh_walls_edge_where_it_meets_the_floor_is_not_a_dark_seam() {
    // A floor and a back wall as meshes (a glTF room), a lamp above. The wall's bottom row of
    // vertices lies in the floor's plane and sees it edge-on; received there, it lacked the
    // floor's whole bounce, and the frame drew a dark line a cell wide along the joint.
    let n = 8;
    let surfaces = vec![
        quad(
            Vec3::new(0.35, 0.9, 0.35),
            Vec3::X * 0.3,
            Vec3::Z * 0.3,
            2,
            0,
            0.0,
            20.0,
        ),
        grid_mesh(Vec3::ZERO, Vec3::Z, Vec3::X, n, 0.8),
        grid_mesh(Vec3::ZERO, Vec3::X, Vec3::Y, n, 0.8),
    ];
    let mut solver = Solver::new(&surfaces, serial()).unwrap();
    while !solver.converged() && solver.step().is_some() {}
    let (direct, indirect) = solver.irradiance(false);
    let wall = surfaces[0].output_len() + surfaces[1].output_len();
    let row = |j: u32| -> f32 {
        (1..n)
            .map(|i| {
                let k = wall + (j * (n + 1) + i) as usize;
                (direct[k] + indirect[k]).x
            })
            .sum::<f32>()
            / (n - 1) as f32
    };
    let (joint, above) = (row(0), row(1));
    assert!(
        joint > 0.9 * above,
        "joint row {joint} against the row above it {above}"
    );
}
