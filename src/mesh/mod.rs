//! Triangle meshes of the solids that polynomial surfaces bound (`kardia mesh`): closed,
//! 2-manifold, outward-oriented, free of self-intersections and of zero-area triangles by
//! construction, with every surface vertex on the exact surface.
//!
//! The steps, one module each: [`field`] (the solid's indicator — inside, outside or a shell
//! — and the exact boundary point on a segment, by the project's root finder and the clip
//! sphere), [`extract`] (labels on tetrahedra, marching tetrahedra), [`bisection`] (conforming
//! local refinement of Kuhn tetrahedra on an integer lattice), [`resolution`] (which
//! tetrahedra to refine, by measurement, from a coarse grid down to the floor step),
//! [`simplify`] (the extracted mesh coarsened by edge collapses where the surface is flat),
//! [`accuracy`] (distances between the mesh and the exact surface, measured with the root
//! finder), [`check`] (every guarantee checked on the finished mesh) and [`write`] (binary
//! STL, OBJ, binary PLY and 3MF, written atomically).

pub mod accuracy;
pub mod bisection;
pub mod check;
pub mod extract;
pub mod field;
pub mod resolution;
pub mod simplify;
pub mod write;

use crate::geometry::{DMat3, DVec3, Frame};
use crate::shapes::PolynomialSolid;
pub use field::{Field, SolidKind, VertexKind};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// A triangle mesh: vertex positions and triangles of three vertex indices, wound
/// counter-clockwise seen from outside (the right-hand normal faces out).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub vertices: Vec<DVec3>,
    /// Triangles as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// The corners of triangle `t`.
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        self.triangles[t].map(|v| self.vertices[v as usize])
    }

    /// The right-hand normal of triangle `t`, of length twice its area.
    pub fn normal(&self, t: usize) -> DVec3 {
        let [a, b, c] = self.corners(t);
        (b - a).cross(c - a)
    }

    /// The area of triangle `t`.
    pub fn area(&self, t: usize) -> f64 {
        0.5 * self.normal(t).length()
    }

    /// The signed enclosed volume (positive when the triangles face outward).
    pub fn volume(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                a.dot(b.cross(c))
            })
            .sum::<f64>()
            / 6.0
    }

    /// The smallest box `(min, max)` holding every vertex.
    pub fn extent(&self) -> (DVec3, DVec3) {
        self.vertices.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
    }

    /// Appends `other`'s vertices and triangles (its indices shifted).
    pub fn append(&mut self, other: &TriangleMesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|v| v + base)));
    }

    /// Each vertex mapped by `map`; `flip` reverses every triangle's winding (for a map that
    /// turns space inside out).
    pub fn mapped(&self, map: impl Fn(DVec3) -> DVec3, flip: bool) -> TriangleMesh {
        TriangleMesh {
            vertices: self.vertices.iter().map(|&p| map(p)).collect(),
            triangles: self
                .triangles
                .iter()
                .map(|&[a, b, c]| if flip { [a, c, b] } else { [a, b, c] })
                .collect(),
        }
    }

    /// The same mesh with every coordinate rounded to `f32` (what STL, PLY and the other
    /// writers store), so that checks see exactly the numbers in the file.
    pub fn rounded_to_f32(&self) -> TriangleMesh {
        self.mapped(|p| p.as_vec3().as_dvec3(), false)
    }
}

/// The share of the tolerance the coarsening may use ([`simplify::coarsen`]'s budget): the
/// rest is the margin for its first-order distance estimates and for the accuracy of the
/// triangles it leaves alone.
pub const COARSEN_SHARE: f64 = 0.5;

/// Budgets tried by the coarsening (each half the last) before the extracted mesh is kept.
pub const COARSEN_ATTEMPTS: u32 = 3;

/// What to mesh and how finely.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshRequest {
    /// Which solid: inside, outside, or a shell (its thickness in world units).
    pub kind: SolidKind,
    /// The grid's target accuracy in world units (> 0); `None`: 1% of the clip radius in
    /// the world.
    pub tolerance: Option<f64>,
    /// The most grid cells along one side; a tolerance that needs more is refused.
    pub max_cells: usize,
}

impl Default for MeshRequest {
    fn default() -> Self {
        Self {
            kind: SolidKind::Inside,
            tolerance: None,
            max_cells: 512,
        }
    }
}

/// Why a solid could not be meshed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// The tolerance asks for a finer grid than allowed.
    #[error(
        "a tolerance of {tolerance} needs {cells} grid cells a side, more than the limit of \
         {limit}: choose a larger --tolerance"
    )]
    TooFine {
        /// The tolerance asked for (world units).
        tolerance: f64,
        /// Cells a side it needs.
        cells: usize,
        /// The limit.
        limit: usize,
    },
    /// A shell's wall asks for a finer grid than allowed ([`SHELL_FLOOR_SHARE`]).
    #[error(
        "a shell {thickness} thick needs {cells} grid cells a side (the grid step at most \
         3/4 of the wall's thickness, so that no part of the wall slips between \
         grid points), more than the limit of {limit}: choose a thicker --shell or a larger \
         --max-cells"
    )]
    TooThin {
        /// The wall's thickness asked for (world units).
        thickness: f64,
        /// Cells a side it needs.
        cells: usize,
        /// The limit.
        limit: usize,
    },
    /// A parameter is out of range.
    #[error("{0}")]
    Invalid(String),
    /// No grid vertex fell inside the solid.
    #[error(
        "the solid is empty at this tolerance (no grid point inside it): it may have no \
         volume (a point or a curve, where the polynomial is a sum of squares), or be thinner \
         than the grid: try a smaller --tolerance"
    )]
    Empty,
    /// A guarantee failed on the finished mesh (a bug: please report it).
    #[error("the mesh failed its own check: {0}")]
    Broken(String),
    /// The caller's cancel flag was set ([`mesh_solids_cancellable`]).
    #[error("the mesh was cancelled")]
    Cancelled,
}

/// A solid's mesh in world coordinates, with what was measured on it.
#[derive(Debug, Clone)]
pub struct MeshedSolid {
    /// The mesh (world units; outward winding).
    pub mesh: TriangleMesh,
    /// Where each vertex lies (on the surface or on the clip sphere).
    pub kinds: Vec<VertexKind>,
    /// The coarsest grid (object units): the cubes the refinement started from
    /// ([`resolution`]), or for a shell the uniform grid of the floor step it is meshed on.
    pub grid: extract::Grid,
    /// What the local refinement made (leaves by level, why tetrahedra were bisected);
    /// `None` for a mesh on the uniform grid of the floor step (a shell).
    pub refined: Option<resolution::Refined>,
    /// The finest step allowed, `2 ×` the tolerance in object units (its grid measures the
    /// mesh's accuracy).
    pub floor: extract::Grid,
    /// The time of each stage.
    pub times: StageTimes,
    /// The tolerance used (world units).
    pub tolerance: f64,
    /// Distances measured between the mesh and the exact surface (world units).
    pub deviation: accuracy::Deviation,
    /// Triangles of the mesh marching tetrahedra made, before it was coarsened.
    pub extracted_triangles: usize,
    /// What the coarsening did ([`simplify::coarsen`]); `None` when its result failed the
    /// check at every budget tried and the extracted mesh was kept.
    pub coarsened: Option<Coarsening>,
}

/// The wall-clock time of the stages of [`mesh_solid`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StageTimes {
    /// Refining the tetrahedra where needed and extracting the mesh on the leaves
    /// ([`resolution::mesh_adaptive`]: the checks of every round, marching tetrahedra).
    pub extraction: Duration,
    /// Coarsening, with the check for crossing triangles each budget tried needs.
    pub coarsening: Duration,
    /// The accuracy measurement ([`accuracy::measure_cancellable`]).
    pub measurement: Duration,
}

impl StageTimes {
    /// Extraction and coarsening: the time to make the mesh, without measuring it.
    pub fn meshing(&self) -> Duration {
        self.extraction + self.coarsening
    }
}

/// The coarsening that made a mesh: what it did and within what distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coarsening {
    /// Collapses, flips and passes made.
    pub done: simplify::Coarsened,
    /// The budget it kept each new triangle within (world units, by the first-order
    /// estimate): [`COARSEN_SHARE`] of the tolerance, or half or a quarter of that where the
    /// larger budget made two triangles cross.
    pub budget: f64,
}

impl MeshedSolid {
    /// The vertices on the crease (on both the surface and the clip sphere).
    pub fn crease_vertices(&self) -> usize {
        self.kinds
            .iter()
            .filter(|&&k| k == VertexKind::Crease)
            .count()
    }

    /// The triangles with both a surface vertex and a cap vertex: where no crease point
    /// was found inside the face of the grid that holds the side between them (0 on every
    /// mesh the tests make).
    pub fn mixed_triangles(&self) -> usize {
        self.mesh
            .triangles
            .iter()
            .filter(|t| {
                let has = |kind| t.iter().any(|&v| self.kinds[v as usize] == kind);
                has(VertexKind::Surface) && has(VertexKind::Cap)
            })
            .count()
    }
}

/// The largest factor by which `m` stretches a vector (its spectral norm).
pub fn stretch(m: &DMat3) -> f64 {
    let mtm = m.transpose() * *m;
    let mut v = DVec3::new(1.0, 0.7, 0.3).normalize();
    for _ in 0..100 {
        let w = mtm * v;
        let len = w.length();
        if len.is_nan() || len <= 0.0 {
            return 0.0;
        }
        v = w / len;
    }
    (mtm * v).length().sqrt()
}

/// Meshes `solid` as `request` asks: the tetrahedra of a grid of step at most the clip radius
/// / 8 refined where [`resolution::refine`] needs down to 2 × the tolerance (carried to
/// object space), the labels and marching tetrahedra on the leaves in object space, the mesh
/// coarsened where
/// the surface is flat ([`simplify::coarsen`], within [`COARSEN_SHARE`] of the tolerance),
/// the vertices carried to the world by the solid's frame, and the deviation from the exact
/// surface measured. `progress(done, total)` reports every stage (from any thread): the
/// grid's layers, the coarsening's passes and the measurement's parts.
pub fn mesh_solid(
    solid: &PolynomialSolid,
    request: &MeshRequest,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<MeshedSolid, MeshError> {
    mesh_solid_cancellable(solid, request, progress, &AtomicBool::new(false))
}

/// [`mesh_solid`], stopping with [`MeshError::Cancelled`] once `cancel` is set (read before
/// each round of the refinement, [`resolution::refine`], or each layer of a uniform grid,
/// [`extract::march_cancellable`], before each vertex is placed, between batches of
/// collapses, and by every sample of the measurement, [`accuracy::measure_cancellable`]).
pub fn mesh_solid_cancellable(
    solid: &PolynomialSolid,
    request: &MeshRequest,
    progress: &(dyn Fn(usize, usize) + Sync),
    cancel: &AtomicBool,
) -> Result<MeshedSolid, MeshError> {
    let frame: Frame = solid.frame;
    let grow = stretch(&frame.m);
    let radius = solid.clip_radius;
    let tolerance = request.tolerance.unwrap_or(0.01 * radius * grow);
    if !(tolerance > 0.0 && tolerance.is_finite()) {
        return Err(MeshError::Invalid(format!(
            "the tolerance must be a finite number greater than 0, not {tolerance}"
        )));
    }
    let kind = object_kind(request.kind, &frame)?;
    let floor_step = floor_step(tolerance / grow, kind);
    let floor = extract::Grid::clear_of_sphere(radius, floor_step, 0);
    if floor.cells > request.max_cells {
        return Err(match request.kind {
            SolidKind::Shell { thickness } if floor_step < 2.0 * tolerance / grow => {
                MeshError::TooThin {
                    thickness,
                    cells: floor.cells,
                    limit: request.max_cells,
                }
            }
            _ => MeshError::TooFine {
                tolerance,
                cells: floor.cells,
                limit: request.max_cells,
            },
        });
    }
    let field = Field::new(&solid.polynomial, radius, kind);
    // Progress over every stage: the floor grid's march steps (each grid tried reports its
    // march scaled to them, never going back), then a quarter as many again for the
    // coarsening (its passes) and for the measurement (its parts).
    let march_total = extract::march_steps(floor);
    let quarter = march_total.div_ceil(4);
    let all = march_total + 2 * quarter;
    let reported = AtomicUsize::new(0);
    let mut times = StageTimes::default();
    let started = Instant::now();
    let scaled = |done: usize, total: usize| {
        let scaled = done * march_total / total.max(1);
        progress(
            reported.fetch_max(scaled, Ordering::Relaxed).max(scaled),
            all,
        )
    };
    let depth = resolution::depth_for(radius, floor_step, field.degree());
    let (extracted, extracted_kinds, grid, refined) = if depth == 0 {
        let (mesh, kinds) = extract::march_cancellable(&field, floor, &scaled, cancel)
            .ok_or(MeshError::Cancelled)?;
        (mesh, kinds, floor, None)
    } else {
        let coarse = extract::Grid::clear_of_sphere(radius, floor_step, depth);
        let (mesh, kinds, refined) =
            resolution::mesh_adaptive(&field, coarse, depth, tolerance / grow, &scaled, cancel)
                .ok_or(MeshError::Cancelled)?;
        (mesh, kinds, coarse, Some(refined))
    };
    times.extraction = started.elapsed();
    if cancel.load(Ordering::Relaxed) {
        return Err(MeshError::Cancelled);
    }
    if extracted.triangles.is_empty() {
        return Err(MeshError::Empty);
    }
    let extracted_triangles = extracted.triangles.len();
    // The collapses keep every guarantee, testing each new fan against the triangles near
    // it; the check of the whole stays the guarantee: where it finds a fault, the coarsening
    // is redone within half the budget (twice), and failing that the extracted mesh (which
    // keeps them all) is used.
    let started = Instant::now();
    let mut coarsened = None;
    let (mut object_mesh, mut kinds) = (extracted.clone(), extracted_kinds.clone());
    let flip = frame.m.determinant() < 0.0;
    for attempt in 0..COARSEN_ATTEMPTS {
        let budget = COARSEN_SHARE * tolerance / grow / f64::from(1u32 << attempt);
        let (mut mesh, mut mesh_kinds) = (extracted.clone(), extracted_kinds.clone());
        let done = simplify::coarsen(
            &field,
            &mut mesh,
            &mut mesh_kinds,
            budget,
            cancel,
            &|pass| progress(march_total + quarter * pass / simplify::MAX_PASSES, all),
        )
        .ok_or(MeshError::Cancelled)?;
        // Checked as computed and as the file will hold it (in the world, rounded to f32).
        let written = mesh
            .mapped(|p| frame.point_to_world(p), flip)
            .rounded_to_f32();
        if check::verify(&mesh).is_ok() && check::verify(&written).is_ok() {
            coarsened = Some(Coarsening {
                done,
                budget: budget * grow,
            });
            (object_mesh, kinds) = (mesh, mesh_kinds);
            break;
        }
    }
    if cancel.load(Ordering::Relaxed) {
        return Err(MeshError::Cancelled);
    }
    times.coarsening = started.elapsed();
    progress(march_total + quarter, all);
    let started = Instant::now();
    let deviation = accuracy::measure_cancellable(
        &field,
        &object_mesh,
        &kinds,
        tolerance / grow,
        measure_step(radius, tolerance / grow),
        cancel,
        &|part| {
            progress(
                march_total + quarter + quarter * part / accuracy::MEASURE_PARTS,
                all,
            )
        },
    )
    .ok_or(MeshError::Cancelled)?
    .scaled(grow);
    times.measurement = started.elapsed();
    let mesh = object_mesh.mapped(|p| frame.point_to_world(p), flip);
    Ok(MeshedSolid {
        mesh,
        kinds,
        grid,
        refined,
        floor,
        times,
        tolerance,
        deviation,
        extracted_triangles,
        coarsened,
    })
}

/// The largest share of a shell's thickness the floor step may be. A flat wall thicker than
/// the step always holds a corner of every grid tetrahedron it passes through (the corners of
/// a Kuhn tetrahedron are a path of steps along the axes), so no part of it slips between
/// grid points; the rest is a margin for the wall's bends.
pub const SHELL_FLOOR_SHARE: f64 = 0.75;

/// `kind` with a shell's thickness (world units) in object units, by the frame's mean scale;
/// an error for a thickness that is not a finite number above 0.
fn object_kind(kind: SolidKind, frame: &Frame) -> Result<SolidKind, MeshError> {
    match kind {
        SolidKind::Shell { thickness } => {
            if !(thickness > 0.0 && thickness.is_finite()) {
                return Err(MeshError::Invalid(format!(
                    "the shell's thickness must be a finite number greater than 0, not \
                     {thickness}"
                )));
            }
            Ok(SolidKind::Shell {
                thickness: thickness / frame.m.determinant().abs().cbrt(),
            })
        }
        k => Ok(k),
    }
}

/// The floor step (object units) for `tolerance` and `kind` (object units): twice the
/// tolerance, and for a shell at most [`SHELL_FLOOR_SHARE`] of its thickness.
fn floor_step(tolerance: f64, kind: SolidKind) -> f64 {
    match kind {
        SolidKind::Shell { thickness } => (2.0 * tolerance).min(SHELL_FLOOR_SHARE * thickness),
        _ => 2.0 * tolerance,
    }
}

/// The spacing of the measurement's surface samples ([`accuracy::measure`]) for `tolerance`
/// (object units) in a clip ball of `radius`: the floor step of a solid, also for a shell,
/// whose thinner grid does not make its samples denser.
fn measure_step(radius: f64, tolerance: f64) -> f64 {
    extract::Grid::clear_of_sphere(radius, 2.0 * tolerance, 0).step()
}

/// Measures a mesh from a file (STL, OBJ or PLY, in world units: another mesher's, or
/// `kardia mesh`'s written without `--size`) against `solid`'s exact surface the way
/// [`mesh_solid`] measures its own ([`accuracy::measure`], with the sample spacing
/// `kardia mesh` would use for `tolerance` in world units; `kind` with a shell's thickness in
/// world units). The file carries no vertex kinds: a vertex within `1e-6` of the clip radius
/// of the clip sphere counts as a cap vertex, every other as a surface vertex, and a vertex's
/// deviation is sought within `tolerance`.
pub fn measure_file(
    solid: &PolynomialSolid,
    kind: SolidKind,
    tolerance: f64,
    path: &std::path::Path,
) -> Result<accuracy::Deviation, MeshError> {
    if !(tolerance > 0.0 && tolerance.is_finite()) {
        return Err(MeshError::Invalid(format!(
            "the tolerance must be a finite number greater than 0, not {tolerance}"
        )));
    }
    let data = crate::shapes::triangles::read::read_mesh_file(path)
        .map_err(|e| MeshError::Invalid(format!("cannot read the mesh file {e}")))?;
    let frame = solid.frame;
    let grow = stretch(&frame.m);
    let radius = solid.clip_radius;
    let object = TriangleMesh {
        vertices: data
            .vertices
            .iter()
            .map(|&p| frame.point_to_object(p))
            .collect(),
        triangles: data.triangles,
    };
    let kinds = object
        .vertices
        .iter()
        .map(|p| {
            if (p.length() - radius).abs() <= 1e-6 * radius {
                VertexKind::Cap
            } else {
                VertexKind::Surface
            }
        })
        .collect::<Vec<_>>();
    let kind = object_kind(kind, &frame)?;
    let field = Field::new(&solid.polynomial, radius, kind);
    let step = measure_step(radius, tolerance / grow);
    Ok(accuracy::measure(&field, &object, &kinds, tolerance / grow, step).scaled(grow))
}

/// A solid to mesh with its name (for messages and files) and colour (sRGB bytes).
#[derive(Debug, Clone)]
pub struct NamedSolid {
    /// E.g. `HEART (line 3)`.
    pub name: String,
    /// The solid.
    pub solid: PolynomialSolid,
    /// Its diffuse colour as sRGB bytes.
    pub colour: [u8; 3],
}

/// The polynomial solids of a scene (its HEART and IMPLICIT objects), in scene order.
pub fn scene_solids(scene: &crate::scene::Scene) -> Vec<NamedSolid> {
    scene
        .objects
        .iter()
        .filter_map(|o| {
            let solid = o.shape.polynomial_solid()?;
            Some(NamedSolid {
                name: format!("{} (line {})", o.keyword, o.line),
                solid,
                colour: o
                    .material
                    .diffuse
                    .to_array()
                    .map(crate::film::linear_to_srgb8),
            })
        })
        .collect()
}

/// The finished, checked mesh of one or more solids: what a file holds.
#[derive(Debug, Clone)]
pub struct Printable {
    /// The mesh as written (after `--size` scaling, coordinates rounded to `f32`).
    pub mesh: TriangleMesh,
    /// The guarantees checked on exactly that mesh, with its counts and volume.
    pub verified: check::Verified,
    /// Each solid's mesh and measurements (world units, before scaling).
    pub parts: Vec<MeshedSolid>,
    /// The factor the world coordinates were multiplied by (`--size`), else 1.
    pub scale: f64,
    /// The time [`check::verify`] took on the joined mesh.
    pub check_time: Duration,
}

/// Meshes every solid, joins them, scales the whole so its largest extent is `size`
/// (moved so its box starts at the origin) when given, rounds to `f32` as the files store it,
/// and checks every guarantee on the result ([`check::verify`]: solids that overlap each
/// other are refused there, as their meshes would cross). `progress(i, done, total)`:
/// solid `i`'s stages ([`mesh_solid`]).
pub fn mesh_solids(
    solids: &[NamedSolid],
    request: &MeshRequest,
    size: Option<f64>,
    progress: &(dyn Fn(usize, usize, usize) + Sync),
) -> Result<Printable, MeshError> {
    mesh_solids_cancellable(solids, request, size, progress, &AtomicBool::new(false))
}

/// [`mesh_solids`], stopping with [`MeshError::Cancelled`] once `cancel` is set: read in
/// each solid's meshing and measuring ([`mesh_solid_cancellable`]) and before the joined
/// mesh is checked. (The final check is not interrupted.)
pub fn mesh_solids_cancellable(
    solids: &[NamedSolid],
    request: &MeshRequest,
    size: Option<f64>,
    progress: &(dyn Fn(usize, usize, usize) + Sync),
    cancel: &AtomicBool,
) -> Result<Printable, MeshError> {
    if solids.is_empty() {
        return Err(MeshError::Invalid(
            "nothing to mesh: the scene has no HEART or IMPLICIT object".into(),
        ));
    }
    let mut parts = Vec::new();
    let mut joined = TriangleMesh::default();
    for (i, s) in solids.iter().enumerate() {
        let part = mesh_solid_cancellable(
            &s.solid,
            request,
            &|done, total| progress(i, done, total),
            cancel,
        )
        .map_err(|e| match e {
            MeshError::Empty => MeshError::Invalid(format!("{}: {e}", s.name)),
            e => e,
        })?;
        joined.append(&part.mesh);
        parts.push(part);
    }
    let mut scale = 1.0;
    if let Some(size) = size {
        if !(size > 0.0 && size.is_finite()) {
            return Err(MeshError::Invalid(format!(
                "--size must be a finite number of millimetres greater than 0, not {size}"
            )));
        }
        let (lo, hi) = joined.extent();
        scale = size / (hi - lo).max_element();
        joined = joined.mapped(|p| (p - lo) * scale, false);
    }
    if cancel.load(Ordering::Relaxed) {
        return Err(MeshError::Cancelled);
    }
    let mesh = joined.rounded_to_f32();
    let started = Instant::now();
    let verified = check::verify(&mesh).map_err(MeshError::Broken)?;
    Ok(Printable {
        mesh,
        verified,
        parts,
        scale,
        check_time: started.elapsed(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::implicit::{expand, preset};
    use std::sync::Arc;

    pub(crate) fn solid(equation: &str, radius: f64) -> PolynomialSolid {
        PolynomialSolid {
            polynomial: Arc::new(expand(equation).unwrap()),
            clip_radius: radius,
            frame: Frame::identity(),
        }
    }

    fn mesh(s: &PolynomialSolid, kind: SolidKind, tolerance: f64) -> MeshedSolid {
        let request = MeshRequest {
            kind,
            tolerance: Some(tolerance),
            ..MeshRequest::default()
        };
        mesh_solid(s, &request, &|_, _| {}).unwrap()
    }

    #[test]
    fn planes_through_the_origin_clipped_to_a_ball_give_closed_solids() {
        // On a plain grid through the origin, the default tolerance put lattice points of
        // these planes on the clip sphere of radius 3.16228 ((0, 30, 40) steps of radius
        // / 50): an end on both the surface and the sphere, whose triangles intersected.
        // The lattice clear of the sphere and `Field::crossing`'s end gap rule each mend
        // that alone (resolution's `an_end_on_the_surface_and_the_sphere_keeps_the_mesh_closed`
        // tests the rule on the old lattice).
        for equation in ["x", "x*y", "x*y*(x - y)"] {
            for kind in [SolidKind::Inside, SolidKind::Outside] {
                let m = mesh(&solid(equation, 3.16228), kind, 0.0316228);
                check::verify(&m.mesh).unwrap_or_else(|e| panic!("{equation} {kind:?}: {e}"));
            }
        }
    }

    #[test]
    fn a_sphere_is_one_closed_piece_of_its_volume() {
        let m = mesh(&solid("x^2 + y^2 + z^2 = 1", 1.5), SolidKind::Inside, 0.02);
        let v = check::verify(&m.mesh).unwrap();
        assert_eq!((v.components, v.euler_characteristic), (1, 2));
        let exact = 4.0 / 3.0 * std::f64::consts::PI;
        // The coarsened mesh lies within its Hausdorff distance of the sphere, so its volume
        // is within the sphere's area times that distance.
        let area = 4.0 * std::f64::consts::PI;
        assert!(
            (v.volume - exact).abs() <= area * m.deviation.hausdorff(),
            "{} {:?}",
            v.volume,
            m.deviation
        );
        assert!(m.kinds.iter().all(|&k| k == VertexKind::Surface));
        assert!(m.deviation.vertex < 1e-12, "{:?}", m.deviation);
        assert!(m.deviation.hausdorff() < 0.02, "{:?}", m.deviation);
        assert_eq!(m.deviation.vertices_beyond, 0);
    }

    #[test]
    fn distances_beyond_the_tolerance_where_a_part_is_thinner_than_the_grid_are_counted_apart() {
        // Two cylinders touching along the lines x = ±1: where one factor is negative the
        // solid has wedges thinner than any grid about the curves where they cross. Far
        // beyond the tolerance there, within it elsewhere.
        let tolerance = 0.0334;
        let m = mesh(
            &solid("(x^2 + y^2 - 1)*(x^2 + z^2 - 1) = 0", 3.34),
            SolidKind::Inside,
            tolerance,
        );
        let d = m.deviation;
        assert!(d.hausdorff() > 2.0 * tolerance, "{d:?}");
        assert!(d.beyond_only_where_thin(tolerance), "{d:?}");
        // A shell's wall meets the clip sphere at glancing angles along the squared-off
        // sphere's edges.
        let tolerance = 0.0114;
        let m = mesh(
            &solid("x^4 + y^4 + z^4 = 1", 1.14),
            SolidKind::Shell { thickness: 0.0342 },
            tolerance,
        );
        let d = m.deviation;
        assert!(d.hausdorff() > 2.0 * tolerance, "{d:?}");
        assert!(d.beyond_only_where_thin(tolerance), "{d:?}");
        // A sphere has no thin part.
        let m = mesh(&solid("x^2 + y^2 + z^2 = 1", 1.5), SolidKind::Inside, 0.02);
        assert_eq!(m.deviation.thin_samples, 0, "{:?}", m.deviation);
        assert!(!m.deviation.beyond_only_where_thin(0.02));
    }

    #[test]
    fn a_clipped_unbounded_surface_is_closed_by_its_cap_on_the_sphere() {
        // The region below the plane z = 0.3 inside the ball of radius 1.
        let m = mesh(&solid("z = 0.3", 1.0), SolidKind::Inside, 0.03);
        check::verify(&m.mesh).unwrap();
        for (p, k) in m.mesh.vertices.iter().zip(&m.kinds) {
            match k {
                VertexKind::Cap => assert!((p.length() - 1.0).abs() < 1e-12),
                VertexKind::Surface => assert!((p.z - 0.3).abs() < 1e-12),
                VertexKind::Crease => {
                    assert!((p.length() - 1.0).abs() < 1e-12 && (p.z - 0.3).abs() < 1e-12)
                }
            }
        }
        assert!(m.kinds.contains(&VertexKind::Cap));
    }

    #[test]
    fn the_crease_is_on_the_sphere_and_the_surface() {
        // A plane (the crease a circle) and a hyperboloid of one sheet (two circles).
        for (equation, on_surface) in [
            ("z = 0.3", (|p: DVec3| p.z - 0.3) as fn(DVec3) -> f64),
            ("x^2 + y^2 - z^2 = 0.3", |p: DVec3| {
                p.x * p.x + p.y * p.y - p.z * p.z - 0.3
            }),
        ] {
            for kind in [SolidKind::Inside, SolidKind::Outside] {
                let m = mesh(&solid(equation, 1.0), kind, 0.03);
                check::verify(&m.mesh).unwrap();
                let (crease, mixed) = (m.crease_vertices(), m.mixed_triangles());
                eprintln!("{equation} {kind:?}: {crease} crease vertices, {mixed} mixed triangles");
                // Where the solid's wedge at the crease is obtuse (these insides), the crease
                // points mostly lie in the faces of the grid, and the crease is split along
                // most of its length. A wedge pokes through edges whose corners are both
                // outside (one in the ball with φ > 0, one just outside it with φ < 0), always
                // where it is acute (the outsides) and at some grid corners near the sphere
                // where it is obtuse, and there the chamfer stays (docs/mesh.md).
                // The crease's length over the grid step (the step is chosen by measurement):
                // the plane's circle of radius √0.91, the hyperboloid's two of radius √0.65.
                let cells = |length: f64| length / m.grid.step();
                let tau = std::f64::consts::TAU;
                let length = match equation {
                    "z = 0.3" => tau * 0.91f64.sqrt(),
                    _ => 2.0 * tau * 0.65f64.sqrt(),
                };
                if kind == SolidKind::Inside {
                    assert!(
                        crease as f64 > 2.0 * cells(length) && mixed < crease,
                        "{crease} {mixed}"
                    );
                    // The plane's crease is split nearly everywhere.
                    assert!(equation != "z = 0.3" || mixed <= 40, "{mixed}");
                }
                for (p, k) in m.mesh.vertices.iter().zip(&m.kinds) {
                    if *k == VertexKind::Crease {
                        assert!((p.length() - 1.0).abs() < 1e-12, "{p}");
                        assert!(on_surface(*p).abs() < 1e-12, "{equation} {p}");
                    }
                }
            }
        }
    }

    #[test]
    fn nodal_surfaces_give_manifold_solids_inside_outside_and_as_shells() {
        for (name, params) in [("kummer", vec![1.3]), ("barth_sextic", vec![])] {
            let p = preset(name, &params).unwrap();
            let s = solid(&p.equation, p.bound);
            for kind in [
                SolidKind::Inside,
                SolidKind::Outside,
                SolidKind::Shell { thickness: 0.1 },
            ] {
                let m = mesh(&s, kind, 0.05);
                let v = check::verify(&m.mesh).unwrap_or_else(|e| panic!("{name} {kind:?}: {e}"));
                assert!(v.volume > 0.0);
                // Every surface vertex confirmed within the tolerance by the root finder,
                // including those an edge ending at one of Barth's nodes holds 1e-4 off it.
                let d = &m.deviation;
                assert_eq!(d.vertices_beyond, 0, "{name} {kind:?} {d:?}");
                assert!(d.vertex <= 0.05, "{name} {kind:?} {d:?}");
            }
        }
    }

    #[test]
    fn a_placement_carries_the_mesh_and_keeps_it_outward() {
        let mut s = solid("x^2 + y^2 + z^2 = 1", 1.5);
        // A mirror (negative determinant) that also stretches x by 2.
        s.frame = Frame::new(
            DVec3::new(5.0, 0.0, 0.0),
            DVec3::X * -2.0,
            DVec3::Y,
            DVec3::Z,
        )
        .unwrap();
        let m = mesh(&s, SolidKind::Inside, 0.04);
        let v = check::verify(&m.mesh).unwrap();
        let exact = 2.0 * 4.0 / 3.0 * std::f64::consts::PI;
        assert!((v.volume - exact).abs() < 0.02 * exact, "{}", v.volume);
        let (lo, hi) = m.mesh.extent();
        assert!((lo.x - 3.0).abs() < 0.05 && (hi.x - 7.0).abs() < 0.05);
    }

    #[test]
    fn a_cancelled_mesh_stops_within_a_few_layers() {
        let named = NamedSolid {
            name: "sphere".into(),
            solid: solid("x^2 + y^2 + z^2 = 1", 1.5),
            colour: [200, 50, 50],
        };
        let request = MeshRequest {
            tolerance: Some(0.02),
            ..MeshRequest::default()
        };
        let cancel = AtomicBool::new(false);
        let layers = std::sync::atomic::AtomicUsize::new(0);
        let total = std::sync::atomic::AtomicUsize::new(0);
        let result = mesh_solids_cancellable(
            std::slice::from_ref(&named),
            &request,
            None,
            &|_, _, all| {
                total.store(all, Ordering::Relaxed);
                if layers.fetch_add(1, Ordering::Relaxed) + 1 == 3 {
                    cancel.store(true, Ordering::Relaxed);
                }
            },
            &cancel,
        );
        assert!(matches!(result, Err(MeshError::Cancelled)), "{result:?}");
        // Layers already started when the flag was set may finish: one per thread.
        let done = layers.into_inner();
        let threads = rayon::current_num_threads();
        assert!(
            done <= 3 + threads,
            "{done} layers of {} done after a cancel at the third ({threads} threads)",
            total.into_inner()
        );
        // Not cancelled, the same call meshes the sphere.
        let whole = mesh_solids_cancellable(
            &[named],
            &request,
            None,
            &|_, _, _| {},
            &AtomicBool::new(false),
        );
        // (Chosen by measurement, the grid and the coarsening leave a few hundred triangles:
        // the count alone says little, so the solid's volume is asked for too.)
        let mesh = whole.unwrap().mesh;
        assert!(mesh.triangles.len() > 100);
        let volume = check::verify(&mesh).unwrap().volume;
        let ball = 4.0 / 3.0 * std::f64::consts::PI;
        assert!((volume - ball).abs() < 0.02 * ball, "{volume}");
    }

    #[test]
    fn a_wall_thinner_than_the_tolerances_grid_has_no_holes() {
        // A hollow sphere 0.04 thick at a tolerance of 0.05: on the tolerance's grid of step
        // 0.1 the wall slipped between grid points wherever it leans (84 pieces); the grid
        // of at most 3/4 of the thickness gives the two closed spheres of the wall.
        let m = mesh(
            &solid("x^2 + y^2 + z^2 = 1", 1.5),
            SolidKind::Shell { thickness: 0.04 },
            0.05,
        );
        let v = check::verify(&m.mesh).unwrap();
        assert_eq!((v.components, v.euler_characteristic), (2, 4));
        // The wall |f|/|∇f| ≤ 0.02: radii 0.980 to 1.020; each sphere of the mesh is within
        // the Hausdorff distance of its own.
        let ball = |r: f64| 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        // |r² − 1| / 2r = 0.02 at r = √1.0004 ∓ 0.02.
        let middle = 1.0004f64.sqrt();
        let (inner, outer) = (middle - 0.02, middle + 0.02);
        let d = m.deviation.hausdorff();
        assert!(d <= 0.05, "{:?}", m.deviation);
        let (least, most) = (
            ball(outer - d) - ball(inner + d),
            ball(outer + d) - ball(inner - d),
        );
        assert!(
            v.volume >= least && v.volume <= most,
            "{} {least} {most}",
            v.volume
        );
        // A thinner wall than the grid's limit allows is refused, naming the thickness.
        let request = MeshRequest {
            kind: SolidKind::Shell { thickness: 0.001 },
            tolerance: Some(0.05),
            ..MeshRequest::default()
        };
        let refused = mesh_solid(&solid("x^2 + y^2 + z^2 = 1", 1.5), &request, &|_, _| {});
        assert!(
            matches!(refused, Err(MeshError::TooThin { .. })),
            "{refused:?}"
        );
    }

    #[test]
    fn a_shell_through_a_singular_point_holds_it_in_its_wall() {
        // The cubic cone's shell: its apex (f and ∇f zero) is a lattice point, which φ = 0
        // would have put outside, a tiny hollow in the wall the measurement could not place.
        let m = mesh(
            &solid("x^3 + y^3 + z^3 + 2*x*y*z", 1.14),
            SolidKind::Shell { thickness: 0.0342 },
            0.0114,
        );
        let v = check::verify(&m.mesh).unwrap();
        assert_eq!((v.components, v.euler_characteristic), (1, 2));
        let d = &m.deviation;
        assert_eq!(d.beyond_reach, 0, "{d:?}");
        assert!(d.hausdorff() <= 0.0114, "{d:?}");
        // The Bohemian dome's double lines x = ±z, y = 0 hold lattice points, where the
        // expanded f and ∇f are rounding, not zero: 22 pieces with 168 vertices in the
        // wall's inside (no wall within the tolerance) when those points were outside.
        let tolerance = 0.0214;
        let m = mesh(
            &solid(
                "y^4 - ((1 - x^2)^2 + (1 - z^2)^2 + 6*(1 - x^2)*(1 - z^2) \
                 + 2*(y^2 - (1 - x^2) - (1 - z^2))*((1 - x^2) + (1 - z^2)))",
                2.14,
            ),
            SolidKind::Shell { thickness: 0.0642 },
            tolerance,
        );
        let v = check::verify(&m.mesh).unwrap();
        assert_eq!(v.components, 3);
        let d = &m.deviation;
        assert_eq!((d.vertices_beyond, d.beyond_reach), (0, 0), "{d:?}");
        assert!(d.hausdorff() <= tolerance, "{d:?}");
    }

    #[test]
    fn a_shell_about_a_singular_curve_is_within_the_tolerance() {
        // The heart's rim (z = 0, 2x² + y² = 1) is a singular curve, inside the wall, where
        // the wall's φ vanishes to rounding: roots found there are not wall points (they
        // were taken as samples of the wall, 99 of them far from any triangle), and the
        // wall bends away from the lines along the normal and ∇φ (a triangle measured at
        // 0.051 whose wall is 0.0066 away along x).
        let m = mesh(
            &solid("(2*x^2 + y^2 + z^2 - 1)^3 - 0.1*x^2*z^3 - y^2*z^3", 2.0),
            SolidKind::Shell { thickness: 0.06 },
            0.02,
        );
        check::verify(&m.mesh).unwrap();
        let d = &m.deviation;
        assert_eq!((d.beyond_reach, d.vertices_beyond), (0, 0), "{d:?}");
        assert!(d.hausdorff() <= 0.02, "{d:?}");
    }

    #[test]
    fn triangles_beside_a_curve_or_a_point_of_the_zero_set_are_measured_to_it() {
        // The cross-cap's stick (x = z = 0, y < 0) and leminescape's z-axis are curves of the
        // zero set, and the blend of two cylinders has an isolated zero at the origin (a
        // lattice point, counted outside: a hollow 2.4e-4 across); no line through a
        // triangle's centroid meets such a curve or point, where it was measured at the
        // search's reach (4 times the tolerance) or at a farther sheet (3.7 times).
        for (equation, radius) in [
            ("x^2*y - z^2", 1.14),
            ("4*x^2*(x^2 + y^2 + z^2 + z) + y^2*(y^2 + z^2 - 1)", 1.0),
            ("(x^2 + y^2 - 1)*(x^2 + z^2 - 1) - 1", 3.0),
        ] {
            let tolerance = 0.01 * radius;
            let m = mesh(&solid(equation, radius), SolidKind::Inside, tolerance);
            let d = &m.deviation;
            assert_eq!(d.beyond_reach, 0, "{equation}: {d:?}");
            assert!(d.mesh_to_surface <= tolerance, "{equation}: {d:?}");
        }
    }

    #[test]
    fn too_fine_a_tolerance_is_refused() {
        let s = solid("x^2 + y^2 + z^2 = 1", 1.5);
        let request = MeshRequest {
            tolerance: Some(1e-6),
            ..MeshRequest::default()
        };
        assert!(matches!(
            mesh_solid(&s, &request, &|_, _| {}),
            Err(MeshError::TooFine { .. })
        ));
    }
}
