//! The paper's method: isolation by a Sturm sequence, refinement by Anderson–Björck false
//! position with a bisection safeguard.
//!
//! # Working basis
//!
//! `P` (already rescaled by `prep`) is re-expressed on its interval, `Q(u) = P(mid + half·u)`,
//! so that `(lo, hi]` is `(−1, 1]` and coefficient sizes measure sizes on the interval. Roots
//! found in `u` are mapped back and, when the shift's rounding could exceed a few ulps of the
//! root, polished on `P` itself (on `P'` or `P''` for a numerically multiple root, which is a
//! simple root of those).
//!
//! # What "distinct" means numerically
//!
//! The sequence is `p₀ = Q`, `p₁ = Q'`, `pₖ₊₁ = −rem(pₖ₋₁, pₖ)`, every member scaled to a
//! largest coefficient of 1 (a positive factor changes no sign). Alongside, a running bound on
//! each member's coefficient error is kept: the input's (a few ulps of `Σ|Pⱼ|·Rʲ`, the size of
//! `P` on the interval) propagated through each division, times a safety factor of 4, plus the
//! division's own rounding. A remainder below that bound is noise, and its last non-zero
//! predecessor `g` is the numerical `gcd(Q, Q')` — but only if `g` also divides `Q` and `Q'`
//! with a remainder below 1000 times their error; otherwise the remainder is kept (trimmed at
//! the level of rounding only). A numerical gcd of positive degree means multiple roots: the
//! square-free part `Q / g` and its own sequence are then used, so a double or triple root,
//! or a cluster rounding has made of one, counts once. Roots are "distinct" when the sequence,
//! so computed, separates them: roots far apart relative to the interval always are; roots
//! whose separation is tiny against the interval's size (say 1e-7 of it), or several multiple
//! roots packed together in a polynomial of degree above 6, may be merged into one.
//!
//! Sign changes are counted with zero members skipped, the standard convention that makes the
//! count `V(a) − V(b)` the number of distinct roots in the half-open `(a, b]`. Bisection splits
//! slightly off the middle so as not to land exactly on dyadic roots, where every member of
//! the sequence can vanish at once. When `P(hi)` is exactly zero, `hi` is reported and the
//! count is taken just below it.

use super::bernstein::{self, Fast};
use super::prep::{horner, max_abs, Prepared};

/// Relative size (against `1 + Σ|quotient|`, the members being scaled to a largest
/// coefficient of 1) below which a remainder coefficient is cancellation noise.
const GCD_SAFETY: f64 = 4.0;

/// Relative error assumed in each input coefficient (a few rounding units).
const INPUT_ERR: f64 = 4.0 * f64::EPSILON;

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
    fn build(c: &[f64], n: usize, input_err: f64) -> Self {
        let mut ch = Chain {
            p: [[0.0; M]; M],
            deg: [0; M],
            len: 1,
        };
        let s = 1.0 / max_abs(&c[..=n]);
        for (d, &a) in ch.p[0].iter_mut().zip(&c[..=n]) {
            *d = a * s;
        }
        ch.deg[0] = n;
        let mut m = 0.0f64;
        for (j, (d, &a)) in ch.p[1].iter_mut().zip(&c[1..=n]).enumerate() {
            *d = a * (j + 1) as f64;
            m = m.max(d.abs());
        }
        let inv = 1.0 / m;
        for j in 0..n {
            ch.p[1][j] *= inv;
        }
        ch.deg[1] = n - 1;
        ch.len = 2;
        // Running bounds on the absolute coefficient error of the last two members.
        let mut ea = input_err * s;
        let mut eb = ea * n as f64 * inv / s;
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
            let rounding = 4.0 * f64::EPSILON * (db + 2) as f64 * (1.0 + qsum);
            let mut err = GCD_SAFETY * (ea + qsum * eb) + rounding;
            if max_abs(&r[..db]) <= err
                && !(divides(&ch.p[0][..=n], &b[..=db], input_err * s)
                    && divides(&ch.p[1][..n], &b[..=db], input_err * s * n as f64))
            {
                // Small, but `b` is no factor of `P`: the remainder is real; keep it.
                err = rounding;
            }
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
            for (d, &a) in ch.p[k].iter_mut().zip(&r[..=dr]) {
                *d = a * s;
            }
            ch.deg[k] = dr;
            ch.len = k + 1;
            ea = eb;
            eb = err / mr;
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

/// Largest remainder of `P / g`, in units of the error in `P`'s coefficients, for `g` to count
/// as a factor.
const DIVIDE_TOL: f64 = 1e3;

/// `P / g` by long division (`p` of degree ≥ that of `g`, `g` non-constant): the quotient and
/// the largest remainder coefficient.
fn divide<const M: usize>(p: &[f64], g: &[f64]) -> ([f64; M], f64) {
    let (n, dg) = (p.len() - 1, g.len() - 1);
    let mut r = [0.0; M];
    r[..=n].copy_from_slice(p);
    let mut q = [0.0; M];
    for i in (0..=n - dg).rev() {
        let qi = r[i + dg] / g[dg];
        q[i] = qi;
        r[i + dg] = 0.0;
        for j in 0..dg {
            r[i + j] -= qi * g[j];
        }
    }
    (q, max_abs(&r[..dg]))
}

/// True when `g` divides `p` (scaled to a largest coefficient of 1) up to a remainder of
/// `DIVIDE_TOL` times the error `err` already in `p`'s coefficients.
fn divides(p: &[f64], g: &[f64], err: f64) -> bool {
    g.len() < 2 || divide::<17>(p, g).1 <= DIVIDE_TOL * (err + f64::EPSILON)
}

/// The Sturm sequence to count with: that of the square-free part `P / gcd(P, P')` when the
/// numerical gcd is not a constant (it has then been checked to divide `P`), else that of `P`.
fn counting_chain<const M: usize>(c: &[f64], n: usize, input_err: f64) -> Chain<M> {
    let ch = Chain::<M>::build(c, n, input_err);
    let g = ch.len - 1;
    let dg = ch.deg[g];
    if dg == 0 {
        return ch;
    }
    let (q, _) = divide::<M>(&ch.p[0][..=n], &ch.p[g][..=dg]);
    Chain::<M>::build(
        &q,
        n - dg,
        (input_err / max_abs(&c[..=n]) + f64::EPSILON) * DIVIDE_TOL * max_abs(&q[..=n - dg]),
    )
}

/// True when `[a, b]` can no longer shrink usefully: no double strictly between the ends, or
/// a width of a few ulps of the larger end plus `floor`.
#[inline]
fn converged(a: f64, b: f64, floor: f64) -> bool {
    let mid = 0.5 * (a + b);
    mid <= a || mid >= b || b - a <= 4.0 * f64::EPSILON * a.abs().max(b.abs()) + floor
}

/// When `P(hi)` is exactly zero, `hi` is reported as a root and the other roots are isolated
/// in `(−1, HI_GUARD]` (in `u`): at a multiple root at `hi` every sequence member vanishes, so
/// the count there is unreliable; a root closer to `hi` than that guard is merged with it.
const HI_GUARD: f64 = 1.0 - 1e-9;

/// The isolation split point of `(a, b)`: slightly off the middle, so that the dyadic points
/// where exactly representable roots tend to sit (and where every sequence member may vanish at
/// a multiple root) are not hit exactly.
#[inline]
fn split(a: f64, b: f64) -> f64 {
    a + (b - a) * 0.496_858_407_346_410_2
}

/// Anderson–Björck false position for the root of `q` in `[a, b]`, where `fa`, `fb` have
/// opposite signs (neither zero); a step that fails to halve the bracket is followed by a
/// bisection step. Returns a point of the final bracket.
pub(crate) fn false_position(
    q: &[f64],
    mut a: f64,
    mut b: f64,
    mut fa: f64,
    mut fb: f64,
    floor: f64,
) -> f64 {
    let a0 = a;
    // `side` is the end replaced last: -1 left, 1 right, 0 none yet.
    let mut side = 0;
    let mut force_bisect = false;
    for _ in 0..MAX_ITER {
        if converged(a, b, floor) {
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

/// Refines the single distinct root of `p` in `(a, b]` isolated by its counting chain `ch`
/// (whose count at `a` is `va`): by false position on `p`, else on the chain's first member
/// (the square-free part), else (an even root) by bisection on the count.
fn refine<const M: usize>(
    ch: &Chain<M>,
    p: &[f64],
    mut a: f64,
    mut b: f64,
    mut va: i32,
    floor: f64,
) -> f64 {
    // `p` itself first: where it changes sign there is certainly a root of it.
    for q in [p, &ch.p[0][..=ch.deg[0]]] {
        let fa = horner(q, a);
        let fb = horner(q, b);
        if fb == 0.0 {
            return b;
        }
        if fa != 0.0 && (fa < 0.0) != (fb < 0.0) {
            return false_position(q, a, b, fa, fb, floor);
        }
    }
    // No usable sign change (rounding has made the root look even): bisect on the count.
    for _ in 0..MAX_ITER {
        if converged(a, b, floor) {
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
    /// Bound on the absolute error of `q`'s coefficients inherited from `P`'s rounding.
    err: f64,
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
        // Each coefficient of `P` carries a relative error of a few ulps; on the interval that
        // is at most `Σ|Pⱼ|·Rʲ` times it, R = max(|lo|, |hi|), whatever the basis.
        let r = p.lo.abs().max(p.hi.abs());
        let mut size = 0.0;
        for &c in p.c[..=n].iter().rev() {
            size = size * r + c.abs();
        }
        let err = INPUT_ERR * (n + 1) as f64 * size;
        Shifted { q, mid, half, err }
    }

    /// Width in `u` below which refinement cannot improve `t = mid + half·u`: an ulp of `mid`.
    fn floor(&self) -> f64 {
        2.0 * f64::EPSILON * self.mid.abs() / self.half
    }

    /// The root `u` of `Q` in `T` coordinates, polished on `P` itself when the shift's
    /// rounding could exceed a few ulps of the root, and kept inside `(lo, hi]`; `None` when
    /// the root is `lo` itself, up to that rounding (the interval excludes `lo`).
    fn to_t(&self, p: &Prepared, u: f64) -> Option<f64> {
        let t = (self.mid + self.half * u).clamp(p.lo, p.hi);
        // Rounding of the shift, in `T`: a few ulps of the interval's magnitude per degree.
        let slack = 4.0 * p.n as f64 * f64::EPSILON * self.mid.abs().max(self.half);
        let c = &p.c[..=p.n];
        // An exact root at `lo` is excluded, and so is what the shift makes of a multiple one.
        if t <= p.lo || (t - p.lo <= 1e3 * slack && horner(c, p.lo) == 0.0) {
            return None;
        }
        if t.abs() <= slack && c[0] == 0.0 && p.lo < 0.0 {
            return Some(0.0); // an exact root at 0, blurred by the shift
        }
        let (a, b) = ((t - slack).max(p.lo), (t + slack).min(p.hi));
        let (fa, fb) = (horner(c, a), horner(c, b));
        let noise = 1e3 * f64::EPSILON * abs_horner(c, t.abs());
        let quiet = fa.abs() <= noise && fb.abs() <= noise;
        if fa != 0.0 && fb != 0.0 && (fa < 0.0) != (fb < 0.0) && !quiet {
            // A clean sign change: known as well as the shift allows, or polished on `P`.
            if slack <= 16.0 * p.n as f64 * f64::EPSILON * t.abs() {
                return Some(t);
            }
            return Some(false_position(c, a, b, fa, fb, 0.0));
        }
        if fa == 0.0 || fb == 0.0 {
            return Some(t);
        }
        // No sign change of `P` at this scale, or only rounding noise: a numerically multiple
        // root. It is a simple root of `P'` (double) or `P''` (triple), which locate it far
        // better than `P` can.
        let scale = self.mid.abs().max(self.half);
        let pt = horner(c, t).abs();
        let mut d = [0.0; M];
        d[..=p.n].copy_from_slice(c);
        for (k, w) in [(1, 1e-6 * scale), (2, 1e-4 * scale)] {
            if k > p.n - 1 {
                break;
            }
            for j in 0..=p.n - k {
                d[j] = d[j + 1] * (j + 1) as f64;
            }
            let dk = &d[..=p.n - k];
            let (a, b) = ((t - w).max(p.lo), (t + w).min(p.hi));
            let (fa, fb) = (horner(dk, a), horner(dk, b));
            if fa != 0.0 && fb != 0.0 && (fa < 0.0) != (fb < 0.0) {
                let x = false_position(dk, a, b, fa, fb, 0.0);
                if x > p.lo && horner(c, x).abs() <= pt.max(noise) {
                    return Some(x);
                }
            }
        }
        Some(t)
    }
}

/// `Σ|cⱼ|·xʲ` for `x ≥ 0`: the scale of the rounding error in evaluating `c` at `±x`.
#[inline]
fn abs_horner(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |s, a| s * x + a.abs())
}

fn first_impl<const M: usize>(p: &Prepared) -> Option<f64> {
    let sh = Shifted::<M>::new(p);
    let ch = counting_chain::<M>(&sh.q, p.n, sh.err);
    let at_hi = horner(&p.c[..=p.n], p.hi) == 0.0;
    let top = if at_hi { HI_GUARD } else { 1.0 };
    let mut a = -1.0;
    let mut va = ch.changes(a);
    let vhi = ch.changes(top);
    for _ in 0..M {
        if va - vhi < 1 {
            return at_hi.then_some(p.hi * p.scale);
        }
        let (mut lo, mut b, mut vlo, mut vb) = (a, top, va, vhi);
        for _ in 0..MAX_ITER {
            if vlo - vb == 1 {
                break;
            }
            let m = split(lo, b);
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
        if let Some(t) = sh.to_t(p, refine(&ch, &sh.q[..=p.n], lo, b, vlo, sh.floor())) {
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
    let ch = counting_chain::<M>(&sh.q, p.n, sh.err);
    let at_hi = horner(&p.c[..=p.n], p.hi) == 0.0;
    let top = if at_hi { HI_GUARD } else { 1.0 };
    let va = ch.changes(-1.0);
    let vb = ch.changes(top);
    // Depth-first, left half first, so roots come out ascending.
    let mut stack = vec![(-1.0, top, va, vb)];
    let mut steps = 0;
    while let Some((a, b, va, vb)) = stack.pop() {
        let count = va - vb;
        if count < 1 {
            continue;
        }
        steps += 1;
        let m = split(a, b);
        if count == 1 || m <= a || m >= b || steps > 64 * MAX_ITER {
            if let Some(t) = sh.to_t(p, refine(&ch, &sh.q[..=p.n], a, b, va, sh.floor())) {
                out.push(t * p.scale);
            }
            continue;
        }
        let vm = ch.changes(m);
        stack.push((m, b, vm, vb));
        stack.push((a, m, va, vm));
    }
    if at_hi {
        out.push(p.hi * p.scale);
    }
}
/// Most pieces a wide interval is cut into.
const MAX_PIECES: usize = 16;

/// The interval cut into pieces `(xᵢ, xᵢ₊₁]` no wider than a sixteenth of the root bound: a
/// Sturm sequence over an interval that the roots fill only a small part of is poorly
/// conditioned (its members are tiny where the roots are), so each piece gets its own.
/// The box-clipped intervals of ray tracing are a single piece.
fn pieces(p: &Prepared) -> impl Iterator<Item = Prepared> + '_ {
    let width = p.hi - p.lo;
    let k = ((width / (p.bound / 16.0)).ceil() as usize).clamp(1, MAX_PIECES);
    let step = width / k as f64;
    (0..k).map(move |i| {
        // Interior ends off the dyadic grid, where exactly representable roots sit.
        let end = |j: usize| p.lo + step * (j as f64 - 0.031_415_926_535_897_93);
        let mut piece = *p;
        piece.lo = if i == 0 { p.lo } else { end(i) };
        piece.hi = if i + 1 == k { p.hi } else { end(i + 1) };
        piece
    })
}

/// See [`super::first_root`].
pub(crate) fn first_root(p: &Prepared) -> Option<f64> {
    match bernstein::first_root(p) {
        Fast::NoRoot => return None,
        Fast::Root(t) => return Some(t),
        Fast::Undecided => {}
    }
    let mut first = None;
    super::cluster::roots(p, &mut |t| {
        first = Some(t * p.scale);
        false
    });
    first
}

/// See [`super::sturm_roots`].
pub(crate) fn all_roots(p: &Prepared) -> Vec<f64> {
    let mut out = Vec::new();
    super::cluster::roots(p, &mut |t| {
        out.push(t * p.scale);
        true
    });
    out
}
