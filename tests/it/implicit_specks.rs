//! No specks on Taubin's heart traced through the generic IMPLICIT path (and through the
//! paper's heart's path, which its preset takes).
//!
//! Taubin's heart `(x² + 9/4·y² + z² − 1)³ − x²z³ − 9/80·y²z³ = 0` has, like the paper's heart,
//! a curve (its equator, `z = 0`, `x² + 9/4·y² = 1`) along which `∇f = 0` although the surface
//! is smooth there: rays crossing near it give the ray polynomial a near-triple root, which
//! `f64` locates only to about `∛ε ≈ 1e-5`. Without care that shows as dark specks along the
//! equator: a normal taken off the surface points anywhere, and a shadow ray leaving the
//! surface meets spurious roots next to its origin. The generic path has no factor to polish
//! on (that is the `HEART` shape's trick); it recomputes such roots, and such gradients, in
//! double-double arithmetic.
//!
//! The speck metric is the one of tests/it/specks.rs ([`Rgb8::specks`] on the 8-bit image, judged
//! inside the heart's silhouette); one sample per pixel, a point light with hard shadows and a
//! specular highlight, and views from the equator plane (edge-on), above and below it. Each
//! view checks that it sees the equator. The scene of the gallery image is checked too.

use crate::render_support;

use kardia::analysis::Rgb8;
use kardia::camera::Camera;
use kardia::film::Image;
use kardia::geometry::{DVec3, Frame};
use kardia::lights::Light;
use kardia::materials::Material;
use kardia::roots::Solver;
use kardia::scene::{parse_file, LoadOptions, Object, Scene};
use kardia::shapes::implicit::presets::preset;
use kardia::shapes::implicit::Implicit;
use render_support::{centre_sampled, pixels, render, RenderSettings};

/// Image side in pixels; odd, so that the middle pixel row lies on the camera's horizon.
const SIZE: u32 = 171;
/// Half-width, in object units, of the band around `z = 0` that counts as "the equator".
const BAND: f64 = 0.02;
/// Linear background colour (blue: far from the heart's red and from black).
const BACKGROUND: DVec3 = DVec3::new(0.05, 0.15, 0.45);

struct View {
    name: &'static str,
    eye: DVec3,
    look_at: DVec3,
    light: DVec3,
}

/// Edge-on: the eye and the look-at point in the equator plane `z = 0`, so the middle pixel
/// row's centre rays lie in it and cross the surface exactly on the equator curve.
const EDGE_ON: View = View {
    name: "edge-on",
    eye: DVec3::new(1.3, 5.0, 0.0),
    look_at: DVec3::ZERO,
    light: DVec3::new(-3.0, 6.0, 5.0),
};

const ABOVE: View = View {
    name: "above the equator",
    eye: DVec3::new(1.6, 4.0, 2.6),
    look_at: DVec3::new(0.0, 0.0, 0.05),
    light: DVec3::new(-3.0, 5.0, 6.0),
};

const BELOW: View = View {
    name: "below the equator",
    eye: DVec3::new(-1.8, 4.2, -2.2),
    look_at: DVec3::new(0.0, 0.0, 0.1),
    light: DVec3::new(-5.0, 4.0, -3.0),
};

/// Taubin's heart through the generic path (`generic`), whose robustness these tests are
/// mainly about, or as its preset goes: through the paper's heart's path, in heart space.
fn heart(solver: Solver, generic: bool) -> Implicit {
    let p = preset("taubin_heart", &[]).unwrap();
    let shape = if generic {
        Implicit::new_generic(&p.equation, Frame::identity(), p.bound).unwrap()
    } else {
        Implicit::from_preset("taubin_heart", &[], Frame::identity(), None).unwrap()
    };
    assert_eq!(shape.is_heart(), !generic, "the path asked for");
    shape.with_solver(solver)
}

fn scene(view: &View, solver: Solver, generic: bool) -> Scene {
    let shape = heart(solver, generic);
    Scene {
        width: SIZE,
        height: SIZE,
        camera: Camera::new(view.eye, view.look_at, DVec3::Z, 36.0).unwrap(),
        background: BACKGROUND,
        ambient: DVec3::splat(0.12),
        lights: vec![Light {
            position: view.light,
            colour: DVec3::splat(0.9),
            radius: 0.0,
            samples: 1,
        }],
        index: Default::default(),
        objects: vec![Object::new(
            Box::new(shape),
            Material {
                specular: 0.4,
                shininess: 40.0,
                ..Material::diffuse(DVec3::new(0.8, 0.06, 0.1))
            },
            "IMPLICIT",
            1,
        )],
    }
}

fn settings() -> RenderSettings {
    RenderSettings {
        spp: 1,
        max_depth: 2,
        seed: 7,
        threads: 1,
    }
}

/// The heart's pixels: those whose centre ray hits object 0 first, with the hit's `z`.
fn heart_mask(scene: &Scene) -> (Vec<bool>, Vec<f64>) {
    let (w, h) = (scene.width, scene.height);
    let mut mask = Vec::new();
    let mut z = Vec::new();
    for i in 0..w * h {
        let ray = scene
            .camera
            .ray((i % w) as f64 + 0.5, (i / w) as f64 + 0.5, w, h);
        let hit = scene
            .intersect(&ray, 0.0, f64::INFINITY)
            .filter(|hit| hit.object == 0);
        mask.push(hit.is_some());
        z.push(hit.map_or(f64::NAN, |hit| hit.point.z));
    }
    (mask, z)
}

/// The specks `(x, y, z of the hit)` of `image`, judged inside the heart's silhouette, and
/// how many judged pixels see the equator band.
fn specks(image: &Image, scene: &Scene) -> (Vec<(usize, usize, f64)>, usize) {
    let px = pixels(image);
    let (w, h) = (scene.width as usize, scene.height as usize);
    let (mask, z) = heart_mask(scene);
    let img = Rgb8 {
        width: w,
        height: h,
        pixels: &px,
    };
    let inside =
        |x: usize, y: usize| (y - 1..=y + 1).all(|j| (x - 1..=x + 1).all(|i| mask[j * w + i]));
    let equator = (1..h - 1)
        .flat_map(|y| (1..w - 1).map(move |x| (x, y)))
        .filter(|&(x, y)| inside(x, y) && z[y * w + x].abs() < BAND)
        .count();
    let found = img
        .specks(&mask)
        .into_iter()
        .map(|(x, y)| (x, y, z[y * w + x]))
        .collect();
    (found, equator)
}

fn assert_no_specks(view: &View) {
    for (&(solver, solver_name), generic) in
        Solver::ALL.iter().flat_map(|s| [(s, true), (s, false)])
    {
        let name = format!(
            "{solver_name}, {} path",
            if generic { "generic" } else { "heart's" }
        );
        let scene = scene(view, solver, generic);
        for (how, image) in [
            ("integrator", render(&scene, &settings())),
            ("pixel centres", centre_sampled(&scene, &settings())),
        ] {
            let (found, equator) = specks(&image, &scene);
            println!(
                "{} / {name} / {how}: {equator} judged pixels near the equator, {} specks",
                view.name,
                found.len()
            );
            assert!(
                equator >= 40,
                "{}: only {equator} pixels see the equator",
                view.name
            );
            assert!(
                found.is_empty(),
                "{} / {name} / {how}: specks (x, y, z) {found:?}",
                view.name
            );
        }
    }
}

#[test]
fn taubin_heart_has_no_specks_edge_on() {
    assert_no_specks(&EDGE_ON);
}

#[test]
fn taubin_heart_has_no_specks_from_above() {
    assert_no_specks(&ABOVE);
}

#[test]
fn taubin_heart_has_no_specks_from_below() {
    assert_no_specks(&BELOW);
}

/// The gallery's scene (a floor, two lights, one of them soft-edged only through its
/// distance), at the gallery's size, through the pixel centres, judged on the heart only.
#[test]
fn taubin_heart_scene_has_no_specks() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/implicit/taubin_heart.scene");
    let mut scene = parse_file(&path, &LoadOptions::default()).unwrap();
    (scene.width, scene.height) = (600, 450);
    let (found, equator) = specks(&centre_sampled(&scene, &settings()), &scene);
    println!(
        "gallery scene: {equator} judged pixels near the equator, {} specks",
        found.len()
    );
    assert!(equator >= 100);
    assert!(found.is_empty(), "specks (x, y, z) {found:?}");
}
