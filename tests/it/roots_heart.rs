//! The root finders on real heart polynomials from camera rays (the shared corpus), checked
//! against an independent reference: the heart function sampled in 3D along the ray.

use kardia::roots::{first_root, first_root_yuksel, sturm_roots, Solver};
use kardia::shapes::heart::{heart_corpus, heart_fn, heart_hard_rays, CorpusRay};

/// First sign change of `heart_fn` along the ray in `(lo, hi]` (4000 samples, then bisection),
/// or `None`. Blind to roots without a sign change (tangent rays: double roots).
fn reference(r: &CorpusRay) -> Option<f64> {
    let f = |t: f64| heart_fn(r.origin + t * r.dir);
    let steps = 4000;
    let h = (r.hi - r.lo) / steps as f64;
    let (mut a, mut fa) = (r.lo, f(r.lo));
    for k in 1..=steps {
        let b = if k == steps {
            r.hi
        } else {
            r.lo + k as f64 * h
        };
        let fb = f(b);
        if fa != 0.0 && (fb == 0.0 || (fa < 0.0) != (fb < 0.0)) {
            let (mut x0, mut x1) = (a, b);
            for _ in 0..200 {
                let m = 0.5 * (x0 + x1);
                if m <= x0 || m >= x1 {
                    break;
                }
                let fm = f(m);
                if fm != 0.0 && (fm < 0.0) == (fa < 0.0) {
                    x0 = m;
                } else {
                    x1 = m;
                }
            }
            return Some(x1);
        }
        a = b;
        fa = fb;
    }
    None
}

/// Both solvers on every corpus ray: the same hit or miss as the reference (or, where the
/// reference sees no sign change, a tangent root: `|f|` at rounding level there), and `t`
/// within 1e-3 of the reference relative (the worst rays graze the equator curve or the
/// silhouette of the `Z = 0` plane, where f's roots are ill-conditioned); on at least 99% of
/// the rays within 1e-9.
#[test]
fn corpus_rays_match_the_reference() {
    let corpus = heart_corpus();
    assert!(corpus.len() > 2000);
    let mut hits = 0;
    for solver in [first_root, first_root_yuksel] {
        let mut tight = 0;
        for (i, r) in corpus.iter().enumerate() {
            let got = solver(&r.coeffs, r.lo, r.hi);
            match (got, reference(r)) {
                (Some(t), Some(t_ref)) => {
                    hits += 1;
                    let err = (t - t_ref).abs() / t_ref;
                    assert!(err <= 1e-3, "ray {i}: t = {t}, reference {t_ref}");
                    tight += usize::from(err <= 1e-9);
                }
                (None, None) => tight += 1,
                (Some(t), None) => {
                    // A tangent root, which sampling cannot see: f must vanish there.
                    let p = r.origin + t * r.dir;
                    assert!(heart_fn(p).abs() <= 1e-9, "ray {i}: spurious root {t}");
                    tight += 1;
                }
                (None, Some(t_ref)) => panic!("ray {i}: missed the root at {t_ref} ({r:?})"),
            }
        }
        assert!(
            tight * 100 >= corpus.len() * 99,
            "{tight} of {}",
            corpus.len()
        );
    }
    assert!(hits > 1000, "the corpus must have hits: {hits}");
}

/// Both solvers agree on every corpus ray: same hit/miss, `t` within 1e-3 relative, and
/// within 1e-9 relative on at least 99% of rays.
#[test]
fn solvers_agree_on_the_corpus() {
    let corpus = heart_corpus();
    let mut tight = 0;
    for (i, r) in corpus.iter().enumerate() {
        let s = Solver::Sturm.first_root(&r.coeffs, r.lo, r.hi);
        let y = Solver::Yuksel.first_root(&r.coeffs, r.lo, r.hi);
        match (s, y) {
            (Some(a), Some(b)) => {
                let err = (a - b).abs() / a.abs().max(1e-300);
                assert!(err <= 1e-3, "ray {i}: sturm {a}, yuksel {b}");
                tight += usize::from(err <= 1e-9);
            }
            (None, None) => tight += 1,
            _ => panic!("ray {i}: sturm {s:?}, yuksel {y:?} ({r:?})"),
        }
    }
    assert!(
        tight * 100 >= corpus.len() * 99,
        "{tight} of {}",
        corpus.len()
    );
}

/// The exactly constructed hard rays, with their exactly known first roots.
#[test]
fn hard_rays_have_the_known_first_root() {
    let hard = heart_hard_rays();
    let expected = [
        Some(2.0),                                // 6-fold root
        Some(1.0),                                // through the dip along Y
        Some(2.0 - (0.1f64 / 8.0).powf(0.25)),    // through the dip along X
        Some(2.0),                                // touches the tip (double)
        Some(2.0),                                // touches the tip along Y (double)
        Some(3.0 - 0.5f64.sqrt()),                // Z = 0: triple
        Some(2.0),                                // Z = 0: triple
        None,                                     // Z = 0 oblique: checked by the corpus test
        None,                                     // Z = 0 near miss
        Some(1.0),                                // the axis: the dip, triple
        Some(2.0),                                // starts on the surface: t = 0 excluded
        Some(2.0 - (1.0f64 - 2.0 * 0.09).sqrt()), // Z = 0 at X = 0.3: triple
    ];
    assert_eq!(hard.len(), expected.len());
    for (i, (r, e)) in hard.iter().zip(expected).enumerate() {
        for solver in Solver::ALL {
            let got = solver.0.first_root(&r.coeffs, r.lo, r.hi);
            if i == 7 {
                assert!(got.is_some(), "ray {i}");
                continue;
            }
            match (got, e) {
                (None, None) => {}
                (Some(t), Some(t0)) => {
                    // Multiple roots (up to 6-fold): eps^(1/m) accuracy; 1e-5 relative covers m ≤ 3,
                    // and the 6-fold and double ones here are exact in floating point.
                    assert!(
                        (t - t0).abs() <= 1e-5 * t0,
                        "ray {i} {}: {t} vs {t0}",
                        solver.1
                    )
                }
                _ => panic!("ray {i} {}: {got:?} vs {e:?}", solver.1),
            }
        }
    }
    // The ray along the axis ends at the tip, exactly at hi: hi is included.
    let axis = &hard[9];
    let all = sturm_roots(&axis.coeffs, axis.lo, axis.hi);
    assert_eq!(all.len(), 2, "{all:?}");
    assert!((all[1] - axis.hi).abs() <= 1e-5, "{all:?}");
}

/// On the whole ray `(1e-9, 1e6]` instead of the box interval (as a shape that does not clip
/// to its box would ask), both solvers give the same hit/miss on every corpus ray, and `t`
/// within 1e-3 relative (1e-9 on 99% of rays; the worst are near-triple roots of the `Z = 0`
/// plane).
#[test]
fn a_wide_interval_gives_the_same_answers() {
    let corpus = heart_corpus();
    for solver in Solver::ALL {
        let mut close = 0;
        for (i, r) in corpus.iter().enumerate() {
            let tight = solver.0.first_root(&r.coeffs, r.lo, r.hi);
            let wide = solver.0.first_root(&r.coeffs, 1e-9, 1e6);
            match (tight, wide) {
                (None, None) => close += 1,
                (Some(a), Some(b)) => {
                    assert!(
                        (a - b).abs() <= 1e-3 * a,
                        "{} ray {i}: {a} vs {b}",
                        solver.1
                    );
                    close += usize::from((a - b).abs() <= 1e-9 * a);
                }
                _ => panic!("{} ray {i}: {tight:?} vs {wide:?}", solver.1),
            }
        }
        assert!(
            close * 100 >= corpus.len() * 99,
            "{close} of {}",
            corpus.len()
        );
    }
}
