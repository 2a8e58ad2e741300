//! `Scene.probe`: many rays at once from numpy arrays, each answered as `kardia probe`
//! answers it (the first hit with t > 0: t, point, outward unit normal, object).

use kardia::geometry::{DVec3, Ray};
use kardia::scene::limits;
use kardia::scene::Scene;
use numpy::ndarray::{Array1, Array2, ArrayView2};
use numpy::{IntoPyArray, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;

/// One ray's answer: (t, point, normal, object index) or a miss.
type Answer = Option<(f64, DVec3, DVec3, usize)>;

/// Row `i` of an (N, 3) array as a vector.
fn row(a: &ArrayView2<'_, f64>, i: usize) -> DVec3 {
    DVec3::new(a[[i, 0]], a[[i, 1]], a[[i, 2]])
}

/// Checks one ray as `kardia probe` checks an input line: finite coordinates within the
/// scene language's range, a direction of usable length.
fn check(i: usize, origin: DVec3, dir: DVec3) -> Result<(), String> {
    for (what, v) in [("origin", origin), ("direction", dir)] {
        for x in v.to_array() {
            if !x.is_finite() {
                return Err(format!("ray {i}: the {what} {v} is not finite"));
            }
            if !limits::COORDINATE.contains(x) {
                return Err(format!(
                    "ray {i}: the {what} {v} is outside the valid range of a coordinate, {}",
                    limits::COORDINATE
                ));
            }
        }
    }
    if dir == DVec3::ZERO {
        return Err(format!("ray {i}: the direction must not be zero"));
    }
    if !limits::DIRECTION_LENGTH.contains(dir.length()) {
        return Err(format!(
            "ray {i}: the direction is too short: its length must be {}",
            limits::DIRECTION_LENGTH
        ));
    }
    Ok(())
}

/// Intersects each ray `origins[i] + t·directions[i]` with `scene`; see `Scene.probe`.
pub(crate) fn probe<'py>(
    py: Python<'py>,
    scene: &Scene,
    origins: PyReadonlyArray2<'py, f64>,
    directions: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let (o, d) = (origins.as_array(), directions.as_array());
    if o.ncols() != 3 || d.ncols() != 3 || o.nrows() != d.nrows() {
        return Err(PyValueError::new_err(format!(
            "origins and directions must both have shape (N, 3), not {:?} and {:?}",
            o.shape(),
            d.shape()
        )));
    }
    let n = o.nrows();
    let rays: Vec<Ray> = (0..n)
        .map(|i| {
            let (origin, dir) = (row(&o, i), row(&d, i));
            check(i, origin, dir).map(|()| Ray::new(origin, dir))
        })
        .collect::<Result<_, _>>()
        .map_err(PyValueError::new_err)?;
    let answers: Vec<Answer> = py.detach(|| {
        rays.par_iter()
            .map(|ray| {
                let hit = scene.intersect(ray, 0.0, f64::INFINITY)?;
                let finite = hit.t.is_finite() && hit.point.is_finite() && hit.normal.is_finite();
                finite.then_some((hit.t, hit.point, hit.normal, hit.object))
            })
            .collect()
    });
    let mut hit = Array1::from_elem(n, false);
    let mut t = Array1::from_elem(n, f64::NAN);
    let mut point = Array2::from_elem((n, 3), f64::NAN);
    let mut normal = Array2::from_elem((n, 3), f64::NAN);
    let mut object = Array1::from_elem(n, -1i64);
    for (i, answer) in answers.iter().enumerate() {
        if let Some((ti, p, nrm, obj)) = answer {
            hit[i] = true;
            t[i] = *ti;
            for k in 0..3 {
                point[[i, k]] = p[k];
                normal[[i, k]] = nrm[k];
            }
            object[i] = *obj as i64;
        }
    }
    let out = PyDict::new(py);
    out.set_item("hit", hit.into_pyarray(py))?;
    out.set_item("t", t.into_pyarray(py))?;
    out.set_item("point", point.into_pyarray(py))?;
    out.set_item("normal", normal.into_pyarray(py))?;
    out.set_item("object", object.into_pyarray(py))?;
    Ok(out)
}
