//! `kardia._kardia`: the Python extension module of kardia. It converts Python arguments and
//! numpy arrays into the library's types and calls the same API the command line calls
//! (`kardia::scene`, `kardia::pipeline`, `kardia::animation`, `kardia::film`, `kardia::roots`,
//! `kardia::mesh`); no rendering logic lives here. The pure-Python package `kardia` wraps it
//! (progress bars, scenes from equations, Dask helpers).

use pyo3::prelude::*;

mod args;
mod errors;
mod image;
mod interrupt;
mod mesh;
mod probe;
mod roots;
mod scene;

/// The file of `frame` for an output pattern such as `out/heart_####.png` (the last run of
/// `#` in the file name becomes the zero-padded frame number), as `kardia render` names frames.
#[pyfunction]
fn frame_path(pattern: std::path::PathBuf, frame: i64) -> PyResult<String> {
    let frame = args::whole("frame", frame, 0, i64::from(u32::MAX))? as u32;
    Ok(kardia::animation::frame_path(&pattern, frame)
        .to_string_lossy()
        .into_owned())
}

/// The module `kardia._kardia`.
#[pymodule]
fn _kardia(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SceneError", py.get_type::<errors::SceneError>())?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<scene::PyCamera>()?;
    m.add_class::<image::PyImage>()?;
    m.add_function(wrap_pyfunction!(roots::roots, m)?)?;
    m.add_function(wrap_pyfunction!(frame_path, m)?)?;
    let views: Vec<&str> = kardia::pipeline::View::ALL
        .iter()
        .map(|(_, n)| *n)
        .collect();
    m.add("VIEWS", views)?;
    let solvers: Vec<&str> = kardia::roots::Solver::ALL.iter().map(|(_, n)| *n).collect();
    m.add("SOLVERS", solvers)?;
    m.add("MAX_SIDE", kardia::scene::Scene::MAX_SIDE)?;
    Ok(())
}
