//! No specks on the heart (issue 5, item 5): the whole renderer, with every root solver, draws
//! the equator curve `Z = 0, 2X² + Y² = 1` without the trail of dark dots POV-Ray leaves there
//! (shared notes, heart-math.md: `f` has a triple root and `∇f = 0` on that curve).
//!
//! # The speck metric
//! [`kardia::analysis::Rgb8::specks`] on the 8-bit sRGB image (converted with
//! [`Image::to_srgb8`], exactly as the PNG writer does). A pixel is a speck when it and its
//! 8 neighbours are inside the silhouette, and it differs by more than
//! [`SPECK_JUMP`](kardia::analysis::SPECK_JUMP) 8-bit levels (largest channel difference) from both its upper and lower
//! neighbours while those two agree to within
//! [`SPECK_AGREE`](kardia::analysis::SPECK_AGREE) levels, or likewise from its
//! left and right neighbours. Smooth shading, silhouettes and shadow edges are not specks; an
//! isolated dot on a smooth surface is. The silhouette is every pixel that differs from the
//! background by more than [`SILHOUETTE`] levels; the background is blue and the heart red, so
//! a black pixel (what a NaN becomes) is inside the silhouette and is judged too.
//!
//! # The renders
//! One spp (no anti-aliasing to blur a speck away), a point light with hard shadows, ambient
//! light so shadowed parts stay inside the silhouette, a specular highlight so a wrong normal
//! shows. Cameras:
//! - exactly in the heart's `Z = 0` plane (eye and look-at with `Z = 0`, up `+Z`, odd image
//!   height), rendered twice: by the integrator (jittered samples near the plane) and through
//!   the pixel centres, so that the middle pixel row lies exactly in the plane and every heart
//!   pixel of it is a ray with a triple root on the equator curve;
//! - above and below the equator plane, where the equator is a curve across the image;
//! - a rotated, non-uniformly scaled and sheared heart;
//! - the heart scaled by 1e-3 and 1e3 (placed away from the origin), in and off its plane.
//!
//! Each view also checks that it really looks at the equator: enough judged pixels must see
//! the heart within a thin band around its `Z = 0` plane.
//!
//! The test can fail: a deliberately planted speck is found exactly, and a heart traced the
//! naive way (first root of the sextic `f`, normal `∇f`, POV-Ray's method) shows specks in the
//! same views.

use crate::render_support;

use kardia::analysis::{Rgb8, SPECK_JUMP};
use kardia::camera::Camera;
use kardia::film::Image;
use kardia::geometry::{Aabb, DVec3, Frame, Ray};
use kardia::lights::Light;
use kardia::materials::Material;
use kardia::roots::Solver;
use kardia::scene::{Object, Scene};
use kardia::shapes::heart::{gradient_f, sextic_coefficients, BOUNDS};
use kardia::shapes::{Heart, Shape};
use render_support::{centre_sampled, pixels, render, RenderSettings};

/// Image side in pixels; odd, so that a pixel row lies on the camera's horizon.
const SIZE: u32 = 171;
/// A pixel is part of the silhouette when it differs from the background by more than this.
const SILHOUETTE: u8 = 8;
/// Half-width, in object units, of the band around `Z = 0` that counts as "the equator".
const BAND: f64 = 0.02;
/// Linear background colour (blue: far from the heart's red and from black).
const BACKGROUND: DVec3 = DVec3::new(0.05, 0.15, 0.45);

/// A camera, a light and a placed heart, all in world space.
#[derive(Debug, Clone, Copy)]
struct View {
    name: &'static str,
    frame: [DVec3; 4],
    eye: DVec3,
    look_at: DVec3,
    light: DVec3,
    fov: f64,
}

impl View {
    /// The same view with everything scaled by `s` about the origin, then moved by `offset`.
    fn scaled(self, name: &'static str, s: f64, offset: DVec3) -> View {
        let [p, u, v, w] = self.frame;
        View {
            name,
            frame: [p * s + offset, u * s, v * s, w * s],
            eye: self.eye * s + offset,
            look_at: self.look_at * s + offset,
            light: self.light * s + offset,
            fov: self.fov,
        }
    }

    fn frame(&self) -> Frame {
        let [p, u, v, w] = self.frame;
        Frame::new(p, u, v, w).unwrap()
    }

    fn heart(&self, solver: Solver) -> Heart {
        Heart::from_frame(self.frame()).with_solver(solver)
    }

    fn scene(&self, shape: Box<dyn Shape>) -> Scene {
        Scene {
            width: SIZE,
            height: SIZE,
            camera: Camera::new(self.eye, self.look_at, DVec3::Z, self.fov).unwrap(),
            background: BACKGROUND,
            ambient: DVec3::splat(0.12),
            lights: vec![Light {
                position: self.light,
                colour: DVec3::splat(0.9),
                radius: 0.0,
                samples: 1,
            }],
            index: Default::default(),
            objects: vec![Object::new(
                shape,
                Material {
                    specular: 0.4,
                    shininess: 40.0,
                    ..Material::diffuse(DVec3::new(0.8, 0.06, 0.1))
                },
                "HEART",
                1,
            )],
        }
    }
}

const IDENTITY: [DVec3; 4] = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];

/// Face on, from the heart's own `Z = 0` plane: the equator is the middle pixel row.
const IN_PLANE: View = View {
    name: "in the Z = 0 plane",
    frame: IDENTITY,
    eye: DVec3::new(5.0, 1.3, 0.0),
    look_at: DVec3::new(0.0, 0.0, 0.0),
    light: DVec3::new(6.0, -3.0, 5.0),
    fov: 34.0,
};

/// From above: the front half of the equator is a curve across the lower half of the heart.
const ABOVE: View = View {
    name: "above the equator",
    frame: IDENTITY,
    eye: DVec3::new(4.0, 1.6, 2.6),
    look_at: DVec3::new(0.0, 0.0, 0.05),
    light: DVec3::new(5.0, -3.0, 6.0),
    fov: 36.0,
};

/// From below, lit from below, so the equator's curve bends the other way.
const BELOW: View = View {
    name: "below the equator",
    frame: IDENTITY,
    eye: DVec3::new(4.2, -1.8, -2.2),
    look_at: DVec3::new(0.0, 0.0, 0.1),
    light: DVec3::new(4.0, -5.0, -3.0),
    fov: 36.0,
};

/// A heart rotated about a skew axis, scaled unevenly and sheared; the camera sits close to
/// its tilted equator plane.
const ROTATED: View = View {
    name: "rotated, scaled and sheared heart",
    frame: [
        DVec3::new(0.3, -0.2, 0.1),
        DVec3::new(0.85, 0.35, -0.2),
        DVec3::new(-0.3, 0.95, 0.25),
        DVec3::new(0.3, -0.15, 1.05),
    ],
    eye: DVec3::new(5.0, 2.0, 0.6),
    look_at: DVec3::new(0.3, -0.2, 0.15),
    light: DVec3::new(6.0, -2.0, 5.0),
    fov: 38.0,
};

fn background8() -> [u8; 3] {
    pixels(&Image {
        width: 1,
        height: 1,
        pixels: vec![BACKGROUND.as_vec3()],
        alpha: None,
    })[0]
}

fn settings() -> RenderSettings {
    RenderSettings {
        spp: 1,
        max_depth: 2,
        seed: 7,
        threads: 1,
    }
}

/// What one image showed.
#[derive(Debug)]
struct Findings {
    /// Pixels the metric judged (inside the silhouette with all 8 neighbours).
    judged: usize,
    /// Judged pixels whose centre ray meets the heart within [`BAND`] of its `Z = 0` plane.
    equator: usize,
    /// Judged pixels on the middle row whose centre ray meets the heart exactly at `Z = 0`.
    on_plane: usize,
    /// The specks, with the object-space `Z` of their centre ray's hit.
    specks: Vec<(usize, usize, f64)>,
}

/// Runs the metric on `image` of the scene whose first object is `heart`.
fn inspect(image: &Image, scene: &Scene, heart: &Heart) -> Findings {
    let px = pixels(image);
    let (w, h) = (SIZE as usize, SIZE as usize);
    let img = Rgb8 {
        width: w,
        height: h,
        pixels: &px,
    };
    let mask = img.silhouette(background8(), SILHOUETTE);
    let object_z = |x: usize, y: usize| {
        let ray = scene.camera.ray(x as f64 + 0.5, y as f64 + 0.5, SIZE, SIZE);
        heart
            .intersect(&ray, 0.0, f64::INFINITY)
            .map(|t| heart.frame().point_to_object(ray.at(t)).z)
    };
    let mut findings = Findings {
        judged: 0,
        equator: 0,
        on_plane: 0,
        specks: Vec::new(),
    };
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let inside = (y - 1..=y + 1).all(|j| (x - 1..=x + 1).all(|i| mask[j * w + i]));
            if !inside {
                continue;
            }
            findings.judged += 1;
            if let Some(z) = object_z(x, y) {
                if z.abs() < BAND {
                    findings.equator += 1;
                }
                if z == 0.0 && y == h / 2 {
                    findings.on_plane += 1;
                }
            }
        }
    }
    findings.specks = img
        .specks(&mask)
        .into_iter()
        .map(|(x, y)| (x, y, object_z(x, y).unwrap_or(f64::NAN)))
        .collect();
    findings
}

/// Renders the view with every solver (and, when `centres`, also through the pixel centres),
/// asserts zero specks and that the equator was in view.
fn assert_no_specks(view: View, centres: bool) {
    for &(solver, name) in Solver::ALL {
        let heart = view.heart(solver);
        let scene = view.scene(Box::new(heart.clone()));
        let mut images = vec![("integrator", render(&scene, &settings()))];
        if centres {
            images.push(("pixel centres", centre_sampled(&scene, &settings())));
        }
        for (how, image) in images {
            let f = inspect(&image, &scene, &heart);
            println!(
                "{} / {name} / {how}: {} pixels judged, {} near the equator, {} on the plane, {} specks",
                view.name,
                f.judged,
                f.equator,
                f.on_plane,
                f.specks.len()
            );
            assert!(
                f.judged > (SIZE * SIZE / 8) as usize,
                "{}: the heart is barely in view",
                view.name
            );
            assert!(
                f.equator >= 40,
                "{}: only {} judged pixels see the equator",
                view.name,
                f.equator
            );
            if centres {
                assert!(
                    how == "integrator" || f.on_plane >= 60,
                    "{}: only {} judged pixels lie exactly on Z = 0",
                    view.name,
                    f.on_plane
                );
            }
            assert!(
                f.specks.is_empty(),
                "{} / {name} / {how}: specks (x, y, object Z) {:?}",
                view.name,
                f.specks
            );
        }
    }
}

#[test]
fn no_specks_from_the_equator_plane() {
    assert_no_specks(IN_PLANE, true);
}

#[test]
fn no_specks_from_above_the_equator() {
    assert_no_specks(ABOVE, false);
}

#[test]
fn no_specks_from_below_the_equator() {
    assert_no_specks(BELOW, false);
}

#[test]
fn no_specks_on_a_rotated_sheared_heart() {
    assert_no_specks(ROTATED, false);
}

#[test]
fn no_specks_on_a_tiny_heart_from_its_equator_plane() {
    let offset = DVec3::new(0.25, -0.5, 0.125);
    assert_no_specks(IN_PLANE.scaled("1e-3 heart, in plane", 1e-3, offset), true);
}

#[test]
fn no_specks_on_a_tiny_heart_from_above() {
    let offset = DVec3::new(-0.3, 0.7, 0.2);
    assert_no_specks(ABOVE.scaled("1e-3 heart, above", 1e-3, offset), false);
}

#[test]
fn no_specks_on_a_huge_heart_from_its_equator_plane() {
    let offset = DVec3::new(2500.0, -1000.0, 500.0);
    assert_no_specks(IN_PLANE.scaled("1e3 heart, in plane", 1e3, offset), true);
}

#[test]
fn no_specks_on_a_huge_rotated_heart() {
    let offset = DVec3::new(-800.0, 1200.0, 300.0);
    assert_no_specks(ROTATED.scaled("1e3 rotated heart", 1e3, offset), false);
}

/// The metric finds a planted speck on the equator row, and nothing else: a black pixel (a
/// NaN shade) and a merely darker one.
#[test]
fn a_planted_speck_on_the_equator_is_found() {
    let heart = IN_PLANE.heart(Solver::default());
    let scene = IN_PLANE.scene(Box::new(heart.clone()));
    let image = centre_sampled(&scene, &settings());
    let (w, y) = (SIZE as usize, SIZE as usize / 2);
    let clean = pixels(&image);
    // The judged equator pixel nearest the image centre.
    let x = (w / 2..w - 1)
        .find(|&x| {
            let ray = scene.camera.ray(x as f64 + 0.5, y as f64 + 0.5, SIZE, SIZE);
            heart.intersect(&ray, 0.0, f64::INFINITY).is_some()
        })
        .unwrap();
    let p = clean[y * w + x];
    let darker = p.map(|c| c.saturating_sub(SPECK_JUMP + 20));
    assert!(
        kardia::analysis::level_difference(p, darker) > SPECK_JUMP,
        "{p:?}"
    );
    for planted in [[0, 0, 0], darker] {
        let mut px = clean.clone();
        px[y * w + x] = planted;
        let img = Rgb8 {
            width: w,
            height: w,
            pixels: &px,
        };
        let mask = img.silhouette(background8(), SILHOUETTE);
        assert_eq!(img.specks(&mask), vec![(x, y)], "planted {planted:?}");
    }
}

/// The heart traced the naive way (POV-Ray's): the first root of the sextic `f` in the
/// clipped interval, with a fixed self-hit tolerance, and the normal `∇f`. It must show
/// specks along the equator where the real heart has none.
#[derive(Debug, Clone)]
struct NaiveHeart {
    frame: Frame,
    solver: Solver,
}

impl Shape for NaiveHeart {
    fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        let r = self.frame.ray_to_object(ray);
        let (t0, t1) = BOUNDS.clip(&r, t_min, t_max)?;
        // Roots closer than 1e-4 (object units) to the ray's origin are its own surface.
        let lo = (t_min + 1e-4 / r.dir.length()).max(t0);
        let o = r.at(t0);
        let c = sextic_coefficients(o, r.dir);
        let s = self.solver.first_root(&c, lo - t0, t1 - t0)?;
        Some(t0 + s)
    }

    fn normal(&self, p: DVec3) -> DVec3 {
        let n = self.frame.normal_matrix * gradient_f(self.frame.point_to_object(p));
        let n = n.normalize_or_zero();
        if n == DVec3::ZERO {
            DVec3::Z
        } else {
            n
        }
    }

    fn bounds(&self) -> Aabb {
        self.frame.bounds_to_world(&BOUNDS)
    }
}

#[test]
fn the_naive_heart_shows_specks_so_the_test_can_fail() {
    for &(solver, name) in Solver::ALL {
        for view in [IN_PLANE, ABOVE] {
            let heart = view.heart(solver);
            let naive = NaiveHeart {
                frame: view.frame(),
                solver,
            };
            let scene = view.scene(Box::new(naive));
            let f = inspect(&centre_sampled(&scene, &settings()), &scene, &heart);
            println!(
                "naive heart, {} / {name} / pixel centres: {} specks {:?}",
                view.name,
                f.specks.len(),
                f.specks
            );
            // Every speck is a pixel that sees the equator.
            assert!(f.specks.iter().all(|s| s.2.abs() < BAND), "{:?}", f.specks);
            if view.name == IN_PLANE.name {
                assert!(
                    f.specks.len() >= 10,
                    "{name}: the naive heart shows only {} specks",
                    f.specks.len()
                );
            }
        }
    }
}
