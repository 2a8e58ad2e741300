//! Typed surfaces asked for [`LANES`] rays at a time (`Shape::intersect_lanes` and
//! `occludes_lanes`, as camera and shadow rays of neighbouring pixels are, their ray
//! polynomials composed together) give exactly the hits they give one ray at a time: every
//! preset, a degree-16 sphere, a surface of double roots, camera and secondary rays, idle and
//! short lanes and lanes of their own `t_min`, with both solvers; the double-double re-solve
//! is among the cases checked.

use kardia::geometry::{DMat3, DVec3, Frame, Hexahedron, Ray};
use kardia::roots::Solver;
use kardia::shapes::implicit::presets::preset;
use kardia::shapes::implicit::Implicit;
use kardia::shapes::{SettledBy, Shape, LANES};

fn surfaces() -> Vec<(String, Implicit)> {
    surfaces_placed(Frame::identity())
}

/// Every preset (Taubin's heart through the heart's path, as its preset goes, and through
/// the generic path), a degree-16 sphere and a surface of double roots, placed by `frame`.
fn surfaces_placed(frame: Frame) -> Vec<(String, Implicit)> {
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
        let shape = Implicit::from_preset(name, &params, frame, None).unwrap();
        out.push((format!("{name} {params:?}"), shape));
    }
    let taubin = preset("taubin_heart", &[]).unwrap();
    out.push((
        "taubin_heart, generic path".into(),
        Implicit::new_generic(&taubin.equation, frame, taubin.bound).unwrap(),
    ));
    for eq in ["(x^2+y^2+z^2)^8 = 1", "(x^2 + y^2 + z^2 - 1)^2 = 0"] {
        out.push((eq.into(), Implicit::new(eq, frame, None).unwrap()));
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

/// Whether `p` lies in the parallelepiped `cell` (corner 0 its origin, corners 1, 2 and 4
/// the ends of its three edges from there), up to a relative `1e-9` of its edges.
fn in_cell(cell: &Hexahedron, p: DVec3) -> bool {
    let o = cell.corners[0];
    let edges = DMat3::from_cols(
        cell.corners[1] - o,
        cell.corners[2] - o,
        cell.corners[4] - o,
    );
    let a = edges.inverse() * (p - o);
    a.cmpge(DVec3::splat(-1e-9)).all() && a.cmple(DVec3::splat(1.0 + 1e-9)).all()
}

#[test]
fn every_hit_of_a_typed_surface_lies_in_one_of_its_cells() {
    // Placed off the origin by a skewed basis, so the cells are parallelepipeds in the world.
    let frame = Frame::new(
        DVec3::new(0.4, -0.2, 0.3),
        DVec3::new(0.9, 0.2, -0.1),
        DVec3::new(-0.3, 1.1, 0.2),
        DVec3::new(0.1, 0.25, 0.8),
    )
    .unwrap();
    let mut with_cells = 0;
    for (name, shape) in surfaces_placed(frame) {
        let cells = shape.enclosing_cells();
        // Chmutov's octics and the degree-16 sphere: cells that fill their box are not given.
        // Hearts take the heart's own bounds instead.
        let fill_their_box = name.starts_with("chmutov") || name.contains(")^8");
        assert_eq!(
            cells.is_empty(),
            fill_their_box || shape.is_heart(),
            "{name}: {} cells",
            cells.len()
        );
        if cells.is_empty() {
            continue;
        }
        with_cells += 1;
        let (camera, secondary) = rays(&shape);
        let mut hits = 0;
        let starts = camera.iter().map(|r| (r, 0.0));
        for (ray, t_min) in starts.chain(secondary.iter().map(|r| (r, 1e-9))) {
            if let Some(t) = shape.intersect(ray, t_min, f64::INFINITY) {
                hits += 1;
                let p = ray.at(t);
                assert!(
                    cells.iter().any(|c| in_cell(c, p)),
                    "{name}: hit {p} in none of {} cells",
                    cells.len()
                );
            }
        }
        assert!(hits > 50, "{name}: {hits} hits");
    }
    assert_eq!(with_cells, 6, "surfaces that gave cells");
}
