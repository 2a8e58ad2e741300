//! The scene: objects with materials, lights, camera, image settings; and its text format
//! (see docs/scene-format.md), read by [`parse`].

mod cursor;
mod error;
mod expr;
mod lexer;
pub mod limits;
mod parser;
mod surface;

pub use error::{InvalidScene, SceneError};
pub use expr::FrameTime;
pub use parser::{parse, parse_animated, parse_file, DEFAULT_SIZE};

use crate::camera::Camera;
use crate::geometry::{Aabb, DVec3, Ray};
use crate::lights::Light;
use crate::materials::Material;
use crate::roots::Solver;
use crate::shapes::{Shape, LANES};

/// The text of the built-in default scene (identical to `scenes/heart.scene`).
pub const DEFAULT_SCENE: &str = include_str!("../../scenes/heart.scene");

/// Choices made when a scene is loaded that the scene text does not make.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LoadOptions {
    /// Root-isolation strategy for polynomial surfaces (hearts, implicit surfaces).
    pub solver: Solver,
    /// The frame to read the scene at (`clock`, `frame`, `frames`); `None` reads it as a still,
    /// frame 0 of 1.
    pub time: Option<FrameTime>,
}

/// What a scene says about its animation, and whether anything in it moves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Animation {
    /// The number of frames given by `FRAMES n` (`None` without a `FRAMES` statement).
    pub frames: Option<u32>,
    /// Frames per second for animated outputs (`FPS f`; 24 when not given).
    pub fps: f64,
    /// True when some value of the scene depends on `clock`, `frame` or `frames`, so frames
    /// differ; false when every frame reads the same scene.
    pub uses_time: bool,
}

impl Animation {
    /// Frames per second when `FPS` is not given.
    pub const DEFAULT_FPS: f64 = 24.0;
}

impl Default for Animation {
    fn default() -> Self {
        Self {
            frames: None,
            fps: Self::DEFAULT_FPS,
            uses_time: false,
        }
    }
}

/// One thing in the scene: a shape, how it looks, and where it was written.
#[derive(Debug)]
pub struct Object {
    /// The geometry.
    pub shape: Box<dyn Shape>,
    /// Its surface properties.
    pub material: Material,
    /// The scene keyword that made it, upper case (`"HEART"`, `"SPHERE"`, …).
    pub keyword: &'static str,
    /// 1-based line of the scene text the object was written on.
    pub line: usize,
    /// Cached `shape.bounds()`.
    pub bounds: Aabb,
    /// Cached `shape.normal_lanes_pays()`.
    pub normal_lanes_pays: bool,
}

impl Object {
    /// An object; its bounds (and whether its normals are cheaper asked four at a time) are
    /// found once here.
    pub fn new(
        shape: Box<dyn Shape>,
        material: Material,
        keyword: &'static str,
        line: usize,
    ) -> Self {
        let bounds = shape.bounds();
        let normal_lanes_pays = shape.normal_lanes_pays();
        Self {
            shape,
            material,
            keyword,
            line,
            bounds,
            normal_lanes_pays,
        }
    }
}

/// The nearest surface a ray meets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneHit {
    /// Index into [`Scene::objects`].
    pub object: usize,
    /// Ray parameter, in units of the ray's direction.
    pub t: f64,
    /// World hit point `ray.at(t)`.
    pub point: DVec3,
    /// Unit outward normal of the surface at the hit (not flipped toward the ray).
    pub normal: DVec3,
}

/// A complete scene, ready to render.
#[derive(Debug)]
pub struct Scene {
    /// The scene's SIZE: the default image width in pixels (1 ..= 32768). A render of
    /// another size says so in its request (`pipeline::RenderRequest`), not by changing this.
    pub width: u32,
    /// The scene's SIZE: the default image height in pixels (1 ..= 32768).
    pub height: u32,
    /// The scene's CAMERA (a render may look through another, `pipeline::RenderRequest`).
    pub camera: Camera,
    /// Colour of rays that hit nothing (linear RGB).
    pub background: DVec3,
    /// Ambient light (linear RGB), multiplied by each surface's diffuse colour.
    pub ambient: DVec3,
    /// Light sources.
    pub lights: Vec<Light>,
    /// Objects, in the order written.
    pub objects: Vec<Object>,
}

impl Scene {
    /// Largest accepted image side, in pixels.
    pub const MAX_SIDE: u32 = 32768;

    /// Whether some object meets the ray with `t_min < t < t_max`: exactly
    /// `self.intersect(ray, t_min, t_max).is_some()`, but it stops at the first object hit and
    /// computes no normal (an any-hit query, for shadow rays).
    pub fn occluded(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        // `intersect` asks each object with the whole (t_min, t_max) until the first one
        // answers, so that first answer alone decides whether it returns a hit.
        self.objects
            .iter()
            .any(|obj| self.asks(obj, ray, t_min, t_max) && obj.shape.occludes(ray, t_min, t_max))
    }

    /// [`Scene::occluded`] for [`LANES`] rays at once, each with its own range: lane `i` is
    /// exactly `self.occluded(&rays[i], t_min[i], t_max[i])` (`false` when
    /// `t_max[i] <= t_min[i]`). Each object is asked for the lanes not yet blocked whose ray
    /// meets its box (every such lane where [`Scene::box_tests_skipped`]), all at once
    /// ([`Shape::occludes_lanes`]).
    pub fn occluded_lanes(
        &self,
        rays: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [bool; LANES] {
        let mut blocked = [false; LANES];
        for obj in &self.objects {
            let mut ask = [f64::NEG_INFINITY; LANES];
            let mut any = false;
            for lane in 0..LANES {
                if !blocked[lane]
                    && t_max[lane] > t_min[lane]
                    && self.asks(obj, &rays[lane], t_min[lane], t_max[lane])
                {
                    ask[lane] = t_max[lane];
                    any = true;
                }
            }
            if !any {
                continue;
            }
            let hits = obj.shape.occludes_lanes(rays, t_min, ask);
            for lane in 0..LANES {
                blocked[lane] |= hits[lane];
            }
        }
        blocked
    }

    /// [`Scene::intersect`] for [`LANES`] rays at once (camera rays of neighbouring pixels):
    /// lane `i` is exactly `self.intersect(&rays[i], t_min, t_max)`. Each object is asked for
    /// the lanes whose ray meets its box (every lane where [`Scene::box_tests_skipped`]), all
    /// at once ([`Shape::intersect_lanes`]).
    pub fn intersect_lanes(
        &self,
        rays: &[Ray; LANES],
        t_min: f64,
        t_max: f64,
    ) -> [Option<SceneHit>; LANES] {
        let mut best: [Option<(usize, f64)>; LANES] = [None; LANES];
        let mut t_far = [t_max; LANES];
        for (i, obj) in self.objects.iter().enumerate() {
            // An idle lane (its ray misses the box) asks for nothing: `t_max = −∞`.
            let mut ask = [f64::NEG_INFINITY; LANES];
            let mut any = false;
            for lane in 0..LANES {
                if self.asks(obj, &rays[lane], t_min, t_far[lane]) {
                    ask[lane] = t_far[lane];
                    any = true;
                }
            }
            if !any {
                continue;
            }
            let hits = obj.shape.intersect_lanes(rays, [t_min; LANES], ask);
            for lane in 0..LANES {
                if let Some(t) = hits[lane] {
                    t_far[lane] = t;
                    best[lane] = Some((i, t));
                }
            }
        }
        // Where every lane that hit met the same object, and that object's normals cost less
        // asked together, they are (the same answers as `hit` gives one at a time).
        let mut objects = best.iter().flatten().map(|&(object, _)| object);
        let Some(first) = objects.next() else {
            return [None; LANES];
        };
        if self.objects[first].normal_lanes_pays && objects.all(|object| object == first) {
            return self.hits_on_one_object(rays, first, best);
        }
        std::array::from_fn(|lane| best[lane].map(|(object, t)| self.hit(&rays[lane], object, t)))
    }

    /// The nearest hit with `t_min < t < t_max`, if any.
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<SceneHit> {
        let mut best: Option<(usize, f64)> = None;
        let mut t_far = t_max;
        for (i, obj) in self.objects.iter().enumerate() {
            if !self.asks(obj, ray, t_min, t_far) {
                continue;
            }
            if let Some(t) = obj.shape.intersect(ray, t_min, t_far) {
                t_far = t;
                best = Some((i, t));
            }
        }
        best.map(|(object, t)| self.hit(ray, object, t))
    }

    /// Whether the scene's queries ask the objects without testing the ray against their
    /// boxes first: when there is one object. The box test only saves work (a shape finds
    /// no hit off its bounds). With several objects it spares most objects most rays; with
    /// one, the object's own query tests its bounds at least as cheaply (a typed surface
    /// clips four rays to its box in vector registers), and the scene's slab tests were pure
    /// cost: 4–8 % of the instructions of a one-object render (docs/performance.md).
    #[inline]
    pub fn box_tests_skipped(&self) -> bool {
        self.objects.len() == 1
    }

    /// Whether a query of the scene asks `obj` about `ray` on `(t_min, t_max)`: where the
    /// box tests are skipped, always; else when the ray meets its box there.
    #[inline]
    fn asks(&self, obj: &Object, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        self.box_tests_skipped() || obj.bounds.clip(ray, t_min, t_max).is_some()
    }

    /// The hit records of the lanes of `best` (each a lane's object and `t`, all on object
    /// `object`), their normals asked together: the same records as [`Scene::hit`] makes.
    /// Kept out of line, so that the callers' other paths compile as they would without it.
    #[inline(never)]
    fn hits_on_one_object(
        &self,
        rays: &[Ray; LANES],
        object: usize,
        best: [Option<(usize, f64)>; LANES],
    ) -> [Option<SceneHit>; LANES] {
        let points: [DVec3; LANES] = std::array::from_fn(|lane| match best[lane] {
            Some((_, t)) => rays[lane].at(t),
            None => DVec3::ZERO,
        });
        let normals = self.objects[object]
            .shape
            .normal_lanes(&points, best.map(|hit| hit.is_some()));
        std::array::from_fn(|lane| {
            let (object, t) = best[lane]?;
            Some(SceneHit {
                object,
                t,
                point: points[lane],
                normal: normals[lane],
            })
        })
    }

    /// The hit record of `ray` meeting object `object` at `t`.
    #[inline]
    fn hit(&self, ray: &Ray, object: usize, t: f64) -> SceneHit {
        let point = ray.at(t);
        SceneHit {
            object,
            t,
            point,
            normal: self.objects[object].shape.normal(point),
        }
    }
}
