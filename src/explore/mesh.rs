//! The page's "Download STL" and "Download 3MF": the scene the page shows, meshed exactly as
//! `kardia mesh SCENE -o FILE` meshes that scene text (its HEART and IMPLICIT objects, the
//! solid inside each surface and its clip ball, the default tolerance and grid limit, no
//! `--size`), so the file's bytes are the command's.

use crate::mesh::write::{write_3mf, write_stl, MeshFormat, MeshMetadata};
use crate::mesh::{mesh_solids_cancellable, scene_solids, MeshRequest, SolidKind};
use crate::scene;
use std::sync::atomic::AtomicBool;

/// `kardia mesh`'s default `--max-cells`.
const MAX_CELLS: usize = 512;

/// The file formats the page offers, by the name it sends: `"stl"` (binary STL) or `"3mf"`.
pub fn format_named(name: &str) -> Result<MeshFormat, String> {
    match name {
        "stl" => Ok(MeshFormat::Stl),
        "3mf" => Ok(MeshFormat::ThreeMf),
        _ => Err(format!(
            "unknown mesh format '{}': stl or 3mf",
            name.chars().take(20).collect::<String>()
        )),
    }
}

/// A finished mesh file.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshFile {
    /// The file's bytes.
    pub bytes: Vec<u8>,
    /// Triangles in it.
    pub triangles: usize,
}

/// Meshes the scene `text` into a file of `format`; `progress(fraction)` (0 to 1) is told how
/// far the meshing has got (the grid, the coarsening and the measurement); once `cancel` is set it stops within about one layer of the grid
/// (see [`crate::mesh::mesh_solids_cancellable`]) with an error. An error (a scene that does
/// not parse, one without a polynomial surface, a mesh that cannot be made, a cancel) is a
/// sentence for the page.
pub fn mesh_scene(
    text: &str,
    format: MeshFormat,
    progress: &(dyn Fn(f64) + Sync),
    cancel: &AtomicBool,
) -> Result<MeshFile, String> {
    let scene = scene::parse(text, "explore.scene", &super::session::page_load_options())
        .map_err(|e| e.to_string())?;
    let solids = scene_solids(&scene);
    let request = MeshRequest {
        kind: SolidKind::Inside,
        tolerance: None,
        max_cells: MAX_CELLS,
    };
    let count = solids.len().max(1);
    let printable = mesh_solids_cancellable(
        &solids,
        &request,
        None,
        &|i, done, total| {
            progress((i as f64 + done as f64 / total.max(1) as f64) / count as f64);
        },
        cancel,
    )
    .map_err(|e| e.to_string())?;
    let meta = MeshMetadata::of_solids(&solids, false);
    let mut bytes = std::io::Cursor::new(Vec::new());
    match format {
        MeshFormat::ThreeMf => write_3mf(&printable.mesh, &meta, &mut bytes),
        _ => write_stl(&printable.mesh, &meta, &mut bytes),
    }
    .map_err(|e| e.to_string())?;
    Ok(MeshFile {
        bytes: bytes.into_inner(),
        triangles: printable.mesh.triangles.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sphere_meshes_into_both_formats_and_a_plane_scene_is_refused() {
        let text = "SIZE 40 30\nCAMERA (0, -5, 0) (0, 0, 0) (0, 0, 1) 40\n\
                    LIGHT (3, -4, 5) (1, 1, 1)\n\
                    IMPLICIT \"x^2 + y^2 + z^2 - 1\" (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) \
                    (0.8, 0.2, 0.2) BOUND 1.5\n";
        let fractions = std::sync::Mutex::new(vec![]);
        let stl = mesh_scene(
            text,
            MeshFormat::Stl,
            &|f| fractions.lock().unwrap().push(f),
            &AtomicBool::new(false),
        )
        .unwrap();
        assert!(stl.triangles > 100, "{}", stl.triangles);
        // Binary STL: 80-byte header, count, 50 bytes a triangle.
        assert_eq!(stl.bytes.len(), 84 + 50 * stl.triangles);
        let fractions = fractions.into_inner().unwrap();
        assert!(fractions.iter().all(|f| (0.0..=1.0).contains(f)) && !fractions.is_empty());
        let three =
            mesh_scene(text, MeshFormat::ThreeMf, &|_| {}, &AtomicBool::new(false)).unwrap();
        assert_eq!(&three.bytes[..2], b"PK", "a zip");
        assert_eq!(three.triangles, stl.triangles);
        let plane = "SIZE 40 30\nCAMERA (0, -5, 0) (0, 0, 0) (0, 0, 1) 40\n\
                     PLANE (0, 0, 1) 0 (0.5, 0.5, 0.5)\n";
        assert!(mesh_scene(plane, MeshFormat::Stl, &|_| {}, &AtomicBool::new(false)).is_err());
        assert!(format_named("obj").is_err());
    }
}
