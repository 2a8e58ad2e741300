//! The triangles' bounding boxes in a hierarchy of loose uniform grids over the clip ball, kept
//! up to date as the coarsening changes triangles, so that a new fan is tested only against
//! the triangles near it.
//!
//! Boxes are stored as `f32` rounded outward (half the memory of `f64`, and never smaller than
//! the exact box, so no overlap is missed); every level is a dense array of cells, each a short
//! list of boxes.

use crate::geometry::DVec3;

/// An axis-aligned box in `f32`, rounded outward from the `f64` box it stands for (it holds
/// that box, so two exact boxes that overlap give `Box32`s that overlap).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Box32 {
    lo: [f32; 3],
    hi: [f32; 3],
}

/// `x` rounded to `f32` toward −∞.
fn down(x: f64) -> f32 {
    let r = x as f32;
    if f64::from(r) > x {
        r.next_down()
    } else {
        r
    }
}

/// `x` rounded to `f32` toward +∞.
fn up(x: f64) -> f32 {
    let r = x as f32;
    if f64::from(r) < x {
        r.next_up()
    } else {
        r
    }
}

impl Box32 {
    /// The box of a triangle's corners, rounded outward.
    pub(super) fn around(points: &[DVec3; 3]) -> Self {
        let lo = points[0].min(points[1]).min(points[2]);
        let hi = points[0].max(points[1]).max(points[2]);
        Self {
            lo: [down(lo.x), down(lo.y), down(lo.z)],
            hi: [up(hi.x), up(hi.y), up(hi.z)],
        }
    }

    /// The smallest box holding both.
    pub(super) fn union(self, other: Self) -> Self {
        Self {
            lo: [0, 1, 2].map(|k| self.lo[k].min(other.lo[k])),
            hi: [0, 1, 2].map(|k| self.hi[k].max(other.hi[k])),
        }
    }

    /// Whether the two (closed) boxes overlap.
    #[inline]
    pub(super) fn overlaps(&self, other: &Self) -> bool {
        self.lo[0] <= other.hi[0]
            && other.lo[0] <= self.hi[0]
            && self.lo[1] <= other.hi[1]
            && other.lo[1] <= self.hi[1]
            && self.lo[2] <= other.hi[2]
            && other.lo[2] <= self.hi[2]
    }

    /// The box grown by `by` (≥ 0) on every side, rounded outward.
    pub(super) fn grown(self, by: f64) -> Self {
        Self {
            lo: self.lo.map(|x| down(f64::from(x) - by)),
            hi: self.hi.map(|x| up(f64::from(x) + by)),
        }
    }

    /// The largest side.
    pub(super) fn extent(&self) -> f64 {
        (0..3)
            .map(|k| f64::from(self.hi[k]) - f64::from(self.lo[k]))
            .fold(0.0, f64::max)
    }

    /// The centre.
    fn centre(&self) -> [f64; 3] {
        [0, 1, 2].map(|k| 0.5 * (f64::from(self.lo[k]) + f64::from(self.hi[k])))
    }
}

/// A triangle in a cell, with its box.
#[derive(Clone, Copy, Debug)]
pub(super) struct Boxed {
    /// The box (rounded outward).
    pub(super) bounds: Box32,
    /// The triangle's index.
    pub(super) triangle: u32,
}

/// One level of [`TriangleGrid`]: `dims³` cells of side `side`.
struct Level {
    side: f64,
    dims: usize,
    cells: Vec<Vec<Boxed>>,
    /// Boxes held at this level.
    count: usize,
}

/// Where a triangle is kept: its level and cell (`level == u8::MAX`: nowhere).
#[derive(Clone, Copy)]
struct Home {
    level: u8,
    cell: u32,
}

/// The triangles' boxes in a hierarchy of loose uniform grids over the cube
/// `[−radius, radius]³`. A triangle is kept in one cell: that of its box's centre in the finest
/// level whose cells are at least as large as its box, so a box query at a level need only look
/// half a cell beyond the box.
pub(super) struct TriangleGrid {
    lo: f64,
    /// Finest first, each next level's cells twice as large, the last one cell.
    levels: Vec<Level>,
    /// Per triangle index, where it is kept.
    homes: Vec<Home>,
}

/// The most cells of one level (a dense array of short lists): a finer level is not made.
const MAX_CELLS: usize = 1 << 21;

impl TriangleGrid {
    /// An empty hierarchy over the cube `[−radius, radius]³` for triangles numbered below
    /// `triangles`, the finest cells of side about `cell` (coarser if that needs more than
    /// [`MAX_CELLS`] cells), each next level's twice as large, the last one cell.
    pub(super) fn new(radius: f64, cell: f64, triangles: usize) -> Self {
        let mut levels = Vec::new();
        let mut dims = ((2.0 * radius / cell).ceil() as usize).clamp(1, 1 << 20);
        while dims.pow(3) > MAX_CELLS {
            dims = dims.div_ceil(2);
        }
        loop {
            levels.push(Level {
                side: 2.0 * radius / dims as f64,
                dims,
                cells: vec![Vec::new(); dims.pow(3)],
                count: 0,
            });
            if dims == 1 {
                break;
            }
            dims = dims.div_ceil(2);
        }
        Self {
            lo: -radius,
            levels,
            homes: vec![
                Home {
                    level: u8::MAX,
                    cell: 0
                };
                triangles
            ],
        }
    }

    /// The index along a side of the cell holding coordinate `x` at a level.
    #[inline]
    fn index(&self, x: f64, level: &Level) -> usize {
        // Truncation is the floor here: what is negative (or NaN) goes to 0 either way.
        let i = ((x - self.lo) / level.side).max(0.0);
        (i as usize).min(level.dims - 1)
    }

    /// Keeps triangle `triangle` (below the count given to [`TriangleGrid::new`], not kept
    /// already) with the box of its corners `c`.
    pub(super) fn insert(&mut self, triangle: u32, c: &[DVec3; 3]) {
        let bounds = Box32::around(c);
        let extent = bounds.extent();
        let level = self
            .levels
            .iter()
            .position(|l| l.side >= extent)
            .unwrap_or(self.levels.len() - 1);
        let centre = bounds.centre();
        let l = &self.levels[level];
        let [x, y, z] = centre.map(|v| self.index(v, l));
        let cell = (x * l.dims + y) * l.dims + z;
        let l = &mut self.levels[level];
        l.cells[cell].push(Boxed { bounds, triangle });
        l.count += 1;
        self.homes[triangle as usize] = Home {
            level: level as u8,
            cell: cell as u32,
        };
    }

    /// Drops triangle `triangle` (if kept).
    pub(super) fn remove(&mut self, triangle: u32) {
        let home = std::mem::replace(
            &mut self.homes[triangle as usize],
            Home {
                level: u8::MAX,
                cell: 0,
            },
        );
        if home.level == u8::MAX {
            return;
        }
        let l = &mut self.levels[usize::from(home.level)];
        let list = &mut l.cells[home.cell as usize];
        if let Some(k) = list.iter().position(|b| b.triangle == triangle) {
            list.swap_remove(k);
            l.count -= 1;
        }
    }

    /// Calls `visit` with every kept triangle whose box may overlap `query` (each once, and
    /// every one whose box does), until it returns true; whether it did.
    pub(super) fn any_near(&self, query: &Box32, mut visit: impl FnMut(&Boxed) -> bool) -> bool {
        for level in &self.levels {
            if level.count == 0 {
                continue;
            }
            let reach = 0.5 * level.side;
            let [x0, y0, z0] = query.lo.map(|v| self.index(f64::from(v) - reach, level));
            let [x1, y1, z1] = query.hi.map(|v| self.index(f64::from(v) + reach, level));
            let dims = level.dims;
            for x in x0..=x1 {
                for y in y0..=y1 {
                    let row = (x * dims + y) * dims;
                    for list in &level.cells[row + z0..=row + z1] {
                        for b in list {
                            if visit(b) {
                                return true;
                            }
                        }
                    }
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_are_rounded_outward() {
        let p = [
            DVec3::new(0.1, -0.3, 1.0 / 3.0),
            DVec3::new(0.7, 0.2, -2.0 / 3.0),
            DVec3::new(1e-9, 0.1 + 1e-12, 0.0),
        ];
        let b = Box32::around(&p);
        for q in p {
            for k in 0..3 {
                assert!(f64::from(b.lo[k]) <= q[k] && q[k] <= f64::from(b.hi[k]));
            }
        }
        // Two exact boxes touching in one coordinate still overlap once rounded.
        let a = Box32::around(&[DVec3::splat(0.1); 3]);
        let c = Box32::around(&[
            DVec3::new(0.1, 0.1, 0.1),
            DVec3::splat(0.2),
            DVec3::splat(0.2),
        ]);
        assert!(a.overlaps(&c) && c.overlaps(&a));
        let far = Box32::around(&[DVec3::splat(0.1 + 1e-6); 3]);
        assert!(!a.overlaps(&far));
    }

    #[test]
    fn the_triangle_grid_finds_every_box_that_overlaps_a_query_as_triangles_change() {
        // Triangles of many sizes (a few much larger than the finest cells) in a ball of
        // radius 2; some moved, some removed; every query must see every overlapping box.
        let mut seed = 12345u64;
        let mut random = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut point = |scale: f64, at: DVec3| {
            at + scale * DVec3::new(random() - 0.5, random() - 0.5, random() - 0.5)
        };
        let mut grid = TriangleGrid::new(2.0, 0.05, 3000);
        let mut triangles: Vec<Option<[DVec3; 3]>> = Vec::new();
        for i in 0..3000 {
            let at = point(2.2, DVec3::ZERO);
            let size = [0.02, 0.1, 0.5, 2.0][i % 4];
            let t = [point(size, at), point(size, at), point(size, at)]
                .map(|p| p.clamp(DVec3::splat(-2.0), DVec3::splat(2.0)));
            grid.insert(i as u32, &t);
            triangles.push(Some(t));
        }
        for i in (0..3000).step_by(3) {
            let old = triangles[i].unwrap();
            grid.remove(i as u32);
            if i % 2 == 0 {
                triangles[i] = None;
            } else {
                let moved = old.map(|p| (p * 0.5).clamp(DVec3::splat(-2.0), DVec3::splat(2.0)));
                grid.insert(i as u32, &moved);
                triangles[i] = Some(moved);
            }
        }
        let mut overlapping = 0;
        for _ in 0..200 {
            let (a, b) = (point(2.0, DVec3::ZERO), point(0.3, DVec3::ZERO));
            let query = Box32::around(&[a, a + b, a]);
            let mut seen = Vec::new();
            grid.any_near(&query, |b| {
                seen.push(b.triangle);
                false
            });
            seen.sort_unstable();
            let count = seen.len();
            seen.dedup();
            assert_eq!(seen.len(), count, "a triangle visited twice");
            for (i, t) in triangles.iter().enumerate() {
                let Some(t) = t else {
                    assert!(seen.binary_search(&(i as u32)).is_err(), "removed {i} seen");
                    continue;
                };
                if Box32::around(t).overlaps(&query) {
                    overlapping += 1;
                    assert!(seen.binary_search(&(i as u32)).is_ok(), "{i} missed");
                }
            }
        }
        assert!(overlapping > 1000, "{overlapping}");
    }
}
