//! The hard cases of shared/notes/heart-math.md as reusable checks, each taking the
//! intersection routine to test: the brute-force root finder (geometry alone) or a real
//! `roots::Solver` through `Shape::intersect`.

use super::*;
use kardia::geometry::{DMat3, Frame};
use kardia::shapes::heart::{self, BOUNDS, EXTENTS};
use kardia::shapes::Shape;

/// An intersection routine: `(heart, world ray, t_min, t_max) → first t`.
pub type HitFn<'a> = &'a dyn Fn(&Heart, &Ray, f64, f64) -> Option<f64>;

/// The heart of the paper, unplaced.
pub fn unit_heart() -> Heart {
    Heart::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z).unwrap()
}

/// A rotated, non-uniformly scaled, sheared and translated heart, `scale` units across.
pub fn placed_heart(scale: f64, position: DVec3) -> Heart {
    let rot = DMat3::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.7);
    let stretch = DMat3::from_diagonal(DVec3::new(0.6, 1.3, 0.9) * scale);
    let shear = DMat3::from_cols(DVec3::X, DVec3::new(0.3, 1.0, 0.0), DVec3::Z);
    let m = rot * stretch * shear;
    Heart::new(position, m.x_axis, m.y_axis, m.z_axis).unwrap()
}

/// A point of the equator curve `Z = 0, 2X² + Y² = 1` at angle `phi`.
pub fn equator_point(phi: f64) -> DVec3 {
    DVec3::new(phi.cos() / 2f64.sqrt(), phi.sin(), 0.0)
}

/// Hard case "the equator curve": rays aimed at, just above and just below the equator curve
/// from all around. The hit must be the high-precision first root of `g` (double-double) to a
/// few ulps, lie on the surface to machine precision, and its normal must match the
/// double-double `∇g` there. Returns (worst world distance error, worst normal angle).
pub fn equator_hits_are_exact(hit: HitFn, rays: usize) -> (f64, f64) {
    let h = unit_heart();
    let mut rng = Rng::new(9);
    let (mut worst_t, mut worst_n) = (0.0f64, 0.0f64);
    let mut hits = 0;
    for k in 0..rays {
        let zt = match k % 4 {
            0 => 0.0,
            1 => 10f64.powf(-rng.range(2.0, 14.0)),
            _ => -(10f64.powf(-rng.range(2.0, 14.0))),
        };
        let target = equator_point(rng.range(0.0, std::f64::consts::TAU)) + DVec3::Z * zt;
        // From outside, mostly near the equator's plane, like a camera at Z ≈ 0.
        let o = loop {
            let o = DVec3::new(
                rng.range(-6.0, 6.0),
                rng.range(-6.0, 6.0),
                rng.range(-0.5, 0.5),
            );
            if o.truncate().length() > 2.0 {
                break o;
            }
        };
        let scale = rng.range(0.2, 2.0);
        let d = (target - o) * scale;
        let ray = Ray::new(o, d);
        let got = hit(&h, &ray, 0.0, f64::INFINITY);
        let Some(tr) = reference_first_root(o, d, 0.0, 1.2 / scale) else {
            // Aimed at a silhouette point: the ray only touches the surface there (a double
            // root, no sign change); a hit, if any, must be at the target.
            if let Some(t) = got {
                assert!((ray.at(t) - target).length() < 1e-3, "{o} {d}");
            }
            continue;
        };
        let t = got.unwrap_or_else(|| panic!("ray {o} {d} aimed at {target} missed"));
        let err = (t - tr.to_f64()).abs() * d.length();
        let p = ray.at(t);
        // Within a few ulps of the ray's own coordinates (|o| up to ~8).
        assert!(
            err <= 16.0 * f64::EPSILON * (o.length() + 1.0),
            "ray {o} {d}: t {t} vs reference {:?} ({err:e} apart)",
            tr
        );
        // On the surface to the rounding of o + t·d itself.
        let dist = surface_distance(p);
        assert!(
            dist <= 2.0 * f64::EPSILON * (o.length() + 1.0),
            "{p} is {dist:e} off"
        );
        let n_ref = dd_grad_g_unit(DdVec::on_ray(o, d, tr));
        let a = angle(h.normal(p), n_ref);
        assert!(a < 1e-12, "normal at {p} off by {a:e} rad");
        worst_t = worst_t.max(err);
        worst_n = worst_n.max(a);
        hits += 1;
    }
    assert!(hits >= rays * 9 / 10, "{hits}");
    (worst_t, worst_n)
}

/// Hard case "rays in the plane Z = 0": `f = A³`, every root triple. Hits must be the exact
/// root of the quadratic `A(t)` and the normal `∇g ∝ (4X, 2Y, −∛B)`.
pub fn z0_plane_triple_roots(hit: HitFn) {
    let h = unit_heart();
    for k in 0..=50 {
        let y0 = -1.2 + 2.4 * k as f64 / 50.0;
        for (o, d) in [
            (DVec3::new(-4.0, y0, 0.0), DVec3::new(1.0, 0.0, 0.0)),
            (DVec3::new(-3.0, y0, 0.0), DVec3::new(1.0, -0.2, 0.0)),
            (DVec3::new(y0 * 0.5, -5.0, 0.0), DVec3::new(0.0, 2.0, 0.0)),
            (DVec3::new(y0 * 0.5, 0.3, 0.0), DVec3::new(0.3, 2.0, 0.0)), // from inside
        ] {
            let ray = Ray::new(o, d);
            let got = hit(&h, &ray, 0.0, f64::INFINITY);
            // Analytic: the first root of A(t) = a + b t + c t² after 0.
            let a = 2.0 * o.x * o.x + o.y * o.y - 1.0;
            let b = 4.0 * o.x * d.x + 2.0 * o.y * d.y;
            let c = 2.0 * d.x * d.x + d.y * d.y;
            let disc = b * b - 4.0 * a * c;
            if disc <= 1e-9 {
                continue; // misses, or tangent to the ellipse (a 6-fold root)
            }
            let q = -0.5 * (b + b.signum() * disc.sqrt());
            let (r0, r1) = ((q / c).min(a / q), (q / c).max(a / q));
            let want = if r0 > 0.0 { r0 } else { r1 };
            if want <= 0.0 {
                continue;
            }
            let t = got.unwrap_or_else(|| panic!("no hit for {o} {d}"));
            assert!(
                (t - want).abs() <= 4.0 * f64::EPSILON * want,
                "{t} vs {want}"
            );
            let p = ray.at(t);
            assert!((2.0 * p.x * p.x + p.y * p.y - 1.0).abs() < 1e-15);
            let n = h.normal(p);
            let want_n =
                DVec3::new(4.0 * p.x, 2.0 * p.y, -(0.1 * p.x * p.x + p.y * p.y).cbrt()).normalize();
            assert!(angle(n, want_n) < 1e-14, "{n} vs {want_n}");
        }
    }
}

/// Hard case "rays tangent to the surface": double roots at the silhouette. Just inside the
/// tangent plane: a hit near the tangent point; just outside: a miss; exactly tangent: a hit at
/// the tangent point or a miss.
pub fn tangent_rays(hit: HitFn) {
    let h = unit_heart();
    // The points of largest Y and of largest X, where the planes Y = Y_max, X = X_max touch.
    let cases = [
        (
            DVec3::new(0.0, EXTENTS.max.y, heart::S_Y / 2.0),
            DVec3::Y,
            [DVec3::X, DVec3::Z],
        ),
        (
            DVec3::new(EXTENTS.max.x, 0.0, heart::S_X / 2.0),
            DVec3::X,
            [DVec3::Y, DVec3::Z],
        ),
    ];
    for (touch, normal, dirs) in cases {
        for (off, expect_hit) in [(-1e-3, true), (-1e-7, true), (1e-9, false), (1e-3, false)] {
            for dir in [dirs[0], dirs[1], (dirs[0] + 0.4 * dirs[1]).normalize()] {
                let o = touch + off * normal - 3.0 * dir;
                let got = hit(&h, &Ray::new(o, dir), 0.0, f64::INFINITY);
                if expect_hit {
                    let t = got.unwrap_or_else(|| panic!("{touch} off={off} dir={dir}: no hit"));
                    let p = o + t * dir;
                    assert!((p - touch).length() < 0.2, "{p}");
                    assert!(surface_distance(p) < 1e-14, "{p}");
                    assert!(h.normal(p).is_finite());
                } else {
                    assert_eq!(got, None, "{touch} off={off} dir={dir}");
                }
            }
        }
        let o = touch - 3.0 * dirs[0];
        if let Some(t) = hit(&h, &Ray::new(o, dirs[0]), 0.0, f64::INFINITY) {
            assert!((t - 3.0).abs() < 1e-3, "{t}");
        }
    }
}

/// Hard case "rays through or near the singular points" (the tip and the dip, where ∇f = 0).
pub fn singular_points(hit: HitFn) {
    let h = unit_heart();
    let tip = DVec3::new(0.0, 0.0, -1.0);
    let dip = DVec3::new(0.0, 0.0, 1.0);
    // Along the axis: f = (Z² − 1)³, triple roots exactly at the dip and the tip.
    let down = Ray::new(DVec3::new(0.0, 0.0, 4.0), DVec3::new(0.0, 0.0, -2.0));
    let t = hit(&h, &down, 0.0, f64::INFINITY).unwrap();
    assert!((down.at(t) - dip).length() < 1e-15, "{}", down.at(t));
    assert_eq!(h.normal(down.at(t)), DVec3::Z);
    let up = Ray::new(DVec3::new(0.0, 0.0, -4.0), DVec3::Z);
    let t = hit(&h, &up, 0.0, f64::INFINITY).unwrap();
    assert!((up.at(t) - tip).length() < 1e-15);
    assert_eq!(h.normal(up.at(t)), DVec3::NEG_Z);
    // From inside, out through the tip and the dip.
    let t = hit(&h, &Ray::new(DVec3::ZERO, DVec3::NEG_Z), 0.0, f64::INFINITY).unwrap();
    assert!((t - 1.0).abs() < 1e-15);
    // Oblique rays aimed at the tip from below and at the dip from above, and rays passing
    // 1e-9 .. 1e-3 beside them: finite unit normals, points on the surface.
    let mut rng = Rng::new(5);
    for k in 0..300 {
        let dir = rng.direction();
        let miss = if k % 3 == 0 {
            0.0
        } else {
            10f64.powf(-rng.range(3.0, 9.0))
        };
        let (target, dir) = if k % 2 == 0 {
            (tip, DVec3::new(dir.x, dir.y, dir.z.abs() + 0.8))
        } else {
            (
                dip,
                DVec3::new(dir.x * 0.1, dir.y * 0.1, -(dir.z.abs() + 0.8)),
            )
        };
        let side = dir.cross(rng.direction()).normalize() * miss;
        let o = target + side - 3.0 * dir;
        let ray = Ray::new(o, dir);
        let Some(t) = hit(&h, &ray, 0.0, f64::INFINITY) else {
            // Only a ray passing beside the tip may miss it (the tip is a cusp).
            assert!(target == tip && miss > 0.0, "{o} {dir}");
            continue;
        };
        let p = ray.at(t);
        let n = h.normal(p);
        assert!(n.is_finite() && (n.length() - 1.0).abs() < 1e-14);
        if target == tip {
            // The tip is a cusp (Z ≈ −1 + ∛B/2 beside it): an oblique ray only touches it and
            // stays outside, so the hit is the tip itself or the body beyond it.
            assert!(
                (p - tip).length() < 1e-4 || (t > 3.0 && surface_distance(p) < 1e-15),
                "{p}"
            );
        } else {
            // Near the dip the surface rises steeply (Z ≈ 1 + ∛B/2): the ray meets a lobe a
            // little before the dip itself.
            assert!(
                p.z >= 1.0 - 1e-12 && surface_distance(p) < 1e-15,
                "{p} {:e}",
                surface_distance(p)
            );
            assert!(
                n.dot(dir) < 0.0,
                "normal {n} faces away from the incoming ray"
            );
        }
    }
}

/// Rays from inside the heart: exactly one hit (the exit), normal along the ray.
pub fn rays_from_inside(hit: HitFn) {
    let h = unit_heart();
    let mut rng = Rng::new(6);
    for o in [
        DVec3::ZERO,
        DVec3::new(0.0, 0.5, 0.6),
        DVec3::new(0.1, -0.3, -0.5),
    ] {
        assert!(heart::heart_fn(o) < 0.0);
        for _ in 0..200 {
            let d = rng.direction() * rng.range(0.001, 100.0);
            let ray = Ray::new(o, d);
            let t = hit(&h, &ray, 0.0, f64::INFINITY).unwrap_or_else(|| panic!("{o} {d}: no exit"));
            let p = ray.at(t);
            assert!(surface_distance(p) < 1e-15, "{p}");
            assert!(h.normal(p).dot(d) > 0.0, "{p}");
        }
    }
}

/// Hard case "rays starting on the surface" (shadow, reflection, refraction rays), for a
/// heart `scale` units across placed at `position`: leaving rays never hit their own origin,
/// entering rays find the far side, and both agree with a reference scan that starts well
/// past the origin. `t_min = 0` is passed: the heart must guard itself. Returns the number of
/// secondary rays checked.
pub fn rays_leaving_the_surface(hit: HitFn, scale: f64, position: DVec3) -> usize {
    let h = placed_heart(scale, position);
    let frame: Frame = *h.frame();
    let mut rng = Rng::new(12);
    let mut checked = 0;
    for k in 0..100 {
        // A primary ray, half of them aimed at the equator curve.
        let target = if k % 2 == 0 {
            equator_point(rng.range(0.0, 6.3))
        } else {
            DVec3::new(
                rng.range(-0.6, 0.6),
                rng.range(-1.0, 1.0),
                rng.range(-0.9, 1.2),
            )
        };
        let o_obj = rng.direction() * 6.0;
        let primary = Ray::new(
            frame.point_to_world(o_obj),
            frame.m * (target - o_obj) * rng.range(0.5, 2.0),
        );
        let Some(t) = hit(&h, &primary, 0.0, f64::INFINITY) else {
            continue;
        };
        let p = primary.at(t);
        let q = frame.point_to_object(p);
        if q.truncate().length() < 1e-3 {
            continue; // beside the cusps the surface turns faster than any fixed guard
        }
        let n = h.normal(p);
        let reflect = primary.dir - 2.0 * primary.dir.dot(n) * n;
        let mut dirs = vec![reflect];
        for _ in 0..3 {
            let r = rng.direction();
            let cos = r.dot(n);
            if cos.abs() > 0.05 {
                dirs.push(r);
                dirs.push(-r);
            }
        }
        for d in dirs {
            let d = d * scale * rng.range(0.1, 10.0);
            let ray = Ray::new(p, d);
            let got = hit(&h, &ray, 0.0, f64::INFINITY);
            // Reference: the first root of g in object space more than 1e-5 (object units)
            // past the origin, up to the box exit.
            let r = frame.ray_to_object(&ray);
            let start = 1e-5 / r.dir.length();
            let want = BOUNDS
                .clip(&r, start, f64::INFINITY)
                .and_then(|(_, t1)| reference_first_root_n(r.origin, r.dir, start, t1, 6000))
                .map(|t| t.to_f64());
            match (got, want) {
                (Some(a), Some(b)) => {
                    assert!((a - b).abs() <= 1e-9 * b, "{p} {d}: {a} vs {b}");
                }
                (None, None) => {}
                (a, b) => panic!(
                    "scale {scale}: ray from {p} (object {q}) along {d} (cos {:.3}): got {a:?}, want {b:?}",
                    d.normalize().dot(n)
                ),
            }
            checked += 1;
        }
    }
    checked
}

/// Rays parallel to each axis (zero direction components everywhere in the slab test and the
/// coefficients), checked against a scan of `g`.
pub fn rays_parallel_to_each_axis(hit: HitFn) {
    let h = unit_heart();
    let mut n = 0;
    for axis in [
        DVec3::X,
        DVec3::Y,
        DVec3::Z,
        -DVec3::X,
        -DVec3::Y,
        -DVec3::Z,
    ] {
        for i in 0..21 {
            for j in 0..21 {
                let (u, v) = (-1.3 + 2.6 * i as f64 / 20.0, -1.3 + 2.6 * j as f64 / 20.0);
                let base = if axis.x != 0.0 {
                    DVec3::new(0.0, u, v)
                } else if axis.y != 0.0 {
                    DVec3::new(u * 0.6, 0.0, v)
                } else {
                    DVec3::new(u * 0.6, v, 0.0)
                };
                let o = base - 5.0 * axis;
                let ray = Ray::new(o, axis);
                let got = hit(&h, &ray, 0.0, f64::INFINITY);
                // The box lies within t ∈ [3.6, 6.4]: scan g there every 1e-3.
                let want = first_sign_change(|t| heart::factor_g(ray.at(t)), 3.0, 7.0, 4000);
                match (got, want) {
                    (Some(a), Some(b)) => {
                        assert!((a - b).abs() < 1e-9, "{o} {axis}: {a} vs {b}");
                        n += 1;
                    }
                    (None, None) => {}
                    (a, b) => panic!("{o} {axis}: {a:?} vs {b:?}"),
                }
            }
        }
    }
    assert!(n > 700, "{n}");
}

/// Hard case "the equator curve", as a render sees it: the benchmark camera (bench/heart.scene,
/// 1600×1600 scaled down to `size`²) looks at the heart from just above its equator's plane;
/// every pixel whose hit lies within 0.05 of the equator's plane must have its point on the
/// surface to machine precision and its normal within 1e-12 rad of the double-double
/// reference: no pixel may be a speck. Returns the number of pixels checked.
pub fn no_specks_along_the_equator(hit: HitFn, size: u32) -> usize {
    let h = unit_heart();
    let cam = kardia::camera::Camera::new(
        DVec3::new(4.5, 0.0, 0.1),
        DVec3::new(0.0, 0.0, 0.1),
        DVec3::Z,
        35.0,
    )
    .unwrap();
    let mut checked = 0;
    for y in 0..size {
        for x in 0..size {
            let ray = cam.ray(x as f64 + 0.5, y as f64 + 0.5, size, size);
            // The heart spans |Z| ≤ 1.24 at distance 4.5: skip rows far from the equator.
            let z_at_heart = ray.origin.z + ray.dir.z / ray.dir.x.abs() * 4.5;
            if z_at_heart.abs() > 0.2 {
                continue;
            }
            let Some(t) = hit(&h, &ray, 0.0, f64::INFINITY) else {
                continue;
            };
            let p = ray.at(t);
            if p.z.abs() > 0.05 {
                continue;
            }
            let w = 1e-9;
            let tr = dd_root_g(ray.origin, ray.dir, t - w, t + w);
            let err = (t - tr.to_f64()).abs();
            assert!(
                err <= 8.0 * f64::EPSILON * t,
                "pixel ({x}, {y}): t {t} vs {tr:?}"
            );
            let n_ref = dd_grad_g_unit(DdVec::on_ray(ray.origin, ray.dir, tr));
            let a = angle(h.normal(p), n_ref);
            assert!(
                a < 1e-12,
                "pixel ({x}, {y}) at {p}: normal off by {a:e} rad"
            );
            checked += 1;
        }
    }
    checked
}
