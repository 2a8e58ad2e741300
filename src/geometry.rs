//! Rays, axis-aligned boxes and affine object frames: the vocabulary every shape speaks.
//!
//! All geometry is `f64`. World space is right-handed; nothing here assumes a unit of length.

pub use glam::{DMat3, DVec3};

/// How many rays the lane-wise queries take at once
/// ([`crate::shapes::Shape::intersect_lanes`]): four `f64` lanes fill one 256-bit vector
/// register.
pub const LANES: usize = 4;

/// A half-line `origin + t·dir`, `t ≥ 0`. `dir` need not be unit length: every `t` in the
/// library is measured in multiples of `dir`, so `t` is shared between world and object space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts (world or object space, as the context says).
    pub origin: DVec3,
    /// Direction; non-zero, not necessarily normalised.
    pub dir: DVec3,
}

impl Ray {
    /// A ray from `origin` along `dir` (not normalised).
    pub fn new(origin: DVec3, dir: DVec3) -> Self {
        Self { origin, dir }
    }

    /// The point `origin + t·dir`.
    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        self.origin + t * self.dir
    }
}

/// An axis-aligned box `[min, max]`. An empty box has `min > max` on some axis; an infinite
/// one (a plane's bounds) has infinite components.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: DVec3,
    /// Upper corner.
    pub max: DVec3,
}

/// A solid ellipsoid: the points `centre + axes·u` with `|u| ≤ 1` (a bound some shapes
/// give besides their box, see [`crate::shapes::Shape::enclosing_ellipsoids`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolidEllipsoid {
    /// The centre.
    pub centre: DVec3,
    /// The linear map from the unit ball: its columns are three conjugate semi-axes.
    pub axes: DMat3,
}

impl SolidEllipsoid {
    /// The ellipsoid `Σ ((p − centre)ᵢ / semi_axesᵢ)² ≤ 1`, its axes along x, y and z.
    pub fn axis_aligned(centre: DVec3, semi_axes: DVec3) -> Self {
        Self {
            centre,
            axes: DMat3::from_diagonal(semi_axes),
        }
    }
}

/// A convex solid, the hull of its eight corners: an object-space box carried to the world
/// by a [`Frame`] (a parallelepiped), one of the cells some shapes give besides their box
/// (see [`crate::shapes::Shape::enclosing_cells`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hexahedron {
    /// The corners, in any order.
    pub corners: [DVec3; 8],
}

impl Aabb {
    /// The box that contains nothing; the identity for [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    /// The box that contains everything.
    pub const EVERYTHING: Aabb = Aabb {
        min: DVec3::splat(f64::NEG_INFINITY),
        max: DVec3::splat(f64::INFINITY),
    };

    /// The box with the given corners (`min ≤ max` componentwise for a non-empty box).
    pub fn new(min: DVec3, max: DVec3) -> Self {
        Self { min, max }
    }

    /// The smallest box holding every point given.
    pub fn from_points(points: impl IntoIterator<Item = DVec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.including(p))
    }

    /// This box grown to hold `p`.
    pub fn including(self, p: DVec3) -> Self {
        Self::new(self.min.min(p), self.max.max(p))
    }

    /// The smallest box holding both boxes.
    pub fn union(self, other: Aabb) -> Self {
        Self::new(self.min.min(other.min), self.max.max(other.max))
    }

    /// The eight corners; corner `i` takes `max` along x when bit 0 of `i` is set, along y
    /// bit 1, along z bit 2, else `min`.
    pub fn corners(&self) -> [DVec3; 8] {
        std::array::from_fn(|i| {
            DVec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }

    /// True when every coordinate of both corners is finite.
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// True when `p` lies inside or on the box.
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// This box grown on every side by `rel × (largest extent + largest |coordinate|)`, so that
    /// points computed on the surface it bounds (with rounding error) still fall inside, and a
    /// flat box (a polygon's) gets some thickness. Empty and infinite boxes come back unchanged.
    pub fn padded(self, rel: f64) -> Self {
        if !self.is_finite() || self.min.cmpgt(self.max).any() {
            return self;
        }
        let scale =
            (self.max - self.min).max_element() + self.min.abs().max(self.max.abs()).max_element();
        let margin = DVec3::splat(rel * scale);
        Self::new(self.min - margin, self.max + margin)
    }

    /// The part `[t_enter, t_exit]` of `[t_min, t_max]` where the ray is inside the box, or
    /// `None` when the ray misses it there. Exact slab test; robust to zero direction
    /// components (a ray parallel to a slab is inside it iff its origin is).
    #[inline]
    pub fn clip(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<(f64, f64)> {
        self.clip_by(ray, |axis| 1.0 / ray.dir[axis], t_min, t_max)
    }

    /// [`Aabb::clip`] with the direction's reciprocals given by `inverse(axis)` (asked only
    /// for an axis whose direction component is not zero): the same slab arithmetic, so the
    /// same answer as `clip` when `inverse(axis)` is `1 / ray.dir[axis]`, whether computed
    /// here (`clip`) or once per ray ahead of many boxes (the scene's hierarchy).
    #[inline(always)]
    pub fn clip_by(
        &self,
        ray: &Ray,
        inverse: impl Fn(usize) -> f64,
        t_min: f64,
        t_max: f64,
    ) -> Option<(f64, f64)> {
        let mut t0 = t_min;
        let mut t1 = t_max;
        for axis in 0..3 {
            let o = ray.origin[axis];
            let d = ray.dir[axis];
            let (lo, hi) = (self.min[axis], self.max[axis]);
            if d == 0.0 {
                if o < lo || o > hi {
                    return None;
                }
                continue;
            }
            let inv = inverse(axis);
            let (mut a, mut b) = ((lo - o) * inv, (hi - o) * inv);
            if a > b {
                std::mem::swap(&mut a, &mut b);
            }
            // NaN (infinite box with o on the boundary) must not shrink the interval.
            if a > t0 {
                t0 = a;
            }
            if b < t1 {
                t1 = b;
            }
            if t0 > t1 {
                return None;
            }
        }
        Some((t0, t1))
    }

    /// [`Aabb::clip`] for [`LANES`] rays at once, given as lanes of their origins' and
    /// directions' coordinates (`o[axis][lane]`): where `clip(ray, t0[i], t1[i])` is
    /// `Some((a, b))`, `(t0[i], t1[i])` becomes `(a, b)`; where it is `None`, `alive[i]` is
    /// cleared (and `t0[i]`, `t1[i]` are meaningless). The same operations as `clip`, without
    /// branches, so that the lanes stay in vector registers.
    #[inline(always)]
    pub fn clip_lanes(
        &self,
        o: &[[f64; LANES]; 3],
        d: &[[f64; LANES]; 3],
        t0: &mut [f64; LANES],
        t1: &mut [f64; LANES],
        alive: &mut [bool; LANES],
    ) {
        let inverse = d.map(|d| d.map(|d| 1.0 / d));
        self.clip_lanes_by(o, d, &inverse, t0, t1, alive);
    }

    /// [`Aabb::clip_lanes`] with the directions' reciprocals given (`inverse[axis][i]` is
    /// `1.0 / d[axis][i]`, so the same bits), for rays tested against many boxes.
    #[inline(always)]
    pub fn clip_lanes_by(
        &self,
        o: &[[f64; LANES]; 3],
        d: &[[f64; LANES]; 3],
        inverse: &[[f64; LANES]; 3],
        t0: &mut [f64; LANES],
        t1: &mut [f64; LANES],
        alive: &mut [bool; LANES],
    ) {
        for axis in 0..3 {
            let (lo, hi) = (self.min[axis], self.max[axis]);
            let (o, d, inv) = (&o[axis], &d[axis], &inverse[axis]);
            for i in 0..LANES {
                let moving = d[i] != 0.0;
                let (a, b) = ((lo - o[i]) * inv[i], (hi - o[i]) * inv[i]);
                let (a, b) = if a > b { (b, a) } else { (a, b) };
                let outside = (o[i] < lo) | (o[i] > hi);
                t0[i] = if moving & (a > t0[i]) { a } else { t0[i] };
                t1[i] = if moving & (b < t1[i]) { b } else { t1[i] };
                // `t0 > t1` is `clip`'s test for an empty interval (a NaN bound passes it).
                let empty = t0[i] > t1[i];
                alive[i] &= if moving { !empty } else { !outside };
            }
        }
    }

    /// [`Aabb::clip_lanes`] on AVX2 registers (lane `i` of each): the same operations, so
    /// the same bits; `alive` is a mask (all ones or zero per lane). Tested through the
    /// typed surfaces' spans, which clip with it.
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) unsafe fn clip_avx2(
        &self,
        o: &[std::arch::x86_64::__m256d; 3],
        d: &[std::arch::x86_64::__m256d; 3],
        t0: &mut std::arch::x86_64::__m256d,
        t1: &mut std::arch::x86_64::__m256d,
        alive: &mut std::arch::x86_64::__m256d,
    ) {
        use std::arch::x86_64::*;
        let one = _mm256_set1_pd(1.0);
        let inverse = d.map(|d| _mm256_div_pd(one, d));
        self.clip_avx2_by(o, d, &inverse, t0, t1, alive);
    }

    /// [`Aabb::clip_avx2`] with the directions' reciprocals given (`1.0 / d`, so the same
    /// bits), as [`Aabb::clip_lanes_by`] is to [`Aabb::clip_lanes`].
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) unsafe fn clip_avx2_by(
        &self,
        o: &[std::arch::x86_64::__m256d; 3],
        d: &[std::arch::x86_64::__m256d; 3],
        inverse: &[std::arch::x86_64::__m256d; 3],
        t0: &mut std::arch::x86_64::__m256d,
        t1: &mut std::arch::x86_64::__m256d,
        alive: &mut std::arch::x86_64::__m256d,
    ) {
        use std::arch::x86_64::*;
        // `if c {a} else {b}`.
        let pick = |c: __m256d, a: __m256d, b: __m256d| _mm256_blendv_pd(b, a, c);
        let zero = _mm256_setzero_pd();
        for axis in 0..3 {
            let (lo, hi) = (
                _mm256_set1_pd(self.min[axis]),
                _mm256_set1_pd(self.max[axis]),
            );
            let (o, d, inv) = (o[axis], d[axis], inverse[axis]);
            // `d != 0.0` (true for a NaN).
            let moving = _mm256_cmp_pd::<_CMP_NEQ_UQ>(d, zero);
            let a = _mm256_mul_pd(_mm256_sub_pd(lo, o), inv);
            let b = _mm256_mul_pd(_mm256_sub_pd(hi, o), inv);
            let swap = _mm256_cmp_pd::<_CMP_GT_OQ>(a, b);
            let (a, b) = (pick(swap, b, a), pick(swap, a, b));
            let outside = _mm256_or_pd(
                _mm256_cmp_pd::<_CMP_LT_OQ>(o, lo),
                _mm256_cmp_pd::<_CMP_GT_OQ>(o, hi),
            );
            *t0 = pick(
                _mm256_and_pd(moving, _mm256_cmp_pd::<_CMP_GT_OQ>(a, *t0)),
                a,
                *t0,
            );
            *t1 = pick(
                _mm256_and_pd(moving, _mm256_cmp_pd::<_CMP_LT_OQ>(b, *t1)),
                b,
                *t1,
            );
            let empty = _mm256_cmp_pd::<_CMP_GT_OQ>(*t0, *t1);
            *alive = _mm256_andnot_pd(pick(moving, empty, outside), *alive);
        }
    }
}

/// [`LANES`] rays laid out by coordinate (`origin[axis][lane]`), with the reciprocals of their
/// directions worked out once: what testing the rays of all lanes against many boxes needs
/// ([`RayLanes::meet`], the hierarchy's walk).
#[derive(Clone, Copy, Debug)]
pub struct RayLanes {
    /// Each lane's origin, by axis.
    pub origin: [[f64; LANES]; 3],
    /// Each lane's direction, by axis.
    pub dir: [[f64; LANES]; 3],
    /// `1 / dir`, by axis (infinite where a component is zero, which [`RayLanes::meet`] then
    /// does not use).
    pub inverse: [[f64; LANES]; 3],
    /// Whether the processor has AVX2 (then [`RayLanes::meet`] tests the lanes in one
    /// vector register each).
    avx2: bool,
}

impl RayLanes {
    /// The lanes of `rays` (lane `i` is `rays[i]`).
    #[inline(always)]
    pub fn new(rays: &[Ray; LANES]) -> Self {
        let origin = std::array::from_fn(|axis| std::array::from_fn(|i| rays[i].origin[axis]));
        let dir: [[f64; LANES]; 3] =
            std::array::from_fn(|axis| std::array::from_fn(|i| rays[i].dir[axis]));
        let inverse = dir.map(|d| d.map(|d| 1.0 / d));
        #[cfg(target_arch = "x86_64")]
        let avx2 = crate::cpu::avx2();
        #[cfg(not(target_arch = "x86_64"))]
        let avx2 = false;
        Self {
            origin,
            dir,
            inverse,
            avx2,
        }
    }

    /// Which lanes meet `bounds` on their ranges, as a mask: bit `i` is set exactly where
    /// `bounds.clip(&rays[i], t_min[i], t_max[i]).is_some()` (the same slab arithmetic as
    /// [`Aabb::clip`], on all lanes at once and without branches; in AVX2 registers where the
    /// processor has them). Bits from [`LANES`] up are clear.
    #[inline(always)]
    pub fn meet(&self, bounds: &Aabb, t_min: [f64; LANES], t_max: [f64; LANES]) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only where the processor has AVX2.
            return unsafe { self.meet_avx2(bounds, t_min, t_max) };
        }
        self.meet_portable(bounds, t_min, t_max)
    }

    /// A cheaper [`RayLanes::meet`] for the walk of a hierarchy, whose items are tested
    /// again: every lane `meet` sets is set, and on a lane whose direction has no zero
    /// component the answer is `meet`'s. A lane whose ray is parallel to a slab of the box and
    /// outside it may be set as well (`meet` clears it: its entry or exit is infinite, which
    /// only an infinite range holds). Each slab's entry and exit are `meet`'s values, taken by
    /// minimum and maximum instead of comparisons and blends, and the range is tested once at
    /// the end: a shorter chain of dependent operations.
    #[inline(always)]
    pub fn may_meet(&self, bounds: &Aabb, t_min: [f64; LANES], t_max: [f64; LANES]) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            // SAFETY: `avx2` is set only where the processor has AVX2.
            return unsafe { self.may_meet_avx2(bounds, t_min, t_max) };
        }
        self.may_meet_portable(bounds, t_min, t_max)
    }

    /// [`RayLanes::may_meet`] in plain arithmetic, lane by lane: the operations of the AVX2
    /// form (`min(b, a)` is `b` where `b < a`, else `a`: a NaN gives `a`; `max` likewise), so
    /// the same answers.
    #[inline(always)]
    fn may_meet_portable(&self, bounds: &Aabb, t_min: [f64; LANES], t_max: [f64; LANES]) -> u32 {
        let (mut t0, mut t1) = (t_min, t_max);
        for axis in 0..3 {
            let (lo, hi) = (bounds.min[axis], bounds.max[axis]);
            for i in 0..LANES {
                let o = self.origin[axis][i];
                let inv = self.inverse[axis][i];
                let (a, b) = ((lo - o) * inv, (hi - o) * inv);
                let near = if b < a { b } else { a };
                let far = if a > b { a } else { b };
                t0[i] = if near > t0[i] { near } else { t0[i] };
                t1[i] = if far < t1[i] { far } else { t1[i] };
            }
        }
        let empty = (0..LANES).fold(0, |mask, i| mask | ((t0[i] > t1[i]) as u32) << i);
        !empty & ((1 << LANES) - 1)
    }

    /// [`RayLanes::may_meet`] on AVX2 registers: `vminpd`/`vmaxpd` return their second
    /// operand where either is NaN, as the portable form's comparisons do.
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn may_meet_avx2(&self, bounds: &Aabb, t_min: [f64; LANES], t_max: [f64; LANES]) -> u32 {
        use std::arch::x86_64::*;
        let load = |x: &[f64; LANES]| _mm256_loadu_pd(x.as_ptr());
        let mut t0 = load(&t_min);
        let mut t1 = load(&t_max);
        for axis in 0..3 {
            let o = load(&self.origin[axis]);
            let inv = load(&self.inverse[axis]);
            let a = _mm256_mul_pd(_mm256_sub_pd(_mm256_set1_pd(bounds.min[axis]), o), inv);
            let b = _mm256_mul_pd(_mm256_sub_pd(_mm256_set1_pd(bounds.max[axis]), o), inv);
            t0 = _mm256_max_pd(_mm256_min_pd(b, a), t0);
            t1 = _mm256_min_pd(_mm256_max_pd(a, b), t1);
        }
        let empty = _mm256_cmp_pd::<_CMP_GT_OQ>(t0, t1);
        !(_mm256_movemask_pd(empty) as u32) & ((1 << LANES) - 1)
    }

    /// [`RayLanes::meet`] in plain arithmetic, lane by lane.
    #[inline(always)]
    fn meet_portable(&self, bounds: &Aabb, t_min: [f64; LANES], t_max: [f64; LANES]) -> u32 {
        let (mut t0, mut t1) = (t_min, t_max);
        let mut alive = [true; LANES];
        bounds.clip_lanes_by(
            &self.origin,
            &self.dir,
            &self.inverse,
            &mut t0,
            &mut t1,
            &mut alive,
        );
        (0..LANES).fold(0, |mask, i| mask | (alive[i] as u32) << i)
    }

    /// [`RayLanes::meet`] on AVX2 registers (lane `i` of each): the same operations as
    /// [`RayLanes::meet_portable`] ([`Aabb::clip_avx2_by`]), so the same answers.
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn meet_avx2(&self, bounds: &Aabb, t_min: [f64; LANES], t_max: [f64; LANES]) -> u32 {
        use std::arch::x86_64::*;
        // Each array holds the four `f64`s read.
        let load = |x: &[f64; LANES]| _mm256_loadu_pd(x.as_ptr());
        let mut t0 = load(&t_min);
        let mut t1 = load(&t_max);
        let mut alive = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
        bounds.clip_avx2_by(
            &[
                load(&self.origin[0]),
                load(&self.origin[1]),
                load(&self.origin[2]),
            ],
            &[load(&self.dir[0]), load(&self.dir[1]), load(&self.dir[2])],
            &[
                load(&self.inverse[0]),
                load(&self.inverse[1]),
                load(&self.inverse[2]),
            ],
            &mut t0,
            &mut t1,
            &mut alive,
        );
        _mm256_movemask_pd(alive) as u32
    }
}

/// Why an object frame could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// A basis vector or the position is NaN or infinite.
    #[error("the position and basis vectors must be finite")]
    NotFinite,
    /// The three basis vectors are (nearly) linearly dependent, so the object would be flat.
    #[error("the basis vectors u, v, w are linearly dependent (or nearly so): the matrix [u v w] has no usable inverse")]
    Singular,
}

/// An affine placement of an object: `p_world = M·p_object + position` with `M = [u v w]`
/// (u, v, w as columns). Any invertible `M` is allowed (rotation, non-uniform scale, shear).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// World position of the object-space origin.
    pub position: DVec3,
    /// Object-to-world linear part `[u v w]`.
    pub m: DMat3,
    /// World-to-object linear part `M⁻¹`.
    pub m_inv: DMat3,
    /// `(M⁻¹)ᵀ`, which carries object-space normals to world space.
    pub normal_matrix: DMat3,
}

impl Frame {
    /// The smallest `|det M| / (|u|·|v|·|w|)` accepted: below it the basis is treated as
    /// singular. The ratio is 1 for an orthogonal basis at any scale and 0 for a flat one.
    pub const MIN_INDEPENDENCE: f64 = 1e-9;

    /// The frame with origin `position` and basis columns `u`, `v`, `w`.
    pub fn new(position: DVec3, u: DVec3, v: DVec3, w: DVec3) -> Result<Self, FrameError> {
        if !(position.is_finite() && u.is_finite() && v.is_finite() && w.is_finite()) {
            return Err(FrameError::NotFinite);
        }
        let m = DMat3::from_cols(u, v, w);
        let scale = u.length() * v.length() * w.length();
        let det = m.determinant();
        let independence = det.abs() / scale;
        let usable = scale > 0.0 && scale.is_finite() && independence >= Self::MIN_INDEPENDENCE;
        if !usable {
            return Err(FrameError::Singular);
        }
        let m_inv = m.inverse();
        if !m_inv.is_finite() {
            return Err(FrameError::Singular);
        }
        Ok(Self {
            position,
            m,
            m_inv,
            normal_matrix: m_inv.transpose(),
        })
    }

    /// The identity placement (object space = world space).
    pub fn identity() -> Self {
        Self {
            position: DVec3::ZERO,
            m: DMat3::IDENTITY,
            m_inv: DMat3::IDENTITY,
            normal_matrix: DMat3::IDENTITY,
        }
    }

    /// The world ray expressed in object space; the direction is not renormalised, so a `t`
    /// found in object space is the same `t` in world space.
    #[inline]
    pub fn ray_to_object(&self, ray: &Ray) -> Ray {
        Ray::new(
            self.m_inv * (ray.origin - self.position),
            self.m_inv * ray.dir,
        )
    }

    /// A world point in object coordinates.
    #[inline]
    pub fn point_to_object(&self, p: DVec3) -> DVec3 {
        self.m_inv * (p - self.position)
    }

    /// An object point in world coordinates.
    #[inline]
    pub fn point_to_world(&self, p: DVec3) -> DVec3 {
        self.m * p + self.position
    }

    /// An object-space solid ellipsoid in world space (the same points, mapped).
    pub fn ellipsoid_to_world(&self, e: &SolidEllipsoid) -> SolidEllipsoid {
        SolidEllipsoid {
            centre: self.point_to_world(e.centre),
            axes: self.m * e.axes,
        }
    }

    /// An object-space normal (any length) as a unit world-space normal, same side.
    #[inline]
    pub fn normal_to_world(&self, n: DVec3) -> DVec3 {
        (self.normal_matrix * n).normalize()
    }

    /// The world box holding the object-space box `b` (exact for the parallelepiped image).
    pub fn bounds_to_world(&self, b: &Aabb) -> Aabb {
        if !b.is_finite() {
            return Aabb::EVERYTHING;
        }
        Aabb::from_points(self.box_to_world(b).corners)
    }

    /// The object-space box `b` in world space: the same points, mapped (a parallelepiped).
    pub fn box_to_world(&self, b: &Aabb) -> Hexahedron {
        Hexahedron {
            corners: b.corners().map(|c| self.point_to_world(c)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_hits_and_misses() {
        let b = Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0));
        let r = Ray::new(DVec3::new(-5.0, 0.0, 0.0), DVec3::X);
        assert_eq!(b.clip(&r, 0.0, f64::INFINITY), Some((4.0, 6.0)));
        let miss = Ray::new(DVec3::new(-5.0, 2.0, 0.0), DVec3::X);
        assert_eq!(b.clip(&miss, 0.0, f64::INFINITY), None);
        let behind = Ray::new(DVec3::new(5.0, 0.0, 0.0), DVec3::X);
        assert_eq!(b.clip(&behind, 0.0, f64::INFINITY), None);
    }

    #[test]
    fn ray_lanes_meet_a_box_exactly_where_clip_does() {
        let mut next = crate::testing::uniform_stream(19);
        let mut coordinate = |zero_often: bool| {
            let u = next();
            // Whole numbers put origins on slabs and directions at zero.
            if zero_often && u < 0.3 {
                0.0
            } else if u < 0.5 {
                (u * 20.0).round() - 5.0
            } else {
                (u - 0.75) * 16.0
            }
        };
        let boxes = [
            Aabb::new(DVec3::splat(-1.0), DVec3::splat(1.0)),
            Aabb::new(DVec3::new(0.0, -2.0, 1.0), DVec3::new(3.0, 0.0, 1.0)),
            Aabb::new(DVec3::splat(f64::NEG_INFINITY), DVec3::splat(f64::INFINITY)),
            Aabb::new(
                DVec3::new(f64::NEG_INFINITY, -1.0, f64::NEG_INFINITY),
                DVec3::new(f64::INFINITY, 1.0, f64::INFINITY),
            ),
            Aabb::EMPTY,
        ];
        let (mut met, mut missed, mut extra) = (0, 0, 0);
        for _ in 0..20_000 {
            let rays: [Ray; LANES] = std::array::from_fn(|_| {
                let o = DVec3::new(coordinate(false), coordinate(false), coordinate(false));
                let mut d = DVec3::new(coordinate(true), coordinate(true), coordinate(true));
                if d == DVec3::ZERO {
                    d.x = 1.0;
                }
                Ray::new(o, d)
            });
            let t_min: [f64; LANES] = std::array::from_fn(|_| coordinate(false));
            // Some lanes idle (an empty or reversed range), some unbounded.
            let t_max: [f64; LANES] = std::array::from_fn(|i| match i {
                3 => f64::INFINITY,
                _ => coordinate(false),
            });
            let lanes = RayLanes::new(&rays);
            for b in &boxes {
                let expected = (0..LANES).fold(0, |mask, i| {
                    mask | (b.clip(&rays[i], t_min[i], t_max[i]).is_some() as u32) << i
                });
                assert_eq!(
                    lanes.meet_portable(b, t_min, t_max),
                    expected,
                    "{b:?} {rays:?}"
                );
                assert_eq!(lanes.meet(b, t_min, t_max), expected, "{b:?} {rays:?}");
                // The walk's cheaper test: never a lane fewer, the same where no direction
                // component is zero.
                let may = lanes.may_meet(b, t_min, t_max);
                assert_eq!(lanes.may_meet_portable(b, t_min, t_max), may);
                assert_eq!(may & expected, expected, "{b:?} {rays:?}");
                let oblique = (0..LANES).fold(0, |mask, i| {
                    mask | (!rays[i].dir.cmpeq(DVec3::ZERO).any() as u32) << i
                });
                assert_eq!(may & oblique, expected & oblique, "{b:?} {rays:?}");
                extra += (may & !expected).count_ones();
                met += expected.count_ones();
                missed += LANES as u32 - expected.count_ones();
            }
        }
        // Both answers are common.
        assert!(
            met > 20_000 && missed > 20_000,
            "{met} met, {missed} missed"
        );
        // Rays parallel to a slab outside it, with an infinite range, are among the cases.
        assert!(extra > 0, "may_meet never set a lane meet clears");
    }

    #[test]
    fn frame_round_trips_and_rejects_singular() {
        let f = Frame::new(
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.5, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 3.0),
        )
        .unwrap();
        let p = DVec3::new(0.3, -0.7, 1.1);
        assert!((f.point_to_object(f.point_to_world(p)) - p).length() < 1e-14);
        assert_eq!(
            Frame::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::X + DVec3::Y),
            Err(FrameError::Singular)
        );
        assert_eq!(
            Frame::new(
                DVec3::ZERO,
                DVec3::X,
                DVec3::Y,
                DVec3::new(f64::NAN, 0.0, 1.0)
            ),
            Err(FrameError::NotFinite)
        );
    }
}
