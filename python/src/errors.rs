//! The library's errors as Python exceptions: a scene error becomes `kardia.SceneError` (a
//! `ValueError`) whose message is the command line's report (file:line:column, the line and a
//! caret), with `file`, `line`, `column` and `message` attributes.

use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    kardia,
    SceneError,
    PyValueError,
    "A scene that could not be read or understood. `str(e)` is the report `kardia render` \
     prints (file:line:column: message, the source line and a caret); `e.file`, `e.line`, \
     `e.column` (1-based; None for an unreadable file) and `e.message` give its parts."
);

/// `err` as a `kardia.SceneError` carrying the CLI's report and its parts.
pub(crate) fn scene_error(py: Python<'_>, err: kardia::scene::SceneError) -> PyErr {
    let location = err.location();
    let message = err.message();
    let file = match &err {
        kardia::scene::SceneError::Unreadable { path, .. } => path.clone(),
        kardia::scene::SceneError::Invalid(e) => e.file.clone(),
    };
    let report = format!("{:?}", miette::Report::new(err));
    let py_err = SceneError::new_err(report.trim_end().to_string());
    let value = py_err.value(py);
    let _ = value.setattr("file", file);
    let _ = value.setattr("line", location.map(|l| l.0));
    let _ = value.setattr("column", location.map(|l| l.1));
    let _ = value.setattr("message", message);
    py_err
}

/// A render error: a bad size or region is the caller's `ValueError`; a cancelled render
/// (cancelled by an interrupt, which raises `KeyboardInterrupt` before this is seen) a
/// `RuntimeError`.
pub(crate) fn render_error(err: kardia::pipeline::RenderError) -> PyErr {
    use kardia::pipeline::RenderError as E;
    match err {
        E::BadSize(_) | E::BadRegion { .. } => PyValueError::new_err(err.to_string()),
        E::Cancelled => PyRuntimeError::new_err(err.to_string()),
    }
}

/// A thread pool that could not be started.
pub(crate) fn pool_error(err: impl std::fmt::Display) -> PyErr {
    PyRuntimeError::new_err(err.to_string())
}

/// An output error: the file system refused (`OSError`: no such folder, a folder in the
/// way, a failed write) or the image or its path cannot be encoded (`ValueError`: an
/// extension that names no format kardia writes).
pub(crate) fn output_error(err: kardia::film::OutputError) -> PyErr {
    use kardia::film::OutputError as E;
    match err {
        E::NoDirectory(_) | E::IsDirectory(_) | E::Write { .. } => {
            PyOSError::new_err(err.to_string())
        }
        E::UnknownFormat(_) | E::Encode(_) => PyValueError::new_err(err.to_string()),
    }
}
