//! Python arguments checked into the library's types: every bad value is a `ValueError` that
//! names the argument (a negative size, an unknown view, a non-finite number), never a panic.

use kardia::geometry::DVec3;
use kardia::pipeline::View;
use kardia::roots::Solver;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// `value` as a whole number in `lo ..= hi`, else a `ValueError` naming `name`.
pub(crate) fn whole(name: &str, value: i64, lo: i64, hi: i64) -> PyResult<u64> {
    if (lo..=hi).contains(&value) {
        Ok(value as u64)
    } else {
        Err(PyValueError::new_err(format!(
            "{name} must be a whole number from {lo} to {hi}, not {value}"
        )))
    }
}

/// An image side (`width`, `height`): 1 ..= `Scene::MAX_SIDE`, or `None`.
pub(crate) fn side(name: &str, value: Option<i64>) -> PyResult<Option<u32>> {
    let max = i64::from(kardia::scene::Scene::MAX_SIDE);
    value
        .map(|v| whole(name, v, 1, max).map(|v| v as u32))
        .transpose()
}

/// A view by its name (`"shaded"`, `"normals"`, …).
pub(crate) fn view(name: &str) -> PyResult<View> {
    name.parse::<View>().map_err(PyValueError::new_err)
}

/// A root solver by its name (`"sturm"`, `"yuksel"`).
pub(crate) fn solver(name: &str) -> PyResult<Solver> {
    name.parse::<Solver>().map_err(PyValueError::new_err)
}

/// A point or vector of three finite numbers.
pub(crate) fn vector(name: &str, v: (f64, f64, f64)) -> PyResult<DVec3> {
    let v = DVec3::new(v.0, v.1, v.2);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(PyValueError::new_err(format!(
            "{name} must be three finite numbers, not {v}"
        )))
    }
}
