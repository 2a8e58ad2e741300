//! A fixed corpus of typed-surface polynomials from camera rays (degrees 4, 6, 8 and 16),
//! shared by tests and benchmarks beside the heart's corpus.

use super::Implicit;
use crate::geometry::{DVec3, Frame, Ray};

/// One first-root query of the corpus: what the generic intersection path asks the solver
/// for one camera ray.
#[derive(Debug, Clone)]
pub struct TypedRay {
    /// The surface, as the preset (or equation) it was typed with.
    pub surface: &'static str,
    /// Degree of the ray polynomial.
    pub degree: usize,
    /// Normalised coefficients in ascending powers of `s`.
    pub coeffs: Vec<f64>,
    /// Lower end of the interval (excluded).
    pub lo: f64,
    /// Upper end of the interval (included).
    pub hi: f64,
}

/// The surfaces of the corpus, with their degree: a torus, Barth's sextic, Chmutov's octic
/// and the unit sphere written with degree 16.
pub const TYPED_SURFACES: [(&str, usize); 4] = [
    ("torus 1 0.3", 4),
    ("barth_sextic", 6),
    ("chmutov 8", 8),
    ("(x^2+y^2+z^2)^8 = 1", 16),
];

/// The surface of a [`TYPED_SURFACES`] entry, in object space (identity frame), through
/// its whole expansion (the degree-16 sphere is a power shifted by a constant, which
/// [`Implicit::new`] would trace as its level sets, of degree 2).
fn surface(text: &str) -> Implicit {
    let mut words = text.split(' ');
    let name = words.next().unwrap_or("");
    let params: Vec<f64> = words.filter_map(|w| w.parse().ok()).collect();
    Implicit::from_preset(name, &params, Frame::identity(), None)
        .or_else(|_| {
            let bound = Implicit::new(text, Frame::identity(), None)
                .map_err(|e| e.message)?
                .bound();
            Implicit::new_generic(text, Frame::identity(), bound).map_err(|e| e.message)
        })
        .expect("a corpus surface")
}

/// Camera rays through each surface of [`TYPED_SURFACES`]: three cameras, 25 × 25 rays each,
/// aimed across the clip sphere, kept when the generic path puts a query to the solver (hits
/// and misses both). Ordered by surface.
pub fn typed_corpus() -> Vec<TypedRay> {
    let mut out = Vec::new();
    for (text, degree) in TYPED_SURFACES {
        let shape = surface(text);
        let r = shape.bound();
        let cameras = [
            DVec3::new(3.0, 0.4, 0.3) * r,
            DVec3::new(1.7, 1.9, 1.3) * r,
            DVec3::new(-0.6, -2.2, 2.1) * r,
        ];
        for eye in cameras {
            let forward = (-eye).normalize();
            let right = forward.cross(DVec3::Z).normalize();
            let up = right.cross(forward);
            for j in 0..25 {
                for i in 0..25 {
                    let u = (i as f64 - 12.0) / 12.0 * 0.4;
                    let w = (j as f64 - 12.0) / 12.0 * 0.4;
                    let ray = Ray::new(eye, forward + u * right + w * up);
                    if let Some((coeffs, lo, hi)) = shape.solver_query(&ray) {
                        out.push(TypedRay {
                            surface: text,
                            degree,
                            coeffs,
                            lo,
                            hi,
                        });
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_surface_contributes_queries_of_its_degree() {
        let corpus = typed_corpus();
        for (text, degree) in TYPED_SURFACES {
            let rays: Vec<_> = corpus.iter().filter(|r| r.surface == text).collect();
            assert!(rays.len() > 500, "{text}: {}", rays.len());
            assert!(rays
                .iter()
                .all(|r| r.coeffs.len() <= degree + 1 && r.lo < r.hi));
            let full = rays.iter().filter(|r| r.coeffs.len() == degree + 1).count();
            assert!(
                full * 10 > rays.len() * 9,
                "{text}: {full} of {}",
                rays.len()
            );
        }
    }
}
