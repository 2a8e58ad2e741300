//! Turning rays into pixels: the [`Shader`] trait (one primary ray in, one colour out) and its
//! implementations, one file each — [`whitted`] (the [`View::Shaded`] image), the geometry
//! study views [`normals`] and [`depth`], and the root-finder study views [`roots`],
//! [`path`], [`iterations`] and [`conditioning`] (one shader, [`solver_view`], with a colour
//! table each) — with their [`legend`]s, plus the sampling of pixels (`sampling`) and the
//! scheduler that spreads a region's tiles over a thread pool (`scheduler`).
//!
//! The render API callers use is [`crate::pipeline`]; this module is what it runs.
//!
//! # Adding a view
//! Write `src/integrator/NAME.rs` with a type that implements [`Shader`] and a
//! `new(&ShadeSetup)` constructor, add a variant to [`View`] with its name in [`View::ALL`],
//! one arm to the `match` in `with_shader`, and its legend to [`View::legend`].

pub mod conditioning;
pub mod depth;
mod group_objects;
pub mod iterations;
pub mod legend;
pub mod normals;
pub mod path;
pub mod roots;
mod sampling;
mod scheduler;
pub mod solver_view;
pub mod whitted;

pub use legend::{Legend, Swatch};

pub use sampling::{strata, stratified_point, Sample};
pub use whitted::{MAX_SHADOW_CROSSINGS, SELF_HIT_EPS};

pub use scheduler::BandDone;
pub(crate) use scheduler::{Hooks, Job, RenderPool};

use crate::camera::Camera;
use crate::film::Image;
use crate::geometry::{DVec3, Ray};
use crate::scene::Scene;
use crate::shapes::LANES;

/// Side of the square image tiles, in pixels; each band of tiles one `TILE_SIZE` tall is one
/// unit of parallel work, rendered straight into its rows of the image. Cancellation is
/// checked before every row of every tile.
pub const TILE_SIZE: u32 = 16;

/// One way of shading a ray: the colour (linear RGB, finite or not: the film makes it finite)
/// seen along a primary ray for one sample of a pixel. Called from many threads at once.
pub trait Shader: Sync {
    /// The colour arriving along `ray` (world space, starting at the eye, unit direction) for
    /// the pixel sample `sample` (its random numbers and ray counter).
    fn radiance(&self, ray: &Ray, sample: &mut Sample) -> DVec3;

    /// [`Shader::radiance`] for [`LANES`] samples at once (the same sample of neighbouring
    /// pixels, each with its own random numbers): lane `i` is always exactly
    /// `self.radiance(&rays[i], &mut samples[i])`, with the same random numbers drawn from
    /// `samples[i]` in the same order. A shader may answer it more cheaply, never differently.
    fn radiance_lanes(&self, rays: &[Ray; LANES], samples: &mut [Sample; LANES]) -> [DVec3; LANES] {
        let mut out = [DVec3::ZERO; LANES];
        for ((colour, ray), sample) in out.iter_mut().zip(rays).zip(samples.iter_mut()) {
            *colour = self.radiance(ray, sample);
        }
        out
    }

    /// [`Shader::radiance_lanes`] for camera rays that may meet only the scene's objects
    /// `objects` (indices in ascending order) and its unbounded ones: every other object's
    /// box is missed by every ray, or met only where the object cannot be hit. The same
    /// colours; a shader may ask only those objects for the rays' first hits (the default
    /// asks the whole scene).
    fn radiance_lanes_among(
        &self,
        rays: &[Ray; LANES],
        samples: &mut [Sample; LANES],
        objects: &[u32],
    ) -> [DVec3; LANES] {
        let _ = objects;
        self.radiance_lanes(rays, samples)
    }

    /// The colour of every primary ray that meets no object's bounding box, when the shader
    /// gives them all one colour, counting the ray once, reporting it as a miss
    /// ([`Sample::report_primary_hit`]) and drawing no random number: then the scheduler may
    /// answer such rays without tracing them. `None` (the default): every ray is traced.
    fn miss_colour(&self) -> Option<DVec3> {
        None
    }
}

/// What a shader is built from for one render.
#[derive(Debug, Clone, Copy)]
pub struct ShadeSetup<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The camera the render sees through (the scene's or the request's).
    pub camera: &'a Camera,
    /// Samples per pixel (≥ 1).
    pub spp: u32,
    /// Maximum depth of reflection and refraction (0 = primary hits only).
    pub max_depth: u32,
    /// At most this many shadow rays per spherical light and sample (`None`: each light's
    /// `SAMPLES`; see [`crate::pipeline::RenderRequest::max_shadow_rays`]).
    pub max_shadow_rays: Option<u32>,
}

/// Which image a render makes: the shaded picture or a study view of the geometry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum View {
    /// Whitted shading: lights, shadows, reflection, refraction ([`whitted`]).
    #[default]
    Shaded,
    /// The outward unit normal of the first hit as a colour, `(n + 1) / 2` ([`normals`]).
    Normals,
    /// The distance to the first hit as a grey level, `exp(−d / d₀)` ([`depth`]).
    Depth,
    /// Distinct real roots of the ray's polynomial in its interval ([`roots`]).
    Roots,
    /// Which method settled the ray's first root ([`path`]).
    Path,
    /// Refinement steps the root finder took ([`iterations`]).
    Iterations,
    /// `|∇f|` at the hit, by decades ([`conditioning`]).
    Conditioning,
}

impl View {
    /// Every view with its name (as `kardia render --view NAME` takes it).
    pub const ALL: &'static [(View, &'static str)] = &[
        (View::Shaded, "shaded"),
        (View::Normals, "normals"),
        (View::Depth, "depth"),
        (View::Roots, "roots"),
        (View::Path, "path"),
        (View::Iterations, "iterations"),
        (View::Conditioning, "conditioning"),
    ];

    /// The view's name.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(v, _)| *v == self)
            .map_or("?", |(_, n)| n)
    }

    /// How to read the view's colours; `None` for the shaded picture.
    pub fn legend(self) -> Option<Legend> {
        match self {
            View::Shaded => None,
            View::Normals => Some(normals::legend()),
            View::Depth => Some(depth::legend()),
            View::Roots => Some(roots::legend()),
            View::Path => Some(path::legend()),
            View::Iterations => Some(iterations::legend()),
            View::Conditioning => Some(conditioning::legend()),
        }
    }
}

impl std::fmt::Display for View {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for View {
    type Err = String;

    /// Parses a view's name (see [`View::ALL`]), ignoring case.
    fn from_str(s: &str) -> Result<Self, String> {
        Self::ALL
            .iter()
            .find(|(_, n)| n.eq_ignore_ascii_case(s))
            .map(|(view, _)| *view)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|(_, n)| *n).collect();
                format!("unknown view '{s}': expected one of {}", names.join(", "))
            })
    }
}

/// Something to do with a view's shader, whatever its type: [`with_shader`] builds the shader
/// and hands it over, so the code that uses it is compiled for each view (no dynamic dispatch
/// per ray).
pub(crate) trait WithShader {
    /// What the work gives.
    type Output;
    /// Does the work with `shader`.
    fn run<S: Shader>(self, shader: &S) -> Self::Output;
}

/// Builds `view`'s shader for `setup` and hands it to `work`. The one place that maps a
/// [`View`] to its implementation.
pub(crate) fn with_shader<W: WithShader>(view: View, setup: &ShadeSetup, work: W) -> W::Output {
    match view {
        View::Shaded => work.run(&whitted::Whitted::new(setup)),
        View::Normals => work.run(&normals::Normals::new(setup)),
        View::Depth => work.run(&depth::Depth::new(setup)),
        View::Roots => work.run(&roots::Roots::new(setup)),
        View::Path => work.run(&path::PathView::new(setup)),
        View::Iterations => work.run(&iterations::Iterations::new(setup)),
        View::Conditioning => work.run(&conditioning::Conditioning::new(setup)),
    }
}

/// Renders `job` in `view` on `pool`: the region's image (when `job.keep_image`) and the rays
/// traced, or `None` when cancelled.
pub(crate) fn render(
    pool: &scheduler::RenderPool,
    view: View,
    setup: &ShadeSetup,
    job: &Job,
    hooks: &Hooks,
) -> Option<(Option<Image>, u64)> {
    struct Render<'a> {
        pool: &'a scheduler::RenderPool,
        job: &'a Job<'a>,
        hooks: &'a Hooks<'a>,
    }
    impl WithShader for Render<'_> {
        type Output = Option<(Option<Image>, u64)>;
        fn run<S: Shader>(self, shader: &S) -> Self::Output {
            scheduler::run(self.pool, shader, self.job, self.hooks)
        }
    }
    with_shader(view, setup, Render { pool, job, hooks })
}

/// The colour `view` gives one world ray (which starts off any surface), as in a render with
/// `setup`; the random numbers (a spherical light's sample point) come from `seed`, as for a
/// pixel's first sample. Meant for tests and probes.
pub fn trace_ray(view: View, setup: &ShadeSetup, seed: u64, ray: &Ray) -> DVec3 {
    struct Trace<'a> {
        seed: u64,
        ray: &'a Ray,
    }
    impl WithShader for Trace<'_> {
        type Output = DVec3;
        fn run<S: Shader>(self, shader: &S) -> DVec3 {
            shader.radiance(self.ray, &mut Sample::new(self.seed, 0, 1))
        }
    }
    with_shader(view, setup, Trace { seed, ray })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::materials::Material;
    use crate::scene::Object;
    use crate::shapes::Sphere;

    /// What a view is built from to shade single samples of `scene`: its camera, 1 spp, no
    /// secondary rays.
    pub(crate) fn one_sample_setup(scene: &Scene) -> ShadeSetup<'_> {
        ShadeSetup {
            scene,
            camera: &scene.camera,
            spp: 1,
            max_depth: 0,
            max_shadow_rays: None,
        }
    }

    /// A unit sphere at the origin seen from z = 5, 8×8 pixels, no lights.
    pub(crate) fn unit_sphere_scene() -> Scene {
        Scene {
            width: 8,
            height: 8,
            camera: Camera::new(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, 40.0).unwrap(),
            background: DVec3::ZERO,
            ambient: DVec3::ZERO,
            lights: vec![],
            index: Default::default(),
            objects: vec![Object::new(
                Box::new(Sphere::new(DVec3::ZERO, 1.0).unwrap()),
                Material::default(),
                "SPHERE",
                1,
            )],
        }
    }

    #[test]
    fn views_by_name() {
        for (view, name) in View::ALL {
            assert_eq!(name.parse::<View>().unwrap(), *view);
            assert_eq!(view.to_string(), *name);
        }
        assert_eq!("NORMALS".parse::<View>().unwrap(), View::Normals);
        assert!("nonsense".parse::<View>().is_err());
        assert_eq!(View::default(), View::Shaded);
    }

    #[test]
    fn every_study_view_has_a_legend() {
        for (view, name) in View::ALL {
            let legend = view.legend();
            assert_eq!(legend.is_none(), *view == View::Shaded, "{name}");
            if let Some(l) = legend {
                assert!(!l.title.is_empty() && l.swatches.len() >= 2, "{name}");
            }
        }
    }
}
