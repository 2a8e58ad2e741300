//! Every scene in scenes/ parses, and valid scene text means what docs/scene-format.md says.

use kardia::geometry::{DVec3, Ray};
use kardia::scene::{parse, parse_file, LoadOptions, DEFAULT_SCENE};

fn ok(text: &str) -> kardia::scene::Scene {
    parse(text, "t.scene", &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// Parses every `.scene` file in `dir`; returns the scenes with their paths.
fn scenes_in(dir: &std::path::Path) -> Vec<(std::path::PathBuf, kardia::scene::Scene)> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "scene") {
            let scene = parse_file(&path, &LoadOptions::default())
                .unwrap_or_else(|e| panic!("{:?}", miette::Report::new(e)));
            assert!(
                !scene.objects.is_empty(),
                "{} has no objects",
                path.display()
            );
            out.push((path, scene));
        }
    }
    out
}

#[test]
fn every_scene_in_the_scenes_folder_parses() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let scenes = scenes_in(&dir);
    for (path, scene) in &scenes {
        assert!(
            scene.objects.iter().any(|o| o.keyword == "HEART"),
            "{} has no heart",
            path.display()
        );
    }
    assert!(
        scenes.len() >= 4,
        "only {} scenes found in {}",
        scenes.len(),
        dir.display()
    );
}

#[test]
fn every_implicit_gallery_scene_parses() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/implicit");
    let scenes = scenes_in(&dir);
    for (path, scene) in &scenes {
        assert!(
            scene.objects.iter().any(|o| o.keyword == "IMPLICIT"),
            "{} has no implicit surface",
            path.display()
        );
    }
    assert!(
        scenes.len() >= 7,
        "only {} scenes found in {}",
        scenes.len(),
        dir.display()
    );
}

#[test]
fn the_default_scene_parses() {
    let s = ok(DEFAULT_SCENE);
    assert_eq!((s.width, s.height), (800, 800));
    assert_eq!(s.objects[0].keyword, "HEART");
}

#[test]
fn a_full_scene_has_the_values_written() {
    let s = ok("# comment\n\
         size 640 480\n\
         Camera (6 0 0) (0, 0, 0) (0,0,1) 40 # trailing comment\n\
         BACKGROUND (0.1, 0.2, 0.3)\n\
         AMBIENT (0.05 0.05 0.05)\n\
         LIGHT (1, 2, 3) (1, 1, 1)\n\
         LIGHT (4, 5, 6) (0.5, 0.5, 0.5) 0.25 samples 8\n\
         MATERIAL glass (0, 0, 0) TRANSMIT 0.9 IOR 1.5 ATTENUATION (0.1, 0.2, 0.3)\n\
         MATERIAL tinted glass REFLECT 0.1 INSIDE (0.2, 0, 0)\n\
         \n\
         SPHERE (0, 0, 0) 1 glass\n\
         sphere (0, 0, 0) 1 tinted SPECULAR 0.5 40 checker (1,1,1) 0.25\n\
         PLANE (0, 0, -1) (0, 0, 2) (0.5, 0.5, 0.5)\n\
         BOX (0,0,0) (1,0,0) (0,1,0) (0,0,1) (1,0,0)\n\
         POLYGON 4 (0,0,0) (1,0,0) (1,1,0) (0.5,0.2,0) (1,0,0)\n\
         ELLIPSOID (0,0,0) (1,0,0) (0,2,0) (0,0,3) (1,0,0)\n\
         HEART (0,0,0) (1,0,0) (0,1,0) (0,0,1) (1,0,0)\n\
         IMPLICIT \"x^2 + y^2 + z^2 = 1\" (0,0,0) (1,0,0) (0,1,0) (0,0,1) (1,0,0) BOUND 2\n");
    assert_eq!((s.width, s.height), (640, 480));
    assert_eq!(s.camera.eye, DVec3::new(6.0, 0.0, 0.0));
    assert_eq!(s.camera.fov_degrees, 40.0);
    assert_eq!(s.background, DVec3::new(0.1, 0.2, 0.3));
    assert_eq!(s.ambient, DVec3::splat(0.05));
    assert_eq!(s.lights.len(), 2);
    assert_eq!(s.lights[0].radius, 0.0);
    assert_eq!(s.lights[1].radius, 0.25);
    assert_eq!((s.lights[0].samples, s.lights[1].samples), (1, 8));
    assert_eq!(s.lights[1].position, DVec3::new(4.0, 5.0, 6.0));
    let kinds: Vec<_> = s.objects.iter().map(|o| (o.keyword, o.line)).collect();
    assert_eq!(
        kinds,
        vec![
            ("SPHERE", 11),
            ("SPHERE", 12),
            ("PLANE", 13),
            ("BOX", 14),
            ("POLYGON", 15),
            ("ELLIPSOID", 16),
            ("HEART", 17),
            ("IMPLICIT", 18)
        ]
    );
    let glass = &s.objects[0].material;
    assert_eq!(glass.diffuse, DVec3::ZERO);
    assert_eq!((glass.transmit, glass.ior), (0.9, 1.5));
    assert_eq!(glass.attenuation, DVec3::new(0.1, 0.2, 0.3));
    assert_eq!(glass.reflect, 0.0);
    // A material built on another keeps its values and adds its own; an object may add more.
    let tinted = &s.objects[1].material;
    assert_eq!(
        (tinted.transmit, tinted.ior, tinted.reflect),
        (0.9, 1.5, 0.1)
    );
    assert_eq!(tinted.inside, Some(DVec3::new(0.2, 0.0, 0.0)));
    assert_eq!((tinted.specular, tinted.shininess), (0.5, 40.0));
    assert_eq!(tinted.checker, Some((DVec3::ONE, 0.25)));
    // Defaults for what is not written.
    let plain = &s.objects[2].material;
    assert_eq!(plain.diffuse, DVec3::splat(0.5));
    assert_eq!(
        (plain.specular, plain.reflect, plain.transmit),
        (0.0, 0.0, 0.0)
    );
    assert_eq!(plain.ior, 1.0);
    assert_eq!(plain.checker, None);
    // The plane's normal is normalised: a ray straight down hits z = -1 at t = 1.
    let down = Ray::new(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0));
    let t = s.objects[2].shape.intersect(&down, 1e-9, f64::INFINITY);
    assert_eq!(t, Some(1.0));
}

#[test]
fn defaults_when_statements_are_left_out() {
    let s = ok("CAMERA (0,0,5) (0,0,0) (0,1,0) 60\n");
    assert_eq!((s.width, s.height), kardia::scene::DEFAULT_SIZE);
    assert_eq!((s.width, s.height), (800, 600));
    assert_eq!(s.background, DVec3::ZERO);
    assert_eq!(s.ambient, DVec3::ZERO);
    assert!(s.lights.is_empty() && s.objects.is_empty());
}

#[test]
fn numbers_in_any_notation() {
    let s = ok("CAMERA (+6e0, 0., -.0) (0,0,0) (0,0,1E0) 4.5e1\nSIZE 8e2 6.0E2\n");
    assert_eq!(s.camera.eye, DVec3::new(6.0, 0.0, 0.0));
    assert_eq!(s.camera.fov_degrees, 45.0);
    assert_eq!((s.width, s.height), (800, 600));
}

#[test]
fn odd_whitespace_line_endings_and_bom() {
    let s = ok(
        "\u{feff}CAMERA\t(6,0,0)(0,0,0)( 0 , 0 , 1 )\t40\r\n\r\n   SPHERE (0,0,0) 1 (1,1,1)   \r\n",
    );
    assert_eq!(s.objects.len(), 1);
    assert_eq!(s.objects[0].line, 3);
}

#[test]
fn the_examples_in_the_format_documentation_parse() {
    let doc = include_str!("../../docs/scene-format.md");
    let mut blocks = 0;
    for block in doc.split("```text\n").skip(1) {
        let block = block.split("```").next().unwrap();
        if block.contains('×') {
            continue; // An error display, not scene text.
        }
        let mut text = String::new();
        if !block.to_uppercase().contains("CAMERA") {
            text.push_str("CAMERA (6, 0, 0) (0, 0, 0) (0, 0, 1) 40\n");
        }
        for name in ["glass", "ruby"] {
            if block.contains(name) && !block.contains(&format!("MATERIAL {name} ")) {
                text.push_str(&format!("MATERIAL {name} (0.5, 0.5, 0.5)\n"));
            }
        }
        text.push_str(block);
        if let Err(e) = parse(&text, "doc.scene", &LoadOptions::default()) {
            panic!("{:?}", miette::Report::new(e));
        }
        blocks += 1;
    }
    assert!(blocks >= 15, "only {blocks} example blocks");
}
