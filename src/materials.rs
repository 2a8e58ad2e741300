//! Surface properties: what a surface does with light in the Whitted model.

use crate::geometry::DVec3;

/// How a surface reflects and transmits light. Colours are linear RGB, normally in `[0, 1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Lambert diffuse colour (also scales the ambient term).
    pub diffuse: DVec3,
    /// Optional 3-D checker pattern: the second colour and the cell size (world units, > 0);
    /// cells alternate between `diffuse` and this colour.
    pub checker: Option<(DVec3, f64)>,
    /// Optional diffuse colour for the back side of a surface (seen where a clipped implicit
    /// surface is cut open); `None` shades both sides alike.
    pub inside: Option<DVec3>,
    /// Specular highlight weight `ks ≥ 0` (white highlight of weight ks).
    pub specular: f64,
    /// Specular exponent (Blinn–Phong), ≥ 1.
    pub shininess: f64,
    /// Mirror reflection weight `kr` in `[0, 1]`, added to whatever the Fresnel term of a
    /// transmissive surface reflects (see [`crate::integrator`]).
    pub reflect: f64,
    /// Transmission weight `kt` in `[0, 1]`: the weight of the dielectric interface, split
    /// by the Fresnel reflectance between refraction and reflection (all reflected under
    /// total internal reflection). Shadow rays lose a factor `kt` per surface crossed.
    pub transmit: f64,
    /// Index of refraction of the inside (> 0; 1 = no bending).
    pub ior: f64,
    /// Beer–Lambert absorption per unit length inside the object, per channel (≥ 0).
    pub attenuation: DVec3,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            diffuse: DVec3::splat(0.8),
            checker: None,
            inside: None,
            specular: 0.0,
            shininess: 32.0,
            reflect: 0.0,
            transmit: 0.0,
            ior: 1.0,
            attenuation: DVec3::ZERO,
        }
    }
}

impl Material {
    /// A plain diffuse material of the given colour.
    pub fn diffuse(colour: DVec3) -> Self {
        Self {
            diffuse: colour,
            ..Self::default()
        }
    }

    /// Shift of the checker lattice, in cells: keeps a surface that lies exactly on a cell
    /// boundary (a floor at `z = 0`) from flickering between two cells with rounding noise.
    pub const CHECKER_OFFSET: f64 = 1e-6;

    /// The diffuse colour at world point `p` (the checker pattern applied, if any). Cells
    /// are `[k·size, (k+1)·size)` per axis, shifted by [`Material::CHECKER_OFFSET`] cells.
    /// Any `p` and `size` give one of the two colours: cell indices beyond 2⁵³ (where every
    /// f64 is an even whole number) count as even, and so do non-finite ones.
    pub fn diffuse_at(&self, p: DVec3) -> DVec3 {
        match self.checker {
            None => self.diffuse,
            Some((other, size)) => {
                let c = (p / size + Self::CHECKER_OFFSET).floor();
                // The parity of each index in floating point: exact for every whole f64, with
                // no conversion to an integer that could saturate and overflow when summed.
                let odd = |k: f64| k.is_finite() && k.rem_euclid(2.0) == 1.0;
                let odd_cells = [c.x, c.y, c.z].into_iter().filter(|&k| odd(k)).count();
                if odd_cells % 2 == 0 {
                    self.diffuse
                } else {
                    other
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker(size: f64) -> Material {
        Material {
            checker: Some((DVec3::ONE, size)),
            ..Material::diffuse(DVec3::ZERO)
        }
    }

    #[test]
    fn checker_cells_alternate() {
        let m = checker(0.5);
        assert_eq!(m.diffuse_at(DVec3::new(0.1, 0.1, 0.1)), DVec3::ZERO);
        assert_eq!(m.diffuse_at(DVec3::new(0.6, 0.1, 0.1)), DVec3::ONE);
        assert_eq!(m.diffuse_at(DVec3::new(0.6, 0.6, 0.1)), DVec3::ZERO);
        assert_eq!(m.diffuse_at(DVec3::new(-0.4, 0.1, 0.1)), DVec3::ONE);
        assert_eq!(m.diffuse_at(DVec3::new(-0.4, -0.4, -0.4)), DVec3::ONE);
    }

    /// The fuzzer's find: a cell size of 11e-308 made the cell index saturate at i64::MAX
    /// and the parity sum overflow (a panic with overflow checks, a wrong colour without).
    #[test]
    fn huge_cell_indices_neither_overflow_nor_wrap() {
        let m = checker(11e-308);
        for p in [
            DVec3::new(3.0, -0.5, -1.0),
            DVec3::new(1e300, 1e300, 1e300),
            DVec3::splat(f64::MAX),
            DVec3::new(f64::INFINITY, f64::NAN, 0.0),
        ] {
            let c = m.diffuse_at(p);
            assert!(c == DVec3::ZERO || c == DVec3::ONE, "{p}: {c}");
        }
        // Indices beyond 2^53 are even whole numbers: only the small one decides.
        let m = checker(1.0);
        let big = 2f64.powi(60);
        assert_eq!(m.diffuse_at(DVec3::new(big, big, 0.5)), DVec3::ZERO);
        assert_eq!(m.diffuse_at(DVec3::new(big, big, 1.5)), DVec3::ONE);
        assert_eq!(m.diffuse_at(DVec3::new(5e-324, 0.5, 0.5)), DVec3::ZERO);
    }
}
