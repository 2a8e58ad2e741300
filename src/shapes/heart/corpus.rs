//! A fixed corpus of heart polynomials from camera rays, shared by tests and benchmarks.

use super::surface::sextic_coefficients;
use crate::geometry::DVec3;

/// One ray of the corpus, in the object space of an axis-aligned heart at the origin, with
/// its sextic and the part `[lo, hi]` of the ray inside the heart's bounding box.
#[derive(Debug, Clone, Copy)]
pub struct CorpusRay {
    /// Ray origin.
    pub origin: DVec3,
    /// Ray direction (not normalised).
    pub dir: DVec3,
    /// `f(origin + t·dir)` in ascending powers of `t`.
    pub coeffs: [f64; 7],
    /// Where the ray enters the box (never below 0).
    pub lo: f64,
    /// Where the ray leaves the box.
    pub hi: f64,
}

/// The heart's bounding box used by the corpus: |X| ≤ 0.72, |Y| ≤ 1.14, −1 ≤ Z ≤ 1.24.
const BOX_MIN: DVec3 = DVec3::new(-0.72, -1.14, -1.0);
const BOX_MAX: DVec3 = DVec3::new(0.72, 1.14, 1.24);

/// The corpus entry for a ray, or `None` when it misses the box.
fn case(origin: DVec3, dir: DVec3) -> Option<CorpusRay> {
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    for k in 0..3 {
        let (o, d) = (origin[k], dir[k]);
        if d == 0.0 {
            if o < BOX_MIN[k] || o > BOX_MAX[k] {
                return None;
            }
        } else {
            let (t0, t1) = ((BOX_MIN[k] - o) / d, (BOX_MAX[k] - o) / d);
            lo = lo.max(t0.min(t1));
            hi = hi.min(t0.max(t1));
        }
    }
    (lo < hi).then(|| CorpusRay {
        origin,
        dir,
        coeffs: sextic_coefficients(origin, dir),
        lo,
        hi,
    })
}

/// Rays chosen for exact degeneracies: multiple roots of order 2, 3 and 6 (the `Z = 0` plane,
/// where `f = A(t)³`), rays through the tip and the dip, a near miss, and a ray starting on
/// the surface.
pub fn heart_hard_rays() -> Vec<CorpusRay> {
    let v = DVec3::new;
    [
        (v(-2.0, 1.0, 0.0), v(1.0, 0.0, 0.0)), // A = 2X²: a 6-fold root at t = 2
        (v(0.0, -2.0, 1.0), v(0.0, 1.0, 0.0)), // through the dip: t = 1, 2 (double), 3
        (v(-2.0, 0.0, 1.0), v(1.0, 0.0, 0.0)), // through the dip along X
        (v(-2.0, 0.0, -1.0), v(1.0, 0.0, 0.0)), // touches the tip: double root t = 2
        (v(0.0, -2.0, -1.0), v(0.0, 1.0, 0.0)), // touches the tip along Y
        (v(3.0, 0.0, 0.0), v(-1.0, 0.0, 0.0)), // Z = 0: triple root at X = 1/√2
        (v(0.0, -3.0, 0.0), v(0.0, 1.0, 0.0)), // Z = 0: triple roots t = 2, 4
        (v(2.0, 2.0, 0.0), v(-1.0, -1.3, 0.0)), // Z = 0, oblique
        (v(2.0, 1.1, 0.0), v(-1.0, 0.0, 0.0)), // Z = 0 near miss: A = 2X² + 0.21 > 0
        (v(0.0, 0.0, 2.0), v(0.0, 0.0, -1.0)), // the axis: triple roots at the dip, and the tip = hi
        (v(0.0, -1.0, 0.0), v(0.0, 1.0, 0.0)), // starts on the surface: roots t = 0, 2
        (v(0.3, -2.0, 0.0), v(0.0, 1.0, 0.0)), // Z = 0 at X = 0.3
    ]
    .into_iter()
    .filter_map(|(o, d)| case(o, d))
    .collect()
}

/// Camera rays through the heart: five cameras (two of them in the `Z = 0` plane, so that a
/// whole row of rays has triple roots), 25 × 25 rays each, kept when they cross the bounding
/// box (hits and misses both), followed by [`heart_hard_rays`].
pub fn heart_corpus() -> Vec<CorpusRay> {
    let cameras = [
        (DVec3::new(3.0, 0.0, 0.0), DVec3::ZERO),
        (DVec3::new(2.5, 1.5, 0.0), DVec3::ZERO),
        (DVec3::new(2.0, 2.0, 2.0), DVec3::new(0.0, 0.0, 0.1)),
        (DVec3::new(0.5, -3.0, -1.2), DVec3::new(0.0, 0.0, 0.1)),
        (DVec3::new(-2.5, 0.7, 1.9), DVec3::ZERO),
    ];
    let mut out = Vec::new();
    for (eye, target) in cameras {
        let forward = (target - eye).normalize();
        let right = forward.cross(DVec3::Z).normalize();
        let up = right.cross(forward);
        for j in 0..25 {
            for i in 0..25 {
                let u = (i as f64 - 12.0) / 12.0 * 0.45;
                let w = (j as f64 - 12.0) / 12.0 * 0.45;
                // Exact zeros keep the centre row in the plane of the eye when it is Z = 0.
                let dir = forward + u * right + w * up;
                let dir = if eye.z == 0.0 && target.z == 0.0 && j == 12 {
                    DVec3::new(dir.x, dir.y, 0.0)
                } else {
                    dir
                };
                out.extend(case(eye, dir));
            }
        }
    }
    out.extend(heart_hard_rays());
    out
}
