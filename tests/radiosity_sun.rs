//! Radiosity's first bounce of the key light (`Options::sun`): a sunlit floor lights a wall
//! beside it by the amount its form factor says, the sun's direct light stays out of the
//! output (the frame shades it with its shadow map), and a shadowed floor bounces nothing.

use fovea::radiosity::{Options, RadiosityError, Solver, Sun, Surface};
use glam::Vec3;

/// A parallelogram with corner `o`, edges `u`, `v`; its front faces u × v.
fn quad(o: Vec3, u: Vec3, v: Vec3, cells: u32, rho: f32) -> Surface {
    Surface::Quad {
        corners: [o, o + u, o + u + v, o + v],
        cells: [cells, cells],
        max_depth: 0,
        reflectance: Vec3::splat(rho),
        emission: Vec3::ZERO,
    }
}

/// The floor: x in [0, 10], z in [−5, 5], facing +y.
fn floor(rho: f32) -> Surface {
    quad(
        Vec3::new(0.0, 0.0, -5.0),
        Vec3::new(0.0, 0.0, 10.0),
        Vec3::new(10.0, 0.0, 0.0),
        10,
        rho,
    )
}

/// The wall on the floor's edge x = 0: y in [0, 10], z in [−5, 5], facing +x (over the floor).
fn wall() -> Surface {
    quad(
        Vec3::new(0.0, 0.0, -5.0),
        Vec3::new(0.0, 10.0, 0.0),
        Vec3::new(0.0, 0.0, 10.0),
        10,
        0.0,
    )
}

fn sun(to_light: Vec3, e: f32) -> Options {
    Options {
        threads: 1,
        sun: Some(Sun {
            to_light: to_light.normalize(),
            irradiance: Vec3::splat(e),
        }),
        ..Options::default()
    }
}

/// Form factor from a point (normal n) to the floor rectangle, by a 400² midpoint sum of
/// cos θ_r cos θ_s / (π r²): independent of the solver's polygon and disc formulas.
fn factor_to_floor(p: Vec3, n: Vec3) -> f64 {
    let k = 400;
    let cell = 10.0 / k as f64;
    let mut f = 0.0;
    for i in 0..k {
        for j in 0..k {
            let q = [(i as f64 + 0.5) * cell, 0.0, -5.0 + (j as f64 + 0.5) * cell];
            let d = [q[0] - p.x as f64, q[1] - p.y as f64, q[2] - p.z as f64];
            let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            let cos_r = (d[0] * n.x as f64 + d[1] * n.y as f64 + d[2] * n.z as f64) / r2.sqrt();
            let cos_s = -d[1] / r2.sqrt();
            if cos_r > 0.0 && cos_s > 0.0 {
                f += cos_r * cos_s / (std::f64::consts::PI * r2) * cell * cell;
            }
        }
    }
    f
}

#[test]
fn a_wall_beside_a_sunlit_floor_gets_the_floor_s_bounce_and_not_the_sun() {
    // The sun shines along the wall (from −z, 45° up), so the wall neither sees it nor shades
    // the floor, which sees it at 45°. The wall reflects nothing: one bounce is the answer.
    let (rho, e) = (0.5f32, 2.0f32);
    let mut solver = Solver::new(&[floor(rho), wall()], sun(Vec3::new(0.0, 1.0, -1.0), e)).unwrap();
    while solver.step().is_some() && !solver.converged() {}
    assert!(solver.converged());
    let (direct, indirect) = solver.irradiance(false);
    assert!(
        direct.iter().all(|d| *d == Vec3::ZERO),
        "the sun's own light is not radiosity's to show"
    );
    let exitance = f64::from(rho * e) * std::f64::consts::FRAC_1_SQRT_2;
    // The wall's lattice points follow the floor's 11 × 11: index 121 + j·11 + i, i up the
    // wall, j across it. Points away from the seams, where the midpoint sum is accurate.
    for (i, j) in [(2usize, 5usize), (5, 5), (3, 2)] {
        let p = Vec3::new(0.0, i as f32, -5.0 + j as f32);
        let expected = exitance * factor_to_floor(p, Vec3::X);
        let got = f64::from(indirect[121 + j * 11 + i].x);
        assert!(
            (got - expected).abs() < 0.02 * expected,
            "wall at height {i}, across {j}: {got} against {expected}"
        );
    }
    // The floor cannot see itself and the wall reflects nothing: the floor gets no bounce.
    assert!(indirect[..121].iter().all(|v| v.x.abs() < 1e-6));
}

#[test]
fn a_floor_in_shadow_bounces_nothing_and_without_sun_or_emitter_nothing_is_solved() {
    // A roof over the whole floor, facing down: the sun overhead reaches neither its front
    // (which faces away) nor the floor (in its shadow), so nothing is lit.
    let roof = quad(
        Vec3::new(-1.0, 3.0, -6.0),
        Vec3::new(12.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 12.0),
        4,
        0.5,
    );
    let shadowed = Solver::new(&[floor(0.5), roof], sun(Vec3::Y, 1.0));
    assert_eq!(shadowed.err(), Some(RadiosityError::NoEmitter));
    let dark = Solver::new(
        &[floor(0.5)],
        Options {
            threads: 1,
            ..Options::default()
        },
    );
    assert_eq!(dark.err(), Some(RadiosityError::NoEmitter));
    // A sun below the horizon lights nothing either.
    let set = Solver::new(&[floor(0.5)], sun(Vec3::new(0.0, -1.0, 0.2), 1.0));
    assert_eq!(set.err(), Some(RadiosityError::NoEmitter));
}

#[test]
fn the_sunlit_floor_s_power_is_what_the_solve_converges_against() {
    // Emitted power = ρ · E · cos θ · area for an unshadowed floor: the unshot fraction starts
    // at 1 and the solve ends under its stop fraction.
    let (rho, e) = (0.8f32, 1.5f32);
    let to_light = Vec3::new(0.0, 2.0, 1.0).normalize();
    let mut solver = Solver::new(&[floor(rho), wall()], sun(to_light, e)).unwrap();
    let first = solver.stats();
    let expected = f64::from(rho * e * to_light.y) * 100.0;
    assert!(
        (first.emitted - expected).abs() < 1e-3 * expected,
        "{first:?}"
    );
    assert!((first.unshot_fraction - 1.0).abs() < 1e-6);
    while solver.step().is_some() && !solver.converged() {}
    assert!(solver.stats().unshot_fraction < 0.001);
}
