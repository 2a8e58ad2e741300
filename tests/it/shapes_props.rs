//! Property tests for the simple primitives: every reported hit is in range, on the surface,
//! inside the bounds, with a unit outward normal; no hit is missed against an independent
//! (naive) reference away from degenerate cases; rays leaving a surface do not re-hit it.

use kardia::geometry::{DMat3, DVec3, Ray};
use kardia::shapes::{Ellipsoid, Parallelepiped, Plane, Polygon, Shape, Sphere};
use proptest::prelude::*;

fn vec3(r: f64) -> impl Strategy<Value = DVec3> {
    prop::array::uniform3(-r..r).prop_map(DVec3::from_array)
}

/// A direction towards `target` (mostly near the shape) or a random one, rescaled to a random
/// length between 1e-3 and 1e3.
fn aimed(o: DVec3, target: DVec3, random: DVec3, k_exp: f64, use_random: bool) -> DVec3 {
    let d = if use_random { random } else { target - o };
    let d = if d.length() > 1e-6 { d } else { DVec3::X };
    d.normalize() * 10f64.powf(k_exp)
}

/// Turns a range given in world distances along the ray into one in units of `d`.
fn per_dir((a, b): (f64, f64), d: DVec3) -> (f64, f64) {
    (a / d.length(), b / d.length())
}

fn t_range() -> impl Strategy<Value = (f64, f64)> {
    prop_oneof![
        Just((1e-9, f64::INFINITY)),
        Just((0.0, f64::INFINITY)),
        (0.0..30.0f64, 0.0..30.0f64).prop_map(|(a, b)| (a, a + b)),
    ]
}

/// Checks shared by every reported hit: returns the hit point and normal.
fn check_hit(s: &dyn Shape, ray: &Ray, t_min: f64, t_max: f64, t: f64) -> (DVec3, DVec3) {
    assert!(t > t_min && t < t_max, "t = {t} outside ({t_min}, {t_max})");
    let p = ray.at(t);
    assert!(s.bounds().contains(p), "{p} outside {:?}", s.bounds());
    let n = s.normal(p);
    assert!(
        n.is_finite() && (n.length() - 1.0).abs() < 1e-12,
        "normal {n}"
    );
    // The smallest t: nothing in (t_min, t).
    assert_eq!(s.intersect(ray, t_min, t), None);
    (p, n)
}

/// Real roots of a·t² + b·t + c (textbook formula) when comfortably distinct.
fn naive_roots(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    let disc = b * b - 4.0 * a * c;
    if disc < 1e-6 * (b * b + (4.0 * a * c).abs()) {
        return None; // near-tangent: not a reference case
    }
    let sq = disc.sqrt();
    Some(((-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a)))
}

fn first_in(ts: &[f64], t_min: f64, t_max: f64) -> Option<f64> {
    ts.iter().copied().find(|&t| t > t_min && t < t_max)
}

fn near(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

/// A well-conditioned random basis (no flat boxes or ellipsoids).
fn basis() -> impl Strategy<Value = (DVec3, DVec3, DVec3)> {
    (vec3(3.0), vec3(3.0), vec3(3.0)).prop_filter("well conditioned", |(u, v, w)| {
        let m = DMat3::from_cols(*u, *v, *w);
        m.determinant().abs() > 0.1 * u.length() * v.length() * w.length()
            && u.length() > 0.1
            && v.length() > 0.1
            && w.length() > 0.1
    })
}

/// A ray leaving `p` (on the surface with outward normal `n`): away from the surface when
/// `out`, otherwise into it; never closer than ~0.06 rad to tangent.
fn leaving_ray(p: DVec3, n: DVec3, d: DVec3, out: bool) -> Option<Ray> {
    let side = if out { 1.0 } else { -1.0 };
    let along = d - d.dot(n) * n;
    let dir = along + side * (0.06 * along.length() + d.dot(n).abs()) * n;
    (dir.length() > 0.0).then(|| Ray::new(p, dir))
}

proptest! {
    #[test]
    fn sphere_hits_are_correct(
        c in vec3(10.0), r in 0.01..5.0f64, o in vec3(20.0), aim in vec3(0.8), rnd in vec3(1.0),
        k in -3.0..3.0f64, use_rnd in prop::bool::weighted(0.2),
        range in t_range(), d2 in vec3(1.0), out: bool,
    ) {
        let d = aimed(o, c + r * aim, rnd, k, use_rnd);
        let (t_min, t_max) = per_dir(range, d);
        let s = Sphere::new(c, r).unwrap();
        let ray = Ray::new(o, d);
        let got = s.intersect(&ray, t_min, t_max);
        let oc = o - c;
        let reference = naive_roots(d.length_squared(), 2.0 * oc.dot(d), oc.length_squared() - r * r)
            .and_then(|(t0, t1)| {
                // Skip references within rounding of the range ends.
                let edge = |t: f64| near(t, t_min, 1e-9) || near(t, t_max, 1e-9);
                (!edge(t0) && !edge(t1)).then(|| first_in(&[t0, t1], t_min, t_max))
            });
        if let Some(expected) = reference {
            match (got, expected) {
                (Some(t), Some(e)) => prop_assert!(near(t, e, 1e-7), "{t} vs {e}"),
                (None, None) => {}
                _ => prop_assert!(false, "got {got:?}, expected {expected:?}"),
            }
        }
        if let Some(t) = got {
            let (p, n) = check_hit(&s, &ray, t_min, t_max, t);
            prop_assert!(((p - c).length() - r).abs() <= 1e-9 * (r + o.length() + c.length()));
            prop_assert!((n - (p - c) / r).length() < 1e-6);
            if let Some(leave) = leaving_ray(p, n, d2, out) {
                let again = s.intersect(&leave, 0.0, f64::INFINITY);
                if out {
                    prop_assert_eq!(again, None);
                } else {
                    let t2 = again.expect("an inward ray must exit");
                    prop_assert!(t2 * leave.dir.length() > 1e-6 * r);
                }
            }
        }
    }

    #[test]
    fn ellipsoid_hits_are_correct(
        c in vec3(5.0), (u, v, w) in basis(), o in vec3(15.0), aim in vec3(0.8), rnd in vec3(1.0),
        k in -3.0..3.0f64, use_rnd in prop::bool::weighted(0.2),
        range in t_range(), d2 in vec3(1.0), out: bool,
    ) {
        let d = aimed(o, c + DMat3::from_cols(u, v, w) * aim, rnd, k, use_rnd);
        let (t_min, t_max) = per_dir(range, d);
        let e = Ellipsoid::new(c, u, v, w).unwrap();
        let m_inv = DMat3::from_cols(u, v, w).inverse();
        let f = |p: DVec3| (m_inv * (p - c)).length_squared() - 1.0;
        let ray = Ray::new(o, d);
        let got = e.intersect(&ray, t_min, t_max);
        let (a, b) = (m_inv * (o - c), m_inv * d);
        let reference = naive_roots(b.length_squared(), 2.0 * a.dot(b), a.length_squared() - 1.0)
            .and_then(|(t0, t1)| {
                let edge = |t: f64| near(t, t_min, 1e-9) || near(t, t_max, 1e-9);
                (!edge(t0) && !edge(t1)).then(|| first_in(&[t0, t1], t_min, t_max))
            });
        if let Some(expected) = reference {
            match (got, expected) {
                (Some(t), Some(x)) => prop_assert!(near(t, x, 1e-7), "{t} vs {x}"),
                (None, None) => {}
                _ => prop_assert!(false, "got {got:?}, expected {expected:?}"),
            }
        }
        if let Some(t) = got {
            let (p, n) = check_hit(&e, &ray, t_min, t_max, t);
            prop_assert!(f(p).abs() < 1e-8, "f = {}", f(p));
            // Finite-difference gradient of the implicit function.
            let h = 1e-6;
            let grad = DVec3::new(
                f(p + h * DVec3::X) - f(p - h * DVec3::X),
                f(p + h * DVec3::Y) - f(p - h * DVec3::Y),
                f(p + h * DVec3::Z) - f(p - h * DVec3::Z),
            ) / (2.0 * h);
            prop_assert!((n - grad.normalize()).length() < 1e-5, "{n} vs {grad}");
            if let Some(leave) = leaving_ray(p, n, d2, out) {
                let again = e.intersect(&leave, 0.0, f64::INFINITY);
                if out {
                    prop_assert_eq!(again, None);
                } else {
                    let t2 = again.expect("an inward ray must exit");
                    prop_assert!(t2 * leave.dir.length() > 1e-7);
                }
            }
        }
    }

    #[test]
    fn box_hits_are_correct(
        corner in vec3(5.0), (e1, e2, e3) in basis(), o in vec3(15.0), aim in vec3(0.8),
        rnd in vec3(1.0), k in -3.0..3.0f64, use_rnd in prop::bool::weighted(0.2),
        range in t_range(), d2 in vec3(1.0), out: bool,
    ) {
        let target = corner + DMat3::from_cols(e1, e2, e3) * (aim + DVec3::splat(0.5));
        let d = aimed(o, target, rnd, k, use_rnd);
        let (t_min, t_max) = per_dir(range, d);
        let b = Parallelepiped::new(corner, e1, e2, e3).unwrap();
        let m_inv = DMat3::from_cols(e1, e2, e3).inverse();
        let ray = Ray::new(o, d);
        let got = b.intersect(&ray, t_min, t_max);
        // Reference: each of the six faces separately.
        let (oo, dd) = (m_inv * (o - corner), m_inv * d);
        let mut cands: Vec<(f64, usize, f64)> = vec![];
        let mut degenerate = false;
        for axis in 0..3 {
            if dd[axis].abs() < 1e-9 {
                degenerate = true;
                continue;
            }
            for face in [0.0, 1.0] {
                let t = (face - oo[axis]) / dd[axis];
                let q = oo + t * dd;
                let others = [(axis + 1) % 3, (axis + 2) % 3];
                let margin = others
                    .iter()
                    .map(|&k| q[k].min(1.0 - q[k]))
                    .fold(f64::INFINITY, f64::min);
                if margin.abs() < 1e-6 || near(t, t_min, 1e-9) || near(t, t_max, 1e-9) {
                    degenerate = true;
                }
                if margin >= 0.0 {
                    cands.push((t, axis, face));
                }
            }
        }
        cands.sort_by(|x, y| x.0.total_cmp(&y.0));
        if !degenerate {
            let expected = cands.iter().find(|c| c.0 > t_min && c.0 < t_max);
            match (got, expected) {
                (Some(t), Some(&(x, axis, face))) => {
                    prop_assert!(near(t, x, 1e-7), "{t} vs {x}");
                    let obj_n = DVec3::AXES[axis] * if face == 1.0 { 1.0 } else { -1.0 };
                    let want = (m_inv.transpose() * obj_n).normalize();
                    prop_assert!((b.normal(ray.at(t)) - want).length() < 1e-9);
                }
                (None, None) => {}
                _ => prop_assert!(false, "got {got:?}, expected {expected:?}"),
            }
        }
        if let Some(t) = got {
            let (p, n) = check_hit(&b, &ray, t_min, t_max, t);
            let q = m_inv * (p - corner);
            let tol = 1e-9 * (1.0 + o.length() + corner.length()) * 30.0;
            prop_assert!(q.cmpge(DVec3::splat(-tol)).all() && q.cmple(DVec3::splat(1.0 + tol)).all());
            prop_assert!(q.min_element().abs() < tol || (1.0 - q.max_element()).abs() < tol, "{q}");
            // Outward: a step along the normal leaves the solid, a step against it enters it.
            let step = 1e-4 * e1.length().min(e2.length()).min(e3.length());
            let inside = |x: DVec3| {
                let y = m_inv * (x - corner);
                y.cmpgt(DVec3::ZERO).all() && y.cmplt(DVec3::ONE).all()
            };
            prop_assert!(!inside(p + step * n));
            if let Some(leave) = leaving_ray(p, n, d2, out) {
                let again = b.intersect(&leave, 0.0, f64::INFINITY);
                if out {
                    prop_assert_eq!(again, None);
                } else {
                    prop_assert!(again.is_none_or(|t2| t2 * leave.dir.length() > 1e-7));
                }
            }
        }
    }

    #[test]
    fn plane_hits_are_correct(
        point in vec3(10.0), normal in vec3(1.0), o in vec3(20.0), rnd in vec3(1.0),
        k in -3.0..3.0f64, range in t_range(),
    ) {
        let d = aimed(o, o, rnd, k, true);
        let (t_min, t_max) = per_dir(range, d);
        prop_assume!(normal.length() > 1e-3);
        let pl = Plane::new(point, normal).unwrap();
        let n = normal.normalize();
        let ray = Ray::new(o, d);
        let got = pl.intersect(&ray, t_min, t_max);
        let cos = n.dot(d) / d.length();
        if cos.abs() > 1e-6 {
            let x = (point - o).dot(n) / n.dot(d);
            if !(near(x, t_min, 1e-9) || near(x, t_max, 1e-9)) {
                let expected = (x > t_min && x < t_max).then_some(x);
                prop_assert_eq!(got.is_some(), expected.is_some());
                if let (Some(t), Some(x)) = (got, expected) {
                    prop_assert!(near(t, x, 1e-9));
                }
            }
        }
        if let Some(t) = got {
            let (p, nn) = check_hit(&pl, &ray, t_min, t_max, t);
            prop_assert!((p - point).dot(n).abs() < 1e-9 * (1.0 + o.length() + point.length()) / cos.abs().max(1e-3));
            prop_assert!((nn - n).length() < 1e-12);
        }
    }

    /// Random star-shaped (generally non-convex) polygons, placed anywhere at any scale;
    /// rays aimed at random points of the plane hit exactly when the point is inside.
    #[test]
    fn polygon_hits_iff_inside(
        steps in prop::collection::vec(0.5..1.0f64, 4..12),
        radii in prop::collection::vec(0.2..2.0f64, 12),
        axis in vec3(1.0), offset in vec3(100.0), scale_exp in -2.0..2.0f64,
        target in prop::array::uniform2(-2.5..2.5f64),
        from in vec3(1.0), above: bool, k_exp in -2.0..2.0f64, reverse: bool,
    ) {
        prop_assume!(axis.length() > 1e-3);
        // Increasing angles around the origin: a star-shaped, simple, usually non-convex outline.
        let total: f64 = steps.iter().sum();
        // Every angular gap is below 0.4 turn, so the origin is inside and the outline
        // counter-clockwise.
        let angles: Vec<f64> = steps
            .iter()
            .scan(0.0, |acc, st| {
                let a = *acc;
                *acc += st / total * std::f64::consts::TAU;
                Some(a)
            })
            .collect();
        let mut pts2: Vec<[f64; 2]> = angles
            .iter()
            .zip(&radii)
            .map(|(a, r)| [r * a.cos(), r * a.sin()])
            .collect();
        if reverse {
            pts2.reverse();
        }
        let s = 10f64.powf(scale_exp);
        let (a, b) = axis.normalize().any_orthonormal_pair();
        let to_world = |x: f64, y: f64| offset + s * (x * a + y * b);
        let poly = Polygon::new(pts2.iter().map(|p| to_world(p[0], p[1])).collect()).unwrap();
        let want_n = if reverse { -a.cross(b) } else { a.cross(b) };
        prop_assert!((poly.unit_normal() - want_n).length() < 1e-9);

        // Reference: winding number by summed angles, and distance to the outline.
        let (tx, ty) = (target[0], target[1]);
        let mut winding = 0.0;
        let mut dist = f64::INFINITY;
        for i in 0..pts2.len() {
            let p = pts2[i];
            let q = pts2[(i + 1) % pts2.len()];
            let (ux, uy, vx, vy) = (p[0] - tx, p[1] - ty, q[0] - tx, q[1] - ty);
            winding += (ux * vy - uy * vx).atan2(ux * vx + uy * vy);
            let (ex, ey) = (q[0] - p[0], q[1] - p[1]);
            let h = ((-ux * ex - uy * ey) / (ex * ex + ey * ey)).clamp(0.0, 1.0);
            dist = dist.min(((ux + h * ex).powi(2) + (uy + h * ey).powi(2)).sqrt());
        }
        prop_assume!(dist > 1e-6);
        let inside = winding.abs() > std::f64::consts::PI;

        let n = want_n;
        // Come from either side, at least ~6° away from the plane.
        let side = if above { 1.0 } else { -1.0 };
        let lean = from - from.dot(n) * n + side * (0.2 + from.dot(n).abs()) * n;
        let hit_point = to_world(tx, ty);
        let origin = hit_point + 3.0 * s * lean;
        let kk = 10f64.powf(k_exp);
        let ray = Ray::new(origin, (hit_point - origin) * kk);
        let got = poly.intersect(&ray, 1e-9, f64::INFINITY);
        prop_assert_eq!(got.is_some(), inside, "winding {}", winding);
        if let Some(t) = got {
            prop_assert!(near(t, 1.0 / kk, 1e-9), "{t} vs {}", 1.0 / kk);
            let (_, nn) = check_hit(&poly, &ray, 1e-9, f64::INFINITY, t);
            prop_assert_eq!(nn, poly.unit_normal());
            // Leaving the polygon: no re-hit, whichever side.
            let again = poly.intersect(&Ray::new(ray.at(t), -ray.dir + 0.01 * s * a), 0.0, f64::INFINITY);
            prop_assert_eq!(again, None);
            let through = poly.intersect(&Ray::new(ray.at(t), ray.dir), 0.0, f64::INFINITY);
            prop_assert_eq!(through, None);
        }
    }
}
