//! The paper's method: isolation by a Sturm sequence, refinement by Anderson–Björck false
//! position with a bisection safeguard.
//!
//! # What "distinct" means numerically
//!
//! The sequence is `p₀ = P`, `p₁ = P'`, `pₖ₊₁ = −rem(pₖ₋₁, pₖ)`, every member scaled to a
//! largest coefficient of 1 (a positive factor changes no sign). A remainder coefficient is
//! treated as zero when `|rⱼ| ≤ GCD_TOL·(1 + max|quotient|)`, i.e. when it is within a fixed
//! relative tolerance of the cancellation that produced it; leading coefficients that small
//! are dropped, and a remainder that small everywhere ends the sequence: its last member is
//! then the (numerical) `gcd(P, P')`. When the gcd is not a constant, the square-free part
//! `P / gcd` is formed and its own Sturm sequence is used for counting and refinement, so a
//! double or triple root, or a cluster that rounding has made of one, is one root. Because
//! the variable is first rescaled so that the roots have magnitude about one (see
//! `prep`), roots closer than roughly `√GCD_TOL` (≈ 3e-6) times the largest root's magnitude
//! may be merged into one; roots farther apart are always reported separately.
//!
//! Sign changes are counted with zero members skipped, the standard convention that makes the
//! count `V(a) − V(b)` the number of distinct roots in the half-open `(a, b]`.

use super::prep::{horner, max_abs, Prepared};

/// Relative size (against `1 + Σ|quotient|`, the members being scaled to a largest
/// coefficient of 1) below which a remainder coefficient is cancellation noise.
const GCD_TOL: f64 = 1e-10;

/// Tolerance, relative to `Σ|cⱼ||x|ʲ`, under which a value at a critical point is zero.
pub(crate) const CRIT_TOL: f64 = 64.0 * f64::EPSILON;

/// Most iterations of any loop (bisection of a `f64` range needs at most about 2100).
const MAX_ITER: usize = 2200;

/// A Sturm sequence of at most `M` members of degree below `M`.
struct Chain<const M: usize> {
    p: [[f64; M]; M],
    deg: [usize; M],
    len: usize,
}

impl<const M: usize> Chain<M> {
    /// The sequence of `c` (degree `n < M`), ended at the numerical gcd.
    fn build(c: &[f64], n: usize) -> Self {
        let mut ch = Chain {
            p: [[0.0; M]; M],
            deg: [0; M],
            len: 1,
        };
        let s = 1.0 / max_abs(&c[..=n]);
        for j in 0..=n {
            ch.p[0][j] = c[j] * s;
        }
        ch.deg[0] = n;
        let mut m = 0.0f64;
        for j in 1..=n {
            let v = c[j] * j as f64;
            ch.p[1][j - 1] = v;
            m = m.max(v.abs());
        }
        let inv = 1.0 / m;
        for j in 0..n {
            ch.p[1][j] *= inv;
        }
        ch.deg[1] = n - 1;
        ch.len = 2;
        while ch.deg[ch.len - 1] > 0 {
            let k = ch.len;
            let (da, db) = (ch.deg[k - 2], ch.deg[k - 1]);
            let mut r = ch.p[k - 2];
            let b = ch.p[k - 1];
            let mut qsum = 0.0f64;
            let lb = b[db];
            for i in (0..=da - db).rev() {
                let q = r[i + db] / lb;
                qsum += q.abs();
                r[i + db] = 0.0;
                for j in 0..db {
                    r[i + j] -= q * b[j];
                }
            }
            let err = GCD_TOL * (1.0 + qsum);
            let mut dr = db - 1;
            loop {
                if r[dr].abs() > err {
                    break;
                }
                r[dr] = 0.0;
                if dr == 0 {
                    return ch; // the remainder is noise: p[k-1] is the gcd
                }
                dr -= 1;
            }
            let mr = max_abs(&r[..=dr]);
            let s = -1.0 / mr;
            for j in 0..=dr {
                ch.p[k][j] = r[j] * s;
            }
            ch.deg[k] = dr;
            ch.len = k + 1;
        }
        ch
    }

    /// Number of sign changes of the sequence at `x`, zeros skipped.
    #[inline]
    fn changes(&self, x: f64) -> i32 {
        let mut count = 0;
        let mut last = 0.0f64;
        for k in 0..self.len {
            let v = horner(&self.p[k][..=self.deg[k]], x);
            if v != 0.0 {
                if (v < 0.0) != (last < 0.0) && last != 0.0 {
                    count += 1;
                }
                last = v;
            }
        }
        count
    }
}

/// Largest relative remainder of `P / gcd` for the division to be trusted.
const DIVIDE_TOL: f64 = 1e-6;

/// The Sturm sequence to count with: that of the square-free part `P / gcd(P, P')` when the
/// numerical gcd is not a constant and really divides `P` (remainder within `DIVIDE_TOL`);
/// otherwise the sequence of `P` itself, ended at the gcd (the sign-change count is the same,
/// the common factor being the same in every member).
fn counting_chain<const M: usize>(c: &[f64], n: usize) -> Chain<M> {
    let ch = Chain::<M>::build(c, n);
    let g = ch.len - 1;
    let dg = ch.deg[g];
    if dg == 0 {
        return ch;
    }
    let scale = max_abs(&c[..=n]);
    let mut r = [0.0; M];
    r[..=n].copy_from_slice(&c[..=n]);
    let mut q = [0.0; M];
    let b = &ch.p[g];
    for i in (0..=n - dg).rev() {
        let qi = r[i + dg] / b[dg];
        q[i] = qi;
        r[i + dg] = 0.0;
        for j in 0..dg {
            r[i + j] -= qi * b[j];
        }
    }
    if max_abs(&r[..dg]) > DIVIDE_TOL * scale {
        return ch;
    }
    Chain::<M>::build(&q, n - dg)
}

/// True when `[a, b]` can no longer shrink usefully: no double strictly between the ends, or
/// a width of a few ulps of the larger end.
#[inline]
fn converged(a: f64, b: f64) -> bool {
    let mid = 0.5 * (a + b);
    mid <= a || mid >= b || b - a <= 4.0 * f64::EPSILON * a.abs().max(b.abs())
}

/// Anderson–Björck false position for the root of `q` in `[a, b]`, where `fa`, `fb` have
/// opposite signs (neither zero); a step that fails to halve the bracket is followed by a
/// bisection step. Returns a point of the final bracket.
fn false_position(q: &[f64], mut a: f64, mut b: f64, mut fa: f64, mut fb: f64) -> f64 {
    let a0 = a;
    // `side` is the end replaced last: -1 left, 1 right, 0 none yet.
    let mut side = 0;
    let mut force_bisect = false;
    for _ in 0..MAX_ITER {
        if converged(a, b) {
            break;
        }
        let width = b - a;
        let mut x = if force_bisect {
            0.5 * (a + b)
        } else {
            b - fb * (width / (fb - fa))
        };
        if !(x > a && x < b) {
            x = 0.5 * (a + b);
        }
        let fx = horner(q, x);
        if fx == 0.0 {
            return x;
        }
        if (fx < 0.0) == (fa < 0.0) {
            if side == -1 {
                let m = 1.0 - fx / fa;
                fb *= if m > 0.0 { m } else { 0.5 };
            }
            a = x;
            fa = fx;
            side = -1;
        } else {
            if side == 1 {
                let m = 1.0 - fx / fb;
                fa *= if m > 0.0 { m } else { 0.5 };
            }
            b = x;
            fb = fx;
            side = 1;
        }
        force_bisect = b - a > 0.5 * width;
    }
    if a > a0 && fa.abs() < fb.abs() {
        a
    } else {
        b
    }
}

/// Refines the single distinct root of the chain's first member in `(a, b]`, where the
/// member's sign change count at `a` is `va`.
fn refine<const M: usize>(ch: &Chain<M>, mut a: f64, mut b: f64, mut va: i32) -> f64 {
    let q = &ch.p[0][..=ch.deg[0]];
    let fa = horner(q, a);
    let fb = horner(q, b);
    if fb == 0.0 {
        return b;
    }
    if fa != 0.0 && (fa < 0.0) != (fb < 0.0) {
        return false_position(q, a, b, fa, fb);
    }
    // No usable sign change (rounding has made the root look even): bisect on the count.
    for _ in 0..MAX_ITER {
        if converged(a, b) {
            break;
        }
        let m = 0.5 * (a + b);
        let vm = ch.changes(m);
        if va - vm >= 1 {
            b = m;
        } else {
            a = m;
            va = vm;
        }
    }
    b
}

/// `P` re-expressed on its interval: `Q(u) = P(mid + half·u)`, so that `(lo, hi]` becomes
/// `(−1, 1]`. Coefficient norms of `Q` (and of its Sturm sequence) then measure sizes where
/// they matter, on the interval, which keeps the gcd test meaningful.
struct Shifted<const M: usize> {
    q: [f64; M],
    mid: f64,
    half: f64,
}

impl<const M: usize> Shifted<M> {
    fn new(p: &Prepared) -> Self {
        let n = p.n;
        let mid = 0.5 * p.lo + 0.5 * p.hi;
        let half = 0.5 * p.hi - 0.5 * p.lo;
        let mut q = [0.0; M];
        q[..=n].copy_from_slice(&p.c[..=n]);
        // Taylor shift by repeated synthetic division, then scale.
        for i in 0..n {
            for j in (i..n).rev() {
                q[j] += mid * q[j + 1];
            }
        }
        let mut w = 1.0;
        for c in q.iter_mut().take(n + 1) {
            *c *= w;
            w *= half;
        }
        Shifted { q, mid, half }
    }

    /// The root `u` of `Q` in `T` coordinates, polished on `P` itself when the shift's
    /// rounding could exceed a few ulps of the root, and kept inside `(lo, hi]`; `None` when
    /// the root is `lo` itself, up to that rounding (the interval excludes `lo`).
    fn to_t(&self, p: &Prepared, u: f64) -> Option<f64> {
        let t = (self.mid + self.half * u).clamp(p.lo, p.hi);
        // Rounding of the shift, in `T`: a few ulps of the interval's magnitude per degree.
        let slack = 4.0 * p.n as f64 * f64::EPSILON * self.mid.abs().max(self.half);
        let c = &p.c[..=p.n];
        if t - p.lo <= slack && (t <= p.lo || horner(c, p.lo) == 0.0) {
            return None;
        }
        if slack <= 16.0 * p.n as f64 * f64::EPSILON * t.abs() {
            return Some(t);
        }
        let (a, b) = ((t - slack).max(p.lo), (t + slack).min(p.hi));
        let (fa, fb) = (horner(c, a), horner(c, b));
        if fa != 0.0 && fb != 0.0 && (fa < 0.0) != (fb < 0.0) {
            Some(false_position(c, a, b, fa, fb))
        } else {
            Some(t)
        }
    }
}

fn first_impl<const M: usize>(p: &Prepared) -> Option<f64> {
    let sh = Shifted::<M>::new(p);
    let ch = counting_chain::<M>(&sh.q, p.n);
    let mut a = -1.0;
    let mut va = ch.changes(a);
    let vhi = ch.changes(1.0);
    for _ in 0..M {
        if va - vhi < 1 {
            return None;
        }
        let (mut lo, mut b, mut vlo, mut vb) = (a, 1.0, va, vhi);
        for _ in 0..MAX_ITER {
            if vlo - vb == 1 {
                break;
            }
            let m = 0.5 * (lo + b);
            if m <= lo || m >= b {
                break; // an unresolvable cluster: one root
            }
            let vm = ch.changes(m);
            if vlo - vm >= 1 {
                b = m;
                vb = vm;
            } else {
                lo = m;
                vlo = vm;
            }
        }
        if let Some(t) = sh.to_t(p, refine(&ch, lo, b, vlo)) {
            return Some(t * p.scale);
        }
        // The root is at `lo` up to rounding, which the interval excludes: try the next one.
        a = b;
        va = vb;
    }
    None
}

fn all_impl<const M: usize>(p: &Prepared, out: &mut Vec<f64>) {
    let sh = Shifted::<M>::new(p);
    let ch = counting_chain::<M>(&sh.q, p.n);
    let va = ch.changes(-1.0);
    let vb = ch.changes(1.0);
    if va - vb < 1 {
        return;
    }
    // Depth-first, left half first, so roots come out ascending.
    let mut stack = vec![(-1.0, 1.0, va, vb)];
    let mut steps = 0;
    while let Some((a, b, va, vb)) = stack.pop() {
        let count = va - vb;
        if count < 1 {
            continue;
        }
        steps += 1;
        let m = 0.5 * (a + b);
        if count == 1 || m <= a || m >= b || steps > 64 * MAX_ITER {
            if let Some(t) = sh.to_t(p, refine(&ch, a, b, va)) {
                out.push(t * p.scale);
            }
            continue;
        }
        let vm = ch.changes(m);
        stack.push((m, b, vm, vb));
        stack.push((a, m, va, vm));
    }
}

/// See [`super::first_root`].
pub(crate) fn first_root(p: &Prepared) -> Option<f64> {
    if p.n < 8 {
        first_impl::<8>(p)
    } else {
        first_impl::<17>(p)
    }
}

/// See [`super::sturm_roots`].
pub(crate) fn all_roots(p: &Prepared) -> Vec<f64> {
    let mut out = Vec::new();
    if p.n < 8 {
        all_impl::<8>(p, &mut out);
    } else {
        all_impl::<17>(p, &mut out);
    }
    // Roots from neighbouring brackets can only coincide by rounding at a shared end.
    out.dedup();
    out
}
