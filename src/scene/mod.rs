//! The scene: objects with materials, lights, camera, image settings; and its text format
//! (see docs/scene-format.md), read by [`parse`].

mod cursor;
mod error;
mod expr;
mod index;
mod lexer;
pub mod limits;
mod parser;
pub mod repeat;
mod surface;
mod words;

pub use error::{InvalidScene, SceneError};
pub use expr::FrameTime;
pub use index::ObjectIndex;
pub use parser::{parse, parse_animated, parse_file, DEFAULT_SIZE};

use crate::camera::Camera;
use crate::geometry::{Aabb, DVec3, Ray, RayLanes};
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
    /// True when the scene may read no file: a `MESH` statement is then an error. The
    /// explorer sets it (its scenes come from a web page); false, the default, for the command
    /// line and the library.
    pub forbid_files: bool,
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
    /// The objects' bounding volume hierarchy, by which the queries skip the objects a ray
    /// cannot meet (the loader builds it; `ObjectIndex::default()` builds it at the first
    /// query).
    pub index: ObjectIndex,
}

impl Scene {
    /// Largest accepted image side, in pixels.
    pub const MAX_SIDE: u32 = 32768;

    /// Whether some object meets the ray with `t_min < t < t_max`: exactly
    /// `self.intersect(ray, t_min, t_max).is_some()`, but it stops at the first object hit and
    /// computes no normal (an any-hit query, for shadow rays).
    pub fn occluded(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        if self.may_use_index() {
            return self.occluded_many(ray, t_min, t_max);
        }
        self.occluded_in_order(ray, t_min, t_max)
    }

    /// [`Scene::occluded`] of a scene that may use its index: by the index when it is built
    /// from these objects, else in order. Out of line, so that the small scenes' path
    /// compiles as it would without the index.
    #[inline(never)]
    fn occluded_many(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        match self.index.get(&self.objects) {
            Some(built) => self.occluded_by_index(built, ray, t_min, t_max),
            None => self.occluded_in_order(ray, t_min, t_max),
        }
    }

    /// [`Scene::occluded`], asking the objects in order.
    #[inline(always)]
    fn occluded_in_order(&self, ray: &Ray, t_min: f64, t_max: f64) -> bool {
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
        if self.may_use_index() {
            return self.occluded_lanes_many(rays, t_min, t_max, None);
        }
        self.occluded_lanes_in_order(rays, t_min, t_max)
    }

    /// [`Scene::occluded_lanes`] for rays that start on or near object `from` (shadow rays
    /// of hits on it): the same answers, for any `from`; with the index, its walk starts at
    /// that object's leaf and climbs, which costs less for rays that meet little beyond it.
    pub fn occluded_lanes_from(
        &self,
        rays: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
        from: usize,
    ) -> [bool; LANES] {
        if self.may_use_index() {
            return self.occluded_lanes_many(rays, t_min, t_max, Some(from));
        }
        self.occluded_lanes_in_order(rays, t_min, t_max)
    }

    /// [`Scene::occluded_lanes`] of a scene that may use its index (see
    /// [`Scene::occluded_many`]), its walk started at object `from`'s leaf when given.
    #[inline(never)]
    fn occluded_lanes_many(
        &self,
        rays: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
        from: Option<usize>,
    ) -> [bool; LANES] {
        match self.index.get(&self.objects) {
            Some(built) => self.occluded_lanes_by_index(built, rays, t_min, t_max, from),
            None => self.occluded_lanes_in_order(rays, t_min, t_max),
        }
    }

    /// [`Scene::occluded_lanes`], asking the objects in order.
    #[inline(always)]
    fn occluded_lanes_in_order(
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

    /// [`Scene::occluded_lanes`] by the index: the unbounded objects, then those of the
    /// hierarchy whose boxes a lane not yet blocked meets. Compiled for AVX2 where the
    /// processor has it, so that the four lanes' box tests run in vector registers (the
    /// same answers).
    #[inline(never)]
    fn occluded_lanes_by_index(
        &self,
        built: &index::Built,
        rays: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
        from: Option<usize>,
    ) -> [bool; LANES] {
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::avx2() {
            // SAFETY: the processor has AVX2.
            return unsafe { self.occluded_lanes_by_index_avx2(built, rays, t_min, t_max, from) };
        }
        self.occluded_lanes_by_index_body(built, rays, t_min, t_max, from)
    }

    /// [`Scene::occluded_lanes_by_index`] compiled for AVX2.
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn occluded_lanes_by_index_avx2(
        &self,
        built: &index::Built,
        rays: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
        from: Option<usize>,
    ) -> [bool; LANES] {
        self.occluded_lanes_by_index_body(built, rays, t_min, t_max, from)
    }

    /// The work of [`Scene::occluded_lanes_by_index`], inlined into each compiled form.
    #[inline(always)]
    fn occluded_lanes_by_index_body(
        &self,
        built: &index::Built,
        rays: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
        from: Option<usize>,
    ) -> [bool; LANES] {
        let mut blocked = [false; LANES];
        let lanes = RayLanes::new(rays);
        let ask_object = |i: usize, blocked: &mut [bool; LANES]| {
            let obj = &self.objects[i];
            let met = lanes.meet(&obj.bounds, t_min, t_max);
            let open: [bool; LANES] = std::array::from_fn(|lane| {
                !blocked[lane] && t_max[lane] > t_min[lane] && met & 1 << lane != 0
            });
            if !open.contains(&true) {
                return;
            }
            let ask = std::array::from_fn(|lane| {
                if open[lane] {
                    t_max[lane]
                } else {
                    f64::NEG_INFINITY
                }
            });
            let hits = obj.shape.occludes_lanes(rays, t_min, ask);
            for lane in 0..LANES {
                blocked[lane] |= hits[lane];
            }
        };
        for &i in &built.unbounded {
            ask_object(i as usize, &mut blocked);
        }
        // A blocked lane's walk ends: its range becomes empty.
        let range = std::array::from_fn(|lane| {
            if blocked[lane] || t_max[lane] <= t_min[lane] {
                f64::NEG_INFINITY
            } else {
                t_max[lane]
            }
        });
        let visit = |i: u32, range: &mut [f64; LANES]| {
            ask_object(i as usize, &mut blocked);
            for lane in 0..LANES {
                if blocked[lane] {
                    range[lane] = f64::NEG_INFINITY;
                }
            }
        };
        // Any object that blocks a lane blocks it, whatever the order the walk asks them in.
        match from.and_then(|object| built.leaf_of.get(object)) {
            Some(&leaf) => built.bvh.walk_lanes_from(&lanes, t_min, range, leaf, visit),
            None => built.bvh.walk_lanes(&lanes, t_min, range, visit),
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
        let best = if self.may_use_index() {
            self.nearest_lanes_many(rays, t_min, t_max)
        } else {
            self.nearest_lanes_in_order(rays, t_min, t_max)
        };
        self.hits_lanes(rays, best)
    }

    /// [`Scene::intersect_lanes`] for rays that may meet only the objects `objects` (indices,
    /// in any order, each at most once) and the unbounded ones: every other object's box is
    /// missed by every lane's ray on `(t_min, t_max)`, or met only where the object has no
    /// hit. The same answers, bit for bit: where the lanes' directions lie in one octant
    /// and there are at most [`Scene::MAX_LISTED`] objects, they are asked in the order the
    /// index's walk would ask them (which decides the ranges each is asked on, and so the
    /// last bits of a hit's `t`) without walking it; otherwise the index is walked. For the
    /// camera rays of a group of pixels, whose objects the scheduler lists from their images.
    pub fn intersect_lanes_among(
        &self,
        rays: &[Ray; LANES],
        t_min: f64,
        t_max: f64,
        objects: &[u32],
    ) -> [Option<SceneHit>; LANES] {
        let best = match (self.index.get(&self.objects), octant(rays)) {
            (Some(built), Some(octant))
                if self.may_use_index() && objects.len() <= Self::MAX_LISTED =>
            {
                self.nearest_lanes_among(built, rays, t_min, t_max, objects, octant)
            }
            _ => return self.intersect_lanes(rays, t_min, t_max),
        };
        self.hits_lanes(rays, best)
    }

    /// The most objects [`Scene::intersect_lanes_among`] asks without the index.
    pub const MAX_LISTED: usize = 16;

    /// The hit records of the lanes' nearest objects and `t`s, `best`.
    #[inline(always)]
    fn hits_lanes(
        &self,
        rays: &[Ray; LANES],
        best: [Option<(usize, f64)>; LANES],
    ) -> [Option<SceneHit>; LANES] {
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

    /// [`Scene::nearest_lanes_in_order`]'s answers for a scene that may use its index (see
    /// [`Scene::occluded_many`]).
    #[inline(never)]
    fn nearest_lanes_many(
        &self,
        rays: &[Ray; LANES],
        t_min: f64,
        t_max: f64,
    ) -> [Option<(usize, f64)>; LANES] {
        match self.index.get(&self.objects) {
            Some(built) => self.nearest_lanes_by_index(built, rays, t_min, t_max),
            None => self.nearest_lanes_in_order(rays, t_min, t_max),
        }
    }

    /// Each lane's nearest object and `t`, asking the objects in order, shrinking each lane's
    /// range as hits are found.
    #[inline(always)]
    fn nearest_lanes_in_order(
        &self,
        rays: &[Ray; LANES],
        t_min: f64,
        t_max: f64,
    ) -> [Option<(usize, f64)>; LANES] {
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
        best
    }

    /// [`Scene::nearest_lanes_in_order`]'s answers, asking only the objects of the index whose
    /// boxes the lanes' rays meet ([`nearer_limit`] keeps the objects' order in ties).
    /// Compiled for AVX2 where the processor has it (see
    /// [`Scene::occluded_lanes_by_index`]).
    #[inline(never)]
    fn nearest_lanes_by_index(
        &self,
        built: &index::Built,
        rays: &[Ray; LANES],
        t_min: f64,
        t_max: f64,
    ) -> [Option<(usize, f64)>; LANES] {
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::avx2() {
            // SAFETY: the processor has AVX2.
            return unsafe { self.nearest_lanes_by_index_avx2(built, rays, t_min, t_max) };
        }
        self.nearest_lanes_by_index_body(built, rays, t_min, t_max)
    }

    /// [`Scene::nearest_lanes_by_index`] compiled for AVX2.
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn nearest_lanes_by_index_avx2(
        &self,
        built: &index::Built,
        rays: &[Ray; LANES],
        t_min: f64,
        t_max: f64,
    ) -> [Option<(usize, f64)>; LANES] {
        self.nearest_lanes_by_index_body(built, rays, t_min, t_max)
    }

    /// The work of [`Scene::nearest_lanes_by_index`], inlined into each compiled form.
    #[inline(always)]
    fn nearest_lanes_by_index_body(
        &self,
        built: &index::Built,
        rays: &[Ray; LANES],
        t_min: f64,
        t_max: f64,
    ) -> [Option<(usize, f64)>; LANES] {
        let mut best: [Option<(usize, f64)>; LANES] = [None; LANES];
        let lanes = RayLanes::new(rays);
        for &i in &built.unbounded {
            self.ask_nearest_lanes(i as usize, rays, &lanes, t_min, t_max, &mut best);
        }
        let range = best.map(|hit| walk_limit(hit, t_max));
        built
            .bvh
            .walk_lanes(&lanes, [t_min; LANES], range, |i, range| {
                self.ask_nearest_lanes(i as usize, rays, &lanes, t_min, t_max, &mut best);
                *range = best.map(|hit| walk_limit(hit, t_max));
            });
        best
    }

    /// Object `i` asked for the lanes whose rays (`lanes`: `rays` by coordinate) meet its box
    /// before [`nearer_limit`] of the lane's nearest hit so far, `best`, which its hits
    /// replace.
    #[inline(always)]
    fn ask_nearest_lanes(
        &self,
        i: usize,
        rays: &[Ray; LANES],
        lanes: &RayLanes,
        t_min: f64,
        t_max: f64,
        best: &mut [Option<(usize, f64)>; LANES],
    ) {
        let obj = &self.objects[i];
        let limit: [f64; LANES] = std::array::from_fn(|lane| nearer_limit(i, best[lane], t_max));
        let met = lanes.meet(&obj.bounds, [t_min; LANES], limit);
        if met == 0 {
            return;
        }
        let ask = std::array::from_fn(|lane| {
            if met & 1 << lane != 0 {
                limit[lane]
            } else {
                f64::NEG_INFINITY
            }
        });
        let hits = obj.shape.intersect_lanes(rays, [t_min; LANES], ask);
        for lane in 0..LANES {
            if let Some(t) = hits[lane] {
                best[lane] = Some((i, t));
            }
        }
    }

    /// [`Scene::nearest_lanes_by_index`]'s answers asking the unbounded objects and
    /// `objects` (at most [`Scene::MAX_LISTED`]) alone, in the walk's order for rays whose
    /// directions lie in `octant` (see [`crate::bvh::Bvh::walk_ranks`] and
    /// [`Scene::intersect_lanes_among`]). Compiled for AVX2 where the processor has it.
    #[inline(never)]
    fn nearest_lanes_among(
        &self,
        built: &index::Built,
        rays: &[Ray; LANES],
        t_min: f64,
        t_max: f64,
        objects: &[u32],
        octant: usize,
    ) -> [Option<(usize, f64)>; LANES] {
        // The objects in the walk's order: a few, sorted by insertion.
        let mut order = [0u32; Self::MAX_LISTED];
        let order = &mut order[..objects.len()];
        for (k, &object) in objects.iter().enumerate() {
            let rank = built.walk_rank[object as usize][octant];
            let mut at = k;
            while at > 0 && built.walk_rank[order[at - 1] as usize][octant] > rank {
                order[at] = order[at - 1];
                at -= 1;
            }
            order[at] = object;
        }
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::avx2() {
            // SAFETY: the processor has AVX2.
            return unsafe { self.nearest_lanes_among_avx2(built, rays, t_min, t_max, order) };
        }
        self.nearest_lanes_among_body(built, rays, t_min, t_max, order)
    }

    /// [`Scene::nearest_lanes_among`] compiled for AVX2.
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn nearest_lanes_among_avx2(
        &self,
        built: &index::Built,
        rays: &[Ray; LANES],
        t_min: f64,
        t_max: f64,
        objects: &[u32],
    ) -> [Option<(usize, f64)>; LANES] {
        self.nearest_lanes_among_body(built, rays, t_min, t_max, objects)
    }

    /// The work of [`Scene::nearest_lanes_among`], inlined into each compiled form.
    #[inline(always)]
    fn nearest_lanes_among_body(
        &self,
        built: &index::Built,
        rays: &[Ray; LANES],
        t_min: f64,
        t_max: f64,
        objects: &[u32],
    ) -> [Option<(usize, f64)>; LANES] {
        let mut best: [Option<(usize, f64)>; LANES] = [None; LANES];
        let lanes = RayLanes::new(rays);
        for &i in built.unbounded.iter().chain(objects) {
            self.ask_nearest_lanes(i as usize, rays, &lanes, t_min, t_max, &mut best);
        }
        best
    }

    /// The nearest hit with `t_min < t < t_max`, if any. Where two objects are met at the same
    /// `t`, the one written first.
    pub fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<SceneHit> {
        let best = if self.may_use_index() {
            self.nearest_many(ray, t_min, t_max)
        } else {
            self.nearest_in_order(ray, t_min, t_max)
        };
        best.map(|(object, t)| self.hit(ray, object, t))
    }

    /// [`Scene::nearest_in_order`]'s answer for a scene that may use its index (see
    /// [`Scene::occluded_many`]).
    #[inline(never)]
    fn nearest_many(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(usize, f64)> {
        match self.index.get(&self.objects) {
            Some(built) => self.nearest_by_index(built, ray, t_min, t_max),
            None => self.nearest_in_order(ray, t_min, t_max),
        }
    }

    /// The nearest object and `t`, asking the objects in order and shrinking the range as
    /// hits are found.
    #[inline(always)]
    fn nearest_in_order(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(usize, f64)> {
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
        best
    }

    /// [`Scene::nearest_in_order`]'s answer, asking only the objects of the index whose boxes
    /// the ray meets ([`nearer_limit`] keeps the objects' order in ties).
    #[inline(never)]
    fn nearest_by_index(
        &self,
        built: &index::Built,
        ray: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<(usize, f64)> {
        let mut best: Option<(usize, f64)> = None;
        let ask_object = |i: usize, best: &mut Option<(usize, f64)>| {
            let obj = &self.objects[i];
            let limit = nearer_limit(i, *best, t_max);
            if obj.bounds.clip(ray, t_min, limit).is_none() {
                return;
            }
            if let Some(t) = obj.shape.intersect(ray, t_min, limit) {
                *best = Some((i, t));
            }
        };
        for &i in &built.unbounded {
            ask_object(i as usize, &mut best);
        }
        built
            .bvh
            .walk(ray, t_min, walk_limit(best, t_max), |i, range| {
                ask_object(i as usize, &mut best);
                *range = walk_limit(best, t_max);
            });
        best
    }

    /// [`Scene::occluded`] by the index: the unbounded objects, then those of the hierarchy
    /// whose boxes the ray meets, until one blocks it.
    #[inline(never)]
    fn occluded_by_index(&self, built: &index::Built, ray: &Ray, t_min: f64, t_max: f64) -> bool {
        let blocks = |i: u32| {
            let obj = &self.objects[i as usize];
            obj.bounds.clip(ray, t_min, t_max).is_some() && obj.shape.occludes(ray, t_min, t_max)
        };
        if built.unbounded.iter().any(|&i| blocks(i)) {
            return true;
        }
        let mut blocked = false;
        built.bvh.walk(ray, t_min, t_max, |i, range| {
            if blocks(i) {
                blocked = true;
                *range = f64::NEG_INFINITY;
            }
        });
        blocked
    }

    /// The fewest objects for which the queries walk the index rather than the objects in
    /// order. Below it the walk in order costs less: on `scenes/heart.scene` (a heart and a
    /// floor) the index cost 12 % more instructions (docs/performance.md). Every shipped scene
    /// has fewer.
    pub const INDEX_MIN_OBJECTS: usize = 9;

    /// Whether the scene has enough objects for the queries to use its index (they do where
    /// it was built from these objects).
    #[inline]
    pub(crate) fn may_use_index(&self) -> bool {
        self.objects.len() >= Self::INDEX_MIN_OBJECTS
    }

    /// The index, when the queries use it: with at least [`Scene::INDEX_MIN_OBJECTS`]
    /// objects, and built from these.
    #[cfg(test)]
    fn indexed(&self) -> Option<&index::Built> {
        if !self.may_use_index() {
            return None;
        }
        self.index.get(&self.objects)
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

/// The end of the range to ask object `i` about, given the nearest hit so far `best`
/// (object, `t`) and the query's `t_max`: objects are met in any order, yet the answer must
/// be the one the objects asked in order would give, where an object met at the same `t` as
/// an earlier one does not replace it. So an object after the best one is asked up to its
/// `t` (excluded), and one before it up to its `t` included (its next float, excluded):
/// whatever hit the object then reports is nearer by `(t, index)`.
#[inline]
fn nearer_limit(i: usize, best: Option<(usize, f64)>, t_max: f64) -> f64 {
    match best {
        None => t_max,
        Some((j, t)) if i < j => t.next_up(),
        Some((_, t)) => t,
    }
}

/// The octant of the lanes' directions, as [`crate::bvh::Bvh::walk_ranks`] numbers them (bit
/// `a` set where the component along axis `a` is not `≥ 0`), or `None` when they do not all
/// lie in one.
#[inline(always)]
fn octant(rays: &[Ray; LANES]) -> Option<usize> {
    // The bits set in every lane and in any lane: the same where the lanes agree.
    let (mut every, mut any) = (7, 0);
    for ray in rays {
        let d = ray.dir;
        // A bit where the component is not `≥ 0` (negative or NaN), as the walk decides.
        let bit = |c: f64| if c >= 0.0 { 0 } else { 1 };
        let bits = bit(d.x) | bit(d.y) << 1 | bit(d.z) << 2;
        every &= bits;
        any |= bits;
    }
    (every == any).then_some(any)
}

/// The end of the range within which a hierarchy's walk still looks for objects, given the
/// nearest hit so far: its `t` included (an earlier object may meet the ray there too).
#[inline]
fn walk_limit(best: Option<(usize, f64)>, t_max: f64) -> f64 {
    best.map_or(t_max, |(_, t)| t.next_up())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::{Heart, Plane, Sphere};
    use crate::testing::uniform_stream;

    /// Spheres at random (every fifth one a copy of the one before, so that two objects meet
    /// rays at the same `t`), two hearts and a floor: enough objects for the index.
    fn crowded_scene(seed: u64, spheres: usize) -> Scene {
        let mut u = uniform_stream(seed);
        let mut r = move |lo: f64, hi: f64| lo + (hi - lo) * u();
        let mut objects = Vec::new();
        let object =
            |shape: Box<dyn Shape>, keyword| Object::new(shape, Material::default(), keyword, 1);
        let mut last = (DVec3::ZERO, 1.0);
        for i in 0..spheres {
            if i % 5 != 4 {
                last = (
                    DVec3::new(r(-3.0, 3.0), r(-3.0, 3.0), r(-3.0, 3.0)),
                    r(0.05, 0.6),
                );
            }
            objects.push(object(
                Box::new(Sphere::new(last.0, last.1).unwrap()),
                "SPHERE",
            ));
            if i == spheres / 2 {
                objects.push(object(
                    Box::new(Plane::new(DVec3::new(0.0, 0.0, -2.5), DVec3::Z).unwrap()),
                    "PLANE",
                ));
            }
        }
        for p in [DVec3::new(0.0, 1.0, 0.0), DVec3::new(1.0, -1.0, 0.5)] {
            let h = Heart::new(p, DVec3::X * 0.8, DVec3::Y * 0.8, DVec3::Z * 0.8).unwrap();
            objects.push(object(Box::new(h), "HEART"));
        }
        Scene {
            width: 10,
            height: 10,
            camera: Camera::new(DVec3::new(8.0, 0.0, 0.0), DVec3::ZERO, DVec3::Z, 40.0).unwrap(),
            background: DVec3::ZERO,
            ambient: DVec3::ZERO,
            lights: Vec::new(),
            index: ObjectIndex::of(&objects),
            objects,
        }
    }

    fn rays(seed: u64) -> impl FnMut() -> Ray {
        let mut u = uniform_stream(seed);
        move || {
            let o = DVec3::new(8.0 * u() - 4.0, 8.0 * u() - 4.0, 8.0 * u() - 4.0) * 2.0;
            let target = DVec3::new(6.0 * u() - 3.0, 6.0 * u() - 3.0, 6.0 * u() - 3.0);
            Ray::new(o, target - o)
        }
    }

    #[test]
    fn the_index_gives_the_answers_of_the_walk_in_order_ties_to_the_first_object() {
        for seed in 1..4 {
            let scene = crowded_scene(seed, 60);
            let built = scene.indexed().expect("the index is used");
            assert_eq!(built.unbounded.len(), 1);
            let mut ray = rays(seed + 10);
            let mut ties = 0;
            for _ in 0..3000 {
                let r = ray();
                let in_order = scene.nearest_in_order(&r, 0.0, f64::INFINITY);
                let by_index = scene.nearest_by_index(built, &r, 0.0, f64::INFINITY);
                assert_eq!(by_index, in_order, "{r:?}");
                // A copied sphere met first: its original (the object before it) must win.
                if let Some((i, t)) = in_order {
                    if i + 1 < scene.objects.len()
                        && scene.objects[i + 1].shape.intersect(&r, 0.0, f64::INFINITY) == Some(t)
                    {
                        ties += 1;
                    }
                }
                let shadow_end = in_order.map_or(5.0, |(_, t)| t * 1.5);
                let any_in_order = scene
                    .objects
                    .iter()
                    .any(|o| o.shape.occludes(&r, 0.0, shadow_end));
                assert_eq!(scene.occluded(&r, 0.0, shadow_end), any_in_order);
            }
            assert!(ties > 20, "only {ties} ties tested");
        }
    }

    #[test]
    fn the_index_lanes_answer_as_each_ray_alone() {
        let scene = crowded_scene(9, 80);
        let mut ray = rays(99);
        for k in 0..1500 {
            let rs: [Ray; LANES] = std::array::from_fn(|_| ray());
            let alone = rs.map(|r| scene.intersect(&r, 0.0, f64::INFINITY));
            assert_eq!(scene.intersect_lanes(&rs, 0.0, f64::INFINITY), alone);
            let t_max = std::array::from_fn(|lane| {
                if lane == k % LANES {
                    0.0
                } else {
                    0.5 + lane as f64
                }
            });
            let each: [bool; LANES] = std::array::from_fn(|lane| {
                t_max[lane] > 0.0 && scene.occluded(&rs[lane], 0.0, t_max[lane])
            });
            assert_eq!(scene.occluded_lanes(&rs, [0.0; LANES], t_max), each);
            // From any object's leaf (or an object out of range), the same answers.
            let from = k * 7 % (scene.objects.len() + 1);
            assert_eq!(
                scene.occluded_lanes_from(&rs, [0.0; LANES], t_max, from),
                each
            );
        }
    }

    #[test]
    fn a_groups_listed_objects_give_the_index_answers_bit_for_bit() {
        // Every object whose box some lane meets, listed in any order: the index's answers,
        // the same bits (the objects asked in the walk's order).
        let scene = crowded_scene(21, 60);
        let built = scene.indexed().expect("an indexed scene");
        let mut ray = rays(23);
        let mut u = uniform_stream(29);
        let (mut several, mut among) = (0, 0);
        for k in 0..3000 {
            // Four rays close together (most in one octant), or four at random.
            let base = ray();
            let rs: [Ray; LANES] = std::array::from_fn(|_| {
                if k % 5 == 0 {
                    return ray();
                }
                let nudge = DVec3::new(u() - 0.5, u() - 0.5, u() - 0.5) * 0.05;
                Ray::new(base.origin, base.dir + nudge * base.dir.length())
            });
            let mut listed: Vec<u32> = (0..scene.objects.len() as u32)
                .filter(|&i| !built.unbounded.contains(&i))
                .filter(|&i| {
                    let b = scene.objects[i as usize].bounds;
                    rs.iter().any(|r| b.clip(r, 0.0, f64::INFINITY).is_some())
                })
                .collect();
            listed.reverse();
            let walked = scene.intersect_lanes(&rs, 0.0, f64::INFINITY);
            assert_eq!(
                scene.intersect_lanes_among(&rs, 0.0, f64::INFINITY, &listed),
                walked,
                "{rs:?}"
            );
            if let Some(octant) = octant(&rs).filter(|_| listed.len() <= Scene::MAX_LISTED) {
                among += 1;
                several += usize::from(listed.len() > 1 && walked.iter().any(Option::is_some));
                let asked = scene.nearest_lanes_among(built, &rs, 0.0, 1e300, &listed, octant);
                assert_eq!(asked, scene.nearest_lanes_by_index(built, &rs, 0.0, 1e300));
            }
        }
        assert!(among > 1500 && several > 500, "{among} {several}");
    }

    #[test]
    fn objects_replaced_after_the_index_was_built_are_walked_in_order() {
        let mut scene = crowded_scene(4, 30);
        let mut ray = rays(5);
        let r0 = ray();
        let _ = scene.intersect(&r0, 0.0, f64::INFINITY);
        scene.objects.truncate(12);
        assert!(scene.indexed().is_none());
        for _ in 0..500 {
            let r = ray();
            let expected = scene.nearest_in_order(&r, 0.0, f64::INFINITY);
            assert_eq!(
                scene
                    .intersect(&r, 0.0, f64::INFINITY)
                    .map(|h| (h.object, h.t)),
                expected
            );
        }
    }
}
