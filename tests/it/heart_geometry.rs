//! The heart's geometry, checked independently of the `roots` module: the intersection runs
//! with a brute-force root finder (`Heart::intersect_with`), and every answer is compared with
//! a direct evaluation of the heart's equation.

use crate::heart_support;

use heart_support::*;
use kardia::geometry::{DMat3, DVec3, Frame, Ray};
use kardia::shapes::heart::{self, Heart, BOUNDS, EXTENTS};
use kardia::shapes::Shape;

fn unit_heart() -> Heart {
    Heart::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z).unwrap()
}

/// A rotated, non-uniformly scaled, sheared and translated heart.
fn placed_heart() -> Heart {
    let rot = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.7);
    let scale = DMat3::from_diagonal(DVec3::new(0.6, 1.7, 2.3));
    let shear = DMat3::from_cols(DVec3::X, DVec3::new(0.3, 1.0, 0.0), DVec3::Z);
    let m = rot * scale * shear;
    Heart::new(DVec3::new(3.0, -2.0, 0.5), m.x_axis, m.y_axis, m.z_axis).unwrap()
}

/// `f` of a world point for a placed heart, straight from the equation (no coefficients).
fn world_f(frame: &Frame, p: DVec3) -> f64 {
    heart::heart_fn(frame.point_to_object(p))
}

/// A ray from a random point at distance `r` aimed at a random point near the heart.
fn random_ray_at(rng: &mut Rng, r: f64) -> Ray {
    let o = rng.direction() * r;
    let target = DVec3::new(
        rng.range(-0.8, 0.8),
        rng.range(-1.2, 1.2),
        rng.range(-1.05, 1.3),
    );
    Ray::new(o, (target - o) * rng.range(0.1, 3.0))
}

#[test]
fn coefficients_equal_direct_evaluation() {
    let mut rng = Rng::new(1);
    for _ in 0..300 {
        let o = DVec3::new(
            rng.range(-3.0, 3.0),
            rng.range(-3.0, 3.0),
            rng.range(-3.0, 3.0),
        );
        let d = rng.direction() * rng.range(0.01, 4.0);
        let c = heart::sextic_coefficients(o, d);
        for k in 0..=20 {
            let t = -2.0 + 4.0 * k as f64 / 20.0;
            let direct = heart::heart_fn(o + t * d);
            let poly = horner(&c, t);
            // Scale of the terms being summed, for a relative comparison.
            let scale: f64 = c
                .iter()
                .enumerate()
                .map(|(i, ci)| ci.abs() * t.abs().powi(i as i32))
                .sum::<f64>()
                + 1.0;
            assert!(
                (direct - poly).abs() <= 1e-12 * scale,
                "o={o} d={d} t={t}: {direct} vs {poly}"
            );
        }
    }
}

#[test]
fn coefficients_in_the_z0_plane_are_a_perfect_cube() {
    // z0 = z1 = 0: f(t) = A(t)³ exactly, every root a triple root.
    let o = DVec3::new(-3.0, 0.25, 0.0);
    let d = DVec3::new(1.0, 0.1, 0.0);
    let c = heart::sextic_coefficients(o, d);
    let (a, b, cc) = (
        2.0 * o.x * o.x + o.y * o.y - 1.0,
        4.0 * o.x * d.x + 2.0 * o.y * d.y,
        2.0 * d.x * d.x + d.y * d.y,
    );
    let cube = [
        a * a * a,
        3.0 * a * a * b,
        3.0 * a * a * cc + 3.0 * a * b * b,
        6.0 * a * b * cc + b * b * b,
        3.0 * b * b * cc + 3.0 * a * cc * cc,
        3.0 * b * cc * cc,
        cc * cc * cc,
    ];
    for (x, y) in c.iter().zip(cube) {
        assert!(
            (x - y).abs() <= 1e-12 * y.abs().max(1.0),
            "{c:?} vs {cube:?}"
        );
    }
}

#[test]
fn bounding_box_holds_dense_samples_of_the_surface() {
    // 1. The exact parametrisation of the proof: (s, Z) with s³ ≤ u ≤ 20s³, u = 1 + sZ − Z².
    let mut seen = [f64::NEG_INFINITY; 4]; // max |X|, max |Y|, max Z, -min Z
    let n = 600;
    for i in 0..=n {
        let s = 1.2 * i as f64 / n as f64;
        for j in 0..=n {
            let z = -1.0 + 2.3 * j as f64 / n as f64;
            let u = 1.0 + s * z - z * z;
            let s3 = s * s * s;
            if u < s3 || u > 20.0 * s3 {
                continue;
            }
            let x = ((u - s3) / 1.9).sqrt();
            let y = ((s3 - 0.05 * u) / 0.95).max(0.0).sqrt();
            let p = DVec3::new(x, y, z);
            assert!(heart::factor_g(p).abs() < 1e-12, "{p} not on the surface");
            for q in [p, (-p.truncate()).extend(z)] {
                assert!(EXTENTS.contains(q), "{q} outside {EXTENTS:?}");
            }
            seen[0] = seen[0].max(x);
            seen[1] = seen[1].max(y);
            seen[2] = seen[2].max(z);
            seen[3] = seen[3].max(-z);
        }
    }
    // 2. Independently of the proof: sign changes of f along dense rays from an inner point.
    let centre = DVec3::new(0.0, 0.0, 0.1);
    let mut rng = Rng::new(7);
    for _ in 0..4000 {
        let dir = rng.direction();
        // Every sign change along the ray out to distance 3.
        let f = |t: f64| heart::heart_fn(centre + t * dir);
        let mut lo = 0.0;
        while let Some(t) = first_sign_change(f, lo, 3.0, 600) {
            let p = centre + t * dir;
            assert!(
                EXTENTS.contains(p) || (p - p.clamp(EXTENTS.min, EXTENTS.max)).length() < 1e-12,
                "{p}"
            );
            seen[0] = seen[0].max(p.x.abs());
            seen[1] = seen[1].max(p.y.abs());
            seen[2] = seen[2].max(p.z);
            seen[3] = seen[3].max(-p.z);
            lo = t + 1e-9;
        }
    }
    // The extents are tight: the samples come close to every face.
    let faces = [EXTENTS.max.x, EXTENTS.max.y, EXTENTS.max.z, -EXTENTS.min.z];
    for (s, f) in seen.iter().zip(faces) {
        assert!(*s <= f && *s > f - 2e-3, "sampled extent {s} vs box {f}");
    }
    // And the clipping box has its margin on every side.
    assert!(BOUNDS.min.cmplt(EXTENTS.min).all() && BOUNDS.max.cmpgt(EXTENTS.max).all());
}

#[test]
fn world_bounds_contain_the_placed_heart() {
    let h = placed_heart();
    let b = h.bounds();
    let mut rng = Rng::new(11);
    for _ in 0..2000 {
        let ray = random_ray_at(&mut rng, 12.0);
        let ray = Ray::new(h.frame().point_to_world(ray.origin), h.frame().m * ray.dir);
        if let Some(t) = brute_intersect(&h, &ray, 0.0, f64::INFINITY) {
            assert!(b.contains(ray.at(t)));
        }
    }
}

#[test]
fn hits_lie_on_the_ray_and_on_the_surface() {
    let h = unit_heart();
    let mut rng = Rng::new(2);
    let mut hits = 0;
    for _ in 0..2000 {
        let ray = random_ray_at(&mut rng, 6.0);
        let Some(t) = brute_intersect(&h, &ray, 0.0, f64::INFINITY) else {
            continue;
        };
        hits += 1;
        let p = ray.at(t);
        // g measures distance to the surface (|∇g| ≈ 1..5): near machine precision.
        assert!(
            heart::factor_g(p).abs() < 2e-14,
            "g({p}) = {}",
            heart::factor_g(p)
        );
        // And f is near zero relative to the scale of its terms (A itself is a cancelling
        // sum, so its rounding enters through ∂f/∂A = 3A²).
        let a = 2.0 * p.x * p.x + p.y * p.y + p.z * p.z - 1.0;
        let b = 0.1 * p.x * p.x + p.y * p.y;
        let scale = 3.0 * a * a * (2.0 * p.x * p.x + p.y * p.y + p.z * p.z + 1.0)
            + 3.0 * (b * p.z.powi(3)).abs();
        assert!(heart::heart_fn(p).abs() <= 1e-14 * scale + 1e-300, "{p}");
        // It is the FIRST crossing: f keeps its sign on the way in.
        let f0 = heart::heart_fn(ray.origin).signum();
        for k in 1..200 {
            let q = ray.at(t * k as f64 / 200.0 * 0.999);
            assert_eq!(
                heart::heart_fn(q).signum(),
                f0,
                "earlier crossing before t={t}"
            );
        }
    }
    assert!(hits > 600, "{hits}");
}

#[test]
fn normal_agrees_with_finite_difference_gradient() {
    for h in [unit_heart(), placed_heart()] {
        let frame = *h.frame();
        let mut rng = Rng::new(3);
        let mut checked = 0;
        for _ in 0..1500 {
            let ray = random_ray_at(&mut rng, 6.0);
            let ray = Ray::new(frame.point_to_world(ray.origin), frame.m * ray.dir);
            let Some(t) = brute_intersect(&h, &ray, 0.0, f64::INFINITY) else {
                continue;
            };
            let p = ray.at(t);
            let q = frame.point_to_object(p);
            // Away from the equator curve and the singular points, where ∇f is healthy.
            if q.z.abs() < 0.05 || q.truncate().length() < 0.05 {
                continue;
            }
            let n = h.normal(p);
            assert!((n.length() - 1.0).abs() < 1e-14);
            let e = 1e-6 * frame.m.x_axis.length().max(frame.m.y_axis.length());
            let fd = DVec3::new(
                world_f(&frame, p + e * DVec3::X) - world_f(&frame, p - e * DVec3::X),
                world_f(&frame, p + e * DVec3::Y) - world_f(&frame, p - e * DVec3::Y),
                world_f(&frame, p + e * DVec3::Z) - world_f(&frame, p - e * DVec3::Z),
            )
            .normalize();
            assert!(angle(n, fd) < 1e-5, "p={p} n={n} fd={fd}");
            checked += 1;
        }
        assert!(checked > 300, "{checked}");
    }
}

#[test]
fn placed_heart_agrees_with_the_transformed_equation() {
    // Roots of F(x) = f(M⁻¹(x − position)) found by sampling F along the WORLD ray: no
    // coefficients, no object-space ray.
    let h = placed_heart();
    let frame = *h.frame();
    let mut rng = Rng::new(4);
    let mut hits = 0;
    for _ in 0..600 {
        let r = random_ray_at(&mut rng, 8.0);
        let ray = Ray::new(frame.point_to_world(r.origin), frame.m * r.dir * 0.37);
        let got = brute_intersect(&h, &ray, 0.0, f64::INFINITY);
        let t_hi = 40.0 / ray.dir.length();
        let want = first_sign_change(|t| world_f(&frame, ray.at(t)), 0.0, t_hi, 20_000);
        match (got, want) {
            (Some(a), Some(b)) => {
                assert!((a - b).abs() <= 1e-9 * b, "t {a} vs {b}");
                hits += 1;
            }
            (None, None) => {}
            // A grazing ray may cross a sliver narrower than the sampling; allow only those.
            (a, b) => {
                let t = a.or(b).unwrap();
                let q = frame.point_to_object(ray.at(t));
                let n = heart::outward_direction(q).normalize();
                let d = (frame.m_inv * ray.dir).normalize();
                assert!(n.dot(d).abs() < 1e-2, "{a:?} vs {b:?} at {q}");
            }
        }
    }
    assert!(hits > 200, "{hits}");
}

#[test]
fn sheared_bases_are_hearts_and_singular_ones_are_errors() {
    // A non-orthogonal basis is a valid (sheared) heart.
    let sheared = Heart::new(
        DVec3::ZERO,
        DVec3::X,
        DVec3::new(0.9, 1.0, 0.0),
        DVec3::new(0.0, 0.5, 1.0),
    );
    assert!(sheared.is_ok());
    // Linearly dependent or nearly so: an error whose message says why.
    for w in [
        DVec3::X + DVec3::Y,
        DVec3::X + DVec3::Y + 1e-12 * DVec3::Z,
        DVec3::ZERO,
    ] {
        let err = Heart::new(DVec3::ZERO, DVec3::X, DVec3::Y, w).unwrap_err();
        assert!(err.to_string().contains("linearly dependent"), "{err}");
    }
    assert!(Heart::new(DVec3::splat(f64::NAN), DVec3::X, DVec3::Y, DVec3::Z).is_err());
}

#[test]
fn normal_is_a_finite_unit_vector_everywhere() {
    let h = placed_heart();
    let mut rng = Rng::new(8);
    let mut points = vec![
        DVec3::ZERO,
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(0.0, 0.0, -1.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(1e-300, 0.0, 1.0),
        DVec3::new(0.0, 1e-160, -1.0),
        DVec3::splat(1e200),
        DVec3::splat(f64::INFINITY),
        DVec3::splat(f64::NAN),
    ];
    for _ in 0..10_000 {
        points.push(rng.direction() * rng.range(0.0, 2.0));
    }
    for q in points {
        // Object-space points placed in the world.
        let n = h.normal(h.frame().point_to_world(q));
        assert!(
            n.is_finite() && (n.length() - 1.0).abs() < 1e-15,
            "{q}: {n}"
        );
    }
}

#[test]
fn t_is_in_units_of_the_direction_at_any_length() {
    for h in [unit_heart(), placed_heart()] {
        let frame = *h.frame();
        let o = frame.point_to_world(DVec3::new(0.5, 0.2, 0.0));
        let d = frame.m * DVec3::new(0.1, -0.2, 1.0);
        let base = brute_intersect(&h, &Ray::new(o, d), 0.0, f64::INFINITY).unwrap();
        for k in [1e-300, 1e-150, 1e-20, 0.37, 1.0, 3.0, 1e20, 1e150, 1e300] {
            let t = brute_intersect(&h, &Ray::new(o, d * k), 0.0, f64::INFINITY)
                .unwrap_or_else(|| panic!("no hit with |d| scaled by {k}"));
            assert!(
                (t * k - base).abs() <= 1e-14 * base,
                "k={k}: {t} · k vs {base}"
            );
        }
    }
}

#[test]
fn lower_half_lies_in_the_ellipsoid_used_for_clipping() {
    // Below Z = 0 the solid heart (g ≤ 0) is inside 2X² + Y² + Z² ≤ 1: check the surface
    // densely (the proof's parametrisation) and solid points on a grid.
    let n = 800;
    for i in 0..=n {
        let s = 1.2 * i as f64 / n as f64;
        for j in 0..=n {
            let z = -(j as f64) / n as f64;
            let u = 1.0 + s * z - z * z;
            let s3 = s * s * s;
            if u < s3 || u > 20.0 * s3 {
                continue;
            }
            assert!(u + z * z <= 1.0 + 1e-15, "s={s} z={z}");
        }
    }
    for i in 0..60 {
        for j in 0..60 {
            for k in 0..40 {
                let p = DVec3::new(
                    -0.75 + 1.5 * i as f64 / 59.0,
                    -1.2 + 2.4 * j as f64 / 59.0,
                    -1.05 + 1.05 * k as f64 / 39.0,
                );
                if heart::factor_g(p) <= 0.0 {
                    assert!(2.0 * p.x * p.x + p.y * p.y + p.z * p.z <= 1.0, "{p}");
                }
            }
        }
    }
    // And rays through the lower corners of the box, beside the tip, are rejected before
    // any root finding: a root finder that is never called proves it.
    let h = unit_heart();
    let ray = Ray::new(DVec3::new(5.0, 1.0, -0.8), DVec3::NEG_X);
    assert!(BOUNDS.clip(&ray, 0.0, f64::INFINITY).is_some());
    let got = h.intersect_with(&ray, 0.0, f64::INFINITY, |_, _, _| panic!("solver called"));
    assert_eq!(got, None);
}
