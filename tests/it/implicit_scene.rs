//! IMPLICIT objects inside a scene: what `kardia probe` reports (the scene's nearest hit,
//! its point and normal) is the same for `IMPLICIT heart` as for `HEART`.

use kardia::camera::Camera;
use kardia::geometry::{DVec3, Frame, Ray};
use kardia::materials::Material;
use kardia::scene::{Object, Scene};
use kardia::shapes::{Heart, Implicit, Shape};

fn scene(shape: Box<dyn Shape>, keyword: &'static str) -> Scene {
    Scene {
        width: 64,
        height: 64,
        camera: Camera::new(DVec3::new(6.0, 1.2, 0.9), DVec3::ZERO, DVec3::Z, 32.0).unwrap(),
        background: DVec3::ZERO,
        ambient: DVec3::ZERO,
        lights: Vec::new(),
        index: Default::default(),
        objects: vec![Object::new(shape, Material::default(), keyword, 1)],
    }
}

#[test]
fn scene_hits_of_implicit_heart_equal_heart() {
    let f = Frame::new(
        DVec3::new(0.1, 0.2, -0.1),
        DVec3::new(1.0, 0.1, 0.0),
        DVec3::new(0.0, 1.0, 0.2),
        DVec3::new(0.1, 0.0, 0.9),
    )
    .unwrap();
    let heart = scene(
        Box::new(Heart::new(f.position, f.m.x_axis, f.m.y_axis, f.m.z_axis).unwrap()),
        "HEART",
    );
    let implicit = scene(
        Box::new(Implicit::from_preset("heart", &[], f, None).unwrap()),
        "IMPLICIT",
    );
    let cam = &heart.camera;
    let mut hits = 0;
    for j in 0..64 {
        for i in 0..64 {
            let ray = cam.ray(i as f64 + 0.5, j as f64 + 0.5, 64, 64);
            let a = heart.intersect(&ray, 0.0, f64::INFINITY);
            let b = implicit.intersect(&ray, 0.0, f64::INFINITY);
            assert_eq!(a, b, "pixel ({i}, {j})");
            hits += a.is_some() as usize;
        }
    }
    assert!(hits > 200, "{hits}");
}

#[test]
fn scene_answers_for_generic_implicit_objects() {
    let torus = Implicit::from_preset("torus", &[1.0, 0.3], Frame::identity(), None).unwrap();
    let s = scene(Box::new(torus), "IMPLICIT");
    let ray = Ray::new(DVec3::new(5.0, 0.0, 0.0), -DVec3::X);
    let hit = s.intersect(&ray, 0.0, f64::INFINITY).unwrap();
    assert_eq!(s.objects[hit.object].keyword, "IMPLICIT");
    assert!((hit.t - 3.7).abs() < 1e-12, "{}", hit.t);
    assert!((hit.point - DVec3::new(1.3, 0.0, 0.0)).length() < 1e-12);
    assert!((hit.normal - DVec3::X).length() < 1e-12, "{}", hit.normal);
}

const CAMERA: &str = "CAMERA (6, 1.2, 0.9) (0, 0, 0) (0, 0, 1) 32\n";
const BASIS: &str = "(0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.8, 0.2, 0.2)";

#[test]
fn every_preset_loads_from_a_scene_without_bound() {
    use kardia::scene::{parse, LoadOptions};
    for line in [
        "heart",
        "taubin_heart",
        "torus 1 0.3",
        "kummer 1.140175425",
        "barth_sextic",
        "clebsch",
        "chmutov 3",
        "chmutov 16",
        "\"(x^2+y^2+z^2)^8 = 1\"",
        "\"x^2 + y^2 = 0.25\" INSIDE (1, 1, 0)",
    ] {
        let (head, tail) = line
            .split_once(" INSIDE")
            .map_or((line, ""), |(h, t)| (h, t));
        let bound = if head.contains("0.25") {
            " BOUND 1"
        } else {
            ""
        };
        let text = format!(
            "{CAMERA}IMPLICIT {head} {BASIS}{}{bound}\n",
            if tail.is_empty() {
                String::new()
            } else {
                format!(" INSIDE{tail}")
            }
        );
        let scene = parse(&text, "t.scene", &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{text}: {}", e.message()));
        assert_eq!(scene.objects.len(), 1);
        assert_eq!(scene.objects[0].keyword, "IMPLICIT");
        assert!(scene.objects[0].bounds.is_finite(), "{line}");
    }
}

#[test]
fn equation_errors_reach_the_scene_with_their_caret() {
    use kardia::scene::{parse, LoadOptions};
    for (eq, at, words) in [
        ("x^2.5 + y", "2.5", "whole number"),
        ("x^2 + w", "w", "unknown variable"),
        ("1/(x+1) + y", "(x+1)", "constant"),
        ("x^2 + y^2 = 1", "x^2", "BOUND"),
    ] {
        let text = format!("{CAMERA}IMPLICIT \"{eq}\" {BASIS}\n");
        let e = parse(&text, "t.scene", &LoadOptions::default()).unwrap_err();
        assert!(e.message().contains(words), "{eq}: {}", e.message());
        let line = text.lines().nth(1).unwrap();
        let column = line.find(at).unwrap() + 1;
        assert_eq!(e.location(), Some((2, column)), "{eq}: {}", e.message());
    }
}
