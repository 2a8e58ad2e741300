//! `kardia.Scene` and `kardia.Camera`: a loaded scene (its text kept, so any frame can be read
//! anew and every image carries the command line's render key) and the render call, which
//! builds a `RenderRequest` and a `FrameJob` exactly as `kardia render` does.

use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::Arc;

use kardia::animation::{self, FrameJob, SceneSource};
use kardia::camera::Camera;
use kardia::pipeline::{Control, Region, RenderRequest};
use kardia::scene::{Animation, LoadOptions, Scene};
use kardia::tiles::{self, PartInfo};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::args;
use crate::errors::{render_error, scene_error};
use crate::image::PyImage;
use crate::interrupt::{give_back, run_interruptible, take_renderer, Watch};

/// A camera: a pinhole with a horizontal field of view in degrees, or an orthographic one
/// (`orthographic_height`: the height of the view in scene units). `up` is only a hint and
/// need not be perpendicular to the view.
#[pyclass(name = "Camera", module = "kardia._kardia", frozen, from_py_object)]
#[derive(Clone)]
pub struct PyCamera {
    pub(crate) inner: Camera,
}

#[pymethods]
impl PyCamera {
    /// A camera at `eye` looking at `look_at` (world coordinates), `up` roughly up; `fov`
    /// is the horizontal field of view in degrees (0 < fov < 180). With
    /// `orthographic_height`, parallel rays over a view that many scene units tall instead.
    /// Raises ValueError for non-finite vectors, `eye == look_at`, `up` along the view or a
    /// field of view out of range.
    #[new]
    #[pyo3(signature = (eye, look_at, up = (0.0, 0.0, 1.0), fov = 40.0, orthographic_height = None))]
    fn new(
        eye: (f64, f64, f64),
        look_at: (f64, f64, f64),
        up: (f64, f64, f64),
        fov: f64,
        orthographic_height: Option<f64>,
    ) -> PyResult<Self> {
        let (eye, look_at, up) = (
            args::vector("eye", eye)?,
            args::vector("look_at", look_at)?,
            args::vector("up", up)?,
        );
        let camera = match orthographic_height {
            Some(h) => Camera::orthographic(eye, look_at, up, h),
            None => Camera::new(eye, look_at, up, fov),
        };
        camera
            .map(|inner| Self { inner })
            .map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The eye position (x, y, z).
    #[getter]
    fn eye(&self) -> (f64, f64, f64) {
        self.inner.eye.into()
    }

    /// The point looked at (x, y, z).
    #[getter]
    fn look_at(&self) -> (f64, f64, f64) {
        self.inner.look_at.into()
    }

    /// The up hint (x, y, z).
    #[getter]
    fn up(&self) -> (f64, f64, f64) {
        self.inner.up.into()
    }

    /// The horizontal field of view in degrees (of a pinhole camera).
    #[getter]
    fn fov(&self) -> f64 {
        self.inner.fov_degrees
    }

    /// The view's height in scene units for an orthographic camera, else None.
    #[getter]
    fn orthographic_height(&self) -> Option<f64> {
        self.inner.orthographic_height()
    }

    /// This camera turned about its look-at point around its up vector by `frame / count`
    /// of a full turn: frame `frame` of a turntable of `count` frames (`--turntable`).
    fn orbit(&self, frame: i64, count: i64) -> PyResult<Self> {
        let frame = args::whole("frame", frame, 0, i64::from(u32::MAX))? as u32;
        let count = args::whole("count", count, 1, i64::from(u32::MAX))? as u32;
        Ok(Self {
            inner: animation::orbit(&self.inner, frame, count),
        })
    }

    fn __repr__(&self) -> String {
        let v = |d: kardia::geometry::DVec3| format!("({}, {}, {})", d.x, d.y, d.z);
        let c = &self.inner;
        match c.orthographic_height() {
            Some(h) => format!(
                "Camera(eye={}, look_at={}, up={}, orthographic_height={h})",
                v(c.eye),
                v(c.look_at),
                v(c.up)
            ),
            None => format!(
                "Camera(eye={}, look_at={}, up={}, fov={})",
                v(c.eye),
                v(c.look_at),
                v(c.up),
                c.fov_degrees
            ),
        }
    }
}

/// A loaded scene: its text (read anew at each frame of an animation), the load options (the
/// root solver) and the scene read as a still. Immutable; share it between threads freely.
#[pyclass(name = "Scene", module = "kardia._kardia", frozen)]
pub struct PyScene {
    pub(crate) source: SceneSource,
    pub(crate) options: LoadOptions,
    pub(crate) scene: Arc<Scene>,
    animation: Animation,
    warnings: Vec<String>,
}

impl PyScene {
    /// The scene of `source`, read as a still with `solver`.
    fn load(
        py: Python<'_>,
        source: SceneSource,
        solver: &str,
        warnings: Vec<String>,
    ) -> PyResult<Self> {
        let options = LoadOptions {
            solver: args::solver(solver)?,
            ..LoadOptions::default()
        };
        let (scene, animation) = source.still(&options).map_err(|e| scene_error(py, e))?;
        Ok(Self {
            source,
            options,
            scene: Arc::new(scene),
            animation,
            warnings,
        })
    }
}

/// Everything a render call may set, checked.
struct Settings {
    request: RenderRequest,
    threads: usize,
    frame: Option<u32>,
    turntable: Option<u32>,
    tile: Option<(u32, u32)>,
}

#[pymethods]
impl PyScene {
    /// A scene from its text (the scene language of docs/scene-format.md); `name` stands for
    /// the file in error messages. Raises SceneError (file:line:column and a caret) for a
    /// text that is not a valid scene.
    #[new]
    #[pyo3(signature = (text, name = "<string>", solver = "sturm"))]
    fn new(py: Python<'_>, text: String, name: &str, solver: &str) -> PyResult<Self> {
        let source = SceneSource {
            text,
            name: name.to_string(),
        };
        Self::load(py, source, solver, Vec::new())
    }

    /// A scene file: kardia's `.scene`, SURFER's `.jsurf` or surf's `.pic` (translated as
    /// `kardia render` translates them; their warnings are in `warnings`). Raises SceneError
    /// for an unreadable or invalid file.
    #[staticmethod]
    #[pyo3(signature = (path, solver = "sturm"))]
    fn from_file(py: Python<'_>, path: PathBuf, solver: &str) -> PyResult<Self> {
        let options = LoadOptions {
            solver: args::solver(solver)?,
            ..LoadOptions::default()
        };
        let loaded = kardia::formats::load(&path, &options).map_err(|e| scene_error(py, e))?;
        let warnings = loaded
            .warnings
            .iter()
            .map(|w| format!("{}:{}: {}", path.display(), w.line, w.message))
            .collect();
        let source = SceneSource {
            text: loaded.text,
            name: path.display().to_string(),
        };
        Self::load(py, source, solver, warnings)
    }

    /// The built-in default heart (the text of scenes/heart.scene): what `kardia render`
    /// renders without a scene.
    #[staticmethod]
    #[pyo3(signature = (solver = "sturm"))]
    fn default_heart(py: Python<'_>, solver: &str) -> PyResult<Self> {
        Self::load(py, SceneSource::default_scene(), solver, Vec::new())
    }

    /// The scene text (for a `.jsurf` or `.pic` file, its translation).
    #[getter]
    fn text(&self) -> &str {
        &self.source.text
    }

    /// The name used in error messages (the path of a file).
    #[getter]
    fn name(&self) -> &str {
        &self.source.name
    }

    /// The root solver the scene's surfaces were built with.
    #[getter]
    fn solver(&self) -> &'static str {
        self.options.solver.name()
    }

    /// The scene's image size (width, height) in pixels, from its SIZE.
    #[getter]
    fn size(&self) -> (u32, u32) {
        (self.scene.width, self.scene.height)
    }

    /// The scene's own camera.
    #[getter]
    fn camera(&self) -> PyCamera {
        PyCamera {
            inner: self.scene.camera.clone(),
        }
    }

    /// The objects, in scene order, as (keyword, line of the scene text) pairs: the index
    /// into this list is what `probe` reports as `object`.
    #[getter]
    fn objects(&self) -> Vec<(&'static str, usize)> {
        self.scene
            .objects
            .iter()
            .map(|o| (o.keyword, o.line))
            .collect()
    }

    /// The number of frames the scene declares with FRAMES, or None.
    #[getter]
    fn declared_frames(&self) -> Option<u32> {
        self.animation.frames
    }

    /// Frames per second for animated outputs (FPS; 24 when not given).
    #[getter]
    fn fps(&self) -> f64 {
        self.animation.fps
    }

    /// True when some value of the scene depends on `clock`, `frame` or `frames`.
    #[getter]
    fn animated(&self) -> bool {
        self.animation.uses_time
    }

    /// What the reader of a `.jsurf` or `.pic` file ignored, one line each.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// How many frames the scene makes: `turntable` when given, else its FRAMES, else 1 (as
    /// `kardia render --print-frame-count`).
    #[pyo3(signature = (turntable = None))]
    fn frame_count(&self, turntable: Option<i64>) -> PyResult<u32> {
        let turntable = turntable
            .map(|n| args::whole("turntable", n, 1, 1_000_000).map(|n| n as u32))
            .transpose()?;
        Ok(turntable.or(self.animation.frames).unwrap_or(1))
    }

    /// Renders the scene; see `kardia.Scene.render` (the Python wrapper) for the arguments.
    /// Releases the GIL while rendering; an interrupt (KeyboardInterrupt) cancels the render
    /// within a tile. Returns a `kardia.Image`.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (width = None, height = None, samples = 4, seed = 0, threads = None,
                        view = "shaded", camera = None, alpha = false, max_depth = 8,
                        linear = false, region = None, tile = None, frame = None,
                        turntable = None, progress = None))]
    fn render(
        &self,
        py: Python<'_>,
        width: Option<i64>,
        height: Option<i64>,
        samples: i64,
        seed: i64,
        threads: Option<i64>,
        view: &str,
        camera: Option<PyCamera>,
        alpha: bool,
        max_depth: i64,
        linear: bool,
        region: Option<(i64, i64, i64, i64)>,
        tile: Option<(i64, i64)>,
        frame: Option<i64>,
        turntable: Option<i64>,
        progress: Option<Bound<'_, PyAny>>,
    ) -> PyResult<PyImage> {
        let max_side = i64::from(Scene::MAX_SIDE);
        let region = region
            .map(|(x, y, w, h)| -> PyResult<Region> {
                Ok(Region {
                    x: args::whole("region x", x, 0, max_side)? as u32,
                    y: args::whole("region y", y, 0, max_side)? as u32,
                    width: args::whole("region width", w, 1, max_side)? as u32,
                    height: args::whole("region height", h, 1, max_side)? as u32,
                })
            })
            .transpose()?;
        let tile = tile
            .map(|(i, n)| -> PyResult<(u32, u32)> {
                let n = args::whole("tile count", n, 1, max_side)?;
                let i = args::whole("tile index", i, 0, n as i64 - 1)?;
                Ok((i as u32, n as u32))
            })
            .transpose()?;
        if region.is_some() && tile.is_some() {
            return Err(PyValueError::new_err("give region or tile, not both"));
        }
        let settings = Settings {
            request: RenderRequest {
                width: args::side("width", width)?,
                height: args::side("height", height)?,
                camera: camera.map(|c| c.inner),
                spp: args::whole("samples", samples, 1, 65536)? as u32,
                seed: args::whole("seed", seed, 0, i64::MAX)?,
                max_depth: args::whole("max_depth", max_depth, 0, 1_000_000)? as u32,
                region,
                view: args::view(view)?,
                alpha,
                max_shadow_rays: None,
            },
            threads: threads
                .map(|t| args::whole("threads", t, 1, 4096))
                .transpose()?
                .unwrap_or(0) as usize,
            frame: frame
                .map(|f| args::whole("frame", f, 0, i64::from(u32::MAX)).map(|f| f as u32))
                .transpose()?,
            turntable: turntable
                .map(|n| args::whole("turntable", n, 1, 1_000_000).map(|n| n as u32))
                .transpose()?,
            tile,
        };
        self.render_settings(py, settings, linear, progress.as_ref())
    }

    /// Rays through many points at once: `origins` and `directions` are float64 arrays of
    /// shape (N, 3) in world space (directions need not be unit length). Returns a dict of
    /// arrays: `hit` (N,) bool, `t` (N,) float64 in units of the direction (NaN where
    /// missed), `point` and `normal` (N, 3) float64 (the unit normal faces out of the solid;
    /// NaN where missed), `object` (N,) int64 (index into `objects`, -1 where missed).
    /// Raises ValueError for another shape, a non-finite number, a coordinate beyond ±1e6 or
    /// a zero direction. Each answer is `kardia probe`'s for that ray.
    fn probe<'py>(
        &self,
        py: Python<'py>,
        origins: numpy::PyReadonlyArray2<'py, f64>,
        directions: numpy::PyReadonlyArray2<'py, f64>,
    ) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        crate::probe::probe(py, &self.scene, origins, directions)
    }

    /// The scene's HEART and IMPLICIT solids as one closed, 2-manifold, outward-wound
    /// triangle mesh (what `kardia mesh` writes): `(vertices, faces)`, float64 (V, 3) and
    /// uint32 (F, 3). `kind` is "solid" (inside the surface and its clip ball), "outside", or
    /// "shell" with `thickness` (scene units); `tolerance` the grid's accuracy (default 1 %
    /// of each clip radius); `size` scales the whole so its largest extent is that many
    /// units. Raises ValueError when the scene has no such solid or the arguments are out of
    /// range.
    #[pyo3(signature = (kind = "solid", thickness = None, tolerance = None, max_cells = 512, size = None))]
    fn mesh(
        &self,
        py: Python<'_>,
        kind: &str,
        thickness: Option<f64>,
        tolerance: Option<f64>,
        max_cells: i64,
        size: Option<f64>,
    ) -> PyResult<(Py<PyAny>, Py<PyAny>)> {
        let max_cells = args::whole("max_cells", max_cells, 2, 4096)? as usize;
        crate::mesh::mesh(py, &self.scene, kind, thickness, tolerance, max_cells, size)
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene(name={:?}, size={}x{}, objects={})",
            self.source.name,
            self.scene.width,
            self.scene.height,
            self.scene.objects.len()
        )
    }
}

impl PyScene {
    /// Renders as `kardia render` would with these settings: a still (no frame, no
    /// turntable) from the scene read as a still, else the frame read anew at its time with
    /// its seed and turntable camera; the image keeps the render key (and, for a part, the
    /// part's metadata) that `kardia render` writes into its file.
    fn render_settings(
        &self,
        py: Python<'_>,
        settings: Settings,
        linear: bool,
        progress: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<PyImage> {
        let Settings {
            mut request,
            threads,
            frame,
            turntable,
            tile,
        } = settings;
        let selects_frames = frame.is_some() || turntable.is_some();
        let count = if selects_frames {
            turntable.or(self.animation.frames).unwrap_or(1)
        } else {
            1
        };
        let frame_number = frame.unwrap_or(0);
        if frame_number >= count {
            return Err(PyValueError::new_err(format!(
                "frame {frame_number} does not exist: the scene makes {count} frame{} \
                 (its FRAMES, or the turntable's count), numbered from 0",
                if count == 1 { "" } else { "s" }
            )));
        }
        let (full_width, full_height) = request.full_size(&self.scene).map_err(render_error)?;
        if let Some((i, n)) = tile {
            request.region =
                Some(tiles::band(i, n, full_width, full_height).map_err(PyValueError::new_err)?);
        }
        let job = FrameJob {
            source: self.source.clone(),
            options: self.options,
            request,
            turntable,
            count,
        };
        let (scene, request) = if selects_frames {
            let (scene, request) = job.frame(frame_number).map_err(|e| scene_error(py, e))?;
            (Arc::new(scene), request)
        } else {
            (self.scene.clone(), job.request.clone())
        };
        let region = request.region_in(&scene).map_err(render_error)?;
        let whole = region == Region::full(full_width, full_height);
        if !whole && request.alpha {
            return Err(PyValueError::new_err(
                "alpha is not available for parts: a region or tile renders opaque",
            ));
        }
        let key = job.key(&scene, &request, frame_number);
        let part = (!whole).then(|| PartInfo {
            full_width,
            full_height,
            region,
            seed: request.seed,
            spp: request.spp.max(1),
            frame: frame_number,
            key: key.clone(),
        });

        let renderer = take_renderer(threads)?;
        let watch = Watch::default();
        let rendered = run_interruptible(py, &watch, region.pixel_count(), progress, || {
            let control = Control::new(watch.cancel.clone(), |p| {
                watch.done.fetch_add(p.finished, Ordering::Relaxed);
            });
            renderer.render(&scene, &request, &control)
        });
        give_back(threads, renderer);
        let rendered = rendered?.map_err(render_error)?;
        PyImage::new(py, rendered, key, part, frame, linear)
    }
}
