//! The scene's objects in a bounding volume hierarchy ([`crate::bvh::Bvh`]), and the objects
//! whose boxes are infinite (planes), which no hierarchy can hold, beside it.

use std::sync::OnceLock;

use crate::bvh::Bvh;

use super::Object;

/// The scene's hierarchy of its objects' boxes: built when the scene is loaded
/// ([`ObjectIndex::of`]) or, for a scene put together in code with
/// [`ObjectIndex::default`], at its first query. It belongs to the objects it was built
/// from: where `Scene::objects` has since been replaced or resized, the queries notice and
/// walk the objects one by one (the same answers, without the speed); a scene whose objects
/// are changed in place after its first query must be given a fresh index.
#[derive(Default)]
pub struct ObjectIndex {
    built: OnceLock<Built>,
}

/// A built index and what it was built from.
pub(super) struct Built {
    /// `(address, length)` of the objects it was built from.
    key: (usize, usize),
    /// The objects with finite boxes, by index.
    pub(super) bvh: Bvh,
    /// The indices of the objects whose boxes are not finite, in order.
    pub(super) unbounded: Vec<u32>,
    /// By object index, the leaf of `bvh` that holds the object ([`Bvh::item_leaves`]), or
    /// `u32::MAX` for an unbounded one.
    pub(super) leaf_of: Vec<u32>,
    /// By object index, its [`Bvh::walk_ranks`] (zeros for an unbounded one): the order in
    /// which the walk asks the objects a group of rays meets, for each octant of directions.
    pub(super) walk_rank: Vec<[u32; 8]>,
}

impl std::fmt::Debug for ObjectIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.built.get() {
            None => f.write_str("ObjectIndex(not built)"),
            Some(b) => write!(
                f,
                "ObjectIndex({} in a hierarchy, {} unbounded)",
                b.bvh.len(),
                b.unbounded.len()
            ),
        }
    }
}

/// What an index is known by: where its objects are and how many.
fn key(objects: &[Object]) -> (usize, usize) {
    (objects.as_ptr() as usize, objects.len())
}

impl ObjectIndex {
    /// The index of `objects`, built now (O(n log n) for n objects).
    pub fn of(objects: &[Object]) -> Self {
        let index = Self::default();
        let _ = index.built.set(Built::new(objects));
        index
    }

    /// The built index of `objects` (building it on the first call), or `None` when it was
    /// built from other objects.
    #[inline]
    pub(super) fn get(&self, objects: &[Object]) -> Option<&Built> {
        let built = self.built.get_or_init(|| Built::new(objects));
        (built.key == key(objects)).then_some(built)
    }
}

impl Built {
    fn new(objects: &[Object]) -> Self {
        let mut boxes = Vec::with_capacity(objects.len());
        let mut unbounded = Vec::new();
        for (i, object) in objects.iter().enumerate() {
            let i = u32::try_from(i).expect("fewer than 2³² objects");
            let b = object.bounds;
            let empty = b.min.cmpgt(b.max).any();
            if b.is_finite() || empty {
                boxes.push((i, b));
            } else {
                unbounded.push(i);
            }
        }
        let bvh = Bvh::new(&boxes);
        let mut leaf_of = vec![u32::MAX; objects.len()];
        for (id, leaf) in bvh.item_leaves() {
            leaf_of[id as usize] = leaf;
        }
        let mut walk_rank = vec![[0; 8]; objects.len()];
        for (id, ranks) in bvh.walk_ranks() {
            walk_rank[id as usize] = ranks;
        }
        Self {
            key: key(objects),
            bvh,
            unbounded,
            leaf_of,
            walk_rank,
        }
    }
}
