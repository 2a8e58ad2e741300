//! `kardia.Image`: a finished render as numpy arrays (row 0 at the top, matplotlib's `imshow`
//! convention), shown by Jupyter through `_repr_png_`, and saved through the library's atomic
//! PNG/EXR writers with the render key `kardia render` stores, so the file is the command
//! line's byte for byte.

use std::path::PathBuf;

use kardia::film::{self, AtomicFile, FileTag, Image, ImageFormat};
use kardia::pipeline::Rendered;
use kardia::tiles::{self, PartInfo};
use numpy::ndarray::Array3;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::errors::output_error;

/// A rendered image (or a region of one). `array` is what the render asked for: uint8 sRGB
/// (H, W, 3), or (H, W, 4) with straight alpha, by default; float32 linear RGB (H, W, 3), or
/// premultiplied RGBA (H, W, 4), with `linear=True`.
#[pyclass(name = "Image", module = "kardia._kardia", frozen)]
pub struct PyImage {
    image: Image,
    key: String,
    part: Option<PartInfo>,
    frame: Option<u32>,
    array: Py<PyAny>,
    rays: u64,
    seconds: f64,
    threads: usize,
}

impl PyImage {
    /// The image of `rendered`, with its render key, its part metadata when it is a region,
    /// and its array in the form asked for.
    pub(crate) fn new(
        py: Python<'_>,
        rendered: Rendered,
        key: String,
        part: Option<PartInfo>,
        frame: Option<u32>,
        linear: bool,
    ) -> PyResult<Self> {
        let array = to_array(py, &rendered.image, linear)?;
        Ok(Self {
            image: rendered.image,
            key,
            part,
            frame,
            array,
            rays: rendered.stats.rays,
            seconds: rendered.stats.elapsed.as_secs_f64(),
            threads: rendered.stats.threads,
        })
    }
}

/// `image` as a new numpy array: uint8 sRGB (straight alpha) or float32 linear
/// (premultiplied alpha), (H, W, 3) or (H, W, 4). The pixels are converted with the GIL
/// released and handed to numpy without a further copy.
fn to_array(py: Python<'_>, image: &Image, linear: bool) -> PyResult<Py<PyAny>> {
    let (h, w) = (image.height as usize, image.width as usize);
    let channels = if image.alpha.is_some() { 4 } else { 3 };
    let shape = (h, w, channels);
    let shape_error = |e: numpy::ndarray::ShapeError| {
        pyo3::exceptions::PyRuntimeError::new_err(format!("image shape: {e}"))
    };
    if linear {
        let values: Vec<f32> = py.detach(|| match &image.alpha {
            None => bytemuck::cast_slice::<_, f32>(&image.pixels).to_vec(),
            Some(alpha) => image
                .pixels
                .iter()
                .zip(alpha)
                .flat_map(|(p, a)| [p.x, p.y, p.z, *a])
                .collect(),
        });
        let array = Array3::from_shape_vec(shape, values).map_err(shape_error)?;
        Ok(array.into_pyarray(py).into_any().unbind())
    } else {
        let bytes = py.detach(|| match image.alpha {
            None => image.to_srgb8(),
            Some(_) => image.to_srgba8(),
        });
        let array = Array3::from_shape_vec(shape, bytes).map_err(shape_error)?;
        Ok(array.into_pyarray(py).into_any().unbind())
    }
}

#[pymethods]
impl PyImage {
    /// The pixels as the render asked for them (a numpy array, row 0 at the top).
    #[getter]
    fn array(&self, py: Python<'_>) -> Py<PyAny> {
        self.array.clone_ref(py)
    }

    /// A new array of the pixels: uint8 sRGB (straight alpha) by default, float32 linear
    /// (premultiplied alpha) with `linear=True`.
    #[pyo3(signature = (linear = false))]
    fn to_array(&self, py: Python<'_>, linear: bool) -> PyResult<Py<PyAny>> {
        to_array(py, &self.image, linear)
    }

    /// numpy's array protocol: `numpy.asarray(image)` is `image.array` (cast to `dtype` when
    /// given).
    #[pyo3(signature = (dtype = None, copy = None))]
    fn __array__(
        &self,
        py: Python<'_>,
        dtype: Option<Bound<'_, PyAny>>,
        copy: Option<bool>,
    ) -> PyResult<Py<PyAny>> {
        let array = self.array.bind(py).clone();
        let array = match dtype {
            Some(d) => array.call_method1("astype", (d,))?,
            None if copy == Some(true) => array.call_method0("copy")?,
            None => array,
        };
        Ok(array.unbind())
    }

    /// Width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.image.width
    }

    /// Height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.image.height
    }

    /// True when the image has an alpha channel (a transparent background).
    #[getter]
    fn alpha(&self) -> bool {
        self.image.alpha.is_some()
    }

    /// The frame number rendered, or None for a still.
    #[getter]
    fn frame(&self) -> Option<u32> {
        self.frame
    }

    /// Where this image lies in the full image, (x, y, width, height): the whole image
    /// unless a region or tile was rendered.
    #[getter]
    fn region(&self) -> (u32, u32, u32, u32) {
        match &self.part {
            Some(p) => (p.region.x, p.region.y, p.region.width, p.region.height),
            None => (0, 0, self.image.width, self.image.height),
        }
    }

    /// The render key `kardia render` stores in its files (a SHA-256 of the scene text and
    /// the settings that change the pixels).
    #[getter]
    fn key(&self) -> &str {
        &self.key
    }

    /// Rays traced.
    #[getter]
    fn rays(&self) -> u64 {
        self.rays
    }

    /// Wall-clock seconds of the render.
    #[getter]
    fn seconds(&self) -> f64 {
        self.seconds
    }

    /// Worker threads used.
    #[getter]
    fn threads(&self) -> usize {
        self.threads
    }

    /// The image as PNG bytes (Jupyter shows it).
    fn _repr_png_<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let mut bytes = Vec::new();
        py.detach(|| film::encode_png(&self.image, &mut bytes))
            .map_err(output_error)?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// Writes the image atomically (a temporary file beside it, then a rename): `.png`
    /// (8-bit sRGB) or `.exr` (linear float; `half=True` for 16-bit halves), byte for byte
    /// what `kardia render` writes for the same scene and settings (a region or tile as the
    /// part file `kardia assemble` joins). Raises ValueError for another extension and
    /// OSError when the file cannot be written.
    #[pyo3(signature = (path, half = false))]
    fn save(&self, py: Python<'_>, path: PathBuf, half: bool) -> PyResult<()> {
        py.detach(|| {
            let mut format = film::check_output_path(&path)?;
            if half && format == ImageFormat::ExrFloat {
                format = ImageFormat::ExrHalf;
            }
            if let Some(info) = &self.part {
                return tiles::write_part(&self.image, info, format, &path);
            }
            let tag = Some(FileTag {
                name: tiles::KEY_TAG,
                text: &self.key,
            });
            let mut file = AtomicFile::create(&path)?;
            film::encode_tagged(&self.image, format, tag, &mut file)?;
            file.commit()
        })
        .map_err(output_error)
    }

    fn __repr__(&self) -> String {
        format!(
            "Image({}x{}{}, {} rays, {:.3} s)",
            self.image.width,
            self.image.height,
            if self.image.alpha.is_some() {
                ", alpha"
            } else {
                ""
            },
            self.rays,
            self.seconds
        )
    }
}
