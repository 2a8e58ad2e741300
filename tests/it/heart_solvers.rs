//! The hard cases of shared/notes/heart-math.md through `Shape::intersect` with every real
//! root finder of the `roots` module (`Solver::ALL`), and the heart inside a `Scene`.

use crate::heart_support;

use heart_support::cases::{self, unit_heart};
use kardia::geometry::{DVec3, Ray};
use kardia::materials::Material;
use kardia::roots::Solver;
use kardia::scene::{Object, Scene};
use kardia::shapes::heart::Heart;
use kardia::shapes::Shape;

/// Runs `check` once per solver, with `Shape::intersect` of a heart re-built for that solver.
fn each_solver(mut check: impl FnMut(cases::HitFn)) {
    for (solver, name) in Solver::ALL {
        eprintln!("solver {name}");
        let hit = |h: &Heart, r: &Ray, t0: f64, t1: f64| {
            h.clone().with_solver(*solver).intersect(r, t0, t1)
        };
        check(&hit);
    }
}

#[test]
fn solvers_rays_in_the_z0_plane_have_triple_roots() {
    each_solver(cases::z0_plane_triple_roots);
}

#[test]
fn solvers_equator_curve_hits_and_normals_are_exact() {
    each_solver(|hit| {
        let (dist, angle) = cases::equator_hits_are_exact(hit, 200);
        eprintln!("equator: worst distance {dist:e}, worst normal angle {angle:e} rad");
    });
}

#[test]
fn solvers_tangent_rays_double_roots() {
    each_solver(cases::tangent_rays);
}

#[test]
fn solvers_rays_through_and_beside_the_singular_points() {
    each_solver(cases::singular_points);
}

#[test]
fn solvers_rays_starting_on_the_surface_unit_scale() {
    each_solver(|hit| {
        assert!(cases::rays_leaving_the_surface(hit, 1.0, DVec3::new(0.5, -0.2, 0.1)) > 250);
    });
}

#[test]
fn solvers_rays_starting_on_the_surface_tiny_heart() {
    each_solver(|hit| {
        let p = DVec3::new(2e-3, -1e-3, 5e-4);
        assert!(cases::rays_leaving_the_surface(hit, 1e-3, p) > 250);
    });
}

#[test]
fn solvers_rays_starting_on_the_surface_huge_heart() {
    each_solver(|hit| {
        let p = DVec3::new(2e3, -1e3, 5e2);
        assert!(cases::rays_leaving_the_surface(hit, 1e3, p) > 250);
    });
}

#[test]
fn solvers_rays_starting_on_the_surface_tiny_heart_far_away() {
    each_solver(|hit| {
        let p = DVec3::new(700.0, -300.0, 50.0);
        assert!(cases::rays_leaving_the_surface(hit, 1e-3, p) > 250);
    });
}

#[test]
fn solvers_rays_starting_inside_exit_once() {
    each_solver(cases::rays_from_inside);
}

#[test]
fn solvers_rays_parallel_to_each_axis() {
    each_solver(cases::rays_parallel_to_each_axis);
}

#[test]
fn solvers_agree_with_the_brute_force_geometry() {
    let mut rng = heart_support::Rng::new(21);
    let h = cases::placed_heart(2.0, DVec3::new(1.0, 2.0, 3.0));
    each_solver(|hit| {
        for _ in 0..2000 {
            let o = DVec3::new(1.0, 2.0, 3.0) + rng.direction() * 8.0;
            let target = DVec3::new(1.0, 2.0, 3.0) + rng.direction() * rng.range(0.0, 3.0);
            let ray = Ray::new(o, (target - o) * rng.range(0.1, 10.0));
            let got = hit(&h, &ray, 0.0, f64::INFINITY);
            let want = heart_support::brute_intersect(&h, &ray, 0.0, f64::INFINITY);
            match (got, want) {
                (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-12 * b, "{a} vs {b}"),
                (None, None) => {}
                (a, b) => {
                    // Only grazing rays (a sliver thinner than the brute grid) may differ.
                    let t = a.or(b).unwrap();
                    let n = h.normal(ray.at(t));
                    assert!(n.dot(ray.dir.normalize()).abs() < 0.05, "{a:?} vs {b:?}");
                }
            }
        }
    });
}

#[test]
fn scene_reports_the_nearest_heart_with_its_normal() {
    let heart = |x: f64, line| {
        Object::new(
            Box::new(Heart::new(DVec3::new(x, 0.0, 0.0), DVec3::X, DVec3::Y, DVec3::Z).unwrap()),
            Material::default(),
            "HEART",
            line,
        )
    };
    let scene = Scene {
        width: 8,
        height: 8,
        camera: kardia::camera::Camera::new(DVec3::new(9.0, 0.0, 0.0), DVec3::ZERO, DVec3::Z, 40.0)
            .unwrap(),
        background: DVec3::ZERO,
        ambient: DVec3::ZERO,
        lights: Vec::new(),
        index: Default::default(),
        objects: vec![heart(0.0, 4), heart(3.0, 5)],
    };
    // Along −X at Y = 0, Z = 0: the equator of the heart at x = 3 first (X = 1/√2).
    let ray = Ray::new(DVec3::new(9.0, 0.0, 0.0), DVec3::new(-2.0, 0.0, 0.0));
    let hit = scene.intersect(&ray, 0.0, f64::INFINITY).unwrap();
    assert_eq!(hit.object, 1);
    assert_eq!(scene.objects[hit.object].line, 5);
    let x = 3.0 + 0.5f64.sqrt();
    assert!(
        (hit.point - DVec3::new(x, 0.0, 0.0)).length() < 1e-15,
        "{}",
        hit.point
    );
    assert!((hit.t - (9.0 - x) / 2.0).abs() < 1e-15);
    // ∇g = (4X, 2Y, −∛B) at (1/√2, 0, 0): (2√2, 0, −∛0.05).
    let want = DVec3::new(2.0 * 2f64.sqrt(), 0.0, -(0.05f64).cbrt()).normalize();
    assert!((hit.normal - want).length() < 1e-15, "{}", hit.normal);
    // Leaving that hit along −X: through the heart (exit), then the other heart.
    let inside = Ray::new(hit.point, ray.dir);
    let exit = scene.intersect(&inside, 0.0, f64::INFINITY).unwrap();
    assert_eq!(exit.object, 1);
    assert!((exit.point.x - (3.0 - 0.5f64.sqrt())).abs() < 1e-15);
}

#[test]
fn unit_heart_is_usable_with_every_solver() {
    for (solver, _) in Solver::ALL {
        let h = unit_heart().with_solver(*solver);
        assert_eq!(h.solver(), *solver);
    }
}

#[test]
fn solvers_equator_curve_no_specks_in_a_render() {
    each_solver(|hit| {
        let n = cases::no_specks_along_the_equator(hit, 320);
        assert!(n > 300, "{n}");
    });
}

#[test]
fn solvers_match_the_reference_over_whole_views() {
    // Four views of the heart (face on, the default scene's, edge on, from below), every pixel
    // of a 40×40 image: hit or miss and t against a scan of g refined in double-double.
    use heart_support::reference_first_root_n;
    use kardia::shapes::heart::BOUNDS;
    let views = [
        (DVec3::new(4.5, 0.0, 0.1), DVec3::new(0.0, 0.0, 0.1)),
        (DVec3::new(6.0, 1.2, 0.9), DVec3::new(0.0, 0.0, 0.05)),
        (DVec3::new(0.3, 5.0, 0.0), DVec3::ZERO),
        (DVec3::new(2.0, -3.0, -3.0), DVec3::ZERO),
    ];
    let mut cases = Vec::new();
    for (eye, at) in views {
        let cam = kardia::camera::Camera::new(eye, at, DVec3::Z, 35.0).unwrap();
        for i in 0..1600 {
            let ray = cam.ray((i % 40) as f64 + 0.5, (i / 40) as f64 + 0.5, 40, 40);
            let want = BOUNDS
                .clip(&ray, 0.0, f64::INFINITY)
                .and_then(|(a, b)| reference_first_root_n(ray.origin, ray.dir, a, b, 2000))
                .map(|t| t.to_f64());
            cases.push((ray, want));
        }
    }
    let hits = cases.iter().filter(|c| c.1.is_some()).count();
    assert!(hits > 1500, "{hits}");
    each_solver(|hit| {
        let h = unit_heart();
        for (ray, want) in &cases {
            let got = hit(&h, ray, 0.0, f64::INFINITY);
            match (got, *want) {
                (Some(a), Some(b)) => {
                    assert!((a - b).abs() <= 1e-12 * b, "{ray:?}: {a} vs {b}");
                    // Seen from outside, the normal faces the viewer: no dark speck.
                    assert!(h.normal(ray.at(a)).dot(ray.dir) < 0.0, "{ray:?}");
                }
                (None, None) => {}
                (a, b) => panic!("{ray:?}: {a:?} vs {b:?}"),
            }
        }
    });
}
