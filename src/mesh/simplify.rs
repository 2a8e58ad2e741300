//! Adaptive coarsening of the extracted mesh: half-edge collapses and edge flips, which keep every
//! vertex where it was (on the exact surface, on the clip sphere, or on the crease), so the
//! grid decides the topology and the collapses only drop vertices where the surface is flat
//! enough for longer triangles.
//!
//! A collapse of the edge `u v` removes `u` and joins its other neighbours to `v`. It is made
//! only when all of these hold:
//!
//! - `u` is a surface vertex whose neighbours are all on the surface (surface or crease
//!   vertices), or a cap vertex whose neighbours are all on the sphere (cap or crease
//!   vertices), and `v` is of the same part; crease vertices are never removed, so the crease
//!   keeps every point the extraction put on it;
//! - the link condition: the vertices joined to both `u` and `v` are exactly the two opposite
//!   the edge, and neither of them nor `u` has only three neighbours (so the mesh stays a
//!   closed 2-manifold, one fan about every vertex);
//! - no new triangle turns by more than [`MAX_TURN_COS`] from the triangle it replaces (no
//!   normal flips), none has zero area, and none is thinner than [`MIN_QUALITY`] unless the
//!   one it replaces already was or it lies along the surface: a thin triangle (down to
//!   [`THIN_QUALITY`]) is made only where its normal is within [`THIN_NORMAL_COS`] of the
//!   surface's at each corner, which holds where its long side runs along the direction in
//!   which the surface curves least (the length of a torus's tube, not around it);
//! - the accuracy: each new triangle's centroid and edge midpoints are within `budget` of the
//!   surface by the estimate [`super::field::Field::distance_estimate`] (of the sphere:
//!   `R − |x|` for a cap triangle), and so is the removed vertex of the nearest new triangle
//!   (the surface side);
//! - no new triangle meets a triangle near it (or another new one) other than in the corners
//!   and sides they share, by the exact test of [`super::check`]; the triangles' boxes are
//!   kept (as `f32` rounded outward) in a hierarchy of loose grids of dense arrays, updated
//!   as triangles change, so a triangle is tested only against those whose boxes overlap it.
//!
//! The last condition is tested optimistically: a pass makes its steps without it (except in
//! the careful region, below), then tests each triangle it changed, once, as the pass left
//! it. A crossing found there is rare; the pass is then undone (from a log of the triangles
//! and fans it changed) and made again with the test made step by step wherever a step's new
//! triangles meet a box about a crossing found (as large again on every side; the region
//! only grows, and at the third time the test is made everywhere for that pass), each step
//! the difference from the last time cannot reach being made as recorded then, unchecked.
//! So the mesh each pass leaves has no crossing (where the one it began with had none), and
//! the result is deterministic.
//!
//! Edges are tried shortest first, in passes until a pass removes few vertices (after the first
//! pass, only the steps whose verdict may have changed: a fan their check reads changed since
//! they were last tried); after each pass, edges are flipped to the other diagonal of their two
//! triangles where that makes the thinner of the two clearly thicker (which frees further
//! collapses), under the same conditions for the new triangles and with neither end of the edge
//! left with three neighbours or fewer. With more than one thread, the steps (collapses, then
//! flips) are checked in parallel in batches against the mesh as each batch begins and made in
//! order, a verdict that an earlier step of its batch could have changed being checked again:
//! the result is the same as one step after another, for any number of threads (a pass made
//! again is made one by one). The check of the finished mesh ([`super::check::verify`]) stays
//! the guarantee: the caller falls back to a smaller budget, then to the uncoarsened mesh, if
//! it ever finds a crossing.
//!
//! A mesh of at least [`regions::MIN_SPLIT_TRIANGLES`] triangles is first split by a plane
//! (across its widest axis, at the median vertex): the two sides are coarsened at once
//! ([`regions`]), each on its own work whose steps may change only triangles with every corner
//! on its side ([`Work::own`]), so that neither reads what the other changes and their new
//! triangles lie in disjoint half spaces; then the passes above run on the whole mesh,
//! confined to a band about the seam the sides could not touch. The split depends on the mesh
//! alone, so the result is still the same for any number of threads.

mod grid;
mod regions;

use super::field::{Field, VertexKind};
use super::{check, TriangleMesh};
use crate::geometry::DVec3;
use crate::shapes::triangles::closest_on_triangle;
use grid::{Box32, TriangleGrid};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// A new triangle's unit normal must be within this cosine of the replaced triangle's (60°).
pub const MAX_TURN_COS: f64 = 0.5;

/// The least quality `4√3·area / Σ edge²` (1 for an equilateral triangle, 0 for a flat one)
/// of a new triangle that need not lie along the surface (see [`THIN_QUALITY`]), unless the
/// triangle it replaces was already thinner.
pub const MIN_QUALITY: f64 = 0.2;

/// The least quality of any new triangle: one thinner than [`MIN_QUALITY`] (and than the
/// one it replaces) is made only if it lies along the surface, its unit normal within
/// [`THIN_NORMAL_COS`] of the surface's at each of its corners, which holds where its long
/// side runs along the direction in which the surface curves least.
pub const THIN_QUALITY: f64 = 0.02;

/// The cosine of the largest angle (about 20°) between a thin new triangle's normal and the
/// surface's unit normal (`∇φ/|∇φ|`, or the sphere's) at each of its corners.
pub const THIN_NORMAL_COS: f64 = 0.94;

/// The least height of a thin new triangle over its longest side, as a share of the clip
/// radius: far above the rounding of the files' `f32` coordinates (about `6e-8` of the
/// largest coordinate), so no triangle becomes flat or flips when written.
pub const THIN_HEIGHT_SHARE: f64 = 1e-5;

/// Passes over the edges at most.
pub const MAX_PASSES: usize = 12;

/// The quality `4√3·area / Σ edge²` of a triangle: 1 when equilateral, 0 when flat.
pub fn quality([a, b, c]: [DVec3; 3]) -> f64 {
    let twice_area = (b - a).cross(c - a).length();
    let edges = (b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared();
    if edges > 0.0 {
        2.0 * 3f64.sqrt() * twice_area / edges
    } else {
        0.0
    }
}

/// What [`coarsen`] did.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Coarsened {
    /// Vertices removed by collapses.
    pub collapses: usize,
    /// Edges flipped to the other diagonal of their two triangles.
    pub flips: usize,
    /// Passes over the edges made.
    pub passes: usize,
    /// Passes (of collapses or of flips) undone and made again because the test of their
    /// steps' new triangles at the end found a crossing (see the module doc).
    pub redone: usize,
}

/// Space one checking thread reuses from check to check (no allocation per collapse).
#[derive(Default)]
struct Scratch {
    /// The new triangles of the check in hand.
    new: Vec<[u32; 3]>,
    /// Their corners.
    new_corners: Vec<[DVec3; 3]>,
    /// Their boxes.
    boxes: Vec<Box32>,
    /// The neighbours of a vertex.
    ring: Vec<u32>,
}

/// A check's answer, with the region whose triangles it read.
#[derive(Clone, Copy, Debug)]
struct Verdict {
    /// Whether every condition holds.
    ok: bool,
    /// The box of the new triangles, when the crossing test was made (it read every
    /// triangle whose box overlaps it).
    near: Option<Box32>,
}

impl Verdict {
    const REFUSED: Verdict = Verdict {
        ok: false,
        near: None,
    };
}

/// Where each step's new triangles are tested for crossings as the step is checked; elsewhere
/// the test waits for the end of the pass ([`Work::crossings_made`]).
#[derive(Clone, Debug, Default, PartialEq)]
struct Careful {
    /// Everywhere (for the rest of the pass in hand).
    everywhere: bool,
    /// Where a new fan's box overlaps one of these boxes (about crossings found before).
    boxes: Vec<Box32>,
}

impl Careful {
    /// Whether a step whose new triangles lie in `fan` is tested as it is checked.
    fn covers(&self, fan: &Box32) -> bool {
        self.everywhere || self.boxes.iter().any(|b| b.overlaps(fan))
    }
}

/// What the steps of a pass changed, to undo the pass: each changed triangle and fan as it
/// was when the pass began, and the vertices removed.
#[derive(Default)]
struct UndoLog {
    /// The pass each triangle was last logged in (0: never).
    triangle_pass: Vec<u32>,
    /// The pass each vertex's fan was last logged in.
    fan_pass: Vec<u32>,
    /// The pass in hand (from 1).
    pass: u32,
    /// Triangles as they were: index, corners, whether live.
    triangles: Vec<(u32, [u32; 3], bool)>,
    /// Fans as they were: vertex, its triangles.
    fans: Vec<(u32, Vec<u32>)>,
    /// Vertices removed in the pass.
    removed: Vec<u32>,
}

/// The mesh being coarsened: triangles with a live flag and the triangles about each vertex.
struct Work<'a> {
    field: &'a Field,
    vertices: &'a [DVec3],
    kinds: &'a [VertexKind],
    triangles: Vec<[u32; 3]>,
    alive: Vec<bool>,
    around: Vec<Vec<u32>>,
    removed: Vec<bool>,
    /// How many vertices are removed.
    removed_count: usize,
    /// The vertices the steps may change a triangle about (every one when `None`): a
    /// region's side ([`regions`]); a step with any other vertex in its footprint is refused.
    own: Option<&'a [bool]>,
    /// How many vertices were removed when the work began and how many of `own` (or of all)
    /// were not, together: `own_count - removed_count` own vertices are left.
    own_count: usize,
    budget: f64,
    h: f64,
    /// Every live triangle's box, for the local crossing test.
    grid: TriangleGrid,
    /// The unit normal of `φ = 0` (`∇φ/|∇φ|`, zero where `∇φ` vanishes) at each vertex on the
    /// surface; zero at the others.
    surface_normals: Vec<DVec3>,
    /// Where steps are tested for crossings one by one (elsewhere at the end of the pass).
    careful: Careful,
    /// What the pass in hand changed.
    log: UndoLog,
    /// The sweep (a pass's collapses or its flips, counted from 1) in which each vertex's
    /// fan last changed (0: never), so that a later sweep tries only the steps it could now
    /// decide differently ([`Work::may_differ`]).
    fan_changed: Vec<u32>,
    /// The sweep in hand.
    sweep: u32,
}

impl Work<'_> {
    fn corners(&self, t: [u32; 3]) -> [DVec3; 3] {
        t.map(|v| self.vertices[v as usize])
    }

    /// The estimated distance of `p` from the part `surface` (φ = 0) or the sphere.
    fn off(&self, p: DVec3, surface: bool) -> f64 {
        if surface {
            self.field.distance_estimate(p, self.h)
        } else {
            (self.field.radius() - p.length()).abs()
        }
    }

    /// The unit normal of the part (`surface` or the sphere) at vertex `w`.
    fn part_normal(&self, w: u32, surface: bool) -> DVec3 {
        if surface {
            self.surface_normals[w as usize]
        } else {
            self.vertices[w as usize].normalize_or_zero()
        }
    }

    /// The neighbours of vertex `w`, each once (on a closed 2-manifold, the corner after `w`
    /// in each of its triangles), into `ring`.
    fn ring_of(&self, w: u32, ring: &mut Vec<u32>) {
        ring.clear();
        for &t in &self.around[w as usize] {
            let tri = self.triangles[t as usize];
            let k = tri.iter().position(|&x| x == w).unwrap();
            ring.push(tri[(k + 1) % 3]);
        }
    }

    /// Whether a new triangle `tri` may be as thin as it is: of quality at least
    /// [`MIN_QUALITY`] (or of `old_quality`, that of the one it replaces, if lower), or else of
    /// at least [`THIN_QUALITY`], [`THIN_HEIGHT_SHARE`] of the radius high, and lying along the
    /// part (its normal within [`THIN_NORMAL_COS`] of the part's at every corner).
    fn thin_enough(&self, tri: [u32; 3], old_quality: f64, surface: bool) -> bool {
        let p = self.corners(tri);
        let q = quality(p);
        if q >= MIN_QUALITY.min(old_quality) {
            return true;
        }
        if q < THIN_QUALITY {
            return false;
        }
        let normal = (p[1] - p[0]).cross(p[2] - p[0]);
        let longest = (p[1] - p[0])
            .length()
            .max((p[2] - p[1]).length())
            .max((p[0] - p[2]).length());
        if normal.length() < THIN_HEIGHT_SHARE * self.field.radius() * longest {
            return false;
        }
        let n = normal.normalize_or_zero();
        tri.iter()
            .all(|&w| n.dot(self.part_normal(w, surface)) >= THIN_NORMAL_COS)
    }

    /// Whether any of the triangles `scratch.new` (replacing the live triangles for which
    /// `replaced` holds, which are left out) would meet a live triangle near it, or another
    /// of them, other than in the corners and sides they share; with the box of the new
    /// triangles (every triangle whose box overlaps it was read). Outside the careful region
    /// ([`Work::careful`]) the test is left to the end of the pass: `(false, None)`.
    fn would_cross(
        &self,
        scratch: &mut Scratch,
        replaced: impl Fn(u32) -> bool,
    ) -> (bool, Option<Box32>) {
        let Scratch {
            new,
            new_corners,
            boxes,
            ..
        } = scratch;
        new_corners.clear();
        new_corners.extend(new.iter().map(|&t| self.corners(t)));
        boxes.clear();
        boxes.extend(new_corners.iter().map(Box32::around));
        let all = boxes.iter().fold(boxes[0], |a, &b| a.union(b));
        if !self.careful.covers(&all) {
            return (false, None);
        }
        let near = self.grid.any_near(&all, |b| {
            if !b.bounds.overlaps(&all) {
                return false;
            }
            let mut checked = false;
            for ((&t, &p), nb) in new.iter().zip(new_corners.iter()).zip(boxes.iter()) {
                if !nb.overlaps(&b.bounds) {
                    continue;
                }
                if !checked {
                    if replaced(b.triangle) {
                        return false;
                    }
                    checked = true;
                }
                let other = self.triangles[b.triangle as usize];
                if check::corners_meet(t, p, other, self.corners(other)) {
                    return true;
                }
            }
            false
        });
        if near {
            return (true, Some(all));
        }
        for i in 0..new.len() {
            for j in i + 1..new.len() {
                if boxes[i].overlaps(&boxes[j])
                    && check::corners_meet(new[i], new_corners[i], new[j], new_corners[j])
                {
                    return (true, Some(all));
                }
            }
        }
        (false, Some(all))
    }

    /// The edge `a b` of live triangle `t` (its `k`-th side), with the triangle on its other
    /// side and that one's corner off the edge: `(a, b, c, t2, d)`.
    fn flip_quad(&self, t: u32, k: usize) -> Option<(u32, u32, u32, u32, u32)> {
        let t1 = self.triangles[t as usize];
        let (a, b, c) = (t1[k], t1[(k + 1) % 3], t1[(k + 2) % 3]);
        let &t2 = self.around[a as usize]
            .iter()
            .find(|&&x| x != t && self.triangles[x as usize].contains(&b))?;
        let other = self.triangles[t2 as usize];
        let d = *other.iter().find(|&&w| w != a && w != b).unwrap();
        Some((a, b, c, t2, d))
    }

    /// Whether the edge `a b` of live triangle `t` (its `k`-th side) may be flipped to the
    /// other diagonal of the two triangles on it: the thinner of the two new triangles
    /// thicker than the thinner of the two old ones by a margin and every condition of the
    /// module doc holding for the new ones (same part, no turn, within the budget).
    fn check_flip(&self, t: u32, k: usize, scratch: &mut Scratch) -> Verdict {
        let Some((a, b, c, t2, d)) = self.flip_quad(t, k) else {
            return Verdict::REFUSED;
        };
        if c == d
            || self.around[a as usize].len() <= 3
            || self.around[b as usize].len() <= 3
            || self.around[c as usize]
                .iter()
                .any(|&x| self.triangles[x as usize].contains(&d))
        {
            return Verdict::REFUSED;
        }
        let kinds = [a, b, c, d].map(|w| self.kinds[w as usize]);
        let surface = if kinds.iter().all(|k| k.on_surface()) {
            true
        } else if kinds.iter().all(|k| k.on_sphere()) {
            false
        } else {
            return Verdict::REFUSED;
        };
        let (new1, new2) = ([a, d, c], [d, b, c]);
        let (o1, o2) = (
            self.corners(self.triangles[t as usize]),
            self.corners(self.triangles[t2 as usize]),
        );
        let (n1, n2) = (self.corners(new1), self.corners(new2));
        let before = quality(o1).min(quality(o2));
        if quality(n1).min(quality(n2)) <= 1.2 * before {
            return Verdict::REFUSED;
        }
        let normal = |p: [DVec3; 3]| (p[1] - p[0]).cross(p[2] - p[0]);
        let unit = |p: [DVec3; 3]| normal(p).normalize_or_zero();
        let old_mean = unit(o1) + unit(o2);
        for n in [n1, n2] {
            let m = unit(n);
            if m == DVec3::ZERO
                || m.dot(unit(o1)) < MAX_TURN_COS
                || m.dot(unit(o2)) < MAX_TURN_COS
                || m.dot(old_mean) <= 0.0
            {
                return Verdict::REFUSED;
            }
        }
        let (pc, pd) = (self.vertices[c as usize], self.vertices[d as usize]);
        for p in [
            0.5 * (pc + pd),
            (n1[0] + n1[1] + n1[2]) / 3.0,
            (n2[0] + n2[1] + n2[2]) / 3.0,
        ] {
            if self.off(p, surface) > self.budget {
                return Verdict::REFUSED;
            }
        }
        scratch.new.clear();
        scratch.new.extend([new1, new2]);
        let (crossed, near) = self.would_cross(scratch, |x| x == t || x == t2);
        Verdict { ok: !crossed, near }
    }

    /// Flips the edge of [`Work::check_flip`] (which must have allowed it, on this mesh).
    fn apply_flip(&mut self, t: u32, k: usize) {
        let (a, b, c, t2, d) = self.flip_quad(t, k).unwrap();
        self.log_triangle(t);
        self.log_triangle(t2);
        for w in [a, b, c, d] {
            self.log_fan(w);
        }
        let (new1, new2) = ([a, d, c], [d, b, c]);
        self.grid.remove(t);
        self.grid.remove(t2);
        self.grid.insert(t, &self.corners(new1));
        self.grid.insert(t2, &self.corners(new2));
        self.triangles[t as usize] = new1;
        self.triangles[t2 as usize] = new2;
        self.around[a as usize].retain(|&x| x != t2);
        self.around[b as usize].retain(|&x| x != t);
        self.around[c as usize].push(t2);
        self.around[d as usize].push(t);
    }

    /// Keeps triangle `t` as it is in the undo log, if the pass has not changed it yet.
    fn log_triangle(&mut self, t: u32) {
        let log = &mut self.log;
        if log.triangle_pass[t as usize] != log.pass {
            log.triangle_pass[t as usize] = log.pass;
            log.triangles
                .push((t, self.triangles[t as usize], self.alive[t as usize]));
        }
    }

    /// Keeps the fan of vertex `w` as it is in the undo log, if the pass has not changed it,
    /// and notes that the sweep in hand changes it.
    fn log_fan(&mut self, w: u32) {
        self.fan_changed[w as usize] = self.sweep;
        let log = &mut self.log;
        if log.fan_pass[w as usize] != log.pass {
            log.fan_pass[w as usize] = log.pass;
            log.fans.push((w, self.around[w as usize].clone()));
        }
    }

    /// Starts a new pass of the undo log (forgetting the last one's changes).
    fn begin_pass(&mut self) {
        let log = &mut self.log;
        log.pass += 1;
        log.triangles.clear();
        log.fans.clear();
        log.removed.clear();
    }

    /// The boxes of the pairs of live triangles, one of them changed in this pass, that meet
    /// other than in the corners and sides they share (by the exact test of
    /// [`super::check`]); empty if none do.
    fn crossings_made(&self) -> Vec<Box32> {
        let mut found = Vec::new();
        // Changed triangles in the order they were logged (a fan's together), in groups
        // near each other, so that one walk of the grid serves a group.
        let mut group: Vec<(u32, [u32; 3], [DVec3; 3], Box32)> = Vec::new();
        let mut test = |group: &[(u32, [u32; 3], [DVec3; 3], Box32)]| {
            let all = group.iter().fold(group[0].3, |a, m| a.union(m.3));
            self.grid.any_near(&all, |b| {
                if !b.bounds.overlaps(&all) {
                    return false;
                }
                let other = b.triangle;
                // A pair of changed triangles is tested once, from the lower index.
                let changed = self.log.triangle_pass[other as usize] == self.log.pass;
                for &(t, tri, p, bounds) in group {
                    if other == t || (changed && other < t) || !b.bounds.overlaps(&bounds) {
                        continue;
                    }
                    let q = self.triangles[other as usize];
                    if check::corners_meet(tri, p, q, self.corners(q)) {
                        found.push(bounds.union(b.bounds));
                    }
                }
                false
            });
        };
        let mut first_extent = 0.0;
        for &(t, ..) in &self.log.triangles {
            if !self.alive[t as usize] {
                continue;
            }
            let tri = self.triangles[t as usize];
            let p = self.corners(tri);
            let bounds = Box32::around(&p);
            if let Some(&(.., start)) = group.first() {
                let joined = group.iter().fold(start, |a, m| a.union(m.3)).union(bounds);
                if group.len() >= CROSSING_GROUP || joined.extent() > 2.0 * first_extent {
                    test(&group);
                    group.clear();
                }
            }
            if group.is_empty() {
                first_extent = bounds.extent();
            }
            group.push((t, tri, p, bounds));
        }
        if !group.is_empty() {
            test(&group);
        }
        found
    }

    /// Undoes every step made since [`Work::begin_pass`] (the caller begins the pass again).
    fn undo_pass(&mut self) {
        let mut log = std::mem::take(&mut self.log);
        for &(t, tri, alive) in &log.triangles {
            self.grid.remove(t);
            self.triangles[t as usize] = tri;
            self.alive[t as usize] = alive;
            if alive {
                self.grid.insert(t, &self.corners(tri));
            }
        }
        for (w, fan) in log.fans.drain(..) {
            self.around[w as usize] = fan;
        }
        for &u in &log.removed {
            self.removed[u as usize] = false;
        }
        self.removed_count -= log.removed.len();
        self.log = log;
    }

    /// Makes `steps` again from the state in which `last` (the record of the last time they
    /// were made) began, now that the careful region has grown: the same mesh as
    /// [`Work::make`], but a step is checked only if its footprint holds a vertex whose fan
    /// may differ from that of the last time (a step checked again and made, or made the last
    /// time and not now, marks both its footprints so) or the box of its footprint's points
    /// (which holds its new triangles) meets the careful region; the others are made as the
    /// last time. Records this time in `record`; how many steps were made, or `None` if
    /// `cancel` stopped it.
    fn remake(
        &mut self,
        steps: &[Step],
        last: &Record,
        record: &mut Record,
        cancel: &AtomicBool,
    ) -> Option<usize> {
        record.clear(steps.len());
        let mut differs = vec![false; self.vertices.len()];
        let mut scratch = Scratch::default();
        let mut footprint = Vec::new();
        let mut made = 0;
        for (i, &step) in steps.iter().enumerate() {
            if i % BATCH == 0 && cancel.load(Ordering::Relaxed) {
                return None;
            }
            self.footprint(step, &mut footprint);
            let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            for &w in &footprint {
                let p = self.vertices[w as usize];
                (lo, hi) = (lo.min(p), hi.max(p));
            }
            let before = last.footprint(i);
            let fresh = footprint.iter().any(|&w| differs[w as usize])
                || self.careful.covers(&Box32::around(&[lo, hi, hi]));
            let ok = if fresh {
                self.check(step, &mut scratch).ok
            } else {
                before.is_some()
            };
            if fresh && (ok || before.is_some()) {
                for &w in footprint.iter().chain(before.into_iter().flatten()) {
                    differs[w as usize] = true;
                }
            }
            if ok {
                record.made(i, &footprint);
                self.apply(step);
                made += 1;
            }
        }
        Some(made)
    }

    /// Makes each of `steps` that every condition allows, in order (as [`Work::make`]), the
    /// crossing test of a step made only where [`Work::careful`] covers it and of the rest
    /// once the steps are made; if that finds a crossing, the pass is undone and made again
    /// with the region about each crossing found added to the careful one (at the third
    /// time, everywhere). How many steps were made, and how many times the pass was redone;
    /// `None` if `cancel` stopped it.
    fn make_pass(
        &mut self,
        steps: &[Step],
        cancel: &AtomicBool,
        checking: Checking,
    ) -> Option<(usize, usize)> {
        let mut redone = 0;
        let (mut last, mut record) = (Record::default(), Record::default());
        loop {
            self.begin_pass();
            let made = if redone == 0 || self.careful.everywhere {
                make(self, steps, cancel, checking, &mut record)?
            } else {
                self.remake(steps, &last, &mut record, cancel)?
            };
            std::mem::swap(&mut last, &mut record);
            if self.careful.everywhere {
                self.careful.everywhere = false;
                return Some((made, redone));
            }
            let crossings = self.crossings_made();
            if crossings.is_empty() {
                return Some((made, redone));
            }
            self.undo_pass();
            redone += 1;
            // About each crossing, a box as large again on every side.
            let grown = crossings.iter().map(|b| b.grown(b.extent()));
            self.careful.boxes.extend(grown);
            self.careful.everywhere = redone >= REDOS_BEFORE_EVERYWHERE;
        }
    }

    /// The two triangles on the edge `u v` (in `u`'s fan) and their corners off it, if there
    /// are exactly two.
    fn edge_wings(&self, u: u32, v: u32) -> Option<([u32; 2], [u32; 2])> {
        let mut shared = [u32::MAX; 2];
        let mut opposite = [u32::MAX; 2];
        let mut count = 0;
        for &t in &self.around[u as usize] {
            let tri = self.triangles[t as usize];
            if tri.contains(&v) {
                if count == 2 {
                    return None;
                }
                shared[count] = t;
                opposite[count] = *tri.iter().find(|&&w| w != u && w != v).unwrap();
                count += 1;
            }
        }
        (count == 2).then_some((shared, opposite))
    }

    /// Whether `u` may be collapsed into `v`: every condition of the module doc.
    fn check_collapse(&self, u: u32, v: u32, scratch: &mut Scratch) -> Verdict {
        let refused = Verdict::REFUSED;
        if self.removed[u as usize] || self.removed[v as usize] {
            return refused;
        }
        let surface = match self.kinds[u as usize] {
            VertexKind::Surface => true,
            VertexKind::Cap => false,
            VertexKind::Crease => return refused,
        };
        let same_part = |w: u32| {
            let k = self.kinds[w as usize];
            if surface {
                k.on_surface()
            } else {
                k.on_sphere()
            }
        };
        // Valences (on a closed 2-manifold, a vertex has as many neighbours as triangles).
        let fan = &self.around[u as usize];
        if fan.len() <= 3 || self.around[v as usize].len() <= 3 {
            return refused;
        }
        if !fan
            .iter()
            .all(|&t| self.triangles[t as usize].iter().all(|&w| same_part(w)))
        {
            return refused;
        }
        // The two triangles on the edge and their opposite vertices.
        let Some((shared, opposite)) = self.edge_wings(u, v) else {
            return refused;
        };
        if opposite[0] == opposite[1]
            || opposite.iter().any(|&o| self.around[o as usize].len() <= 3)
        {
            return refused;
        }
        // The link condition: none of u's neighbours but v and the two opposite may be v's.
        self.ring_of(v, &mut scratch.ring);
        for &t in fan {
            let tri = self.triangles[t as usize];
            let k = tri.iter().position(|&x| x == u).unwrap();
            let w = tri[(k + 1) % 3];
            if w != v && !opposite.contains(&w) && scratch.ring.contains(&w) {
                return refused;
            }
        }
        // The new triangles: no turn, not too thin, the removed vertex near one of them.
        let target = self.vertices[v as usize];
        let removed_at = self.vertices[u as usize];
        let mut nearest_to_removed = f64::INFINITY;
        scratch.new.clear();
        for &t in fan {
            if shared.contains(&t) {
                continue;
            }
            let old_tri = self.triangles[t as usize];
            let new_tri = old_tri.map(|w| if w == u { v } else { w });
            let (old, new) = (self.corners(old_tri), self.corners(new_tri));
            let n_old = (old[1] - old[0]).cross(old[2] - old[0]);
            let n_new = (new[1] - new[0]).cross(new[2] - new[0]);
            let (l_old, l_new) = (n_old.length(), n_new.length());
            if !(l_new > 0.0 && l_old > 0.0) || n_old.dot(n_new) < MAX_TURN_COS * l_old * l_new {
                return refused;
            }
            if !self.thin_enough(new_tri, quality(old), surface) {
                return refused;
            }
            scratch.new.push(new_tri);
            nearest_to_removed = nearest_to_removed
                .min((closest_on_triangle(removed_at, new) - removed_at).length());
        }
        if nearest_to_removed > self.budget {
            return refused;
        }
        // The accuracy: each new triangle's centroid, and the midpoint of each side from v
        // (each once: the sides from v to u's other neighbours).
        for &tri in &scratch.new {
            let [a, b, c] = self.corners(tri);
            if self.off((a + b + c) / 3.0, surface) > self.budget {
                return refused;
            }
        }
        for &t in fan {
            let tri = self.triangles[t as usize];
            let k = tri.iter().position(|&x| x == u).unwrap();
            let w = tri[(k + 1) % 3];
            if w != v && self.off(0.5 * (target + self.vertices[w as usize]), surface) > self.budget
            {
                return refused;
            }
        }
        let (crossed, near) =
            self.would_cross(scratch, |x| self.triangles[x as usize].contains(&u));
        Verdict { ok: !crossed, near }
    }

    /// Collapses `u` into `v` (which [`Work::check_collapse`] must have allowed, on this
    /// mesh): the two triangles on the edge go, the rest of `u`'s fan turns to `v`.
    fn apply_collapse(&mut self, u: u32, v: u32) {
        let (shared, _) = self.edge_wings(u, v).unwrap();
        for k in 0..self.around[u as usize].len() {
            let t = self.around[u as usize][k];
            self.log_triangle(t);
            for w in self.triangles[t as usize] {
                self.log_fan(w);
            }
        }
        self.log.removed.push(u);
        for &t in &self.around[u as usize] {
            self.grid.remove(t);
        }
        for &t in &shared {
            self.alive[t as usize] = false;
            let tri = self.triangles[t as usize];
            for w in tri {
                if w != u {
                    self.around[w as usize].retain(|&x| x != t);
                }
            }
        }
        let fan = std::mem::take(&mut self.around[u as usize]);
        for t in fan {
            if shared.contains(&t) {
                continue;
            }
            for w in &mut self.triangles[t as usize] {
                if *w == u {
                    *w = v;
                }
            }
            let corners = self.corners(self.triangles[t as usize]);
            self.grid.insert(t, &corners);
            self.around[v as usize].push(t);
        }
        self.removed[u as usize] = true;
        self.removed_count += 1;
    }

    /// Whether `step` may be made on the mesh as it is.
    fn check(&self, step: Step, scratch: &mut Scratch) -> Verdict {
        if !self.owns(step) {
            return Verdict::REFUSED;
        }
        match step {
            Step::Collapse(u, v) => self.check_collapse(u, v, scratch),
            Step::Flip(t, k) if self.alive[t as usize] => {
                self.check_flip(t, usize::from(k), scratch)
            }
            Step::Flip(..) => Verdict::REFUSED,
        }
    }

    /// Whether every triangle `step` changes or makes has all its corners in [`Work::own`]
    /// (always, with no `own`): for a collapse of `u`, `u` and all its neighbours are own;
    /// for a flip, the four corners of its two triangles. An own vertex's whole fan is in the
    /// work, so what the check reads about them is exact.
    fn owns(&self, step: Step) -> bool {
        let Some(own) = self.own else {
            return true;
        };
        let is_own = |w: u32| own[w as usize];
        match step {
            Step::Collapse(u, _) => {
                is_own(u)
                    && self.around[u as usize]
                        .iter()
                        .all(|&t| self.triangles[t as usize].iter().all(|&w| is_own(w)))
            }
            Step::Flip(t, k) => {
                self.alive[t as usize]
                    && self.triangles[t as usize].iter().all(|&w| is_own(w))
                    && self
                        .flip_quad(t, usize::from(k))
                        .is_some_and(|(.., d)| is_own(d))
            }
        }
    }

    /// How many vertices the steps may remove are left: those of [`Work::own`] (or all) not
    /// removed.
    fn live_vertices(&self) -> usize {
        self.own_count - self.removed_count
    }

    /// Makes `step` (which [`Work::check`] must have allowed, on this mesh).
    fn apply(&mut self, step: Step) {
        debug_assert!(
            self.owns(step),
            "{step:?} reaches beyond the work's own vertices"
        );
        match step {
            Step::Collapse(u, v) => self.apply_collapse(u, v),
            Step::Flip(t, k) => self.apply_flip(t, usize::from(k)),
        }
    }

    /// The vertices whose fans a check of `step` reads and that making it changes, into
    /// `out`: for a collapse of `u`, `u` and its neighbours; for a flip, the corners of the
    /// two triangles. A check's verdict stands while none of them has changed (nor any
    /// triangle whose box overlaps the verdict's `near`): every triangle or fan it reads is
    /// about one of them.
    fn footprint(&self, step: Step, out: &mut Vec<u32>) {
        out.clear();
        match step {
            Step::Collapse(u, v) => {
                out.push(v);
                out.push(u);
                for &t in &self.around[u as usize] {
                    out.extend(self.triangles[t as usize]);
                }
            }
            Step::Flip(t, k) => {
                out.extend(self.triangles[t as usize]);
                if let Some((.., d)) = self.flip_quad(t, usize::from(k)) {
                    out.push(d);
                }
            }
        }
    }

    /// Makes each of `steps` that every condition allows, in order, as if one by one;
    /// how many were made, or `None` if `cancel` stopped it. The steps go in batches; a
    /// batch is checked either one step after another, or (with more than one thread) in
    /// parallel against the mesh as the batch begins and then made in order, a verdict whose
    /// footprint ([`Work::footprint`]) an earlier step of the batch changed, or whose new
    /// triangles' box a changed triangle overlaps, being checked again on the mesh as it is
    /// then. Either way the result is the same as one by one, for any number of threads;
    /// `checking` says which way is taken.
    fn make(
        &mut self,
        steps: &[Step],
        cancel: &AtomicBool,
        checking: Checking,
        record: &mut Record,
    ) -> Option<usize> {
        record.clear(steps.len());
        let mut scratch = Scratch::default();
        let mut made = 0;
        let parallel = rayon::current_num_threads() > 1 && checking != Checking::Serial;
        let mut changed_at = vec![0u32; self.vertices.len()];
        let mut changed_boxes: Vec<Box32> = Vec::new();
        let mut footprint = Vec::new();
        let mut begun = 0;
        let mut stamp = 0;
        while begun < steps.len() {
            if cancel.load(Ordering::Relaxed) {
                return None;
            }
            // Batches a sixty-fourth of the live vertices long: each step made marks a
            // handful of vertices changed, so about as few verdicts go stale whatever the
            // size of the mesh.
            let live = self.live_vertices();
            let length = (live / 64).max(BATCH);
            let first = begun;
            let batch = &steps[begun..(begun + length).min(steps.len())];
            begun += batch.len();
            stamp += 1;
            if !parallel {
                for (i, &step) in (first..).zip(batch) {
                    if self.check(step, &mut scratch).ok {
                        self.footprint(step, &mut footprint);
                        record.made(i, &footprint);
                        self.apply(step);
                        made += 1;
                    }
                }
                continue;
            }
            changed_boxes.clear();
            let this = &*self;
            let verdicts: Vec<Verdict> = batch
                .par_iter()
                .with_min_len(BATCH / 16)
                .map_init(Scratch::default, |scratch, &step| this.check(step, scratch))
                .collect();
            for ((i, &step), verdict) in (first..).zip(batch).zip(verdicts) {
                self.footprint(step, &mut footprint);
                let stale = footprint.iter().any(|&w| changed_at[w as usize] == stamp)
                    || verdict
                        .near
                        .is_some_and(|near| changed_boxes.iter().any(|b| b.overlaps(&near)));
                let ok = if stale {
                    self.check(step, &mut scratch).ok
                } else {
                    verdict.ok
                };
                if ok {
                    let mut changed = Box32::around(&[self.vertices[footprint[0] as usize]; 3]);
                    for &w in &footprint {
                        changed_at[w as usize] = stamp;
                        changed = changed.union(Box32::around(&[self.vertices[w as usize]; 3]));
                    }
                    changed_boxes.push(changed);
                    record.made(i, &footprint);
                    self.apply(step);
                    made += 1;
                }
            }
        }
        Some(made)
    }
}

/// How [`Work::make`] checks a batch of steps (the mesh made is the same every way).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Checking {
    /// One step after another.
    Serial,
    /// In parallel, when the pool has more than one thread.
    Parallel,
}

/// One step of a pass: `u` collapsed into `v`, or side `k` of triangle `t` flipped.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Step {
    Collapse(u32, u32),
    Flip(u32, u8),
}

/// [`Work::make`] on a thread of the pool (so each batch's parallel checks are split there,
/// not handed over from outside it and waited for).
fn make(
    work: &mut Work,
    steps: &[Step],
    cancel: &AtomicBool,
    checking: Checking,
    record: &mut Record,
) -> Option<usize> {
    rayon::scope(|_| work.make(steps, cancel, checking, record))
}

/// Which steps of a pass were made, each with its footprint ([`Work::footprint`]) as it was
/// made, so that the pass can be made again ([`Work::remake`]) checking only the steps a
/// change could reach.
#[derive(Default)]
struct Record {
    /// Per step, its footprint's range in `footprints` if it was made.
    made: Vec<Option<(u32, u32)>>,
    /// The footprints of the steps made, one after another.
    footprints: Vec<u32>,
}

impl Record {
    /// Forgets every step, for a pass of `steps` steps.
    fn clear(&mut self, steps: usize) {
        self.made.clear();
        self.made.resize(steps, None);
        self.footprints.clear();
    }

    /// Notes that step `i` was made with the footprint `footprint`.
    fn made(&mut self, i: usize, footprint: &[u32]) {
        let start = self.footprints.len() as u32;
        self.footprints.extend_from_slice(footprint);
        self.made[i] = Some((start, self.footprints.len() as u32));
    }

    /// Step `i`'s footprint, if it was made.
    fn footprint(&self, i: usize) -> Option<&[u32]> {
        self.made[i].map(|(a, b)| &self.footprints[a as usize..b as usize])
    }
}

/// The most changed triangles tested for crossings with one walk of the grid at the end of a
/// pass ([`Work::crossings_made`]).
const CROSSING_GROUP: usize = 6;

/// Times a pass is redone with a larger careful region ([`Work::make_pass`]) before the
/// crossing test is made step by step everywhere.
const REDOS_BEFORE_EVERYWHERE: usize = 2;

/// The fewest steps checked together by [`Work::make`].
const BATCH: usize = 1024;

/// Where a [`Work`] starts: the triangles (indexed as in the whole mesh) with which of them
/// are its own or shared, the vertices already removed, and the vertices its steps may touch.
struct Start<'a> {
    /// Every triangle of the mesh, by its index there.
    triangles: Vec<[u32; 3]>,
    /// Which of them are in the work (live); the others it never reads nor changes.
    alive: Vec<bool>,
    /// The vertices removed before the work begins.
    removed: Vec<bool>,
    /// [`Work::surface_normals`].
    surface_normals: Vec<DVec3>,
    /// [`Work::own`].
    own: Option<&'a [bool]>,
}

/// The unit normal of `φ = 0` at each surface vertex of `vertices` (zero at the others).
fn surface_normals(field: &Field, vertices: &[DVec3], kinds: &[VertexKind]) -> Vec<DVec3> {
    let h = 1e-7 * field.radius();
    vertices
        .par_iter()
        .zip(kinds.par_iter())
        .map(|(&p, k)| {
            if k.on_surface() {
                field.value_and_gradient(p, h).1.normalize_or_zero()
            } else {
                DVec3::ZERO
            }
        })
        .collect()
}

impl<'a> Work<'a> {
    /// The work of coarsening `mesh` (with each vertex's kind) within `budget`: every
    /// triangle live and in the grid, nothing logged, the careful region empty.
    fn new(
        field: &'a Field,
        mesh: &'a TriangleMesh,
        kinds: &'a [VertexKind],
        budget: f64,
    ) -> Work<'a> {
        let start = Start {
            triangles: mesh.triangles.clone(),
            alive: vec![true; mesh.triangles.len()],
            removed: vec![false; mesh.vertices.len()],
            surface_normals: surface_normals(field, &mesh.vertices, kinds),
            own: None,
        };
        Work::starting(field, &mesh.vertices, kinds, budget, start)
    }

    /// The work of coarsening the live triangles of `start` (on `vertices`, with each
    /// vertex's kind) within `budget`: each of them in the grid, nothing logged, the careful
    /// region empty.
    fn starting(
        field: &'a Field,
        vertices: &'a [DVec3],
        kinds: &'a [VertexKind],
        budget: f64,
        start: Start<'a>,
    ) -> Work<'a> {
        let Start {
            triangles,
            alive,
            removed,
            surface_normals,
            own,
        } = start;
        let n = vertices.len();
        let corners = |tri: &[u32; 3]| tri.map(|v| vertices[v as usize]);
        let live = || {
            triangles
                .iter()
                .zip(&alive)
                .filter(|(_, &a)| a)
                .map(|(t, _)| t)
        };
        let mut around: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (t, tri) in triangles.iter().enumerate() {
            if alive[t] {
                for &v in tri {
                    around[v as usize].push(t as u32);
                }
            }
        }
        // The finest cells about twice the triangles' mean longest side at the start.
        let mut longest = 0.0;
        for [a, b, c] in live().map(corners) {
            longest += (b - a).length().max((c - b).length()).max((a - c).length());
        }
        let cell = 2.0 * longest / live().count().max(1) as f64;
        let mut grid = TriangleGrid::new(
            field.radius() * (1.0 + 1e-9),
            cell.max(1e-12),
            triangles.len(),
        );
        for (t, tri) in triangles.iter().enumerate() {
            if alive[t] {
                grid.insert(t as u32, &corners(tri));
            }
        }
        let removed_count = removed.iter().filter(|&&r| r).count();
        // Counting the removed ones too, so that `own_count - removed_count` is how many own
        // vertices are left.
        let own_count = removed_count
            + match own {
                Some(own) => (0..n).filter(|&v| own[v] && !removed[v]).count(),
                None => n - removed_count,
            };
        Work {
            field,
            vertices,
            kinds,
            log: UndoLog {
                triangle_pass: vec![0; triangles.len()],
                fan_pass: vec![0; n],
                ..UndoLog::default()
            },
            triangles,
            alive,
            around,
            removed,
            removed_count,
            own,
            own_count,
            budget,
            h: 1e-7 * field.radius(),
            grid,
            surface_normals,
            careful: Careful::default(),
            fan_changed: vec![0; n],
            sweep: 0,
        }
    }

    /// Begins the next sweep with `steps`: all of them in the first pass (`every`), else only
    /// those that [`Work::may_differ`].
    fn begin_sweep(&mut self, mut steps: Vec<Step>, every: bool) -> Vec<Step> {
        self.sweep += 1;
        if !every {
            let mut footprint = Vec::new();
            steps.retain(|&step| self.may_differ(step, &mut footprint));
        }
        steps
    }

    /// Whether `step`, refused when tried in the sweep before the last, may be decided
    /// differently now: a fan its check reads ([`Work::footprint`]) changed since that sweep
    /// began. (A refusal for a crossing with a triangle farther off may not be tried again,
    /// which only leaves a vertex the mesh could have lost.)
    fn may_differ(&self, step: Step, footprint: &mut Vec<u32>) -> bool {
        let since = self.sweep.saturating_sub(2);
        self.footprint(step, footprint);
        footprint
            .iter()
            .any(|&w| self.fan_changed[w as usize] >= since)
    }
}

/// A pass's collapses: every live edge in both directions, from a vertex the work owns
/// ([`Work::owns`]), shortest first (equal lengths in the order of the triangles).
fn shortest_first_collapses(work: &Work) -> Vec<Step> {
    let mut edges: Vec<(f64, u32, u32)> = Vec::new();
    for (t, tri) in work.triangles.iter().enumerate() {
        if !work.alive[t] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if work.own.is_some_and(|own| !own[a as usize]) {
                continue; // Refused by `Work::owns` whatever the mesh.
            }
            let length = (work.vertices[a as usize] - work.vertices[b as usize]).length();
            edges.push((length, a, b));
        }
    }
    edges.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    edges
        .iter()
        .map(|&(_, a, b)| Step::Collapse(a, b))
        .collect()
}

/// Makes at most `limit` passes over `work`'s edges (collapses shortest first, then flips),
/// until a pass removes fewer than a fiftieth of the vertices left, adding what they did to
/// `done` and calling `pass_done` with `done.passes` as each ends; `None` if `cancel`
/// stopped them.
fn passes(
    work: &mut Work,
    done: &mut Coarsened,
    limit: usize,
    cancel: &AtomicBool,
    pass_done: &(dyn Fn(usize) + Sync),
    checking: Checking,
) -> Option<()> {
    for pass in 0..limit {
        let steps = shortest_first_collapses(work);
        let steps = work.begin_sweep(steps, pass == 0);
        let (collapsed, redone) = work.make_pass(&steps, cancel, checking)?;
        done.collapses += collapsed;
        done.redone += redone;
        // Flips toward thicker triangles, which free further collapses.
        let steps: Vec<Step> = (0..work.triangles.len() as u32)
            .filter(|&t| work.alive[t as usize])
            .flat_map(|t| (0..3).map(move |k| Step::Flip(t, k)))
            .collect();
        let steps = work.begin_sweep(steps, pass == 0);
        let (flipped, redone) = work.make_pass(&steps, cancel, checking)?;
        done.flips += flipped;
        done.redone += redone;
        done.passes += 1;
        pass_done(done.passes);
        let alive_vertices = work.live_vertices();
        if collapsed * 50 < alive_vertices {
            break;
        }
    }
    Some(())
}

/// Coarsens `mesh` (object space, with each vertex's kind) by half-edge collapses within
/// `budget` of the exact boundary (object units; see the module doc), in place: removed
/// vertices are dropped and the kinds kept in step. Gives up (`None`, the mesh untouched)
/// once `cancel` is set (read between batches of collapses). `pass_done(k)` is called as
/// pass `k` (1 to at most [`MAX_PASSES`]; for a mesh split in two, as both sides have ended
/// pass `k`, then as each pass about the seam ends) ends. The steps are checked one by one
/// unless the environment variable `KARDIA_COARSEN_CHECKS` is `parallel` (batches checked in
/// parallel):
/// the mesh is the same either way, for any number of threads (on two cores, busy or quiet,
/// one by one was the faster).
pub fn coarsen(
    field: &Field,
    mesh: &mut TriangleMesh,
    kinds: &mut Vec<VertexKind>,
    budget: f64,
    cancel: &AtomicBool,
    pass_done: &(dyn Fn(usize) + Sync),
) -> Option<Coarsened> {
    let checking = match std::env::var("KARDIA_COARSEN_CHECKS").as_deref() {
        Ok("parallel") => Checking::Parallel,
        _ => Checking::Serial,
    };
    coarsen_checking(field, mesh, kinds, budget, cancel, pass_done, checking)
}

/// [`coarsen`], checking the steps of each batch as `checking` says (the result is the same
/// every way).
pub(crate) fn coarsen_checking(
    field: &Field,
    mesh: &mut TriangleMesh,
    kinds: &mut Vec<VertexKind>,
    budget: f64,
    cancel: &AtomicBool,
    pass_done: &(dyn Fn(usize) + Sync),
    checking: Checking,
) -> Option<Coarsened> {
    let n = mesh.vertices.len();
    // A large mesh's two sides of a plane first, at once, then the steps about the seam
    // (see [`regions`]).
    let seam;
    let (mut work, mut done) = match regions::Cut::of(mesh, regions::MIN_SPLIT_TRIANGLES) {
        Some(cut) => {
            let (start, band, done) = regions::coarsen_sides(
                field, mesh, kinds, budget, cut, cancel, pass_done, checking,
            )?;
            seam = band;
            let start = Start {
                own: Some(&seam),
                ..start
            };
            (
                Work::starting(field, &mesh.vertices, kinds, budget, start),
                done,
            )
        }
        None => (Work::new(field, mesh, kinds, budget), Coarsened::default()),
    };
    let limit = MAX_PASSES - done.passes;
    passes(&mut work, &mut done, limit, cancel, pass_done, checking)?;
    // Compact: live triangles, live vertices renumbered.
    let mut index = vec![u32::MAX; n];
    let mut vertices = Vec::with_capacity(n - done.collapses);
    let mut new_kinds = Vec::with_capacity(n - done.collapses);
    for v in 0..n {
        if !work.removed[v] {
            index[v] = vertices.len() as u32;
            vertices.push(mesh.vertices[v]);
            new_kinds.push(kinds[v]);
        }
    }
    let triangles = work
        .triangles
        .iter()
        .zip(&work.alive)
        .filter(|(_, &alive)| alive)
        .map(|(t, _)| t.map(|v| index[v as usize]))
        .collect();
    *mesh = TriangleMesh {
        vertices,
        triangles,
    };
    *kinds = new_kinds;
    Some(done)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{check, extract, SolidKind};
    use crate::shapes::implicit::expand;

    #[test]
    fn quality_is_one_for_an_equilateral_triangle_and_zero_for_a_flat_one() {
        let equilateral = [DVec3::ZERO, DVec3::X, DVec3::new(0.5, 0.75f64.sqrt(), 0.0)];
        assert!((quality(equilateral) - 1.0).abs() < 1e-12);
        assert_eq!(quality([DVec3::ZERO, DVec3::X, DVec3::X * 2.0]), 0.0);
    }

    #[test]
    fn a_thin_triangle_is_made_only_along_the_surface() {
        // On the cylinder x² + y² = 1, a thin triangle along the axis lies along the surface;
        // the same triangle turned across it (around the cylinder) does not.
        let poly = expand("x^2 + y^2 = 1").unwrap();
        let field = Field::new(&poly, 3.0, SolidKind::Inside);
        let at = |angle: f64, z: f64| DVec3::new(angle.cos(), angle.sin(), z);
        let vertices = vec![
            at(0.0, 0.0),
            at(0.05, 0.0),
            at(0.0, 1.0),
            at(0.0, 0.0),
            at(0.3, 0.01),
            at(0.6, 0.0),
        ];
        let kinds = vec![VertexKind::Surface; vertices.len()];
        let mesh = TriangleMesh {
            vertices: vertices.clone(),
            triangles: vec![[0, 1, 2], [3, 4, 5]],
        };
        let h = 1e-7;
        let work = Work {
            field: &field,
            vertices: &vertices,
            kinds: &kinds,
            triangles: mesh.triangles.clone(),
            alive: vec![true; 2],
            around: vec![Vec::new(); vertices.len()],
            removed: vec![false; vertices.len()],
            removed_count: 0,
            own: None,
            own_count: vertices.len(),
            budget: 1.0,
            h,
            grid: TriangleGrid::new(3.0, 0.5, 2),
            surface_normals: vertices
                .iter()
                .map(|&p| field.gradient(p, h).normalize())
                .collect(),
            careful: Careful::default(),
            log: UndoLog::default(),
            fan_changed: vec![0; vertices.len()],
            sweep: 0,
        };
        let (along, across) = (mesh.corners(0), mesh.corners(1));
        assert!(quality(along) < MIN_QUALITY && quality(along) > THIN_QUALITY);
        assert!(quality(across) < MIN_QUALITY && quality(across) > THIN_QUALITY);
        // Outward winding: the normal of [0, 1, 2] points away from the axis.
        assert!(work.thin_enough([0, 1, 2], 1.0, true));
        assert!(!work.thin_enough([3, 4, 5], 1.0, true));
        // Inward (reversed) is refused, and so is either one when only quality counts.
        assert!(!work.thin_enough([0, 2, 1], 1.0, true));
        assert!(work.thin_enough([3, 4, 5], 0.01, true));
    }

    #[test]
    fn the_coarsening_is_the_same_for_one_thread_and_two() {
        // One thread makes the steps one by one; two check them in batches in parallel and
        // recheck the verdicts an earlier step of the batch made stale: the same mesh.
        let poly = expand("x^4 + y^4 + z^4 - 0.5*(x^2 + y^2 + z^2) = 0.4").unwrap();
        let field = Field::new(&poly, 1.5, SolidKind::Inside);
        let grid = extract::Grid::covering(1.5, 0.03);
        let (extracted, extracted_kinds) = extract::march(&field, grid, &|_, _| {});
        let run = |threads: usize, checking: Checking| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (mut mesh, mut kinds) = (extracted.clone(), extracted_kinds.clone());
            let done = pool
                .install(|| {
                    coarsen_checking(
                        &field,
                        &mut mesh,
                        &mut kinds,
                        0.01,
                        &AtomicBool::new(false),
                        &|_| {},
                        checking,
                    )
                })
                .unwrap();
            (mesh, kinds, done)
        };
        let one = run(1, Checking::Serial);
        let two = run(2, Checking::Parallel);
        eprintln!(
            "{} -> {} triangles, {:?}",
            extracted.triangles.len(),
            one.0.triangles.len(),
            one.2
        );
        assert!(one.2.collapses > 1000 && one.2.flips > 0, "{:?}", one.2);
        check::verify(&one.0).unwrap();
        assert!(one == two, "the meshes differ between 1 and 2 threads");
    }

    /// The extracted mesh of the unit sphere (clip radius 3, grid step 0.1).
    fn sphere_mesh(field: &Field) -> (TriangleMesh, Vec<VertexKind>) {
        extract::march(field, extract::Grid::covering(3.0, 0.1), &|_, _| {})
    }

    /// The unit sphere clipped to radius 3, as [`sphere_mesh`] meshes it.
    fn unit_sphere() -> Field {
        Field::new(
            &expand("x^2 + y^2 + z^2 = 1").unwrap(),
            3.0,
            SolidKind::Inside,
        )
    }

    #[test]
    fn a_later_sweep_skips_only_steps_still_refused() {
        let field = unit_sphere();
        let (mesh, kinds) = sphere_mesh(&field);
        let mut work = Work::new(&field, &mesh, &kinds, 0.004);
        let cancel = AtomicBool::new(false);
        let mut done = Coarsened::default();
        passes(&mut work, &mut done, 2, &cancel, &|_| {}, Checking::Serial).unwrap();
        assert!(work.removed_count > 100, "{}", work.removed_count);
        // The third pass's collapses: those skipped are refused on the mesh as it is.
        // (The sweep keeps its steps in order, so what it left out is found in one walk.)
        let steps = shortest_first_collapses(&work);
        let tried = work.begin_sweep(steps.clone(), false);
        let mut tried = tried.iter().peekable();
        let skipped: Vec<Step> = steps
            .iter()
            .copied()
            .filter(|step| tried.next_if_eq(&step).is_none())
            .collect();
        assert!(
            !skipped.is_empty() && skipped.len() < steps.len(),
            "{} of {}",
            skipped.len(),
            steps.len()
        );
        let mut scratch = Scratch::default();
        for step in skipped {
            assert!(!work.check(step, &mut scratch).ok, "{step:?}");
        }
    }

    #[test]
    fn undoing_a_pass_gives_back_the_mesh_as_it_began() {
        let field = unit_sphere();
        let (mesh, kinds) = sphere_mesh(&field);
        let mut work = Work::new(&field, &mesh, &kinds, 0.05);
        let fans = |work: &Work| {
            work.around
                .iter()
                .map(|f| {
                    let mut f = f.clone();
                    f.sort_unstable();
                    f
                })
                .collect::<Vec<_>>()
        };
        let before = (work.triangles.clone(), fans(&work), work.removed.clone());
        work.begin_pass();
        let steps = shortest_first_collapses(&work);
        let made = make(
            &mut work,
            &steps,
            &AtomicBool::new(false),
            Checking::Serial,
            &mut Record::default(),
        )
        .unwrap();
        assert!(made > 100, "{made}");
        assert!(work.removed_count == made && !work.log.triangles.is_empty());
        work.undo_pass();
        assert_eq!(work.removed_count, 0);
        assert!(work.alive.iter().all(|&a| a));
        assert!((work.triangles.clone(), fans(&work), work.removed.clone()) == before);
        // The grid holds every triangle again, with its box as it began.
        let everywhere = Box32::around(&[DVec3::splat(-3.0), DVec3::splat(3.0), DVec3::ZERO]);
        let mut kept = Vec::new();
        work.grid.any_near(&everywhere, |b| {
            kept.push((b.triangle, b.bounds));
            false
        });
        kept.sort_unstable_by_key(|k| k.0);
        assert_eq!(kept.len(), mesh.triangles.len());
        for (t, bounds) in kept {
            assert_eq!(bounds, Box32::around(&mesh.corners(t as usize)));
        }
    }

    #[test]
    fn the_end_of_pass_test_finds_the_crossings_of_changed_triangles() {
        // Two spheres of radius 1, 1.5 apart, pass through each other; 3 apart, they do not.
        let field = unit_sphere();
        let (one, one_kinds) = sphere_mesh(&field);
        let two_spheres = |apart: f64| {
            let mut mesh = one.clone();
            let count = one.vertices.len() as u32;
            mesh.vertices
                .extend(one.vertices.iter().map(|&p| p + DVec3::X * apart));
            mesh.triangles
                .extend(one.triangles.iter().map(|t| t.map(|v| v + count)));
            mesh
        };
        let kinds = [one_kinds.clone(), one_kinds].concat();
        for (apart, crossing) in [(1.5, true), (3.0, false)] {
            let mesh = two_spheres(apart);
            let mut work = Work::new(&field, &mesh, &kinds, 0.05);
            work.begin_pass();
            assert!(work.crossings_made().is_empty(), "nothing changed yet");
            // The second sphere's triangles marked changed, as if a pass had made them.
            for t in one.triangles.len()..mesh.triangles.len() {
                work.log_triangle(t as u32);
            }
            let found = work.crossings_made();
            assert_eq!(
                !found.is_empty(),
                crossing,
                "{apart}: {} found",
                found.len()
            );
            assert_eq!(!check::crossing_triangles(&mesh).is_empty(), crossing);
        }
    }

    #[test]
    fn a_coarsened_sphere_keeps_every_guarantee_with_far_fewer_triangles() {
        let poly = expand("x^2 + y^2 + z^2 = 1").unwrap();
        let field = Field::new(&poly, 1.5, SolidKind::Inside);
        let grid = extract::Grid::covering(1.5, 0.04);
        let (mut mesh, mut kinds) = extract::march(&field, grid, &|_, _| {});
        let before = mesh.triangles.len();
        let done = coarsen(
            &field,
            &mut mesh,
            &mut kinds,
            0.01,
            &AtomicBool::new(false),
            &|_| {},
        )
        .unwrap();
        let v = check::verify(&mesh).unwrap();
        assert_eq!((v.components, v.euler_characteristic), (1, 2));
        assert_eq!(kinds.len(), mesh.vertices.len());
        eprintln!("{before} -> {} triangles, {done:?}", mesh.triangles.len());
        assert!(
            mesh.triangles.len() * 4 < before,
            "{before} -> {}",
            mesh.triangles.len()
        );
        for p in &mesh.vertices {
            assert!((p.length() - 1.0).abs() < 1e-12);
        }
        // Every triangle's centroid within the budget (chord error of the sphere).
        for t in 0..mesh.triangles.len() {
            let [a, b, c] = mesh.corners(t);
            assert!(1.0 - ((a + b + c) / 3.0).length() <= 0.0101);
        }
    }
}
