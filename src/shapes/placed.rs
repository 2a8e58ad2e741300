//! Placement in the world of a shape defined in its own object space: one wrapper,
//! [`Placed`], for every shape given by a position and a basis (`BOX`, `ELLIPSOID`, `HEART`,
//! `IMPLICIT`). The wrapper owns the [`Placement`] (the validated [`Frame`] with the ∞-norm of
//! `M⁻¹`, computed once), carries each world ray into object space once (the direction is
//! not renormalised, so `t` is the same in both spaces) and hands it to the object-space shape
//! ([`ObjectShape`]) together with the placement, which also maps normals and boxes back.

use super::{Shape, ShapeError, SolverReport, LANES};
use crate::geometry::{Aabb, DMat3, DVec3, Frame, FrameError, Hexahedron, Ray, SolidEllipsoid};

/// A validated object frame (`p_world = M·p_object + position`) and `‖M⁻¹‖∞`, which bounds how
/// much the rounding of a world point grows on its way into object space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    frame: Frame,
    inv_norm: f64,
    /// The frame maps nothing: position `+0` and every matrix the identity, bit for bit.
    identity: bool,
}

/// How a shape's placement parameters are called in its error messages: the shape (`"box"`),
/// its position (`"corner"`) and its basis vectors (`"edge"`).
#[derive(Debug, Clone, Copy)]
pub struct PlacementNames {
    /// The shape, as in "the box's …".
    pub shape: &'static str,
    /// The position parameter, as in "… corner and edge vectors …".
    pub position: &'static str,
    /// The basis vectors, as in "… three edge vectors …".
    pub vectors: &'static str,
}

impl Placement {
    /// The placement by an already validated frame.
    pub fn new(frame: Frame) -> Self {
        let inv_norm = (0..3)
            .map(|i| frame.m_inv.row(i).abs().element_sum())
            .fold(0.0, f64::max);
        let bits = |m: DMat3| m.to_cols_array().map(f64::to_bits);
        let unit = bits(DMat3::IDENTITY);
        let identity = frame.position.to_array().map(f64::to_bits) == [0; 3]
            && bits(frame.m) == unit
            && bits(frame.m_inv) == unit
            && bits(frame.normal_matrix) == unit;
        Self {
            frame,
            inv_norm,
            identity,
        }
    }

    /// The placement at `position` with basis columns `u`, `v`, `w` (finite, linearly
    /// independent: see [`Frame::new`]).
    pub fn from_basis(position: DVec3, u: DVec3, v: DVec3, w: DVec3) -> Result<Self, FrameError> {
        Frame::new(position, u, v, w).map(Self::new)
    }

    /// [`Placement::from_basis`] with the errors worded for the shape's own parameters: "the
    /// box's corner and edge vectors must all be finite", "the box's three edge vectors lie in
    /// one plane (…), so the box would be flat".
    pub fn named(
        position: DVec3,
        u: DVec3,
        v: DVec3,
        w: DVec3,
        names: PlacementNames,
    ) -> Result<Self, ShapeError> {
        let PlacementNames {
            shape,
            position: origin,
            vectors,
        } = names;
        Self::from_basis(position, u, v, w).map_err(|e| match e {
            FrameError::NotFinite => ShapeError(format!(
                "the {shape}'s {origin} and {vectors} vectors must all be finite"
            )),
            FrameError::Singular => ShapeError(format!(
                "the {shape}'s three {vectors} vectors lie in one plane (or nearly so, or one is \
                 zero), so the {shape} would be flat"
            )),
        })
    }

    /// The frame.
    #[inline]
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// `‖M⁻¹‖∞`, the largest absolute row sum of the world-to-object matrix.
    #[inline]
    pub fn inv_norm(&self) -> f64 {
        self.inv_norm
    }

    /// `‖M⁻¹‖∞·(‖o‖∞ + ‖position‖∞)` for a world point `o`: the object-space size of the
    /// quantities `o` goes through on its way into object space, so that `ε` times it bounds
    /// the rounding of its object coordinates (up to a small factor).
    #[inline]
    pub fn origin_reach(&self, o: DVec3) -> f64 {
        self.inv_norm * (o.abs().max_element() + self.frame.position.abs().max_element())
    }

    /// `‖M⁻¹‖∞·‖position‖∞`: how large the world position is in object units.
    #[inline]
    pub fn position_reach(&self) -> f64 {
        self.inv_norm * self.frame.position.abs().max_element()
    }

    /// The world ray in object space, with the same `t` (see [`Frame::ray_to_object`]).
    #[inline]
    pub fn ray_to_object(&self, ray: &Ray) -> Ray {
        // The identity frame's product would give the same numbers but for the sign of a
        // zero (`1·(−0) + 0·y` is `+0`): a placement at the origin with the unit basis, the
        // usual one of a typed surface, skips the nine products and sums per vector.
        if self.identity {
            *ray
        } else {
            self.frame.ray_to_object(ray)
        }
    }

    /// Whether object space is world space: the placement at `+0` with the unit basis, bit
    /// for bit (the usual placement of a typed surface). Then [`Placement::ray_to_object`]
    /// and [`Placement::point_to_object`] hand back what they are given.
    #[inline]
    pub fn is_identity(&self) -> bool {
        self.identity
    }

    /// The world point `p` in object coordinates (see [`Frame::point_to_object`]).
    #[inline]
    pub fn point_to_object(&self, p: DVec3) -> DVec3 {
        if self.identity {
            p
        } else {
            self.frame.point_to_object(p)
        }
    }

    /// An object-space normal direction `n` (any length, outward) as a unit world normal:
    /// `(M⁻¹)ᵀ·n` rescaled by its largest component before normalising, so tiny or huge
    /// vectors neither underflow nor overflow; `+Z` when that is zero or not finite (never
    /// NaN).
    #[inline]
    pub fn normal_to_world(&self, n: DVec3) -> DVec3 {
        let w = if self.identity {
            n
        } else {
            self.frame.normal_matrix * n
        };
        let big = w.abs().max_element();
        if big > 0.0 && big.is_finite() {
            (w / big).normalize()
        } else {
            DVec3::Z
        }
    }

    /// The world box holding the object-space box `b` (see [`Frame::bounds_to_world`]).
    #[inline]
    pub fn bounds_to_world(&self, b: &Aabb) -> Aabb {
        self.frame.bounds_to_world(b)
    }
}

/// A shape in its own object space, placed in the world by a [`Placed`] wrapper.
///
/// The contract is [`Shape`]'s, with the ray already in object space: `intersect` gets the
/// world ray and the same ray in object space (`local`, same `t`), and returns the smallest
/// `t` in `(t_min, t_max)` on the surface; `normal` gets an object-space point and returns the
/// unit outward normal in world space (never NaN); `bounds` is a world box holding the
/// surface. The placement is passed to each, for the rounding bounds and mappings it offers.
pub trait ObjectShape: Send + Sync + std::fmt::Debug {
    /// Smallest `t` in `(t_min, t_max)` at which the ray meets the surface.
    fn intersect(
        &self,
        at: &Placement,
        world: &Ray,
        local: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<f64>;
    /// [`Shape::intersect_lanes`]: lane `i` is exactly
    /// `self.intersect(at, &world[i], &local[i], t_min[i], t_max[i])`, `None` when
    /// `t_max[i] <= t_min[i]`.
    fn intersect_lanes(
        &self,
        at: &Placement,
        world: &[Ray; LANES],
        local: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [Option<f64>; LANES] {
        super::each_lane(t_min, t_max, |i| {
            self.intersect(at, &world[i], &local[i], t_min[i], t_max[i])
        })
    }
    /// [`ObjectShape::intersect_lanes`] of the world rays `world`, each lane's object-space ray
    /// made by `at`'s frame ([`Frame::ray_to_object`]), for a placement that is not the
    /// identity: the same answers. A shape may map the rays its own way if each lane's
    /// object-space ray is the same bits (the heart maps them in vector registers).
    #[inline]
    fn intersect_lanes_mapped(
        &self,
        at: &Placement,
        world: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [Option<f64>; LANES] {
        // Made fresh from the world rays, not updated in place: an in-place update reads
        // each ray back in wide loads while the copy's narrower stores are pending. By the
        // frame itself: the caller has ruled out the identity, once for the group (asked
        // again in each lane's mapping, it cost Barth's sextic 1.9 %).
        let frame = at.frame();
        let local: [Ray; LANES] = std::array::from_fn(|i| frame.ray_to_object(&world[i]));
        self.intersect_lanes(at, world, &local, t_min, t_max)
    }
    /// Unit outward world normal at the object-space point `q` on the surface.
    fn normal(&self, at: &Placement, q: DVec3) -> DVec3;
    /// [`ObjectShape::normal`] at the [`LANES`] object-space points `q` where `live` is set:
    /// lane `i` is exactly `self.normal(at, q[i])` there, and zero elsewhere.
    fn normal_lanes(
        &self,
        at: &Placement,
        q: &[DVec3; LANES],
        live: [bool; LANES],
    ) -> [DVec3; LANES] {
        normals_one_at_a_time(self, at, q, live)
    }
    /// See [`Shape::normal_lanes_pays`].
    fn normal_lanes_pays(&self) -> bool {
        false
    }
    /// World-space box containing the surface.
    fn bounds(&self, at: &Placement) -> Aabb;
    /// See [`Shape::enclosing_ellipsoids`], in object space.
    fn enclosing_ellipsoids(&self) -> Vec<SolidEllipsoid> {
        Vec::new()
    }
    /// See [`Shape::enclosing_cells`]: object-space boxes.
    fn enclosing_cells(&self) -> Vec<Aabb> {
        Vec::new()
    }
    /// See [`Shape::solver_report`]; the rays as for `intersect`.
    fn solver_report(
        &self,
        at: &Placement,
        world: &Ray,
        local: &Ray,
        t_min: f64,
        t_max: f64,
    ) -> Option<SolverReport> {
        let _ = (at, world, local, t_min, t_max);
        None
    }
    /// The SHA-256 (hex) of the file the shape was read from (a `MESH`'s), else `None`.
    fn source_digest(&self) -> Option<String> {
        None
    }
    /// See [`Shape::polynomial_solid`]: the object-space polynomial (negative inside) and the
    /// object-space clip radius; the placement is added by [`Placed`].
    fn polynomial_solid(&self) -> Option<(std::sync::Arc<super::implicit::poly::Poly>, f64)> {
        None
    }
}

/// [`ObjectShape::normal_lanes`] asked of `shape` lane by lane: its default, and the answer of
/// a shape whose own lanes path does not cover a case.
pub(crate) fn normals_one_at_a_time<S: ObjectShape + ?Sized>(
    shape: &S,
    at: &Placement,
    q: &[DVec3; LANES],
    live: [bool; LANES],
) -> [DVec3; LANES] {
    std::array::from_fn(|i| {
        if live[i] {
            shape.normal(at, q[i])
        } else {
            DVec3::ZERO
        }
    })
}

/// An object-space shape `S` placed in the world by a [`Placement`]; implements [`Shape`].
#[derive(Debug, Clone, PartialEq)]
pub struct Placed<S> {
    at: Placement,
    shape: S,
}

impl<S> Placed<S> {
    /// `shape` placed by `at`.
    pub fn place(at: Placement, shape: S) -> Self {
        Self { at, shape }
    }

    /// The placement of the shape.
    #[inline]
    pub fn frame(&self) -> &Frame {
        self.at.frame()
    }

    /// The placement with its rounding bound.
    #[inline]
    pub fn placement(&self) -> &Placement {
        &self.at
    }

    /// The object-space shape.
    #[inline]
    pub fn object(&self) -> &S {
        &self.shape
    }

    /// The object-space shape, to change its settings.
    #[inline]
    pub(crate) fn object_mut(&mut self) -> &mut S {
        &mut self.shape
    }
}

impl<S: ObjectShape> Shape for Placed<S> {
    #[inline]
    fn intersect(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
        let local = self.at.ray_to_object(ray);
        self.shape.intersect(&self.at, ray, &local, t_min, t_max)
    }

    #[inline]
    fn intersect_lanes(
        &self,
        rays: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [Option<f64>; LANES] {
        if self.at.is_identity() {
            // Object space is world space: the world rays themselves, not copies.
            return self
                .shape
                .intersect_lanes(&self.at, rays, rays, t_min, t_max);
        }
        self.shape
            .intersect_lanes_mapped(&self.at, rays, t_min, t_max)
    }

    #[inline]
    fn occludes_lanes(
        &self,
        rays: &[Ray; LANES],
        t_min: [f64; LANES],
        t_max: [f64; LANES],
    ) -> [bool; LANES] {
        // `occludes` is `intersect(…).is_some()` for every placed shape.
        self.intersect_lanes(rays, t_min, t_max)
            .map(|hit| hit.is_some())
    }

    fn normal(&self, p: DVec3) -> DVec3 {
        self.shape.normal(&self.at, self.at.point_to_object(p))
    }

    #[inline]
    fn normal_lanes(&self, p: &[DVec3; LANES], live: [bool; LANES]) -> [DVec3; LANES] {
        if self.at.is_identity() {
            return self.shape.normal_lanes(&self.at, p, live);
        }
        let frame = self.at.frame();
        let q = p.map(|p| frame.point_to_object(p));
        self.shape.normal_lanes(&self.at, &q, live)
    }

    fn normal_lanes_pays(&self) -> bool {
        self.shape.normal_lanes_pays()
    }

    fn bounds(&self) -> Aabb {
        self.shape.bounds(&self.at)
    }

    fn enclosing_ellipsoids(&self) -> Vec<SolidEllipsoid> {
        let frame = self.at.frame();
        self.shape
            .enclosing_ellipsoids()
            .iter()
            .map(|e| frame.ellipsoid_to_world(e))
            .collect()
    }

    fn enclosing_cells(&self) -> Vec<Hexahedron> {
        let frame = self.at.frame();
        self.shape
            .enclosing_cells()
            .iter()
            .map(|b| frame.box_to_world(b))
            .collect()
    }

    fn solver_report(&self, ray: &Ray, t_min: f64, t_max: f64) -> Option<SolverReport> {
        let local = self.at.ray_to_object(ray);
        self.shape
            .solver_report(&self.at, ray, &local, t_min, t_max)
    }

    fn source_digest(&self) -> Option<String> {
        self.shape.source_digest()
    }
    fn polynomial_solid(&self) -> Option<super::PolynomialSolid> {
        let (polynomial, clip_radius) = self.shape.polynomial_solid()?;
        Some(super::PolynomialSolid {
            polynomial,
            clip_radius,
            frame: *self.at.frame(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit sphere in object space, by the plain quadratic formula.
    #[derive(Debug)]
    struct Ball;

    impl ObjectShape for Ball {
        fn intersect(
            &self,
            _: &Placement,
            _: &Ray,
            r: &Ray,
            t_min: f64,
            t_max: f64,
        ) -> Option<f64> {
            let (a, b, c) = (
                r.dir.length_squared(),
                r.origin.dot(r.dir),
                r.origin.length_squared() - 1.0,
            );
            let disc = (b * b - a * c).sqrt();
            [(-b - disc) / a, (-b + disc) / a]
                .into_iter()
                .find(|&t| t > t_min && t < t_max)
        }
        fn normal(&self, at: &Placement, q: DVec3) -> DVec3 {
            at.normal_to_world(q)
        }
        fn bounds(&self, at: &Placement) -> Aabb {
            at.bounds_to_world(&Aabb::new(DVec3::splat(-1.0), DVec3::ONE))
        }
    }

    fn placed() -> Placed<Ball> {
        let at = Placement::from_basis(
            DVec3::new(1.0, -2.0, 3.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 0.5, 0.0),
            DVec3::new(0.0, 0.0, 4.0),
        )
        .unwrap();
        Placed::place(at, Ball)
    }

    #[test]
    fn t_is_shared_between_world_and_object_space() {
        // The ellipsoid x²/4 + y²/0.25 + z²/16 = 1 about (1, −2, 3): along x from x = −9 with
        // a direction of length 2, it is hit at x = −1, t = 4.
        let s = placed();
        let ray = Ray::new(DVec3::new(-9.0, -2.0, 3.0), DVec3::new(2.0, 0.0, 0.0));
        let t = s.intersect(&ray, 0.0, f64::INFINITY).unwrap();
        assert!((t - 4.0).abs() < 1e-12, "{t}");
        assert!((s.normal(ray.at(t)) - DVec3::NEG_X).length() < 1e-12);
        // Off-axis, the normal is the world gradient (x/4, y/0.25, z/16) of the ellipsoid.
        let q = DVec3::new(0.6, 0.0, 0.8);
        let p = s.frame().point_to_world(q);
        let g = DVec3::new((p.x - 1.0) / 4.0, 0.0, (p.z - 3.0) / 16.0).normalize();
        assert!((s.normal(p) - g).length() < 1e-12);
        let b = s.bounds();
        assert_eq!(
            (b.min, b.max),
            (DVec3::new(-1.0, -2.5, -1.0), DVec3::new(3.0, -1.5, 7.0))
        );
    }

    #[test]
    fn the_inverse_norm_and_reaches() {
        let s = placed();
        // M⁻¹ = diag(1/2, 2, 1/4): its largest row sum is 2.
        assert_eq!(s.placement().inv_norm(), 2.0);
        assert_eq!(s.placement().position_reach(), 6.0);
        assert_eq!(s.placement().origin_reach(DVec3::new(0.0, 5.0, -1.0)), 16.0);
    }

    #[test]
    fn normals_never_nan_at_any_scale() {
        let at = placed().at;
        for n in [
            DVec3::splat(1e-300),
            DVec3::new(1e300, -1e300, 1e300),
            DVec3::ZERO,
            DVec3::splat(f64::NAN),
        ] {
            let w = at.normal_to_world(n);
            assert!(
                w.is_finite() && (w.length() - 1.0).abs() < 1e-12,
                "{n}: {w}"
            );
        }
        assert_eq!(at.normal_to_world(DVec3::ZERO), DVec3::Z);
    }

    /// The identity placement hands rays, points and normals through unchanged, where the
    /// frame's products give the same values (up to the sign of a zero); any other placement,
    /// even at `−0` or with a unit basis in another order, maps them.
    #[test]
    fn the_identity_placement_maps_nothing() {
        let unit = |p: DVec3| Placement::from_basis(p, DVec3::X, DVec3::Y, DVec3::Z).unwrap();
        let at = unit(DVec3::ZERO);
        assert!(at.is_identity());
        let others = [
            unit(DVec3::new(0.0, -0.0, 0.0)),
            unit(DVec3::new(0.0, 0.0, 1e-300)),
            Placement::from_basis(DVec3::ZERO, DVec3::Y, DVec3::X, DVec3::Z).unwrap(),
            Placement::from_basis(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z * 2.0).unwrap(),
        ];
        assert!(others.iter().all(|o| !o.is_identity()));
        let frame = at.frame();
        let mut uniform = crate::testing::uniform_stream(0x9e37_79b9_7f4a_7c15);
        let mut next = move || 2.0 * uniform() - 1.0;
        for _ in 0..1000 {
            let (o, d) = (
                DVec3::new(next(), next(), next()),
                DVec3::new(next(), next(), next()),
            );
            let ray = Ray::new(o * 10.0, d);
            let (got, want) = (at.ray_to_object(&ray), frame.ray_to_object(&ray));
            assert_eq!((got.origin, got.dir), (ray.origin, ray.dir));
            assert_eq!((got.origin, got.dir), (want.origin, want.dir));
            assert_eq!(at.point_to_object(o), frame.point_to_object(o));
            assert_eq!(
                at.normal_to_world(d).to_array().map(f64::to_bits),
                frame
                    .normal_to_world(d / d.abs().max_element())
                    .to_array()
                    .map(f64::to_bits),
            );
        }
    }

    #[test]
    fn errors_name_the_shapes_parameters() {
        let names = PlacementNames {
            shape: "box",
            position: "corner",
            vectors: "edge",
        };
        let flat = Placement::named(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::X, names);
        assert_eq!(
            flat.unwrap_err().0,
            "the box's three edge vectors lie in one plane (or nearly so, or one is zero), so \
             the box would be flat"
        );
        let nan = Placement::named(DVec3::splat(f64::NAN), DVec3::X, DVec3::Y, DVec3::Z, names);
        assert_eq!(
            nan.unwrap_err().0,
            "the box's corner and edge vectors must all be finite"
        );
    }
}
