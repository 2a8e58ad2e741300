//! Implicit surfaces seen through the Shape trait: grids of camera rays compared with known
//! shapes (the heart, the sphere), clipping, transforms, and robustness (no NaN, no specks).

use kardia::camera::Camera;
use kardia::geometry::{DVec3, Frame, Ray};
use kardia::roots::Solver;
use kardia::shapes::implicit::{preset_equation, Implicit};
use kardia::shapes::{Heart, Shape, Sphere};

const N: u32 = 96;

fn camera(eye: DVec3) -> Camera {
    Camera::new(eye, DVec3::ZERO, DVec3::Z, 40.0).unwrap()
}

/// For each pixel of an N×N image: the hit `t`, if any.
fn cast(shape: &dyn Shape, cam: &Camera) -> Vec<Option<f64>> {
    (0..N * N)
        .map(|i| {
            let ray = cam.ray((i % N) as f64 + 0.5, (i / N) as f64 + 0.5, N, N);
            shape.intersect(&ray, 1e-9, f64::INFINITY)
        })
        .collect()
}

/// Asserts that `b` sees from `cam` what `a` sees: the same pixels hit, with depths within
/// `depth` (relative) and unit normals within `normal` of `a`'s; returns `a`'s hits.
fn assert_same_view(
    a: &dyn Shape,
    b: &dyn Shape,
    cam: &Camera,
    depth: f64,
    normal: f64,
    what: &str,
) -> usize {
    let (ta, tb) = (cast(a, cam), cast(b, cam));
    for (i, (x, y)) in ta.iter().zip(&tb).enumerate() {
        match (x, y) {
            (Some(x), Some(y)) => {
                assert!((x - y).abs() < depth * x, "{what}, pixel {i}: {x} vs {y}")
            }
            (None, None) => {}
            _ => panic!("{what}, pixel {i}: {x:?} against {y:?}"),
        }
        if let Some(t) = y {
            let ray = cam.ray(
                (i as u32 % N) as f64 + 0.5,
                (i as u32 / N) as f64 + 0.5,
                N,
                N,
            );
            let p = ray.at(*t);
            assert!(
                (a.normal(p) - b.normal(p)).length() < normal,
                "{what}, pixel {i} at {p}"
            );
        }
    }
    ta.iter().filter(|t| t.is_some()).count()
}

fn tilted_frame() -> Frame {
    Frame::new(
        DVec3::new(0.3, -0.2, 0.1),
        DVec3::new(0.9, 0.2, 0.0),
        DVec3::new(-0.2, 0.9, 0.3),
        DVec3::new(0.0, -0.3, 1.1),
    )
    .unwrap()
}

fn eyes() -> [DVec3; 4] {
    [
        DVec3::new(6.0, 0.0, 0.0),
        DVec3::new(4.0, 3.0, 2.0),
        DVec3::new(0.5, -5.0, 1.0),
        DVec3::new(5.0, 1.0, 0.0),
    ]
}

#[test]
fn heart_preset_is_identical_to_heart() {
    let f = tilted_frame();
    let heart = Heart::new(f.position, f.m.x_axis, f.m.y_axis, f.m.z_axis).unwrap();
    let preset = Implicit::from_preset("heart", &[], f, None).unwrap();
    let typed = Implicit::new(&preset_equation("heart", &[]).unwrap(), f, None).unwrap();
    assert!(preset.is_heart() && typed.is_heart());
    for eye in eyes() {
        let cam = camera(eye);
        let a = cast(&heart, &cam);
        assert!(a.iter().any(|t| t.is_some()));
        for shape in [&preset, &typed] {
            let b = cast(shape, &cam);
            assert_eq!(a, b, "hits differ from HEART seen from {eye}");
            for (i, t) in a.iter().enumerate() {
                if let Some(t) = t {
                    let ray = cam.ray(
                        (i as u32 % N) as f64 + 0.5,
                        (i as u32 / N) as f64 + 0.5,
                        N,
                        N,
                    );
                    let p = ray.at(*t);
                    assert_eq!(heart.normal(p), shape.normal(p));
                }
            }
        }
    }
}

#[test]
fn generic_heart_matches_heart_closely() {
    let f = tilted_frame();
    let heart = Heart::new(f.position, f.m.x_axis, f.m.y_axis, f.m.z_axis).unwrap();
    let generic =
        Implicit::new_generic("(2x^2 + y^2 + z^2 - 1)^3 = (0.1x^2 + y^2)*z^3", f, 2.0).unwrap();
    assert!(!generic.is_heart());
    for eye in eyes() {
        // Only rays grazing the silhouette may disagree. Depths agree to ~2e-6 at worst
        // (measured over 4 × 400² rays): f's roots are ill-conditioned near the equator curve,
        // which HEART handles specially and the generic path does not.
        assert_close_to_heart(&heart, &generic, &camera(eye), &format!("from {eye}"));
    }
}

/// Asserts that the generic path's `generic` sees from `cam` nearly what `heart` sees:
/// depths within 1e-5 (relative) where both hit, at most two (grazing) pixels hit by one only.
fn assert_close_to_heart(heart: &dyn Shape, generic: &dyn Shape, cam: &Camera, what: &str) {
    let (a, b) = (cast(heart, cam), cast(generic, cam));
    let mut mismatched = 0;
    for (ta, tb) in a.iter().zip(&b) {
        match (ta, tb) {
            (Some(x), Some(y)) => assert!((x - y).abs() < 1e-5 * x, "{x} vs {y} {what}"),
            (None, None) => {}
            _ => mismatched += 1,
        }
    }
    assert!(mismatched <= 2, "{mismatched} pixels differ {what}");
}

/// Taubin's heart is the paper's heart with `x = Y`, `y = √(8/9)·X`: its preset (and the
/// equation typed otherwise, or scaled) takes the heart's path, and gives the hits and normals
/// of `HEART` placed by the frame composed with that map (to the rounding of the two frames);
/// the generic path agrees to the accuracy of its roots.
#[test]
fn taubin_heart_takes_the_heart_s_path_and_matches_the_generic_one() {
    let f = tilted_frame();
    let alpha = (8.0f64 / 9.0).sqrt();
    let (u, v, w) = (f.m * DVec3::new(0.0, alpha, 0.0), f.m.x_axis, f.m.z_axis);
    let heart = Heart::new(f.position, u, v, w).unwrap();
    let equation = preset_equation("taubin_heart", &[]).unwrap();
    let preset = Implicit::from_preset("taubin_heart", &[], f, None).unwrap();
    let retyped = Implicit::new(
        "2*(x^2 + 2.25y^2 + z^2 - 1)^3 = 2*(x^2 + 0.1125y^2)*z^3",
        f,
        Some(2.0),
    )
    .unwrap();
    let generic = Implicit::new_generic(&equation, f, 2.0).unwrap();
    assert!(preset.is_heart() && retyped.is_heart() && !generic.is_heart());
    for eye in eyes() {
        let cam = camera(eye);
        for shape in [&preset, &retyped] {
            // The two frames differ by the rounding of √(8/9)·u: depths to ~1e-15.
            let hits = assert_same_view(&heart, shape, &cam, 1e-12, 1e-9, &format!("from {eye}"));
            assert!(hits > 500, "from {eye}");
        }
        assert_close_to_heart(&heart, &generic, &cam, &format!("from {eye}"));
    }
    // The equation's value and gradient, through the map: those of the expansion.
    for p in [
        DVec3::new(0.3, -0.2, 0.5),
        DVec3::new(-0.7, 0.1, -0.4),
        DVec3::new(0.05, 0.4, 1.1),
    ] {
        let q = f.m_inv * (p - f.position);
        let (vp, vg) = (retyped.value(q), 2.0 * generic.value(q));
        assert!((vp - vg).abs() < 1e-12, "{vp} vs {vg}");
        let (gp, gg) = (retyped.gradient(q), 2.0 * generic.gradient(q));
        assert!((gp - gg).length() < 1e-11, "{gp} vs {gg}");
        assert!((preset.value(q) - generic.value(q)).abs() < 1e-12);
    }
}

#[test]
fn degree_16_sphere_has_exactly_the_unit_sphere_silhouette() {
    let s16 = Implicit::new("(x^2+y^2+z^2)^8 - 1 = 0", Frame::identity(), None).unwrap();
    let unit = Sphere::new(DVec3::ZERO, 1.0).unwrap();
    for (eye, fov) in [
        (DVec3::new(4.0, 0.0, 0.0), 40.0),
        (DVec3::new(2.0, -2.5, 1.5), 40.0),
        (DVec3::new(0.0, 0.0, 30.0), 5.0),
        (DVec3::new(3000.0, 200.0, -100.0), 0.05),
    ] {
        let cam = Camera::new(eye, DVec3::ZERO, DVec3::new(0.0, 1.0, 0.3), fov).unwrap();
        assert_same_view(&unit, &s16, &cam, 1e-9, 1e-9, &format!("from {eye}"));
    }
}

/// Pixels whose hit/miss state differs from all 8 neighbours.
fn isolated(mask: &[bool]) -> Vec<(u32, u32)> {
    let n = N as i64;
    let mut out = Vec::new();
    for y in 1..n - 1 {
        for x in 1..n - 1 {
            let me = mask[(y * n + x) as usize];
            let alone = (-1..=1)
                .flat_map(|dy| (-1..=1).map(move |dx| (dx, dy)))
                .filter(|&d| d != (0, 0))
                .all(|(dx, dy)| mask[((y + dy) * n + x + dx) as usize] != me);
            if alone {
                out.push((x as u32, y as u32));
            }
        }
    }
    out
}

/// Whether the ray meets the surface inside the clip sphere, by dense sampling of `f` itself
/// (evaluated directly at points of the ray, no per-ray polynomial): the independent
/// reference for suspicious pixels.
fn reference_hits(shape: &Implicit, ray: &Ray) -> bool {
    let Some(rp) = shape.ray_polynomial(ray) else {
        return false;
    };
    let samples = 20_000;
    let f = |k: i32| {
        shape.value(ray.at(rp.t_mid + rp.t_half * (2.0 * k as f64 / samples as f64 - 1.0)))
    };
    let first = f(0);
    (1..=samples).any(|k| (f(k) > 0.0) != (first > 0.0))
}

#[test]
fn degree_16_chmutov_has_no_nan_and_no_specks() {
    for &(solver, _) in Solver::ALL {
        chmutov_16_is_clean(solver);
    }
}

fn chmutov_16_is_clean(solver: Solver) {
    let eq = preset_equation("chmutov", &[16.0]).unwrap();
    let shape = Implicit::from_preset("chmutov", &[16.0], Frame::identity(), None)
        .unwrap()
        .with_solver(solver);
    assert_eq!(shape.degree(), 16, "{eq}");
    for eye in [
        DVec3::new(5.0, 4.0, 3.0),
        DVec3::new(4.0, 4.0, 4.0),
        DVec3::new(2.2, 0.3, 1.9),
    ] {
        let cam = camera(eye);
        let hits = cast(&shape, &cam);
        let mask: Vec<bool> = hits.iter().map(|t| t.is_some()).collect();
        assert!(mask.iter().filter(|&&m| m).count() > (N * N / 8) as usize);
        // An isolated pixel is a speck unless it is real (a pinhole through the lattice
        // seen along a diagonal): check each against dense sampling of f.
        for (x, y) in isolated(&mask) {
            let ray = cam.ray(x as f64 + 0.5, y as f64 + 0.5, N, N);
            assert_eq!(
                reference_hits(&shape, &ray),
                mask[(y * N + x) as usize],
                "speck at pixel ({x}, {y}) from {eye} with {solver:?}"
            );
        }
        let mut back = 0;
        for (i, t) in hits.iter().enumerate() {
            if let Some(t) = t {
                assert!(t.is_finite());
                let ray = cam.ray(
                    (i as u32 % N) as f64 + 0.5,
                    (i as u32 / N) as f64 + 0.5,
                    N,
                    N,
                );
                let p = ray.at(*t);
                let n = shape.normal(p);
                assert!(
                    n.is_finite() && (n.length() - 1.0).abs() < 1e-12,
                    "{n} at {p}"
                );
                // Seen from outside, the first hit of this closed surface faces the viewer:
                // a back-facing normal would be a missed root or a wrong normal (a speck).
                if n.dot(ray.dir) >= 0.0 {
                    back += 1;
                }
                // The hit is on the surface: |f| / |∇f| (distance) is tiny.
                let dist = shape.value(p).abs() / shape.gradient(p).length();
                assert!(dist < 1e-9, "{dist} at {p}");
            }
        }
        assert_eq!(back, 0, "back-facing hits from {eye}");
    }
}

#[test]
fn t_is_in_units_of_the_callers_direction_through_a_frame() {
    let f = tilted_frame();
    let world = Implicit::new("x^4 + y^4 + z^4 = 1", f, None).unwrap();
    let eye = DVec3::new(5.0, 1.0, 2.0);
    let d = (f.position - eye).normalize();
    let t1 = world
        .intersect(&Ray::new(eye, d), 0.0, f64::INFINITY)
        .unwrap();
    let t3 = world
        .intersect(&Ray::new(eye, 3.0 * d), 0.0, f64::INFINITY)
        .unwrap();
    assert!((t1 - 3.0 * t3).abs() < 1e-9 * t1);
    let p = eye + t1 * d;
    let q = f.point_to_object(p);
    assert!((q.x.powi(4) + q.y.powi(4) + q.z.powi(4) - 1.0).abs() < 1e-9);
    // The outward normal points away from the object's centre here.
    assert!(world.normal(p).dot(p - f.position) > 0.0);
    // A shadow ray from the hit point does not re-hit its own origin.
    let n = world.normal(p);
    let out = Ray::new(p, n + DVec3::new(0.1, 0.0, 0.0));
    assert_eq!(world.intersect(&out, 1e-9, f64::INFINITY), None);
    // Grazing the other way, into the surface: the next hit is the far side, not ~0.
    let inward = Ray::new(p, -n);
    let t = world.intersect(&inward, 1e-9, f64::INFINITY).unwrap();
    assert!(t > 0.1, "{t}");
}

#[test]
fn clipping_limits_hits_and_shows_the_inside() {
    // The plane z = 0 clipped to the unit sphere: a disc.
    let disc = Implicit::new("z = 0", Frame::identity(), Some(1.0)).unwrap();
    let down = |x: f64| Ray::new(DVec3::new(x, 0.0, 5.0), -DVec3::Z);
    assert!((disc.intersect(&down(0.99), 0.0, f64::INFINITY).unwrap() - 5.0).abs() < 1e-12);
    assert_eq!(disc.intersect(&down(1.01), 0.0, f64::INFINITY), None);
    // A cylinder x² + y² = 0.25 clipped to radius 1: a ray through its open end meets the
    // inside, whose outward normal faces away from the viewer.
    let tube = Implicit::new("x^2 + y^2 = 0.25", Frame::identity(), Some(1.0)).unwrap();
    let eye = DVec3::new(0.0, 0.0, 3.0);
    let dir = DVec3::new(0.45, 0.0, 0.5) - eye;
    let t = tube
        .intersect(&Ray::new(eye, dir), 0.0, f64::INFINITY)
        .unwrap();
    let p = eye + t * dir;
    assert!(p.length() <= 1.0 + 1e-12);
    assert!((p.x.hypot(p.y) - 0.5).abs() < 1e-12);
    assert!(
        tube.normal(p).dot(dir) > 0.0,
        "the inside is seen from the back"
    );
    // Bounds: the clip sphere's box, narrowed to the tube (|x|, |y| ≤ 0.5) up to one cell
    // of the load-time subdivision (2/32 wide).
    let b = tube.bounds();
    assert!(
        (b.max.z - 1.0).abs() < 1e-8 && (b.min.z + 1.0).abs() < 1e-8,
        "{b:?}"
    );
    assert!(b.max.x >= 0.5 && b.max.x <= 0.5 + 0.0626, "{b:?}");
    assert!(b.min.y <= -0.5 && b.min.y >= -0.5 - 0.0626, "{b:?}");
    assert!(b.contains(DVec3::new(0.0, 0.0, 1.0)));
}

#[test]
fn singular_points_give_finite_normals() {
    // The cone x² + y² = z² has ∇f = 0 at its apex; the Kummer surface has 16 nodes.
    let cone = Implicit::new("x^2 + y^2 = z^2", Frame::identity(), Some(1.0)).unwrap();
    let n = cone.normal(DVec3::ZERO);
    assert!(n.is_finite() && (n.length() - 1.0).abs() < 1e-12);
    let n = cone.normal(DVec3::new(0.0, 0.0, 1e-200));
    assert!(n.is_finite() && (n.length() - 1.0).abs() < 1e-12);
    let tip = Implicit::new(
        "(2x^2 + y^2 + z^2 - 1)^3 = (0.1x^2 + y^2)*z^3",
        Frame::identity(),
        None,
    )
    .unwrap();
    assert!((tip.normal(DVec3::new(0.0, 0.0, -1.0)) - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-12);
}

#[test]
fn secondary_rays_never_re_hit_their_origin() {
    // Reflection, shadow-like and refraction-like rays from every primary hit.
    let cam = camera(DVec3::new(5.0, 4.0, 3.0));
    let n = 48u32;
    for (name, params) in [
        ("chmutov", vec![16.0]),
        ("barth_sextic", vec![]),
        ("kummer", vec![1.14]),
    ] {
        let shape = Implicit::from_preset(name, &params, Frame::identity(), None).unwrap();
        let mut primaries = 0;
        for i in 0..n * n {
            let ray = cam.ray((i % n) as f64 + 0.5, (i / n) as f64 + 0.5, n, n);
            let Some(t) = shape.intersect(&ray, 1e-9, f64::INFINITY) else {
                continue;
            };
            primaries += 1;
            let p = ray.at(t);
            let nn = shape.normal(p);
            let facing = if nn.dot(ray.dir) < 0.0 { nn } else { -nn };
            let reflected = ray.dir - 2.0 * ray.dir.dot(facing) * facing;
            for d in [reflected, facing + DVec3::new(0.15, -0.1, 0.25), -facing] {
                if let Some(t2) = shape.intersect(&Ray::new(p, d), 1e-9, f64::INFINITY) {
                    assert!(t2 > 1e-5, "{name}: re-hit at t = {t2} from {p} along {d}");
                }
            }
        }
        assert!(primaries > 100, "{name}: {primaries}");
    }
}

#[test]
fn clipped_heart_preset_shows_only_the_inside_of_its_bound() {
    let f = Frame::identity();
    let clipped = Implicit::from_preset("heart", &[], f, Some(0.9)).unwrap();
    assert!(clipped.is_heart());
    let heart = Heart::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z).unwrap();
    let cam = camera(DVec3::new(6.0, 1.2, 0.9));
    let (mut hits, mut inner) = (0, 0);
    for i in 0..N * N {
        let ray = cam.ray((i % N) as f64 + 0.5, (i / N) as f64 + 0.5, N, N);
        let whole = heart.intersect(&ray, 1e-9, f64::INFINITY);
        match clipped.intersect(&ray, 1e-9, f64::INFINITY) {
            Some(t) => {
                hits += 1;
                let p = ray.at(t);
                assert!(p.length() <= 0.9 + 1e-9, "{p}");
                // Where the heart's own first hit is inside the ball, it is the same hit (to
                // the solver's accuracy: the search interval differs).
                if let Some(w) = whole.filter(|&w| ray.at(w).length() < 0.9) {
                    assert!((w - t).abs() < 1e-8 * t, "{w} vs {t}");
                    inner += 1;
                }
                // Otherwise it is a hit further on (the inside seen through the cut).
                if whole.is_some_and(|w| ray.at(w).length() >= 0.9) {
                    assert!(clipped.normal(p).dot(ray.dir) > 0.0 || t > whole.unwrap());
                }
            }
            None => assert!(whole.is_none_or(|w| ray.at(w).length() >= 0.9)),
        }
    }
    assert!(hits > 100 && inner < hits, "{hits} {inner}");
}
