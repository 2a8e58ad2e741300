//! `kardia.roots`: the distinct real roots of a polynomial on an interval, as `kardia roots`
//! prints them.

use kardia::roots::sturm_roots;
use numpy::ndarray::Array1;
use numpy::{IntoPyArray, PyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// The distinct real roots `t` with `lo < t <= hi` of `c0 + c1·t + … + cn·tⁿ` (`coeffs` in
/// ascending powers, 1 to 17 finite numbers), ascending, as a float64 array; each root right
/// to a few ulps times its condition (docs/roots.md). With `first=True`, only the smallest
/// (an array of 0 or 1 roots) by `solver` ("sturm" or "yuksel"). The interval's ends may be
/// infinite. Raises ValueError for a bad coefficient count, a non-finite coefficient, a NaN
/// end or `lo >= hi`.
#[pyfunction]
#[pyo3(signature = (coeffs, interval = (f64::NEG_INFINITY, f64::INFINITY), first = false, solver = "sturm"))]
pub(crate) fn roots<'py>(
    py: Python<'py>,
    coeffs: Vec<f64>,
    interval: (f64, f64),
    first: bool,
    solver: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let solver = crate::args::solver(solver)?;
    if coeffs.is_empty() || coeffs.len() > 17 {
        return Err(PyValueError::new_err(format!(
            "expected 1 to 17 coefficients, got {}",
            coeffs.len()
        )));
    }
    if let Some(c) = coeffs.iter().find(|c| !c.is_finite()) {
        return Err(PyValueError::new_err(format!(
            "coefficient {c} is not finite"
        )));
    }
    let (lo, hi) = interval;
    if lo.is_nan() || hi.is_nan() || lo >= hi {
        return Err(PyValueError::new_err(format!(
            "the interval ({lo}, {hi}] needs lo < hi (and no NaN)"
        )));
    }
    let found: Vec<f64> = py.detach(|| {
        if first {
            solver
                .first_root_at_any_scale(&coeffs, lo, hi)
                .into_iter()
                .collect()
        } else {
            sturm_roots(&coeffs, lo, hi)
        }
    });
    Ok(Array1::from_vec(found).into_pyarray(py))
}
