//! Readers of triangle-mesh files for the `MESH` primitive: STL (binary and ASCII), Wavefront
//! OBJ and PLY (ASCII, binary little- and big-endian), at least everything `kardia mesh`
//! writes. Each gives shared vertices and triangles (polygons cut into fans about their first
//! corner), with the triangles' winding as stored; STL's separate corners are joined where
//! their coordinates are equal bit for bit.

use crate::geometry::DVec3;
use std::collections::HashMap;
use std::path::Path;

/// The vertices and triangles (indices into the vertices) read from a mesh file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions (the file's units).
    pub vertices: Vec<DVec3>,
    /// Triangles as three vertex indices, wound as in the file.
    pub triangles: Vec<[u32; 3]>,
}

/// Reads a mesh file, its format chosen by the extension (`.stl`, `.obj`, `.ply`, any case).
/// The message of an error completes "cannot read the mesh file: …".
pub fn read_mesh_file(path: &Path) -> Result<MeshData, String> {
    read_mesh_file_with_digest(path).map(|(mesh, _)| mesh)
}

/// [`read_mesh_file`], with the SHA-256 (hex) of the bytes it read: what a render key
/// ([`crate::tiles::render_key`]) takes of the file, so a changed file is a new render.
pub fn read_mesh_file_with_digest(path: &Path) -> Result<(MeshData, String), String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let reader: fn(&[u8]) -> Result<MeshData, String> = match ext.as_deref() {
        Some("stl") => read_stl,
        Some("obj") => read_obj,
        Some("ply") => read_ply,
        _ => {
            return Err(format!(
                "{}: unknown mesh format (use a .stl, .obj or .ply file)",
                path.display()
            ))
        }
    };
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mesh = reader(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    if mesh.triangles.is_empty() {
        return Err(format!("{}: the file holds no triangles", path.display()));
    }
    use sha2::Digest;
    let digest = sha2::Sha256::digest(&bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    Ok((mesh, digest))
}

/// Joins corners given one triangle at a time into shared vertices (equal bits, one vertex).
#[derive(Default)]
struct Joiner {
    mesh: MeshData,
    seen: HashMap<[u64; 3], u32>,
}

impl Joiner {
    fn vertex(&mut self, p: DVec3) -> Result<u32, String> {
        if !p.is_finite() {
            return Err(format!("a corner is not finite: {p}"));
        }
        // +0 and −0 are one point.
        let key = (p + DVec3::ZERO).to_array().map(f64::to_bits);
        let next = self.mesh.vertices.len() as u32;
        let index = *self.seen.entry(key).or_insert(next);
        if index == next {
            self.mesh.vertices.push(p);
        }
        Ok(index)
    }

    fn triangle(&mut self, corners: [DVec3; 3]) -> Result<(), String> {
        let t = [
            self.vertex(corners[0])?,
            self.vertex(corners[1])?,
            self.vertex(corners[2])?,
        ];
        self.mesh.triangles.push(t);
        Ok(())
    }
}

/// STL: binary when the size is 84 bytes plus 50 per triangle counted in the header,
/// otherwise ASCII (`solid … facet … vertex x y z … endsolid`).
pub fn read_stl(bytes: &[u8]) -> Result<MeshData, String> {
    if bytes.len() >= 84 {
        let count = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as usize;
        if count.checked_mul(50).and_then(|n| n.checked_add(84)) == Some(bytes.len()) {
            let mut joiner = Joiner::default();
            for record in bytes[84..].chunks_exact(50) {
                let float = |i: usize| {
                    f64::from(f32::from_le_bytes(
                        record[4 * i..4 * i + 4].try_into().unwrap(),
                    ))
                };
                // Floats 0–2 are the facet normal, which the winding already gives.
                let corner =
                    |k: usize| DVec3::new(float(3 + 3 * k), float(4 + 3 * k), float(5 + 3 * k));
                joiner.triangle([corner(0), corner(1), corner(2)])?;
            }
            return Ok(joiner.mesh);
        }
    }
    let text = std::str::from_utf8(bytes).map_err(|_| {
        "neither a binary STL (the size does not match its triangle count) nor ASCII text"
    })?;
    if !text.trim_start().starts_with("solid") {
        return Err(
            "neither a binary STL (the size does not match its triangle count) nor an ASCII \
             STL (it does not start with `solid`)"
                .into(),
        );
    }
    let mut joiner = Joiner::default();
    let mut corners = Vec::with_capacity(3);
    for (n, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("vertex") => {
                let p = numbers3(&mut words).map_err(|e| format!("line {}: {e}", n + 1))?;
                corners.push(p);
            }
            Some("endloop") => {
                if corners.len() < 3 {
                    return Err(format!(
                        "line {}: a facet with fewer than 3 vertices",
                        n + 1
                    ));
                }
                for k in 1..corners.len() - 1 {
                    joiner.triangle([corners[0], corners[k], corners[k + 1]])?;
                }
                corners.clear();
            }
            _ => {}
        }
    }
    Ok(joiner.mesh)
}

/// Three numbers from `words`.
fn numbers3<'a>(words: &mut impl Iterator<Item = &'a str>) -> Result<DVec3, String> {
    let mut c = [0.0; 3];
    for x in &mut c {
        let w = words.next().ok_or("expected three coordinates")?;
        *x = w
            .parse::<f64>()
            .map_err(|_| format!("{w:?} is not a number"))?;
    }
    Ok(DVec3::from_array(c))
}

/// OBJ: `v x y z` vertices and `f` faces of three or more corners (`i`, `i/t`, `i//n` or
/// `i/t/n`; 1-based, or negative counting back from the last vertex read); every other
/// statement is ignored.
pub fn read_obj(bytes: &[u8]) -> Result<MeshData, String> {
    let text = std::str::from_utf8(bytes).map_err(|_| "the file is not UTF-8 text")?;
    let mut mesh = MeshData::default();
    for (n, line) in text.lines().enumerate() {
        let at = |e: String| format!("line {}: {e}", n + 1);
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let p = numbers3(&mut words).map_err(at)?;
                if !p.is_finite() {
                    return Err(at(format!("a vertex is not finite: {p}")));
                }
                mesh.vertices.push(p);
            }
            Some("f") => {
                let count = mesh.vertices.len() as i64;
                let corners = words
                    .map(|w| {
                        let first = w.split('/').next().unwrap_or("");
                        let i: i64 = first
                            .parse()
                            .map_err(|_| format!("{w:?} is not a vertex index"))?;
                        let index = if i < 0 { count + i } else { i - 1 };
                        if (0..count).contains(&index) {
                            Ok(index as u32)
                        } else {
                            Err(format!(
                                "vertex index {i} is not among the {count} read so far"
                            ))
                        }
                    })
                    .collect::<Result<Vec<u32>, String>>()
                    .map_err(at)?;
                if corners.len() < 3 {
                    return Err(at("a face with fewer than 3 corners".into()));
                }
                for k in 1..corners.len() - 1 {
                    mesh.triangles
                        .push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok(mesh)
}

/// A PLY scalar type.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Result<Self, String> {
        Ok(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return Err(format!("unknown PLY type {name:?}")),
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }
}

/// A PLY property: a scalar, or a list (count type, item type).
#[derive(Debug, Clone)]
struct Property {
    name: String,
    count: Option<Scalar>,
    item: Scalar,
}

/// A PLY element: its name, how many, and its properties.
#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

/// How the body of a PLY file is stored.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Encoding {
    Ascii,
    Little,
    Big,
}

/// Reads the values of a PLY body, one at a time.
struct Values<'a> {
    encoding: Encoding,
    bytes: &'a [u8],
    at: usize,
    words: std::str::SplitAsciiWhitespace<'a>,
}

impl Values<'_> {
    fn next(&mut self, ty: Scalar) -> Result<f64, String> {
        if self.encoding == Encoding::Ascii {
            let w = self.words.next().ok_or("the file ends early")?;
            return w
                .parse::<f64>()
                .map_err(|_| format!("{w:?} is not a number"));
        }
        let n = ty.size();
        let raw = self
            .bytes
            .get(self.at..self.at + n)
            .ok_or("the file ends early")?;
        self.at += n;
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(raw);
        if self.encoding == Encoding::Big {
            b[..n].reverse();
        }
        Ok(match ty {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }
}

/// PLY (ASCII, binary little- or big-endian): the `vertex` element's `x`, `y`, `z` and the
/// `face` element's list (`vertex_indices` or `vertex_index`); other elements and
/// properties are read past.
pub fn read_ply(bytes: &[u8]) -> Result<MeshData, String> {
    const END: &[u8] = b"end_header";
    let end = bytes
        .windows(END.len())
        .position(|w| w == END)
        .ok_or("not a PLY file (no end_header)")?;
    let body_start = bytes[end..]
        .iter()
        .position(|&b| b == b'\n')
        .map_or(bytes.len(), |i| end + i + 1);
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| "the PLY header is not text")?;
    let mut lines = header.lines();
    if lines.next().map(str::trim) != Some("ply") {
        return Err("not a PLY file (it does not start with `ply`)".into());
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    for line in lines {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            ["format", kind, _] => {
                encoding = Some(match *kind {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Little,
                    "binary_big_endian" => Encoding::Big,
                    _ => return Err(format!("unknown PLY format {kind:?}")),
                })
            }
            ["element", name, count] => elements.push(Element {
                name: name.to_string(),
                count: count
                    .parse()
                    .map_err(|_| format!("bad element count {count:?}"))?,
                properties: Vec::new(),
            }),
            ["property", "list", count, item, name] => elements
                .last_mut()
                .ok_or("a property before any element")?
                .properties
                .push(Property {
                    name: name.to_string(),
                    count: Some(Scalar::parse(count)?),
                    item: Scalar::parse(item)?,
                }),
            ["property", ty, name] => elements
                .last_mut()
                .ok_or("a property before any element")?
                .properties
                .push(Property {
                    name: name.to_string(),
                    count: None,
                    item: Scalar::parse(ty)?,
                }),
            _ => {}
        }
    }
    let encoding = encoding.ok_or("the PLY header has no format line")?;
    let body = &bytes[body_start..];
    let mut values = Values {
        encoding,
        bytes: body,
        at: 0,
        words: if encoding == Encoding::Ascii {
            std::str::from_utf8(body)
                .map_err(|_| "the ASCII PLY body is not text")?
                .split_ascii_whitespace()
        } else {
            "".split_ascii_whitespace()
        },
    };
    let mut mesh = MeshData::default();
    for element in &elements {
        let find = |n: &str| element.properties.iter().position(|p| p.name == n);
        let xyz = [find("x"), find("y"), find("z")];
        let list = find("vertex_indices").or_else(|| find("vertex_index"));
        let is_vertex = element.name == "vertex";
        if is_vertex && xyz.iter().any(Option::is_none) {
            return Err("the PLY vertex element lacks x, y or z".into());
        }
        for _ in 0..element.count {
            let mut p = [0.0; 3];
            for (k, prop) in element.properties.iter().enumerate() {
                match prop.count {
                    None => {
                        let x = values.next(prop.item)?;
                        if let Some(axis) = xyz.iter().position(|&a| a == Some(k)) {
                            p[axis] = x;
                        }
                    }
                    Some(count_type) => {
                        let n = values.next(count_type)?;
                        if !(0.0..=1e6).contains(&n) {
                            return Err(format!("a list of {n} items"));
                        }
                        let items = (0..n as usize)
                            .map(|_| values.next(prop.item))
                            .collect::<Result<Vec<f64>, String>>()?;
                        if element.name == "face" && Some(k) == list {
                            face(&mut mesh, &items)?;
                        }
                    }
                }
            }
            if is_vertex {
                let p = DVec3::from_array(p);
                if !p.is_finite() {
                    return Err(format!("a vertex is not finite: {p}"));
                }
                mesh.vertices.push(p);
            }
        }
    }
    let count = mesh.vertices.len();
    if let Some(bad) = mesh
        .triangles
        .iter()
        .flatten()
        .find(|&&i| i as usize >= count)
    {
        return Err(format!(
            "vertex index {bad} is not among the {count} vertices"
        ));
    }
    Ok(mesh)
}

/// Adds the fan of a PLY face's indices.
fn face(mesh: &mut MeshData, items: &[f64]) -> Result<(), String> {
    if items.len() < 3 {
        return Err("a face with fewer than 3 corners".into());
    }
    let index = |x: f64| {
        if x >= 0.0 && x < f64::from(u32::MAX) && x.fract() == 0.0 {
            Ok(x as u32)
        } else {
            Err(format!("{x} is not a vertex index"))
        }
    };
    let first = index(items[0])?;
    for k in 1..items.len() - 1 {
        mesh.triangles
            .push([first, index(items[k])?, index(items[k + 1])?]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tetrahedron with outward faces.
    fn tetrahedron() -> MeshData {
        MeshData {
            vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    #[test]
    fn ascii_stl_and_obj_with_polygons_and_negative_indices() {
        let stl = "solid t\n facet normal 0 0 -1\n  outer loop\n   vertex 0 0 0\n   vertex 0 1 0\n   \
                   vertex 1 0 0\n  endloop\n endfacet\n facet normal 0 0 1\n  outer loop\n   \
                   vertex 1 0 0\n   vertex 0 1 0\n   vertex 0 0 1e0\n  endloop\n endfacet\nendsolid t\n";
        let m = read_stl(stl.as_bytes()).unwrap();
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.triangles, vec![[0, 1, 2], [2, 1, 3]]);
        let obj = "# a square and a triangle\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
                   f 1/1/1 2/2/2 3 4\nvn 0 0 1\nf -4//1 -2//1 -1//1\n";
        let m = read_obj(obj.as_bytes()).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
        assert!(read_obj(b"v 0 0 0\nf 1 2 3\n")
            .unwrap_err()
            .contains("index 2"));
        assert!(read_stl(b"not an stl").is_err());
    }

    #[test]
    fn ply_in_every_encoding_reads_the_same() {
        let t = tetrahedron();
        let header = |format: &str| {
            format!(
                "ply\nformat {format} 1.0\ncomment x\nelement vertex 4\nproperty double x\n\
                 property float y\nproperty float z\nproperty uchar red\nelement face 4\n\
                 property list uchar int vertex_indices\nelement edge 0\nproperty int v\nend_header\n"
            )
        };
        let mut ascii = header("ascii");
        for p in &t.vertices {
            ascii += &format!("{} {} {} 255\n", p.x, p.y, p.z);
        }
        for f in &t.triangles {
            ascii += &format!("3 {} {} {}\n", f[0], f[1], f[2]);
        }
        assert_eq!(read_ply(ascii.as_bytes()).unwrap(), t);
        for (format, big) in [("binary_little_endian", false), ("binary_big_endian", true)] {
            let mut b = header(format).into_bytes();
            let order = |mut x: Vec<u8>| {
                if big {
                    x.reverse();
                }
                x
            };
            for p in &t.vertices {
                b.extend(order(p.x.to_le_bytes().to_vec()));
                b.extend(order((p.y as f32).to_le_bytes().to_vec()));
                b.extend(order((p.z as f32).to_le_bytes().to_vec()));
                b.push(255);
            }
            for f in &t.triangles {
                b.push(3);
                for i in f {
                    b.extend(order((*i as i32).to_le_bytes().to_vec()));
                }
            }
            assert_eq!(read_ply(&b).unwrap(), t, "{format}");
            assert!(read_ply(&b[..b.len() - 1])
                .unwrap_err()
                .contains("ends early"));
        }
    }
}
