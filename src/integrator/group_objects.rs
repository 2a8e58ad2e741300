//! Which objects the camera rays of each group of [`LANES`] neighbouring pixels may meet: a
//! list per group, worked out with the seen mask (`scheduler::seen_mask`) from the same
//! per-row spans of each object's image, so that a group's camera rays ask those objects alone
//! instead of walking the scene's hierarchy from its root.
//!
//! A group is [`LANES`] pixels of one row of a region, from a region column that is a
//! multiple of [`LANES`] (the scheduler's groups: tiles are [`super::TILE_SIZE`] wide, a
//! multiple of it). Lists are stored one after another (compressed rows): building costs a
//! count and a copy of the objects' marks, a lookup two reads.

use crate::geometry::LANES;

/// Each group's objects, in ascending order without repeats: every object marked on a pixel
/// of the group ([`GroupObjectsBuilder::mark`]).
#[derive(Debug, Clone)]
pub(super) struct GroupObjects {
    /// Groups a row: the region's width in pixels over [`LANES`], rounded up.
    groups_per_row: usize,
    /// Group `g`'s objects are `objects[starts[g] .. starts[g + 1]]`.
    starts: Vec<u32>,
    objects: Vec<u32>,
}

impl GroupObjects {
    /// The objects marked on the group of row `row` (from the region's top) whose first pixel
    /// is region column `column`, or `None` when `column` does not start a group or the row or
    /// column lie outside the region.
    #[inline]
    pub(super) fn of(&self, row: usize, column: u32) -> Option<&[u32]> {
        let column = column as usize;
        if !column.is_multiple_of(LANES) || column / LANES >= self.groups_per_row {
            return None;
        }
        let group = row.checked_mul(self.groups_per_row)? + column / LANES;
        let (&start, &end) = (self.starts.get(group)?, self.starts.get(group + 1)?);
        Some(&self.objects[start as usize..end as usize])
    }
}

/// Collects the marks of the objects, one object at a time in ascending order, and makes the
/// lists ([`GroupObjectsBuilder::finish`]).
#[derive(Debug)]
pub(super) struct GroupObjectsBuilder {
    width: u32,
    height: u32,
    groups_per_row: usize,
    /// `(group, object)` in the order marked.
    marks: Vec<(u32, u32)>,
    /// Where the current object's marks start in `marks`.
    object_start: usize,
    /// The current object, the last row marked for it, and whether a row was marked again
    /// or out of order (its marks are then sorted and their repeats dropped).
    object: u32,
    last_row: Option<usize>,
    repeats: bool,
}

impl GroupObjectsBuilder {
    /// No mark yet, for a region of `width × height` pixels; `None` when it has more groups
    /// than a `u32` counts.
    pub(super) fn new(width: u32, height: u32) -> Option<Self> {
        let groups_per_row = (width as usize).div_ceil(LANES);
        let groups = groups_per_row.checked_mul(height as usize)?;
        u32::try_from(groups).ok()?;
        Some(Self {
            width,
            height,
            groups_per_row,
            marks: Vec::new(),
            object_start: 0,
            object: 0,
            last_row: None,
            repeats: false,
        })
    }

    /// Starts the marks of `object`, which must be above every object marked before.
    pub(super) fn start_object(&mut self, object: u32) {
        self.close_object();
        self.object = object;
    }

    /// Marks the current object on the region's `row` in region columns `lo ..= hi`, clipped
    /// to the region (nothing when `lo > hi`, or for a row below the region); a row may be
    /// marked several times, in any order (the object is listed once a group).
    pub(super) fn mark(&mut self, row: usize, (lo, hi): (i64, i64)) {
        let (lo, hi) = (lo.max(0), hi.min(i64::from(self.width) - 1));
        if lo > hi || row >= self.height as usize {
            return;
        }
        self.repeats |= self.last_row.is_some_and(|last| row <= last);
        self.last_row = Some(row);
        let base = row * self.groups_per_row;
        for group in lo as usize / LANES..=hi as usize / LANES {
            // Fits: `new` checked the number of groups.
            self.marks.push(((base + group) as u32, self.object));
        }
    }

    /// Ends the current object's marks: sorted by group, repeats dropped, where a row was
    /// marked again or out of order.
    fn close_object(&mut self) {
        if self.repeats {
            let own = &mut self.marks[self.object_start..];
            own.sort_unstable();
            let mut kept = self.object_start;
            for i in self.object_start..self.marks.len() {
                if kept == self.object_start || self.marks[kept - 1] != self.marks[i] {
                    self.marks[kept] = self.marks[i];
                    kept += 1;
                }
            }
            self.marks.truncate(kept);
        }
        self.object_start = self.marks.len();
        self.last_row = None;
        self.repeats = false;
    }

    /// The lists: each group's objects in the order marked (ascending).
    pub(super) fn finish(mut self) -> GroupObjects {
        self.close_object();
        let groups = self.groups_per_row * self.height as usize;
        let mut starts = vec![0u32; groups + 1];
        for &(group, _) in &self.marks {
            starts[group as usize + 1] += 1;
        }
        for g in 0..groups {
            starts[g + 1] += starts[g];
        }
        let mut next = starts.clone();
        let mut objects = vec![0u32; self.marks.len()];
        for &(group, object) in &self.marks {
            let at = &mut next[group as usize];
            objects[*at as usize] = object;
            *at += 1;
        }
        GroupObjects {
            groups_per_row: self.groups_per_row,
            starts,
            objects,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_group_lists_the_objects_marked_on_its_pixels_once_in_order() {
        // A region 10 wide (groups of columns 0–3, 4–7, 8–9) and 3 tall.
        let mut b = GroupObjectsBuilder::new(10, 3).unwrap();
        b.start_object(2);
        b.mark(0, (3, 4));
        b.mark(1, (9, 9));
        b.start_object(5);
        // Row 2 before row 0, and row 0 twice (as an object with several cells marks them):
        // listed once a group.
        b.mark(2, (5, 4)); // empty
        b.mark(2, (-1, 2)); // clipped to the region
        b.mark(0, (0, 1));
        b.mark(0, (2, 6));
        b.mark(3, (0, 9)); // below the region
        b.start_object(7);
        b.mark(0, (8, 12));
        let lists = b.finish();
        let of = |row, column| lists.of(row, column).map(<[u32]>::to_vec);
        assert_eq!(of(0, 0), Some(vec![2, 5]));
        assert_eq!(of(0, 4), Some(vec![2, 5]));
        assert_eq!(of(0, 8), Some(vec![7]));
        assert_eq!(of(1, 0), Some(vec![]));
        assert_eq!(of(1, 8), Some(vec![2]));
        assert_eq!(of(2, 0), Some(vec![5]));
        assert_eq!(of(2, 4), Some(vec![]));
        // Not a group's first column, past the region's columns or rows.
        assert_eq!(of(0, 2), None);
        assert_eq!(of(0, 12), None);
        assert_eq!(of(3, 0), None);
    }
}
