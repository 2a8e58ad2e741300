//! Small golden images: scenes built in code, rendered at 48×48 and compared with the PNGs in
//! tests/golden/.
//!
//! Tolerance: the 8-bit sRGB channel values may differ by at most 2 steps on 99% of all
//! channel values, and by at most 1.0 step on average (a few silhouette pixels may flip when
//! the floating-point details of a shape change). Regenerate the files after an intended
//! change with `KARDIA_BLESS=1 cargo test --test it render_golden` and look at them
//! (`KARDIA_PREVIEW=DIR` also writes 256×256, 16-spp versions into DIR for a closer look).

use crate::render_support;

use kardia::film::{write_image, Image};
use kardia::geometry::DVec3;
use kardia::materials::Material;
use kardia::scene::Scene;
use render_support::*;
use std::path::PathBuf;

const SIZE: u32 = 48;
const MAX_STEP: u8 = 2;
const ALLOWED_OUTLIERS: f64 = 0.01;
const MAX_MEAN_STEP: f64 = 1.0;

fn settings() -> RenderSettings {
    RenderSettings {
        spp: 4,
        max_depth: 6,
        seed: 42,
        threads: 2,
    }
}

fn golden(name: &str, build: fn(u32) -> Scene) {
    if let Some(dir) = std::env::var_os("KARDIA_PREVIEW") {
        let preview = RenderSettings {
            spp: 16,
            ..settings()
        };
        let path = PathBuf::from(dir).join(format!("{name}.png"));
        write_image(&render(&build(256), &preview), &path).unwrap();
    }
    let scene = build(SIZE);
    let image: Image = render(&scene, &settings());
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/golden")
        .join(format!("{name}.png"));
    if std::env::var_os("KARDIA_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        write_image(&image, &path).unwrap();
        return;
    }
    let reference = image::open(&path)
        .unwrap_or_else(|e| {
            panic!(
                "cannot read {}: {e} (bless with KARDIA_BLESS=1)",
                path.display()
            )
        })
        .to_rgb8();
    assert_eq!(reference.dimensions(), (image.width, image.height));
    let got = image.to_srgb8();
    let want = reference.into_raw();
    let diffs: Vec<u8> = got.iter().zip(&want).map(|(a, b)| a.abs_diff(*b)).collect();
    let outliers = diffs.iter().filter(|&&d| d > MAX_STEP).count();
    let mean = diffs.iter().map(|&d| d as f64).sum::<f64>() / diffs.len() as f64;
    assert!(
        outliers as f64 <= ALLOWED_OUTLIERS * diffs.len() as f64 && mean <= MAX_MEAN_STEP,
        "{name}: {outliers} of {} channel values differ by more than {MAX_STEP}; mean {mean:.3}",
        diffs.len()
    );
}

/// Diffuse, specular and mirror balls on a checker floor under a point and a spherical light.
#[test]
fn golden_spheres() {
    golden("spheres", spheres);
}

fn spheres(size: u32) -> Scene {
    let mut s = scene(
        size,
        size,
        DVec3::new(4.0, -5.0, 2.5),
        DVec3::new(0.0, 0.0, 0.3),
        45.0,
    );
    s.background = DVec3::new(0.05, 0.07, 0.12);
    s.ambient = DVec3::splat(0.08);
    plane(
        &mut s,
        DVec3::ZERO,
        DVec3::Z,
        Material {
            checker: Some((DVec3::splat(0.2), 0.7)),
            ..Material::diffuse(DVec3::splat(0.8))
        },
    );
    sphere(
        &mut s,
        DVec3::new(-0.8, 0.4, 0.7),
        0.7,
        Material {
            specular: 0.6,
            shininess: 60.0,
            ..Material::diffuse(DVec3::new(0.8, 0.1, 0.12))
        },
    );
    sphere(
        &mut s,
        DVec3::new(0.9, -0.2, 0.6),
        0.6,
        Material {
            reflect: 0.85,
            ..Material::diffuse(DVec3::splat(0.05))
        },
    );
    light(&mut s, DVec3::new(3.0, -2.0, 6.0), DVec3::splat(0.8), 0.8);
    light(&mut s, DVec3::new(-4.0, -3.0, 3.0), DVec3::splat(0.3), 0.0);
    s
}

/// A tinted glass ball (refraction, Fresnel, Beer–Lambert) and its tinted soft shadow.
#[test]
fn golden_glass() {
    golden("glass", glass);
}

fn glass(size: u32) -> Scene {
    let mut s = scene(
        size,
        size,
        DVec3::new(0.0, -5.0, 2.0),
        DVec3::new(0.0, 0.0, 0.5),
        40.0,
    );
    s.background = DVec3::new(0.6, 0.7, 0.9);
    s.ambient = DVec3::splat(0.1);
    plane(
        &mut s,
        DVec3::ZERO,
        DVec3::Z,
        Material {
            checker: Some((DVec3::new(0.1, 0.1, 0.3), 0.5)),
            ..Material::diffuse(DVec3::splat(0.9))
        },
    );
    sphere(
        &mut s,
        DVec3::new(0.0, 0.0, 0.9),
        0.9,
        Material {
            diffuse: DVec3::ZERO,
            specular: 0.8,
            shininess: 120.0,
            transmit: 0.95,
            ior: 1.5,
            attenuation: DVec3::new(0.05, 0.6, 0.9),
            ..Material::default()
        },
    );
    light(&mut s, DVec3::new(2.0, -1.0, 5.0), DVec3::ONE, 0.5);
    s
}

/// The built-in default scene (the paper's heart over a reflective floor, a soft shadow).
#[test]
fn golden_default_heart() {
    golden("heart", default_heart);
}

fn default_heart(size: u32) -> Scene {
    let mut s = kardia::scene::parse(
        kardia::scene::DEFAULT_SCENE,
        "heart.scene",
        &kardia::scene::LoadOptions::default(),
    )
    .unwrap();
    s.width = size;
    s.height = size;
    s
}
