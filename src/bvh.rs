//! A bounding volume hierarchy over anything with a box: built once in O(n log n) by binned
//! surface-area heuristic, stored flat (depth first, a node's first child right after it), and
//! walked by one ray or by [`LANES`] rays at once, nearest child first.
//!
//! It knows items only by an id and an [`Aabb`]: the scene uses it for its objects (with the
//! object's index as id), and a mesh can use it for its triangles. The walk hands each item of
//! a leaf the ray meets to a visitor, which asks the item itself and may shrink the ray's
//! range; what "nearest" means (ties, any hit) is the visitor's to say.

use crate::geometry::{Aabb, DVec3, Ray, RayLanes, LANES};

/// Most items a leaf holds.
const MAX_LEAF: usize = 4;
/// Buckets of the binned surface-area heuristic along the chosen axis.
const BINS: usize = 12;
/// Depth beyond which nodes are split at the median, so the walk's stack (of
/// [`MAX_DEPTH`] entries) never overflows whatever the boxes.
const SAH_DEPTH: usize = 40;
/// The deepest a node can be: below [`SAH_DEPTH`] each median split halves the items, and
/// fewer than 2⁶⁴ items fit in memory.
const MAX_DEPTH: usize = SAH_DEPTH + 64;
/// Cost of walking into a node, relative to asking one item (the heuristic's only constant).
const TRAVERSAL_COST: f64 = 0.5;
/// [`Node::parent`] of the root.
const NO_PARENT: u32 = u32::MAX;

/// One node of the flattened tree.
#[derive(Debug, Clone, Copy)]
struct Node {
    /// Holds every item below the node.
    bounds: Aabb,
    /// A leaf: its first item in [`Bvh::items`]; an inner node: the index of its second
    /// child (its first is the next node).
    offset: u32,
    /// A leaf: how many items it holds (≥ 1); an inner node: 0.
    count: u32,
    /// The node's parent ([`NO_PARENT`] for the root).
    parent: u32,
    /// An inner node: the axis its children were split on, the first child's items lower.
    axis: u8,
}

/// A bounding volume hierarchy over items given as `(id, box)`: every finite box is held
/// by each of its ancestors' boxes, and each item sits in exactly one leaf.
#[derive(Debug, Clone, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// The items' ids, leaf by leaf.
    items: Vec<u32>,
}

/// An item while building: its id, box and the box's centre.
#[derive(Clone, Copy)]
struct Build {
    id: u32,
    bounds: Aabb,
    centre: DVec3,
}

impl Bvh {
    /// The hierarchy of `items` (each an id and a box with finite corners, or an empty box
    /// such as [`Aabb::EMPTY`], which holds nothing: the walk need not visit it). Ids need not be distinct or in order. Time
    /// O(n log n) for n items.
    ///
    /// # Panics
    /// When a box has a NaN or infinite corner other than [`Aabb::EMPTY`]'s, or when there are
    /// 2³² items or more.
    pub fn new(items: &[(u32, Aabb)]) -> Self {
        assert!(
            u32::try_from(items.len()).is_ok(),
            "too many items for a Bvh"
        );
        let mut build: Vec<Build> = items
            .iter()
            .map(|&(id, bounds)| {
                let empty = bounds.min.cmpgt(bounds.max).any();
                assert!(
                    bounds.is_finite() || empty,
                    "a Bvh holds finite boxes only: {bounds:?}"
                );
                // An empty box sorts with the others by a centre of zeros.
                let centre = if empty {
                    DVec3::ZERO
                } else {
                    (bounds.min + bounds.max) * 0.5
                };
                Build { id, bounds, centre }
            })
            .collect();
        let mut bvh = Self {
            nodes: Vec::with_capacity(2 * items.len().div_ceil(MAX_LEAF).max(1)),
            items: Vec::with_capacity(items.len()),
        };
        if !build.is_empty() {
            bvh.split(&mut build, 0, NO_PARENT);
        }
        bvh
    }

    /// Whether it holds no item.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// The number of items it holds.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Each item as `(id, leaf)`: the leaf that holds it, by which [`Bvh::walk_lanes_from`]
    /// starts a walk there.
    pub fn item_leaves(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        self.nodes
            .iter()
            .enumerate()
            .filter(|(_, n)| n.count > 0)
            .flat_map(move |(k, n)| {
                let first = n.offset as usize;
                // Fits: fewer nodes than twice the items (see `split`).
                self.items[first..first + n.count as usize]
                    .iter()
                    .map(move |&id| (id, k as u32))
            })
    }

    /// Adds the node of `items` (non-empty) at `depth`, below node `parent`, and its subtree;
    /// returns its index.
    fn split(&mut self, items: &mut [Build], depth: usize, parent: u32) -> usize {
        let bounds = items.iter().fold(Aabb::EMPTY, |b, i| b.union(i.bounds));
        let index = self.nodes.len();
        self.nodes.push(Node {
            bounds,
            offset: 0,
            count: 0,
            parent,
            axis: 0,
        });
        let Some((axis, mid)) = self.choose_split(items, &bounds, depth) else {
            self.nodes[index].offset = self.items.len() as u32;
            self.nodes[index].count = items.len() as u32;
            self.items.extend(items.iter().map(|i| i.id));
            return index;
        };
        let (low, high) = items.split_at_mut(mid);
        // Fits: fewer nodes than twice the items, which `new` checked fit in a `u32`.
        self.split(low, depth + 1, index as u32);
        let second = self.split(high, depth + 1, index as u32);
        self.nodes[index].offset = second as u32;
        self.nodes[index].axis = axis as u8;
        index
    }

    /// Splits `items` in place into two non-empty parts, the first lower along the returned
    /// axis, and returns `(axis, length of the first part)`; `None` when they are better kept
    /// as one leaf.
    fn choose_split(
        &self,
        items: &mut [Build],
        bounds: &Aabb,
        depth: usize,
    ) -> Option<(usize, usize)> {
        let n = items.len();
        if n <= 1 {
            return None;
        }
        let centres = items.iter().fold(Aabb::EMPTY, |b, i| b.including(i.centre));
        let extent = centres.max - centres.min;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let by_centre = |a: &Build, b: &Build| a.centre[axis].total_cmp(&b.centre[axis]);
        if extent[axis] <= 0.0 || depth >= SAH_DEPTH {
            // All centres alike (or too deep for the heuristic): a leaf if small enough,
            // else halves by count.
            if n <= MAX_LEAF {
                return None;
            }
            items.select_nth_unstable_by(n / 2, by_centre);
            return Some((axis, n / 2));
        }
        // Binned SAH: each item to one of BINS buckets by its centre.
        let (lo, scale) = (centres.min[axis], BINS as f64 / extent[axis]);
        let bin_of = |c: f64| (((c - lo) * scale) as usize).min(BINS - 1);
        let mut counts = [0usize; BINS];
        let mut boxes = [Aabb::EMPTY; BINS];
        for item in items.iter() {
            let b = bin_of(item.centre[axis]);
            counts[b] += 1;
            boxes[b] = boxes[b].union(item.bounds);
        }
        // Cost of cutting after bin k: areas of both sides times their counts.
        let mut below = [(0usize, 0.0f64); BINS - 1];
        let (mut count, mut acc) = (0, Aabb::EMPTY);
        for k in 0..BINS - 1 {
            count += counts[k];
            acc = acc.union(boxes[k]);
            below[k] = (count, half_area(&acc));
        }
        let (mut best, mut best_cost) = (0, f64::INFINITY);
        let (mut count, mut acc) = (0, Aabb::EMPTY);
        for k in (0..BINS - 1).rev() {
            count += counts[k + 1];
            acc = acc.union(boxes[k + 1]);
            let (n_below, a_below) = below[k];
            if n_below == 0 || count == 0 {
                continue;
            }
            let cost = n_below as f64 * a_below + count as f64 * half_area(&acc);
            if cost < best_cost {
                (best, best_cost) = (k, cost);
            }
        }
        let area = half_area(bounds);
        let split_cost = TRAVERSAL_COST + best_cost / area.max(f64::MIN_POSITIVE);
        if n <= MAX_LEAF && (split_cost.is_nan() || split_cost >= n as f64) {
            return None;
        }
        if best_cost.is_infinite() {
            items.select_nth_unstable_by(n / 2, by_centre);
            return Some((axis, n / 2));
        }
        let mut mid = 0;
        for i in 0..n {
            if bin_of(items[i].centre[axis]) <= best {
                items.swap(i, mid);
                mid += 1;
            }
        }
        Some((axis, mid))
    }

    /// Walks the tree for `ray` on `(t_min, t_max)`: calls `visit(id, &mut t_max)` for each
    /// item of each leaf whose box the ray meets within the current range (nearest child
    /// first), where `visit` asks the item (the item's own box is not tested here) and may
    /// lower `t_max`; lowering it below `t_min` (e.g. to `−∞`) ends the walk. Every item whose
    /// box meets the ray on the range as it stands when its leaf is reached is visited.
    #[inline]
    pub fn walk(
        &self,
        ray: &Ray,
        t_min: f64,
        mut t_max: f64,
        mut visit: impl FnMut(u32, &mut f64),
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let inv = DVec3::ONE / ray.dir;
        // Never read beyond `top`: left uninitialised (zeroing it cost more than a short walk).
        let mut stack = [std::mem::MaybeUninit::<u32>::uninit(); MAX_DEPTH];
        let mut top = 0;
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            if t_max >= t_min && meets(&n.bounds, ray, inv, t_min, t_max) {
                if n.count > 0 {
                    let first = n.offset as usize;
                    for &id in &self.items[first..first + n.count as usize] {
                        visit(id, &mut t_max);
                        if t_max.is_nan() || t_min.is_nan() || t_max < t_min {
                            return;
                        }
                    }
                } else {
                    // Nearest child first: the first child is lower along the axis.
                    let (near, far) = if ray.dir[n.axis as usize] >= 0.0 {
                        (node + 1, n.offset as usize)
                    } else {
                        (n.offset as usize, node + 1)
                    };
                    stack[top].write(far as u32);
                    top += 1;
                    node = near;
                    continue;
                }
            }
            if top == 0 {
                return;
            }
            top -= 1;
            // SAFETY: entries below `top` were written before `top` passed them.
            node = unsafe { stack[top].assume_init() } as usize;
        }
    }

    /// Walks the tree about the point `p`: calls `visit(id, &mut reach)` for each item of each
    /// leaf whose box comes within `reach` of `p` (nearest child first), where `visit` asks
    /// the item and may lower `reach` (to the distance of the nearest item found, say);
    /// lowering it below 0 ends the walk. Every item whose box is within `reach` of `p`, as
    /// `reach` stands when its leaf is reached, is visited.
    pub fn walk_near(&self, p: DVec3, mut reach: f64, mut visit: impl FnMut(u32, &mut f64)) {
        if self.nodes.is_empty() || reach < 0.0 || reach.is_nan() {
            return;
        }
        // Never read beyond `top`; no deeper than the tree.
        let mut stack = [std::mem::MaybeUninit::<(u32, f64)>::uninit(); MAX_DEPTH];
        let mut top = 0;
        let mut node = (0usize, box_distance(&self.nodes[0].bounds, p));
        loop {
            let (k, near) = node;
            if near <= reach {
                let n = &self.nodes[k];
                if n.count > 0 {
                    let first = n.offset as usize;
                    for &id in &self.items[first..first + n.count as usize] {
                        visit(id, &mut reach);
                        if reach < 0.0 || reach.is_nan() {
                            return;
                        }
                    }
                } else {
                    let (low, high) = (k + 1, n.offset as usize);
                    let low = (low, box_distance(&self.nodes[low].bounds, p));
                    let high = (high, box_distance(&self.nodes[high].bounds, p));
                    let (first, second) = if low.1 <= high.1 {
                        (low, high)
                    } else {
                        (high, low)
                    };
                    if second.1 <= reach {
                        stack[top].write((second.0 as u32, second.1));
                        top += 1;
                    }
                    node = first;
                    continue;
                }
            }
            if top == 0 {
                return;
            }
            top -= 1;
            // SAFETY: entries below `top` were written before `top` passed them.
            let (k, near) = unsafe { stack[top].assume_init() };
            node = (k as usize, near);
        }
    }

    /// [`Bvh::walk`] for [`LANES`] rays at once: calls `visit(id, &mut t_max)` for each item of
    /// each leaf whose box some lane's ray meets within that lane's current range (lane `i`
    /// on `(t_min[i], t_max[i])`; a lane with `t_max[i] < t_min[i]` is idle), nearest child
    /// first along the first active lane's direction. `visit` asks the item for the lanes it
    /// chooses and may lower any lane's `t_max`; the walk ends once every lane is idle. Every
    /// item whose box meets some lane's ray on its range as it stands when the item's leaf is
    /// reached is visited (and maybe an item of a leaf that only a lane parallel to one of
    /// its slabs, outside it, could meet with an infinite range: [`RayLanes::may_meet`]).
    /// Both children of a node the lanes meet are tested together (two independent chains of
    /// vector operations), the walk goes on into the nearer one met and keeps the other for
    /// later, tested again only where a visit since may have shortened the ranges. Inlined
    /// into its caller, so that it is compiled for the caller's instruction set.
    #[inline(always)]
    pub fn walk_lanes(
        &self,
        rays: &RayLanes,
        t_min: [f64; LANES],
        mut t_max: [f64; LANES],
        mut visit: impl FnMut(u32, &mut [f64; LANES]),
    ) {
        let Some(root) = self.nodes.first() else {
            return;
        };
        let mut awake = active_lanes(&t_min, &t_max);
        if rays.may_meet(&root.bounds, t_min, t_max) & awake == 0 {
            return;
        }
        self.walk_below(rays, t_min, &mut t_max, &mut awake, 0, &mut visit);
    }

    /// Each item as `(id, ranks)`: `ranks[octant]` is its place in the order in which
    /// [`Bvh::walk_lanes`] visits items for rays whose directions' components along the
    /// three axes are all `≥ 0` or all not, as the bits of `octant` say (bit `a` set: not
    /// `≥ 0` along axis `a`); the walk visits the items a group of such rays meets in that
    /// order. Time O(n) for each octant.
    pub fn walk_ranks(&self) -> Vec<(u32, [u32; 8])> {
        let mut ranks = vec![[0u32; 8]; self.items.len()];
        for (octant, _) in [(); 8].iter().enumerate() {
            let mut next = 0u32;
            let mut stack: Vec<usize> = Vec::with_capacity(MAX_DEPTH);
            if !self.nodes.is_empty() {
                stack.push(0);
            }
            while let Some(k) = stack.pop() {
                let n = &self.nodes[k];
                if n.count > 0 {
                    let first = n.offset as usize;
                    for rank in &mut ranks[first..first + n.count as usize] {
                        rank[octant] = next;
                        next += 1;
                    }
                } else {
                    // As the walk: the first child (lower along the axis) first where the
                    // direction's component is `≥ 0`.
                    let (low, high) = (k + 1, n.offset as usize);
                    let (near, far) = if octant >> n.axis & 1 == 0 {
                        (low, high)
                    } else {
                        (high, low)
                    };
                    stack.push(far);
                    stack.push(near);
                }
            }
        }
        self.items.iter().copied().zip(ranks).collect()
    }

    /// [`Bvh::walk_lanes`] for rays that start in the box of leaf `leaf` (as
    /// [`Bvh::item_leaves`] gives it; any other node, or none, walks from the root): the same
    /// items visited, in another order, the leaf's items first (without its box test), then
    /// each of its ancestors' other subtrees from the leaf upwards, each walked as
    /// `walk_lanes` walks the tree. A ray that meets little beyond the leaf's box tests one
    /// box a level instead of two. Inlined into its caller.
    #[inline(always)]
    pub fn walk_lanes_from(
        &self,
        rays: &RayLanes,
        t_min: [f64; LANES],
        mut t_max: [f64; LANES],
        leaf: u32,
        mut visit: impl FnMut(u32, &mut [f64; LANES]),
    ) {
        let Some(start) = self.nodes.get(leaf as usize).filter(|n| n.count > 0) else {
            return self.walk_lanes(rays, t_min, t_max, visit);
        };
        let mut awake = active_lanes(&t_min, &t_max);
        if awake == 0 {
            return;
        }
        let first = start.offset as usize;
        for &id in &self.items[first..first + start.count as usize] {
            visit(id, &mut t_max);
        }
        awake = active_lanes(&t_min, &t_max);
        let mut node = leaf as usize;
        loop {
            if awake == 0 {
                return;
            }
            let parent = self.nodes[node].parent;
            if parent == NO_PARENT {
                return;
            }
            let parent = parent as usize;
            // The parent's other child: its first is the next node, its second at `offset`.
            let sibling = if node == parent + 1 {
                self.nodes[parent].offset as usize
            } else {
                parent + 1
            };
            if rays.may_meet(&self.nodes[sibling].bounds, t_min, t_max) & awake != 0 {
                self.walk_below(rays, t_min, &mut t_max, &mut awake, sibling, &mut visit);
            }
            node = parent;
        }
    }

    /// The walk of [`Bvh::walk_lanes`] below node `top` (included), whose box meets a lane of
    /// `awake` (the lanes not idle): `awake` is updated after each leaf, and the walk ends
    /// early when no lane is left.
    #[inline(always)]
    fn walk_below(
        &self,
        rays: &RayLanes,
        t_min: [f64; LANES],
        t_max: &mut [f64; LANES],
        awake: &mut u32,
        top: usize,
        visit: &mut impl FnMut(u32, &mut [f64; LANES]),
    ) {
        // Nodes kept for later, each with the number of leaves visited when it was kept: the
        // ranges are as they were then while no leaf has been visited since. Never read
        // beyond `top`, and never deeper than the tree.
        let mut stack = [std::mem::MaybeUninit::<(u32, u32)>::uninit(); MAX_DEPTH];
        let mut kept_count = 0;
        let mut visits = 0u32;
        let mut node = top;
        loop {
            // `node`'s box meets an awake lane.
            let n = &self.nodes[node];
            if n.count > 0 {
                let first = n.offset as usize;
                for &id in &self.items[first..first + n.count as usize] {
                    visit(id, t_max);
                }
                visits = visits.wrapping_add(1);
                *awake = active_lanes(&t_min, t_max);
                if *awake == 0 {
                    return;
                }
            } else {
                let (low, high) = (node + 1, n.offset as usize);
                let low_met = rays.may_meet(&self.nodes[low].bounds, t_min, *t_max) & *awake;
                let high_met = rays.may_meet(&self.nodes[high].bounds, t_min, *t_max) & *awake;
                if low_met != 0 && high_met != 0 {
                    // Nearest child first: the first child is lower along the axis.
                    let lead = (low_met | high_met).trailing_zeros() as usize;
                    let (near, far) = if rays.dir[n.axis as usize][lead] >= 0.0 {
                        (low, high)
                    } else {
                        (high, low)
                    };
                    stack[kept_count].write((far as u32, visits));
                    kept_count += 1;
                    node = near;
                    continue;
                } else if low_met != 0 {
                    node = low;
                    continue;
                } else if high_met != 0 {
                    node = high;
                    continue;
                }
            }
            // The latest node kept whose box still meets an awake lane.
            loop {
                if kept_count == 0 {
                    return;
                }
                kept_count -= 1;
                // SAFETY: entries below `kept_count` were written before it passed them.
                let (kept, then) = unsafe { stack[kept_count].assume_init() };
                node = kept as usize;
                if then == visits
                    || rays.may_meet(&self.nodes[node].bounds, t_min, *t_max) & *awake != 0
                {
                    break;
                }
            }
        }
    }
}

/// The lanes that are not idle (`t_max ≥ t_min`), as a mask (bit `i` for lane `i`).
#[inline(always)]
fn active_lanes(t_min: &[f64; LANES], t_max: &[f64; LANES]) -> u32 {
    (0..LANES).fold(0u32, |mask, i| mask | ((t_max[i] >= t_min[i]) as u32) << i)
}

/// The distance from `p` to the nearest point of `bounds` (0 inside it, +∞ for an empty box).
#[inline(always)]
fn box_distance(bounds: &Aabb, p: DVec3) -> f64 {
    let gap = (bounds.min - p).max(p - bounds.max).max(DVec3::ZERO);
    if bounds.min.cmpgt(bounds.max).any() {
        f64::INFINITY
    } else {
        gap.length()
    }
}

/// Half the surface area of a box (0 for an empty one).
fn half_area(b: &Aabb) -> f64 {
    let d = (b.max - b.min).max(DVec3::ZERO);
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// Whether `ray` meets `bounds` on `[t_min, t_max]`, with `inv = 1 / ray.dir`: true
/// whenever [`Aabb::clip`] of the same box, or of any box inside it, is `Some` there (the
/// same slab arithmetic, so never a miss where the items' own tests would meet).
#[inline(always)]
fn meets(bounds: &Aabb, ray: &Ray, inv: DVec3, t_min: f64, t_max: f64) -> bool {
    bounds
        .clip_by(ray, |axis| inv[axis], t_min, t_max)
        .is_some()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::uniform_stream;

    /// Draws uniform numbers in a range from a stream.
    struct Uniform(Box<dyn FnMut() -> f64>);

    impl Uniform {
        fn new(seed: u64) -> Self {
            Self(Box::new(uniform_stream(seed)))
        }

        fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * (self.0)()
        }
    }

    /// Random small boxes in a cube of side 20, some of them empty.
    fn boxes(rng: &mut Uniform, n: usize) -> Vec<(u32, Aabb)> {
        (0..n)
            .map(|i| {
                let c = DVec3::new(
                    rng.range(-10.0, 10.0),
                    rng.range(-10.0, 10.0),
                    rng.range(-10.0, 10.0),
                );
                let h = DVec3::new(
                    rng.range(0.0, 1.0),
                    rng.range(0.0, 1.0),
                    rng.range(0.0, 1.0),
                );
                let b = if i % 17 == 5 {
                    Aabb::EMPTY
                } else {
                    Aabb::new(c - h, c + h)
                };
                (i as u32, b)
            })
            .collect()
    }

    /// Whether a box holds nothing.
    fn is_empty(b: &Aabb) -> bool {
        b.min.cmpgt(b.max).any()
    }

    fn random_ray(rng: &mut Uniform) -> Ray {
        let o = DVec3::new(
            rng.range(-15.0, 15.0),
            rng.range(-15.0, 15.0),
            rng.range(-15.0, 15.0),
        );
        let mut d = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        // Some rays parallel to a slab.
        if rng.range(0.0, 1.0) < 0.2 {
            d.y = 0.0;
        }
        Ray::new(o, d)
    }

    #[test]
    fn every_item_is_in_one_leaf_and_every_box_inside_its_ancestors() {
        let mut rng = Uniform::new(3);
        for n in [0, 1, 2, 3, 5, 17, 100, 1000] {
            let items = boxes(&mut rng, n);
            let bvh = Bvh::new(&items);
            let mut ids = bvh.items.clone();
            ids.sort_unstable();
            assert_eq!(ids, (0..n as u32).collect::<Vec<_>>());
            // Each node's box holds its items' boxes.
            for (k, node) in bvh.nodes.iter().enumerate() {
                let (first, count) = leaf_range(&bvh, k);
                for &id in &bvh.items[first..first + count] {
                    let b = items[id as usize].1;
                    if b.min.cmpgt(b.max).any() {
                        continue;
                    }
                    assert!(node.bounds.contains(b.min) && node.bounds.contains(b.max));
                }
            }
        }
    }

    /// The items below node `k`, as a range of `items` (leaves are laid out depth first).
    fn leaf_range(bvh: &Bvh, k: usize) -> (usize, usize) {
        let node = &bvh.nodes[k];
        if node.count > 0 {
            return (node.offset as usize, node.count as usize);
        }
        let (a, na) = leaf_range(bvh, k + 1);
        let (b, nb) = leaf_range(bvh, node.offset as usize);
        assert_eq!(a + na, b);
        (a, na + nb)
    }

    #[test]
    fn the_walk_near_a_point_visits_every_box_within_its_reach_and_finds_the_nearest() {
        let mut rng = Uniform::new(11);
        let items = boxes(&mut rng, 700);
        let bvh = Bvh::new(&items);
        for _ in 0..2000 {
            let p = DVec3::new(
                rng.range(-14.0, 14.0),
                rng.range(-14.0, 14.0),
                rng.range(-14.0, 14.0),
            );
            let reach = rng.range(0.0, 6.0);
            // A fixed reach: exactly the boxes within it.
            let mut seen = vec![false; items.len()];
            bvh.walk_near(p, reach, |id, _| seen[id as usize] = true);
            for (id, b) in &items {
                let within = !is_empty(b) && box_distance(b, p) <= reach;
                assert!(!within || seen[*id as usize], "item {id} missed");
                assert!(
                    !is_empty(b) || !seen[*id as usize],
                    "empty box {id} visited"
                );
            }
            // A shrinking reach finds the box nearest p, as a scan does.
            let mut best = f64::INFINITY;
            bvh.walk_near(p, f64::INFINITY, |id, reach| {
                best = best.min(box_distance(&items[id as usize].1, p));
                *reach = best;
            });
            let scan = items
                .iter()
                .map(|(_, b)| box_distance(b, p))
                .fold(f64::INFINITY, f64::min);
            assert_eq!(best, scan);
        }
        // A negative reach ends the walk at once.
        let mut visits = 0;
        bvh.walk_near(DVec3::ZERO, f64::INFINITY, |_, reach| {
            visits += 1;
            *reach = -1.0;
        });
        assert_eq!(visits, 1);
    }

    #[test]
    fn the_walk_visits_every_item_whose_box_the_ray_meets() {
        let mut rng = Uniform::new(7);
        let items = boxes(&mut rng, 500);
        let bvh = Bvh::new(&items);
        for _ in 0..2000 {
            let ray = random_ray(&mut rng);
            let (t_min, t_max) = (rng.range(-5.0, 1.0), rng.range(0.5, 40.0));
            let mut seen = vec![false; items.len()];
            bvh.walk(&ray, t_min, t_max, |id, _| seen[id as usize] = true);
            for (id, b) in items.iter().filter(|(_, b)| !is_empty(b)) {
                if b.clip(&ray, t_min, t_max).is_some() {
                    assert!(seen[*id as usize], "item {id} missed");
                }
            }
            // The same for four rays at once: each lane's items are among those visited.
            let rays: [Ray; LANES] = std::array::from_fn(|_| random_ray(&mut rng));
            let mut seen = vec![false; items.len()];
            bvh.walk_lanes(
                &RayLanes::new(&rays),
                [t_min; LANES],
                [t_max; LANES],
                |id, _| seen[id as usize] = true,
            );
            for (id, b) in items.iter().filter(|(_, b)| !is_empty(b)) {
                if rays.iter().any(|r| b.clip(r, t_min, t_max).is_some()) {
                    assert!(seen[*id as usize], "item {id} missed by the lanes");
                }
            }
        }
    }

    #[test]
    fn a_walk_from_a_leaf_visits_every_item_the_lanes_meet_once() {
        let mut rng = Uniform::new(17);
        let items = boxes(&mut rng, 500);
        let bvh = Bvh::new(&items);
        let leaves: Vec<(u32, u32)> = bvh.item_leaves().collect();
        assert_eq!(leaves.len(), items.len());
        for &(id, leaf) in &leaves {
            let node = &bvh.nodes[leaf as usize];
            let first = node.offset as usize;
            assert!(bvh.items[first..first + node.count as usize].contains(&id));
        }
        let mut missed_boxes = 0;
        for k in 0..2000 {
            // Rays from inside the leaf's first item's box, or anywhere; from a leaf, the
            // root (not a leaf) or no node.
            let (id, leaf) = leaves[k * 37 % leaves.len()];
            let leaf = match k % 10 {
                0 => 0,
                1 => u32::MAX,
                _ => leaf,
            };
            let b = items[id as usize].1;
            let rays: [Ray; LANES] = std::array::from_fn(|lane| {
                let r = random_ray(&mut rng);
                if lane < 3 && !is_empty(&b) {
                    Ray::new((b.min + b.max) * 0.5, r.dir)
                } else {
                    r
                }
            });
            let (t_min, t_max) = (rng.range(-1.0, 0.5), rng.range(0.5, 40.0));
            let mut seen = vec![0; items.len()];
            bvh.walk_lanes_from(
                &RayLanes::new(&rays),
                [t_min; LANES],
                [t_max; LANES],
                leaf,
                |id, _| seen[id as usize] += 1,
            );
            for (id, b) in items.iter() {
                assert!(seen[*id as usize] <= 1, "item {id} visited twice");
                if !is_empty(b) && rays.iter().any(|r| b.clip(r, t_min, t_max).is_some()) {
                    assert_eq!(seen[*id as usize], 1, "item {id} missed");
                } else {
                    missed_boxes += usize::from(seen[*id as usize] == 0);
                }
            }
        }
        // The walk skips the subtrees no lane meets.
        assert!(missed_boxes > 2000 * 400, "{missed_boxes}");
    }

    #[test]
    fn the_walk_visits_items_in_the_order_of_their_ranks_for_its_octant() {
        let mut rng = Uniform::new(19);
        let items = boxes(&mut rng, 400);
        let bvh = Bvh::new(&items);
        let ranks: Vec<[u32; 8]> = {
            let mut by_id = vec![[0; 8]; items.len()];
            for (id, r) in bvh.walk_ranks() {
                by_id[id as usize] = r;
            }
            by_id
        };
        // Each octant's ranks number the items 0 … n − 1.
        for octant in 0..8 {
            let mut seen: Vec<u32> = ranks.iter().map(|r| r[octant]).collect();
            seen.sort_unstable();
            assert_eq!(seen, (0..items.len() as u32).collect::<Vec<_>>());
        }
        let mut long_walks = 0;
        for _ in 0..1000 {
            // Four rays with the same direction signs, each lane's range shrinking as it
            // meets boxes (as the nearest-hit queries shrink theirs).
            let base = random_ray(&mut rng);
            let rays: [Ray; LANES] = std::array::from_fn(|_| {
                let o = base.origin + DVec3::splat(rng.range(-0.5, 0.5));
                Ray::new(o, base.dir.abs() * base.dir.signum() * rng.range(0.5, 1.5))
            });
            let octant = (0..3).fold(0, |b, a| b | usize::from(base.dir[a] < 0.0) << a);
            let mut order = Vec::new();
            bvh.walk_lanes(
                &RayLanes::new(&rays),
                [0.0; LANES],
                [100.0; LANES],
                |id, t_max| {
                    order.push(ranks[id as usize][octant]);
                    for lane in 0..LANES {
                        if let Some((t, _)) =
                            items[id as usize].1.clip(&rays[lane], 0.0, t_max[lane])
                        {
                            t_max[lane] = t_max[lane].min(t + 1.0);
                        }
                    }
                },
            );
            long_walks += usize::from(order.len() > 3);
            assert!(order.windows(2).all(|w| w[0] < w[1]), "{order:?}");
        }
        assert!(long_walks > 30, "{long_walks}");
    }

    #[test]
    fn nearest_by_walk_equals_nearest_by_list() {
        // The nearest box entry found by shrinking t_max is the nearest over all boxes.
        let mut rng = Uniform::new(11);
        let items = boxes(&mut rng, 300);
        let bvh = Bvh::new(&items);
        let mut visited = 0;
        for _ in 0..2000 {
            let ray = random_ray(&mut rng);
            let by_list = items
                .iter()
                .filter(|(_, b)| !is_empty(b))
                .filter_map(|(id, b)| Some((b.clip(&ray, 0.0, 100.0)?.0, *id)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let mut by_walk: Option<(f64, u32)> = None;
            bvh.walk(&ray, 0.0, 100.0, |id, t_max| {
                visited += 1;
                let b = items[id as usize].1;
                if is_empty(&b) {
                    return;
                }
                if let Some((t, _)) = b.clip(&ray, 0.0, *t_max) {
                    if by_walk.is_none_or(|(best, _)| t < best) {
                        by_walk = Some((t, id));
                        *t_max = t;
                    }
                }
            });
            assert_eq!(by_walk.map(|b| b.0), by_list.map(|b| b.0));
        }
        // The walk asks far fewer than every item of every ray.
        assert!(visited < 2000 * 300 / 10, "{visited} visits");
    }

    #[test]
    fn nearest_by_lane_walk_equals_nearest_by_list() {
        // Four rays at once, each lane's range shrinking as its hits are found (the walk
        // keeps far children and tests them again only after a visit).
        let mut rng = Uniform::new(13);
        let items = boxes(&mut rng, 300);
        let bvh = Bvh::new(&items);
        let mut visited = 0;
        for _ in 0..1000 {
            let rays: [Ray; LANES] = std::array::from_fn(|_| random_ray(&mut rng));
            let mut by_walk: [Option<f64>; LANES] = [None; LANES];
            bvh.walk_lanes(
                &RayLanes::new(&rays),
                [0.0; LANES],
                [100.0; LANES],
                |id, t_max| {
                    visited += 1;
                    let b = items[id as usize].1;
                    if is_empty(&b) {
                        return;
                    }
                    for lane in 0..LANES {
                        if let Some((t, _)) = b.clip(&rays[lane], 0.0, t_max[lane]) {
                            if by_walk[lane].is_none_or(|best| t < best) {
                                by_walk[lane] = Some(t);
                                t_max[lane] = t;
                            }
                        }
                    }
                },
            );
            for lane in 0..LANES {
                let by_list = items
                    .iter()
                    .filter(|(_, b)| !is_empty(b))
                    .filter_map(|(_, b)| Some(b.clip(&rays[lane], 0.0, 100.0)?.0))
                    .min_by(f64::total_cmp);
                assert_eq!(by_walk[lane], by_list, "lane {lane} of {rays:?}");
            }
        }
        assert!(visited < 1000 * 300 / 2, "{visited} visits");
    }

    #[test]
    fn lowering_t_max_below_t_min_ends_the_walk() {
        let mut rng = Uniform::new(5);
        let items = boxes(&mut rng, 200);
        let bvh = Bvh::new(&items);
        let ray = Ray::new(DVec3::new(-20.0, 0.0, 0.0), DVec3::X);
        let mut calls = 0;
        bvh.walk(&ray, 0.0, f64::INFINITY, |_, t_max| {
            calls += 1;
            *t_max = f64::NEG_INFINITY;
        });
        assert!(calls <= 1);
    }

    #[test]
    fn identical_boxes_in_any_number_build_and_walk() {
        let b = Aabb::new(DVec3::ZERO, DVec3::ONE);
        let items: Vec<_> = (0..10_000).map(|i| (i, b)).collect();
        let bvh = Bvh::new(&items);
        assert_eq!(bvh.len(), 10_000);
        let mut count = 0;
        let ray = Ray::new(DVec3::new(0.5, 0.5, -1.0), DVec3::Z);
        bvh.walk(&ray, 0.0, 10.0, |_, _| count += 1);
        assert_eq!(count, 10_000);
    }
}
