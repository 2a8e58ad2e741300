//! `Scene.mesh`: the scene's HEART and IMPLICIT solids as one closed, manifold triangle mesh
//! (what `kardia mesh` writes), as numpy arrays.

use kardia::mesh::{mesh_solids, scene_solids, MeshRequest, SolidKind};
use kardia::scene::Scene;
use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

/// The mesh of `scene`'s polynomial solids: `(vertices, faces)`, float64 (V, 3) in scene
/// units (or scaled so the largest extent is `size`) and uint32 (F, 3) indices wound
/// counter-clockwise seen from outside. `kind`: "solid" (inside the surface, the default),
/// "outside", or "shell" with `thickness`.
pub(crate) fn mesh<'py>(
    py: Python<'py>,
    scene: &Scene,
    kind: &str,
    thickness: Option<f64>,
    tolerance: Option<f64>,
    max_cells: usize,
    size: Option<f64>,
) -> PyResult<(Py<PyAny>, Py<PyAny>)> {
    let kind = match (kind, thickness) {
        ("solid", None) => SolidKind::Inside,
        ("outside", None) => SolidKind::Outside,
        ("shell", Some(thickness)) => SolidKind::Shell { thickness },
        ("shell", None) => return Err(PyValueError::new_err("a shell needs its thickness")),
        (other, _) => {
            return Err(PyValueError::new_err(format!(
                "kind must be \"solid\", \"outside\" or \"shell\" (with a thickness), not {other:?}"
            )))
        }
    };
    let request = MeshRequest {
        kind,
        tolerance,
        max_cells,
    };
    let printable = py
        .detach(|| mesh_solids(&scene_solids(scene), &request, size, &|_, _, _| {}))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let mesh = printable.mesh;
    let vertices: Vec<f64> = mesh.vertices.iter().flat_map(|v| v.to_array()).collect();
    let faces: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let shape_error = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
    let vertices =
        Array2::from_shape_vec((mesh.vertices.len(), 3), vertices).map_err(shape_error)?;
    let faces = Array2::from_shape_vec((mesh.triangles.len(), 3), faces).map_err(shape_error)?;
    Ok((
        vertices.into_pyarray(py).into_any().unbind(),
        faces.into_pyarray(py).into_any().unbind(),
    ))
}
