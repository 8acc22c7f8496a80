//! Progressive refinement radiosity: form factors against closed forms, conservation, the
//! extremes named in the seeds digest, convergence.

mod common;

use common::radiosity::{opposed_rectangles, quad, serial};
use fovea::radiosity::{Options, RadiosityError, Solver, Surface};
use glam::Vec3;

/// The six inward faces of the unit cube; the ceiling (index 1) emits `emission`.
fn closed_cube(cells: u32, depth: u32, rho: f32, emission: f32) -> Vec<Surface> {
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    vec![
        quad(Vec3::ZERO, z, x, cells, depth, rho, 0.0),
        quad(y, x, z, cells, depth, rho, emission),
        quad(Vec3::ZERO, y, z, cells, depth, rho, 0.0),
        quad(x, z, y, cells, depth, rho, 0.0),
        quad(Vec3::ZERO, x, y, cells, depth, rho, 0.0),
        quad(z, y, x, cells, depth, rho, 0.0),
    ]
}

#[test]
fn form_factors_from_one_patch_to_a_closed_cube_sum_to_one() {
    // Tolerance 1%, corner patches included (their nearest receivers touch them: the exact
    // polygon factor and sub-sampled receivers hold there). A product clamp max(cos_i cos_j,
    // 0) or an off-by-one in the sampling would miss by far more.
    let solver = Solver::new(&closed_cube(8, 0, 0.5, 1.0), serial()).unwrap();
    // Patches: a floor centre (27), a floor corner (0), a side wall patch (2·64 + 35).
    for (p, tolerance) in [(27usize, 0.01), (163, 0.01), (0, 0.01)] {
        let sum: f32 = solver.patch_factors(p).iter().map(|f| f.2).sum();
        assert!((sum - 1.0).abs() < tolerance, "patch {p}: Σ F = {sum}");
    }
}

#[test]
fn form_factors_are_reciprocal() {
    // Receivers are sampled (at their centre, or a grid near the shooter), so reciprocity
    // holds to the sampling's accuracy: within 3%, touching patches included.
    let mut cube = closed_cube(8, 0, 0.5, 1.0);
    // Walls with patches of different sizes from the floor's, so the disc formula's
    // symmetry does not make reciprocity trivial.
    for wall in &mut cube[2..] {
        if let Surface::Quad { cells, .. } = wall {
            *cells = [4, 4];
        }
    }
    let solver = Solver::new(&cube, serial()).unwrap();
    for (i, j) in [
        (0usize, 128),
        (9, 128 + 1),
        (18, 128 + 5),
        (0, 144 + 15),
        (27, 176 + 10),
        (42, 160 + 7),
        (9, 64 + 20),
    ] {
        let fij = solver.patch_factors(i)[j].2;
        let fji = solver.patch_factors(j)[i].2;
        let (ai, aj) = (solver.patch_area(i), solver.patch_area(j));
        let (a, b) = (ai * fij, aj * fji);
        eprintln!("{i}↔{j}: {a} vs {b} {}", (a - b).abs() / a.max(b));
        assert!(
            a > 0.0 && (a - b).abs() < 0.03 * a.max(b),
            "{i}↔{j}: {a} vs {b}"
        );
    }
}

#[test]
fn two_opposed_squares_exchange_what_the_closed_form_says() {
    let exact = opposed_rectangles(1.0, 1.0, 1.0);
    assert!(
        (exact - 0.19982).abs() < 1e-4,
        "closed form itself: {exact}"
    );
    // An emitting square above a receiving one: after the emitter has shot, the receiver's
    // radiosity is ρ · F · M (the emitter absorbs what comes back, so there is one bounce).
    let (rho, m) = (0.5f32, 2.0f32);
    let surfaces = vec![
        quad(Vec3::Y, Vec3::X, Vec3::Z, 8, 0, 0.0, m),
        quad(Vec3::ZERO, Vec3::Z, Vec3::X, 8, 0, rho, 0.0),
    ];
    let mut solver = Solver::new(&surfaces, serial()).unwrap();
    while solver.step().is_some_and(|s| s.patch < 64) {}
    let b: f32 = (64..128).map(|p| solver.patch_radiosity(p).x).sum::<f32>() / 64.0;
    let expected = f64::from(rho * m) * exact;
    assert!(
        (f64::from(b) - expected).abs() < 0.01 * expected,
        "receiver radiosity {b} vs closed form {expected}"
    );
}

#[test]
fn energy_is_conserved_and_unshot_power_never_grows() {
    let rho = 0.7;
    // Light that reaches the emitting ceiling is absorbed there (a lamp reflects nothing).
    let mut solver = Solver::new(&closed_cube(6, 2, rho, 1.0), serial()).unwrap();
    let emitted = solver.stats().emitted;
    let (mut absorbed, mut last) = (0.0, solver.stats().unshot_fraction);
    for _ in 0..400 {
        let Some(shot) = solver.step() else { break };
        assert!(shot.received <= shot.power * (1.0 + 1e-5), "{shot:?}");
        assert!(shot.absorbed <= shot.received);
        if std::env::var("DBG").is_ok() {
            eprintln!(
                "{} {:.4} {:.4} {}",
                shot.patch,
                shot.power,
                shot.received / shot.power,
                shot.subdivided
            );
        }
        absorbed += shot.absorbed;
        let now = solver.stats().unshot_fraction;
        assert!(now <= last + 1e-9, "unshot grew: {last} → {now}");
        last = now;
    }
    let remaining = last * emitted;
    assert!(
        absorbed + remaining <= emitted * (1.0 + 1e-4),
        "{absorbed} + {remaining} > {emitted}"
    );
    // The cube is closed: little may leak through the approximation.
    assert!(
        absorbed + remaining > 0.97 * emitted,
        "{absorbed} + {remaining} ≪ {emitted}"
    );
}

#[test]
fn reflectance_near_one_keeps_everything_finite() {
    for rho in [0.99f32, 0.999, 1.0] {
        let mut solver = Solver::new(
            &closed_cube(3, 0, rho, 1.0),
            Options {
                max_shots: 600,
                ..serial()
            },
        )
        .unwrap();
        while !solver.converged() && solver.step().is_some() {}
        let s = solver.stats();
        assert!(
            s.unshot_fraction.is_finite() && s.unshot_fraction <= 1.0 + 1e-6,
            "{s:?}"
        );
        let ambient = solver.ambient();
        assert!(ambient.is_finite(), "ρ {rho}: ambient {ambient}");
        let (direct, indirect) = solver.irradiance(true);
        assert!(
            direct.iter().chain(&indirect).all(|e| e.is_finite()),
            "ρ {rho}"
        );
        // The 1/(1 − ρ̄) series is capped at 100: the preview cannot exceed 100× the mean
        // unshot exitance, however white the walls.
        assert!(
            ambient.x <= 100.0 * 6.0 / 6.0 * 1.0 + 1e-3,
            "ρ {rho}: {ambient}"
        );
    }
}

#[test]
fn back_to_back_and_coincident_elements_exchange_nothing_or_a_bounded_amount() {
    // An emitter facing +Z and a receiver in the same plane facing −Z: back to back.
    let back = vec![
        quad(Vec3::ZERO, Vec3::X, Vec3::Y, 2, 0, 0.0, 1.0),
        quad(Vec3::ZERO, Vec3::Y, Vec3::X, 2, 0, 0.8, 0.0),
    ];
    let mut solver = Solver::new(&back, serial()).unwrap();
    while solver.step().is_some() {}
    for p in 4..8 {
        assert_eq!(solver.patch_radiosity(p), Vec3::ZERO);
    }
    // Facing each other close up (r → 0): a white receiver gets nearly all the emitter's
    // exitance, never more; closer than the shadow rays' margin it stays finite and bounded.
    for (gap, least) in [(1e-2f32, 0.9f32), (1e-6, 0.0)] {
        let facing = vec![
            quad(Vec3::ZERO, Vec3::X, Vec3::Y, 2, 0, 0.0, 1.0),
            quad(Vec3::Z * gap, Vec3::Y, Vec3::X, 2, 0, 1.0, 0.0),
        ];
        let mut solver = Solver::new(&facing, serial()).unwrap();
        while solver.step().is_some() {}
        for p in 4..8 {
            let b = solver.patch_radiosity(p);
            assert!(
                b.is_finite() && b.x <= 1.0 + 1e-4 && b.x >= least,
                "gap {gap}: {b}"
            );
        }
    }
}

/// The closed cube (not emitting) with a small lamp under the ceiling, facing down (X × Z =
/// −Y), and a blocker halfway down casting a hard shadow on the floor. The lamp is patch 96.
fn lamp_over_blocker() -> Vec<Surface> {
    let mut surfaces = closed_cube(4, 2, 0.5, 0.0);
    let (lamp, blocker) = (Vec3::new(0.4, 0.98, 0.4), Vec3::new(0.3, 0.5, 0.3));
    surfaces.push(quad(lamp, Vec3::X * 0.2, Vec3::Z * 0.2, 1, 0, 0.0, 20.0));
    surfaces.push(quad(blocker, Vec3::X * 0.4, Vec3::Z * 0.4, 1, 0, 0.5, 0.0));
    surfaces
}

#[test]
fn shadow_edges_subdivide_within_the_depth_bound() {
    let surfaces = lamp_over_blocker();
    let mut solver = Solver::new(&surfaces, serial()).unwrap();
    let before = solver.stats().elements;
    let first = solver.step().expect("the lamp shoots");
    assert_eq!(first.patch, 96, "the lamp has the most unshot power");
    let after = solver.stats().elements;
    assert!(first.subdivided > 0 && after > before, "{before} → {after}");
    // Bounded: at most 4^2 elements per patch.
    assert!(after <= before + 96 * 15);
    let (direct, _) = solver.irradiance(false);
    assert!(direct
        .iter()
        .all(|e| e.is_finite() && e.min_element() >= 0.0));
}

#[test]
fn a_scene_without_an_emitter_or_with_a_bad_quad_is_refused() {
    assert_eq!(
        Solver::new(&closed_cube(2, 0, 0.5, 0.0), serial()).err(),
        Some(RadiosityError::NoEmitter)
    );
    let bad = vec![Surface::Quad {
        corners: [Vec3::ZERO, Vec3::X, Vec3::new(3.0, 1.0, 0.0), Vec3::Y],
        cells: [1, 1],
        max_depth: 0,
        reflectance: Vec3::splat(0.5),
        emission: Vec3::ONE,
    }];
    assert_eq!(
        Solver::new(&bad, serial()).err(),
        Some(RadiosityError::BadQuad(0))
    );
}

#[test]
fn the_ambient_preview_lights_the_scene_before_any_shot_and_fades_as_it_converges() {
    let mut solver = Solver::new(&closed_cube(6, 1, 0.7, 1.0), serial()).unwrap();
    let mean = |v: &[Vec3]| v.iter().map(|e| e.x).sum::<f32>() / v.len() as f32;
    let (_, preview) = solver.irradiance(true);
    let ambient0 = solver.ambient().x;
    assert!(ambient0 > 0.0 && mean(&preview) > 0.0);
    while !solver.converged() && solver.step().is_some() {}
    let ambient1 = solver.ambient().x;
    assert!(ambient1 < 0.01 * ambient0, "{ambient0} → {ambient1}");
    // Before a single shot the preview already shows the right overall brightness: within
    // 20% of the converged mean irradiance (direct + indirect) of the room.
    let (direct, indirect) = solver.irradiance(true);
    let converged = mean(&direct) + mean(&indirect);
    assert!(
        (mean(&preview) - converged).abs() < 0.2 * converged,
        "preview {} vs converged {converged}",
        mean(&preview)
    );
}

#[test]
fn one_solve_is_shared_publishes_monotone_snapshots_and_converges() {
    use fovea::radiosity::RadiosityHandle;
    let surfaces = closed_cube(5, 1, 0.6, 1.0);
    let a = RadiosityHandle::start("cube", surfaces.clone(), Options::default()).unwrap();
    let b = RadiosityHandle::start("cube", surfaces, Options::default()).unwrap();
    assert!(a.same_solve(&b), "same geometry and lights: one solve");
    let last = a
        .wait(std::time::Duration::from_secs(120))
        .expect("a snapshot");
    assert!(
        last.converged && last.stats.unshot_fraction < 0.001,
        "{:?}",
        last.stats
    );
    let history = a.history();
    assert!(history
        .windows(2)
        .all(|w| w[1].1.unshot_fraction <= w[0].1.unshot_fraction + 1e-9));
    let other =
        RadiosityHandle::start("cube", closed_cube(5, 1, 0.5, 1.0), Options::default()).unwrap();
    assert!(!other.same_solve(&a), "different reflectance: a new solve");
}

#[test]
fn depth_cube_visibility_agrees_with_shadow_rays() {
    use fovea::radiosity::Visibility;
    let surfaces = lamp_over_blocker();
    let run = |visibility| {
        let mut s = Solver::new(
            &surfaces,
            Options {
                visibility,
                ..serial()
            },
        )
        .unwrap();
        s.step().expect("the lamp shoots");
        s.irradiance(false).0
    };
    let rays = run(Visibility::Rays);
    let cube = run(Visibility::Cube { resolution: 256 });
    assert_eq!(rays.len(), cube.len());
    // The floor's centre (lattice point (8, 8) of 17 × 17) lies in the blocker's shadow in both.
    let peak = rays.iter().map(|e| e.x).fold(0.0, f32::max);
    let centre = 8 * 17 + 8;
    assert!(rays[centre].x < 0.02 * peak && cube[centre].x < 0.02 * peak);
    // The back wall above the blocker (surface 4, lattice point (8, 12)) is lit in both.
    let wall = 4 * 17 * 17 + 12 * 17 + 8;
    assert!(
        rays[wall].x > 0.1 * peak && cube[wall].x > 0.1 * peak,
        "the back wall is lit"
    );
    // The same hard shadow: irradiance differs by more than 10% of the peak at few vertices
    // (shadow-edge texels and subdivision that followed them).
    let differ = rays
        .iter()
        .zip(&cube)
        .filter(|(a, b)| (a.x - b.x).abs() > 0.1 * peak)
        .count();
    assert!(
        differ * 50 < rays.len(),
        "{differ} of {} vertices differ",
        rays.len()
    );
    let mean = |v: &[Vec3]| v.iter().map(|e| e.x).sum::<f32>() / v.len() as f32;
    assert!((mean(&rays) - mean(&cube)).abs() < 0.03 * mean(&rays));
}
