//! The root finders on real heart polynomials from camera rays (the shared corpus).

use kardia::roots::{first_root, first_root_yuksel, heart_corpus, heart_hard_rays, CorpusRay};
use kardia::shapes::heart::heart_fn;

/// Reference first sign change of the heart function along the ray (sampled directly in 3D,
/// independently of the sextic), refined by bisection; `None` if no sign change is seen.
fn reference(r: &CorpusRay) -> Option<f64> {
    let f = |t: f64| heart_fn(r.origin + t * r.dir);
    let steps = 4000;
    let h = (r.hi - r.lo) / steps as f64;
    let mut a = r.lo;
    let mut fa = f(a);
    for k in 1..=steps {
        let b = if k == steps { r.hi } else { r.lo + k as f64 * h };
        let fb = f(b);
        if fa != 0.0 && (fb == 0.0 || (fa < 0.0) != (fb < 0.0)) {
            let (mut x0, mut x1) = (a, b);
            for _ in 0..200 {
                let m = 0.5 * (x0 + x1);
                if m <= x0 || m >= x1 {
                    break;
                }
                if (f(m) < 0.0) == (fa < 0.0) && f(m) != 0.0 {
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

#[test]
fn explore() {
    let corpus = heart_corpus();
    let (mut hits, mut n) = (0, 0);
    for (idx, r) in corpus.iter().enumerate() {
        n += 1;
        let s = first_root(&r.coeffs, r.lo, r.hi);
        let y = first_root_yuksel(&r.coeffs, r.lo, r.hi);
        let rf = reference(r);
        if s.is_some() {
            hits += 1;
        }
        let bad = s.is_some() != y.is_some()
            || s.is_some() != rf.is_some()
            || matches!((s, y), (Some(a), Some(b)) if (a - b).abs() > 1e-5 * a.abs().max(1.0))
            || matches!((s, rf), (Some(a), Some(b)) if (a - b).abs() > 1e-5 * a.abs().max(1.0));
        if bad {
            println!("{idx}: o={:?} d={:?} sturm={s:?} yuksel={y:?} ref={rf:?} lo={} hi={}", r.origin, r.dir, r.lo, r.hi);
        }
    }
    println!("{n} rays, {hits} hits, hard {}", heart_hard_rays().len());
}

#[test]
fn debug_cases() {
    let corpus = heart_corpus();
    for idx in [1857usize, 2220, 1302] {
        let r = &corpus[idx];
        println!("{idx}: c={:?}", r.coeffs);
        println!("  all sturm {:?}", kardia::roots::sturm_roots(&r.coeffs, r.lo, r.hi));
        let mut t = r.lo;
        let mut prev = heart_fn(r.origin + t * r.dir);
        while t < r.hi {
            t += (r.hi - r.lo) / 2000.0;
            let v = heart_fn(r.origin + t * r.dir);
            if (v < 0.0) != (prev < 0.0) { println!("  sign change near {t}"); }
            prev = v;
        }
    }
}
