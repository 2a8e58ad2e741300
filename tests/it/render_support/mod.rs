//! Scene-building helpers shared by the render tests (scenes are built in code so these
//! tests do not depend on the parser).
#![allow(dead_code)]

use kardia::camera::Camera;
use kardia::film::Image;
use kardia::geometry::DVec3;
use kardia::lights::Light;
use kardia::materials::Material;
use kardia::pipeline::{self, Control, RenderRequest, RenderStats, Renderer};
use kardia::scene::{Object, Scene};
use kardia::shapes::{Plane, Sphere};

/// An empty scene: `w × h`, camera at `eye` looking at `at` with +Z up unless the view is
/// vertical, black background, no ambient light.
pub fn scene(w: u32, h: u32, eye: DVec3, at: DVec3, fov: f64) -> Scene {
    let forward = (at - eye).normalize();
    let up = if forward.cross(DVec3::Z).length() > 1e-6 {
        DVec3::Z
    } else {
        DVec3::Y
    };
    Scene {
        width: w,
        height: h,
        camera: Camera::new(eye, at, up, fov).unwrap(),
        background: DVec3::ZERO,
        ambient: DVec3::ZERO,
        lights: Vec::new(),
        index: Default::default(),
        objects: Vec::new(),
    }
}

/// Adds a sphere.
pub fn sphere(s: &mut Scene, centre: DVec3, radius: f64, m: Material) {
    let line = s.objects.len() + 1;
    s.objects.push(Object::new(
        Box::new(Sphere::new(centre, radius).unwrap()),
        m,
        "SPHERE",
        line,
    ));
}

/// Adds a plane.
pub fn plane(s: &mut Scene, point: DVec3, normal: DVec3, m: Material) {
    let line = s.objects.len() + 1;
    s.objects.push(Object::new(
        Box::new(Plane::new(point, normal).unwrap()),
        m,
        "PLANE",
        line,
    ));
}

/// Adds a light (`radius` 0 for a point light).
pub fn light(s: &mut Scene, position: DVec3, colour: DVec3, radius: f64) {
    s.lights.push(Light {
        position,
        colour,
        radius,
        samples: 1,
    });
}

/// First `t > 1e-9` where the ray `o + t·d` meets the sphere, computed independently of
/// the library.
pub fn hit_sphere(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<f64> {
    let oc = o - c;
    let a = d.dot(d);
    let b = oc.dot(d);
    let cc = oc.dot(oc) - r * r;
    let disc = b * b - a * cc;
    if disc < 0.0 {
        return None;
    }
    let sq = disc.sqrt();
    [(-b - sq) / a, (-b + sq) / a]
        .into_iter()
        .find(|&t| t > 1e-9)
}

/// The image through the pixel centres (no jitter), each pixel shaded as a render with
/// `settings` shades it.
pub fn centre_sampled(scene: &Scene, settings: &RenderSettings) -> Image {
    let mut image = Image::new(scene.width, scene.height);
    for y in 0..scene.height {
        for x in 0..scene.width {
            let ray = scene
                .camera
                .ray(x as f64 + 0.5, y as f64 + 0.5, scene.width, scene.height);
            image.set(x, y, trace_ray(scene, settings, &ray));
        }
    }
    image
}

/// The image as 8-bit sRGB pixels, row-major, converted as the PNG writer converts.
pub fn pixels(image: &Image) -> Vec<[u8; 3]> {
    image
        .to_srgb8()
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

/// How the render tests render: the request's samples, depth and seed, on `threads` threads
/// (0: one per core), the scene's own size and camera.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderSettings {
    /// Samples per pixel.
    pub spp: u32,
    /// Maximum recursion depth.
    pub max_depth: u32,
    /// Seed.
    pub seed: u64,
    /// Worker threads.
    pub threads: usize,
}

impl RenderSettings {
    /// The render request these settings describe.
    pub fn request(&self) -> RenderRequest {
        RenderRequest {
            spp: self.spp,
            max_depth: self.max_depth,
            seed: self.seed,
            ..RenderRequest::default()
        }
    }
}

/// The whole image of `scene` rendered by the library's pipeline with `settings`.
pub fn render(scene: &Scene, settings: &RenderSettings) -> Image {
    render_with_progress(scene, settings, &|_| {}).0
}

/// [`render`], calling `progress(n)` each time `n` more pixels are finished; also returns
/// what the render cost.
pub fn render_with_progress(
    scene: &Scene,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64) + Sync),
) -> (Image, RenderStats) {
    let renderer = Renderer::new(settings.threads).unwrap();
    let control = Control::new(Default::default(), |p| progress(p.finished));
    let rendered = renderer
        .render(scene, &settings.request(), &control)
        .unwrap();
    (rendered.image, rendered.stats)
}

/// The colour one world ray gets in a render with `settings`.
pub fn trace_ray(scene: &Scene, settings: &RenderSettings, ray: &kardia::geometry::Ray) -> DVec3 {
    pipeline::trace_ray(scene, &settings.request(), ray)
}
