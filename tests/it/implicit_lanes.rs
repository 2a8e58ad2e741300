//! Typed surfaces asked for [`LANES`] rays at a time (`Shape::intersect_lanes` and
//! `occludes_lanes`, as camera and shadow rays of neighbouring pixels are, their ray
//! polynomials composed together) give exactly the hits they give one ray at a time: every
//! preset, a degree-16 sphere, a surface of double roots, camera and secondary rays, idle and
//! short lanes and lanes of their own `t_min`, with both solvers; the double-double re-solve
//! is among the cases checked.

use kardia::geometry::{DVec3, Frame, Ray};
use kardia::roots::Solver;
use kardia::shapes::implicit::Implicit;
use kardia::shapes::{SettledBy, Shape, LANES};

fn surfaces() -> Vec<(String, Implicit)> {
    let mut out = Vec::new();
    for (name, params) in [
        ("torus", vec![1.0, 0.3]),
        ("barth_sextic", vec![]),
        ("chmutov", vec![8.0]),
        ("chmutov", vec![16.0]),
        ("taubin_heart", vec![]),
        ("kummer", vec![1.3f64.sqrt()]),
        ("clebsch", vec![]),
    ] {
        let shape = Implicit::from_preset(name, &params, Frame::identity(), None).unwrap();
        out.push((format!("{name} {params:?}"), shape));
    }
    for eq in ["(x^2+y^2+z^2)^8 = 1", "(x^2 + y^2 + z^2 - 1)^2 = 0"] {
        out.push((
            eq.into(),
            Implicit::new(eq, Frame::identity(), None).unwrap(),
        ));
    }
    out
}

/// Rays from three cameras across the clip sphere, then from their hit points outwards and
/// back through the surface (secondary rays start on it).
fn rays(shape: &Implicit) -> (Vec<Ray>, Vec<Ray>) {
    let r = shape.bound();
    let mut state = 0x5851_f42d_4c95_7f2du64;
    let mut jitter = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let mut camera = Vec::new();
    for eye in [
        DVec3::new(3.0, 0.4, 0.3),
        DVec3::new(1.7, 1.9, 1.3),
        DVec3::new(-0.6, -2.2, 2.1),
    ] {
        let eye = eye * r;
        let forward = (-eye).normalize();
        let right = forward.cross(DVec3::Z).normalize();
        let up = right.cross(forward);
        for j in 0..24 {
            for i in 0..24 {
                let u = (i as f64 + jitter() - 11.5) / 11.5 * 0.4;
                let w = (j as f64 + jitter() - 11.5) / 11.5 * 0.4;
                camera.push(Ray::new(eye, forward + u * right + w * up));
            }
        }
    }
    let mut secondary = Vec::new();
    for ray in &camera {
        if let Some(t) = shape.intersect(ray, 0.0, f64::INFINITY) {
            let p = ray.at(t);
            secondary.push(Ray::new(p, -ray.dir));
            secondary.push(Ray::new(p, ray.dir));
            secondary.push(Ray::new(p, DVec3::new(0.6, -0.3, 0.74)));
        }
    }
    (camera, secondary)
}

/// Checks `rays` in groups of `LANES` (every fourth lane idle or bounded short); returns
/// the hits and how many of the rays were re-solved in double-double arithmetic.
fn check(shape: &Implicit, rays: &[Ray], t_min: f64, what: &str) -> (usize, usize) {
    let (mut hits, mut recentred) = (0, 0);
    for (k, group) in rays.chunks_exact(LANES).enumerate() {
        let lanes: [Ray; LANES] = std::array::from_fn(|i| group[i]);
        let t_max: [f64; LANES] = std::array::from_fn(|i| match (k + i) % 8 {
            0 => f64::NEG_INFINITY,
            1 => 0.5 * shape.bound(),
            _ => f64::INFINITY,
        });
        // One lane starts a little later (lanes have their own t_min, as shadow rays do).
        let t_min: [f64; LANES] = std::array::from_fn(|i| match (k + i) % 8 {
            2 => t_min + 0.25 * shape.bound(),
            _ => t_min,
        });
        let together = shape.intersect_lanes(&lanes, t_min, t_max);
        let occluded = shape.occludes_lanes(&lanes, t_min, t_max);
        for i in 0..LANES {
            let t_min = t_min[i];
            let alone = shape.intersect(&lanes[i], t_min, t_max[i]);
            assert_eq!(occluded[i], alone.is_some(), "{what}: {:?}", lanes[i]);
            assert_eq!(
                together[i].map(f64::to_bits),
                alone.map(f64::to_bits),
                "{what}: {:?} in ({t_min}, {})",
                lanes[i],
                t_max[i]
            );
            hits += usize::from(alone.is_some());
            let report = shape.solver_report(&lanes[i], t_min, t_max[i]);
            recentred += usize::from(report.is_some_and(|r| r.settled_by == SettledBy::Recentred));
        }
    }
    (hits, recentred)
}

#[test]
fn typed_surfaces_give_the_same_hits_in_lanes_as_alone() {
    let mut recentred_total = 0;
    for (name, shape) in surfaces() {
        let (camera, secondary) = rays(&shape);
        for (solver, solver_name) in Solver::ALL {
            let shape = shape.clone().with_solver(*solver);
            let what = format!("{name}, {solver_name}");
            let (hits, recentred) = check(&shape, &camera, 0.0, &what);
            assert!(hits > 10, "{what}: {hits} camera hits");
            let (_, recentred_2) = check(&shape, &secondary, 0.0, &what);
            check(&shape, &secondary, 1e-9, &what);
            recentred_total += recentred + recentred_2;
        }
    }
    assert!(recentred_total > 100, "{recentred_total} rays re-solved");
}
