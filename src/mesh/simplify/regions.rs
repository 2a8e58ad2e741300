//! The two sides of a plane coarsened at once, then the whole mesh.
//!
//! The coarsening never moves a vertex (a collapse keeps `v` where it is; a flip makes no
//! vertex), so which side of a fixed plane a vertex lies on never changes. The plane is
//! across the axis along which the vertices spread widest, at the median of their
//! coordinates along it (so it depends on the mesh alone, never on the thread count): side A
//! holds the vertices whose coordinate is below the cut, side B the others. A triangle is
//! A's if all its corners are in A, B's if all are in B, and straddles otherwise.
//!
//! Side A's work ([`Work`] with [`Work::own`] the vertices of A) holds A's triangles and the
//! straddling ones, and refuses every step that would change a triangle with a corner outside
//! A: a collapse of `u` into `v` needs `u` and all of its neighbours in A (the triangles it
//! changes or removes are `u`'s fan, and its new ones have `v` and `u`'s neighbours for
//! corners), a flip needs the four corners of its two triangles in A. Then:
//!
//! - every triangle with a corner in A is in A's work, so the fan, ring and valence of a
//!   vertex of A, all that a step of A reads, are exact there; B's steps change only
//!   triangles with every corner in B, which are in no fan of a vertex of A, so nothing A
//!   reads is changed by B (nor the other way round), and straddling triangles never change;
//! - A's triangles, old or new, have every corner strictly below the cut, so they lie in the
//!   open half space below it, and B's in the closed half space above: none of A's can meet
//!   one of B's. What a new triangle of A may meet is A's or a straddling triangle, all in
//!   A's grid, where the crossing test (optimistic at the end of a pass, with its undo and
//!   careful redo) looks.
//!
//! So the two sides run at once on separate works (sharing the vertices, kinds and field,
//! each with its own copy of the surface normals and its own grid, log and careful region),
//! and the mesh they leave together, A's triangles, B's and the straddling ones, is the mesh
//! that making A's steps and then B's on the whole mesh would give, each step checked there
//! as it was on its side: every guarantee of the coarsening holds for it as it would for one
//! pass loop.
//!
//! The existing passes ([`super::passes`]) then run on the whole of it, collapsing and
//! flipping about the seam, where the vertices next to the plane were left, but only there:
//! their steps are confined ([`Work::own`] again) to the band of vertices within
//! [`SEAM_RINGS`] rings of neighbours of a corner of a straddling triangle. Elsewhere each side
//! had every step it has now and stopped by the same rule as the whole would (a pass removing
//! fewer than a fiftieth of the vertices left); trying every edge of the mesh again cost
//! Barth's sextic and Kummer's surface about twice as long as the band for 0.2 to 0.3% fewer
//! triangles. The band's steps are those of one work on the whole mesh (every triangle live
//! and in its grid), so nothing of the argument above is needed for them, and
//! [`super::super::check::verify`] of the finished mesh stays the guarantee.
//!
//! Each side makes its passes until one removes fewer than a fiftieth of its own vertices
//! left (the band likewise, of its own); the band then makes at most [`MAX_PASSES`] less the
//! passes of the side that made more, so [`super::Coarsened::passes`] (the larger side's
//! passes and the whole's) stays within [`MAX_PASSES`]. `pass_done(k)` is called as both
//! sides have ended pass `k`, then as each pass of the band ends (numbered on from the
//! larger side's), never going back.
//!
//! A small mesh is coarsened whole ([`MIN_SPLIT_TRIANGLES`]): below it, the passes about the
//! seam cost more than the second thread saves (the torus's 9 680 and the heart's 4 398
//! extracted triangles at the default tolerance are split, and coarsened sooner). One split,
//! not four: the machines have two cores, and every further plane adds a seam to finish on
//! one thread.

use super::{passes, Checking, Coarsened, Start, Work, MAX_PASSES};
use crate::geometry::DVec3;
use crate::mesh::field::{Field, VertexKind};
use crate::mesh::TriangleMesh;
use std::sync::atomic::AtomicBool;
use std::sync::Mutex;

/// The fewest triangles of a mesh coarsened as two sides at once (fewer: whole).
pub(super) const MIN_SPLIT_TRIANGLES: usize = 4_000;

/// A plane across a coordinate axis, splitting the vertices into side A (below `at`) and
/// side B (at or above it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Cut {
    /// The axis (0, 1, 2 for x, y, z).
    axis: usize,
    /// The coordinate along it.
    at: f64,
}

/// Whose a triangle is: side A's (every corner in A), side B's, or both (it straddles).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Owner {
    A,
    B,
    Both,
}

impl Cut {
    /// The cut of `mesh` across the axis of its vertices' largest extent at the median of
    /// their coordinates along it (the first axis of the largest, on a tie), or `None` if
    /// `mesh` has fewer than `min_triangles` triangles.
    pub(super) fn of(mesh: &TriangleMesh, min_triangles: usize) -> Option<Cut> {
        if mesh.triangles.len() < min_triangles || mesh.vertices.is_empty() {
            return None;
        }
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for &p in &mesh.vertices {
            (lo, hi) = (lo.min(p), hi.max(p));
        }
        let extent = hi - lo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let mut along: Vec<f64> = mesh.vertices.iter().map(|p| p[axis]).collect();
        let middle = along.len() / 2;
        let (_, &mut at, _) = along.select_nth_unstable_by(middle, f64::total_cmp);
        Some(Cut { axis, at })
    }

    /// Whether `p` is on side A (below the cut).
    fn below(&self, p: DVec3) -> bool {
        p[self.axis] < self.at
    }

    /// Per vertex, whether it is on side A.
    fn side_a(&self, vertices: &[DVec3]) -> Vec<bool> {
        vertices.iter().map(|&p| self.below(p)).collect()
    }
}

/// Per triangle, whose it is, given which vertices are on side A.
fn owners(triangles: &[[u32; 3]], side_a: &[bool]) -> Vec<Owner> {
    triangles
        .iter()
        .map(|t| match t.map(|v| side_a[v as usize]) {
            [true, true, true] => Owner::A,
            [false, false, false] => Owner::B,
            _ => Owner::Both,
        })
        .collect()
}

/// Where the work of one side starts: its own triangles and the straddling ones live, its
/// vertices its own.
fn side_start<'a>(
    triangles: &[[u32; 3]],
    owners: &[Owner],
    other: Owner,
    own: &'a [bool],
    surface_normals: Vec<DVec3>,
) -> Start<'a> {
    Start {
        triangles: triangles.to_vec(),
        alive: owners.iter().map(|&o| o != other).collect(),
        removed: vec![false; own.len()],
        surface_normals,
        own: Some(own),
    }
}

/// Coarsens the two sides of `cut` of `mesh` (with each vertex's kind) within `budget`, at
/// once (see the module doc), each for at most [`MAX_PASSES`] − 1 passes; where the work of
/// the whole mesh they leave starts (with no [`Start::own`]), the band about the seam
/// ([`seam_band`]) and what they did together (the passes of the side that made more). `None`
/// if `cancel` stopped either.
#[allow(clippy::too_many_arguments)]
pub(super) fn coarsen_sides<'a>(
    field: &'a Field,
    mesh: &'a TriangleMesh,
    kinds: &'a [VertexKind],
    budget: f64,
    cut: Cut,
    cancel: &AtomicBool,
    pass_done: &(dyn Fn(usize) + Sync),
    checking: Checking,
) -> Option<(Start<'a>, Vec<bool>, Coarsened)> {
    let side_a = cut.side_a(&mesh.vertices);
    let side_b: Vec<bool> = side_a.iter().map(|&a| !a).collect();
    let owners = owners(&mesh.triangles, &side_a);
    let normals = super::surface_normals(field, &mesh.vertices, kinds);
    // Each side's passes ended; `pass_done` told of the fewer.
    let ended = Mutex::new(([0usize; 2], 0usize));
    let report = |side: usize, pass: usize| {
        let mut ended = ended.lock().unwrap_or_else(|e| e.into_inner());
        ended.0[side] = pass;
        let both = ended.0[0].min(ended.0[1]);
        if both > ended.1 {
            ended.1 = both;
            pass_done(both);
        }
    };
    let run = |side: usize, start: Start<'_>| {
        let mut work = Work::starting(field, &mesh.vertices, kinds, budget, start);
        let mut done = Coarsened::default();
        passes(
            &mut work,
            &mut done,
            MAX_PASSES - 1,
            cancel,
            &|pass| report(side, pass),
            checking,
        )?;
        Some((work.triangles, work.alive, work.removed, done))
    };
    let start_a = side_start(&mesh.triangles, &owners, Owner::B, &side_a, normals.clone());
    let start_b = side_start(&mesh.triangles, &owners, Owner::A, &side_b, normals.clone());
    let (a, b) = rayon::join(|| run(0, start_a), || run(1, start_b));
    let ((a_triangles, a_alive, a_removed, a_done), (b_triangles, b_alive, b_removed, b_done)) =
        (a?, b?);
    // Each triangle as its side left it (a straddling one as it was).
    let mut triangles = mesh.triangles.clone();
    let mut alive = vec![true; triangles.len()];
    for (t, owner) in owners.iter().enumerate() {
        match owner {
            Owner::A => (triangles[t], alive[t]) = (a_triangles[t], a_alive[t]),
            Owner::B => (triangles[t], alive[t]) = (b_triangles[t], b_alive[t]),
            Owner::Both => {}
        }
    }
    let removed = a_removed
        .iter()
        .zip(&b_removed)
        .map(|(&a, &b)| a || b)
        .collect();
    let done = Coarsened {
        collapses: a_done.collapses + b_done.collapses,
        flips: a_done.flips + b_done.flips,
        passes: a_done.passes.max(b_done.passes),
        redone: a_done.redone + b_done.redone,
    };
    let seam = seam_band(&triangles, &alive, &owners, mesh.vertices.len(), SEAM_RINGS);
    let start = Start {
        triangles,
        alive,
        removed,
        surface_normals: normals,
        own: None,
    };
    Some((start, seam, done))
}

/// How many rings of neighbours about the straddling triangles the passes after the sides'
/// may change ([`seam_band`]): 3 and 5 rings gave Barth's sextic 6 516 and 6 500 triangles
/// and Kummer's surface 6 824 and 6 836, against 6 504 and 6 804 with every edge tried again.
pub(super) const SEAM_RINGS: usize = 3;

/// The vertices within `rings` rings of neighbours (along the live triangles) of a corner
/// of a straddling triangle: where the sides left steps undone.
fn seam_band(
    triangles: &[[u32; 3]],
    alive: &[bool],
    owners: &[Owner],
    vertices: usize,
    rings: usize,
) -> Vec<bool> {
    let mut band = vec![false; vertices];
    for (t, tri) in triangles.iter().enumerate() {
        if owners[t] == Owner::Both {
            for &v in tri {
                band[v as usize] = true;
            }
        }
    }
    for _ in 0..rings {
        let mut grown = band.clone();
        for (t, tri) in triangles.iter().enumerate() {
            if alive[t] && tri.iter().any(|&v| band[v as usize]) {
                for &v in tri {
                    grown[v as usize] = true;
                }
            }
        }
        band = grown;
    }
    band
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{check, extract, SolidKind};
    use crate::shapes::implicit::expand;

    /// A quartic's extracted mesh, large enough to be split.
    fn quartic() -> (Field, TriangleMesh, Vec<VertexKind>) {
        let poly = expand("x^4 + y^4 + z^4 - 0.5*(x^2 + y^2 + z^2) = 0.4").unwrap();
        let field = Field::new(&poly, 1.5, SolidKind::Inside);
        let grid = extract::Grid::covering(1.5, 0.05);
        let (mesh, kinds) = extract::march(&field, grid, &|_, _| {});
        (field, mesh, kinds)
    }

    #[test]
    fn the_cut_is_at_the_median_across_the_widest_axis_and_small_meshes_are_not_cut() {
        let vertices = [0.0, 1.0, 2.0, 3.0, 10.0]
            .map(|x| DVec3::new(0.5 * x, x, 0.1 * x))
            .to_vec();
        let mesh = TriangleMesh {
            vertices,
            triangles: vec![[0, 1, 2], [2, 3, 4]],
        };
        assert_eq!(Cut::of(&mesh, 2), Some(Cut { axis: 1, at: 2.0 }));
        assert_eq!(Cut::of(&mesh, 3), None);
        let side_a = Cut { axis: 1, at: 2.0 }.side_a(&mesh.vertices);
        assert_eq!(side_a, [true, true, false, false, false]);
        assert_eq!(owners(&mesh.triangles, &side_a), [Owner::Both, Owner::B]);
    }

    #[test]
    fn the_seam_band_grows_a_ring_at_a_time_from_the_straddling_triangles() {
        // A strip of triangles along x, vertex i at x = i (top) or i (bottom), cut at 2.5.
        let vertices: Vec<DVec3> = (0..12)
            .map(|i| DVec3::new((i / 2) as f64, (i % 2) as f64, 0.0))
            .collect();
        let triangles: Vec<[u32; 3]> = (0..10u32)
            .map(|i| {
                if i % 2 == 0 {
                    [i, i + 1, i + 2]
                } else {
                    [i, i + 2, i + 1]
                }
            })
            .collect();
        let side_a = Cut { axis: 0, at: 2.5 }.side_a(&vertices);
        let owners = owners(&triangles, &side_a);
        let alive = vec![true; triangles.len()];
        let band = |rings| seam_band(&triangles, &alive, &owners, vertices.len(), rings);
        let columns = |b: Vec<bool>| {
            (0..6)
                .filter(|&c| b[2 * c] || b[2 * c + 1])
                .collect::<Vec<_>>()
        };
        assert_eq!(columns(band(0)), [2, 3]);
        assert_eq!(columns(band(1)), [1, 2, 3, 4]);
        assert_eq!(columns(band(2)), [0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn a_side_changes_only_triangles_with_every_corner_on_it() {
        let (field, mesh, kinds) = quartic();
        let cut = Cut::of(&mesh, 0).unwrap();
        let side_a = cut.side_a(&mesh.vertices);
        let owners = owners(&mesh.triangles, &side_a);
        assert!(owners.contains(&Owner::Both));
        let normals = super::super::surface_normals(&field, &mesh.vertices, &kinds);
        for (side, own, other) in [
            (Owner::A, side_a.clone(), Owner::B),
            (Owner::B, side_a.iter().map(|&a| !a).collect(), Owner::A),
        ] {
            let start = side_start(&mesh.triangles, &owners, other, &own, normals.clone());
            let mut work = Work::starting(&field, &mesh.vertices, &kinds, 0.01, start);
            let mut done = Coarsened::default();
            let no = AtomicBool::new(false);
            passes(&mut work, &mut done, 3, &no, &|_| {}, Checking::Serial).unwrap();
            assert!(done.collapses > 500 && done.flips > 0, "{side:?}: {done:?}");
            for (t, &owner) in owners.iter().enumerate() {
                if owner == side {
                    // Its own triangles, where alive, keep every corner on the side.
                    let tri = work.triangles[t];
                    assert!(!work.alive[t] || tri.iter().all(|&v| own[v as usize]));
                } else {
                    // The straddling ones (and the other side's, not in the work) unchanged.
                    assert_eq!(work.triangles[t], mesh.triangles[t], "{side:?}: {t}");
                    assert_eq!(work.alive[t], owner == Owner::Both, "{side:?}: {t}");
                }
            }
            for (v, (&removed, &own)) in work.removed.iter().zip(&own).enumerate() {
                assert!(!removed || own, "{side:?}: {v} removed");
            }
        }
    }

    #[test]
    fn the_sides_and_the_whole_keep_every_guarantee() {
        let (field, mut mesh, mut kinds) = quartic();
        let before = mesh.triangles.len();
        assert!(
            before >= MIN_SPLIT_TRIANGLES,
            "{before} triangles: not split"
        );
        let passes_ended = Mutex::new(Vec::new());
        let done = super::super::coarsen_checking(
            &field,
            &mut mesh,
            &mut kinds,
            0.01,
            &AtomicBool::new(false),
            &|k| passes_ended.lock().unwrap().push(k),
            Checking::Serial,
        )
        .unwrap();
        check::verify(&mesh).unwrap();
        assert_eq!(kinds.len(), mesh.vertices.len());
        assert!(mesh.triangles.len() * 4 < before, "{before} -> {done:?}");
        let ended = passes_ended.into_inner().unwrap();
        assert!(ended.windows(2).all(|w| w[0] < w[1]), "{ended:?}");
        assert!(done.passes <= MAX_PASSES && ended.last() == Some(&done.passes));
    }
}
