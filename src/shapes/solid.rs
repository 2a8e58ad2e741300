//! The solid a polynomial surface bounds, as the mesher ([`crate::mesh`]) reads it from a
//! scene object: the exact polynomial in object space, the clip ball and the placement.

use super::implicit::{expand, poly::Poly, HEART_EQUATION};
use crate::geometry::Frame;
use std::sync::{Arc, OnceLock};

/// A polynomial solid placed in the world: the object-space region `f ≤ 0` (`f` negative
/// inside, positive outside, as [`super::Implicit::value`] promises) cut by the object-space
/// ball of radius `clip_radius` about the origin, carried to the world by `frame`
/// (`p_world = M·p_obj + position`).
#[derive(Debug, Clone)]
pub struct PolynomialSolid {
    /// `f`, exactly expanded (rational coefficients), in object coordinates.
    pub polynomial: Arc<Poly>,
    /// Object-space radius of the clip ball (> 0, finite).
    pub clip_radius: f64,
    /// The object's placement.
    pub frame: Frame,
}

/// The paper's heart `(2x² + y² + z² − 1)³ − (0.1x² + y²)·z³`, expanded once per process.
pub fn heart_polynomial() -> Arc<Poly> {
    static HEART: OnceLock<Arc<Poly>> = OnceLock::new();
    HEART
        .get_or_init(|| Arc::new(expand(HEART_EQUATION).expect("the heart's equation expands")))
        .clone()
}

/// An object-space radius about the origin that holds the whole heart with room to spare
/// (the farthest corner of its box, grown by 5%), so the clip ball never cuts it.
pub fn heart_clip_radius() -> f64 {
    super::heart::BOUNDS
        .corners()
        .iter()
        .map(|c| c.length())
        .fold(0.0, f64::max)
        * 1.05
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::DVec3;
    use crate::shapes::implicit::poly::Compiled;

    #[test]
    fn the_heart_polynomial_is_the_heart_function() {
        let f = Compiled::new(&heart_polynomial());
        for p in [
            DVec3::new(0.1, 0.2, 0.3),
            DVec3::new(-0.5, 0.9, 1.1),
            DVec3::new(0.7, -1.0, -0.2),
        ] {
            let want = super::super::heart::heart_fn(p);
            assert!((f.eval(p.to_array()) - want).abs() <= 1e-12 * (1.0 + want.abs()));
        }
    }

    #[test]
    fn the_heart_clip_ball_holds_the_heart_box() {
        let r = heart_clip_radius();
        for c in super::super::heart::EXTENTS.corners() {
            assert!(c.length() < r / 1.04);
        }
    }
}
