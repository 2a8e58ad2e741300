//! Mesh files: binary STL, OBJ, binary little-endian PLY and 3MF (a zip holding the 3D
//! model XML with its unit and the object's colour). Every writer takes any `Write` (3MF
//! also `Seek`); [`write_file`] writes through [`AtomicFile`], so a file appears whole or
//! not at all. Coordinates are stored as `f32` (STL, PLY, and the decimal text of OBJ and 3MF
//! prints the same `f32` values), so a mesh checked after
//! [`TriangleMesh::rounded_to_f32`] is exactly the mesh in the file.

use super::TriangleMesh;
use crate::film::{AtomicFile, OutputError};
use std::io::{Seek, Write};
use std::path::Path;

/// A mesh file format, chosen by the output's extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Binary STL (`.stl`): triangles with facet normals, no shared vertices.
    Stl,
    /// Wavefront OBJ (`.obj`): text, shared vertices, 1-based indices.
    Obj,
    /// PLY (`.ply`), binary little-endian: shared vertices, `float` coordinates.
    Ply,
    /// 3D Manufacturing Format (`.3mf`): a zip with the model, its unit and colour.
    ThreeMf,
}

impl MeshFormat {
    /// The format of a file name's extension (case-insensitive), or an error naming the ones
    /// accepted.
    pub fn from_path(path: &Path) -> Result<Self, String> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("stl") => Ok(Self::Stl),
            Some("obj") => Ok(Self::Obj),
            Some("ply") => Ok(Self::Ply),
            Some("3mf") => Ok(Self::ThreeMf),
            _ => Err(format!(
                "cannot tell the mesh format of {}: use a .stl, .3mf, .obj or .ply file name",
                path.display()
            )),
        }
    }
}

/// What a file carries besides the triangles.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshMetadata {
    /// The object's name (3MF, OBJ comment, PLY comment, STL header).
    pub name: String,
    /// Its colour as sRGB bytes (3MF).
    pub colour: [u8; 3],
    /// Whether one unit is one millimetre (3MF's unit; otherwise stated as millimetre too,
    /// the 3MF default, one scene unit per millimetre).
    pub millimetres: bool,
}

impl MeshMetadata {
    /// What a file of `solids` carries: their names joined by commas and the first one's
    /// colour (black for none); `millimetres` as above.
    pub fn of_solids(solids: &[super::NamedSolid], millimetres: bool) -> Self {
        Self {
            name: solids
                .iter()
                .map(|s| s.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            colour: solids.first().map_or([0; 3], |s| s.colour),
            millimetres,
        }
    }
}

fn io(e: std::io::Error) -> OutputError {
    OutputError::Encode(e.to_string())
}

/// Binary STL: an 80-byte header, the triangle count, then per triangle its unit normal and
/// three corners as little-endian `f32`, and a zero attribute.
pub fn write_stl(
    mesh: &TriangleMesh,
    meta: &MeshMetadata,
    mut out: impl Write,
) -> Result<(), OutputError> {
    let mut header = [b' '; 80];
    let text = format!("kardia mesh: {}", meta.name);
    let n = text.len().min(80);
    header[..n].copy_from_slice(&text.as_bytes()[..n]);
    // A header starting with "solid" would read as ASCII STL to some readers.
    out.write_all(&header).map_err(io)?;
    out.write_all(&(mesh.triangles.len() as u32).to_le_bytes())
        .map_err(io)?;
    for t in 0..mesh.triangles.len() {
        let normal = mesh.normal(t).normalize_or_zero();
        let mut record = Vec::with_capacity(50);
        for p in std::iter::once(normal).chain(mesh.corners(t)) {
            for c in p.to_array() {
                record.extend_from_slice(&(c as f32).to_le_bytes());
            }
        }
        record.extend_from_slice(&[0, 0]);
        out.write_all(&record).map_err(io)?;
    }
    Ok(())
}

/// OBJ: `v x y z` lines (the `f32` values) and `f a b c` lines (1-based).
pub fn write_obj(
    mesh: &TriangleMesh,
    meta: &MeshMetadata,
    mut out: impl Write,
) -> Result<(), OutputError> {
    writeln!(out, "# kardia mesh: {}", meta.name).map_err(io)?;
    writeln!(out, "o {}", meta.name.replace(char::is_whitespace, "_")).map_err(io)?;
    for p in &mesh.vertices {
        let [x, y, z] = p.to_array().map(|c| c as f32);
        writeln!(out, "v {x} {y} {z}").map_err(io)?;
    }
    for [a, b, c] in &mesh.triangles {
        writeln!(out, "f {} {} {}", a + 1, b + 1, c + 1).map_err(io)?;
    }
    Ok(())
}

/// PLY, binary little-endian: `float` x y z per vertex, a `uchar`-counted `int` list per face.
pub fn write_ply(
    mesh: &TriangleMesh,
    meta: &MeshMetadata,
    mut out: impl Write,
) -> Result<(), OutputError> {
    write!(
        out,
        "ply\nformat binary_little_endian 1.0\ncomment kardia mesh: {}\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        meta.name.replace('\n', " "),
        mesh.vertices.len(),
        mesh.triangles.len()
    )
    .map_err(io)?;
    let mut buf = Vec::with_capacity(12 * mesh.vertices.len());
    for p in &mesh.vertices {
        for c in p.to_array() {
            buf.extend_from_slice(&(c as f32).to_le_bytes());
        }
    }
    out.write_all(&buf).map_err(io)?;
    buf.clear();
    for t in &mesh.triangles {
        buf.push(3);
        for v in t {
            buf.extend_from_slice(&(*v as i32).to_le_bytes());
        }
    }
    out.write_all(&buf).map_err(io)
}

/// The 3MF package's content types part.
const CONTENT_TYPES: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">
  <Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>
  <Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>
</Types>
"#;

/// The 3MF package's relationship to its model part.
const RELATIONSHIPS: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">
  <Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>
</Relationships>
"#;

/// Escapes text for an XML attribute.
fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The 3MF model XML: the unit, one base material with the object's colour, one mesh object.
pub fn model_xml(mesh: &TriangleMesh, meta: &MeshMetadata) -> String {
    use std::fmt::Write as _;
    let [r, g, b] = meta.colour;
    let mut x = String::with_capacity(64 * (mesh.vertices.len() + mesh.triangles.len()) + 1024);
    let _ = write!(
        x,
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"millimeter\" xml:lang=\"en-US\" \
         xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\">\n \
         <metadata name=\"Title\">{name}</metadata>\n <metadata name=\"Application\">kardia</metadata>\n \
         <resources>\n  <basematerials id=\"1\">\n   <base name=\"{name}\" displaycolor=\"#{r:02X}{g:02X}{b:02X}\"/>\n  \
         </basematerials>\n  <object id=\"2\" type=\"model\" name=\"{name}\" pid=\"1\" pindex=\"0\">\n   <mesh>\n    <vertices>\n",
        name = xml_escape(&meta.name)
    );
    for p in &mesh.vertices {
        let [px, py, pz] = p.to_array().map(|c| c as f32);
        let _ = writeln!(x, "     <vertex x=\"{px}\" y=\"{py}\" z=\"{pz}\"/>");
    }
    x.push_str("    </vertices>\n    <triangles>\n");
    for [a, b, c] in &mesh.triangles {
        let _ = writeln!(x, "     <triangle v1=\"{a}\" v2=\"{b}\" v3=\"{c}\"/>");
    }
    x.push_str("    </triangles>\n   </mesh>\n  </object>\n </resources>\n <build>\n  <item objectid=\"2\"/>\n </build>\n</model>\n");
    x
}

/// 3MF: the zip package (content types, relationships, `3D/3dmodel.model`, deflated).
pub fn write_3mf(
    mesh: &TriangleMesh,
    meta: &MeshMetadata,
    out: impl Write + Seek,
) -> Result<(), OutputError> {
    let zip_error = |e: zip::result::ZipError| OutputError::Encode(e.to_string());
    let mut zip = zip::ZipWriter::new(out);
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated);
    for (name, text) in [
        ("[Content_Types].xml", CONTENT_TYPES.to_string()),
        ("_rels/.rels", RELATIONSHIPS.to_string()),
        ("3D/3dmodel.model", model_xml(mesh, meta)),
    ] {
        zip.start_file(name, options).map_err(zip_error)?;
        zip.write_all(text.as_bytes()).map_err(io)?;
    }
    zip.finish().map_err(zip_error)?;
    Ok(())
}

/// Writes `mesh` to `path` in `format`, atomically: the whole file or nothing.
pub fn write_file(
    mesh: &TriangleMesh,
    meta: &MeshMetadata,
    format: MeshFormat,
    path: &Path,
) -> Result<(), OutputError> {
    let mut file = AtomicFile::create(path)?;
    match format {
        MeshFormat::Stl => write_stl(mesh, meta, &mut file),
        MeshFormat::Obj => write_obj(mesh, meta, &mut file),
        MeshFormat::Ply => write_ply(mesh, meta, &mut file),
        MeshFormat::ThreeMf => write_3mf(mesh, meta, &mut file),
    }?;
    file.commit()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::DVec3;

    fn tetrahedron() -> TriangleMesh {
        TriangleMesh {
            vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    fn meta() -> MeshMetadata {
        MeshMetadata {
            name: "t".into(),
            colour: [255, 128, 0],
            millimetres: true,
        }
    }

    #[test]
    fn stl_has_its_length_and_outward_normals() {
        let mut out = Vec::new();
        write_stl(&tetrahedron(), &meta(), &mut out).unwrap();
        assert_eq!(out.len(), 84 + 50 * 4);
        assert_eq!(u32::from_le_bytes(out[80..84].try_into().unwrap()), 4);
        // The first facet (0, 2, 1) lies in z = 0 facing −z.
        let nz = f32::from_le_bytes(out[92..96].try_into().unwrap());
        assert_eq!(nz, -1.0);
        assert!(!out.starts_with(b"solid"));
    }

    #[test]
    fn obj_and_ply_list_vertices_and_faces() {
        let mut obj = Vec::new();
        write_obj(&tetrahedron(), &meta(), &mut obj).unwrap();
        let text = String::from_utf8(obj).unwrap();
        assert_eq!(text.lines().filter(|l| l.starts_with("v ")).count(), 4);
        assert!(text.contains("f 1 3 2"));
        let mut ply = Vec::new();
        write_ply(&tetrahedron(), &meta(), &mut ply).unwrap();
        let header_end = ply.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        assert_eq!(ply.len() - header_end, 4 * 12 + 4 * 13);
    }

    #[test]
    fn a_3mf_is_a_zip_with_the_model_unit_and_colour() {
        let mut out = std::io::Cursor::new(Vec::new());
        write_3mf(&tetrahedron(), &meta(), &mut out).unwrap();
        let mut zip = zip::ZipArchive::new(std::io::Cursor::new(out.into_inner())).unwrap();
        let mut model = String::new();
        std::io::Read::read_to_string(&mut zip.by_name("3D/3dmodel.model").unwrap(), &mut model)
            .unwrap();
        assert!(model.contains("unit=\"millimeter\""));
        assert!(model.contains("displaycolor=\"#FF8000\""));
        assert_eq!(model.matches("<triangle ").count(), 4);
        assert!(zip.by_name("[Content_Types].xml").is_ok());
        assert!(zip.by_name("_rels/.rels").is_ok());
    }

    #[test]
    fn formats_follow_the_extension() {
        assert_eq!(
            MeshFormat::from_path(Path::new("a.STL")),
            Ok(MeshFormat::Stl)
        );
        assert_eq!(
            MeshFormat::from_path(Path::new("a.3mf")),
            Ok(MeshFormat::ThreeMf)
        );
        assert!(MeshFormat::from_path(Path::new("a.png")).is_err());
    }
}
