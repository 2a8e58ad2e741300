//! Test-only references for the heart: a brute-force first-root finder (independent of the
//! `roots` module), double-double arithmetic for high-precision surface points and normals,
//! and a small deterministic random generator.
#![allow(dead_code)]

pub mod cases;

use kardia::geometry::{DVec3, Ray};
use kardia::shapes::heart::Heart;

/// Deterministic xorshift generator (tests must not depend on a seed source).
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
    /// Uniform on the unit sphere.
    pub fn direction(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

/// Horner evaluation of ascending coefficients.
pub fn horner(c: &[f64], x: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &k| acc * x + k)
}

/// Brute-force smallest root in `(lo, hi]`: sign changes of the polynomial on a fine grid,
/// refined by bisection. Misses roots of even multiplicity (tangencies), like any sign test.
/// The grid is geometric near `lo` (steps from 1e-17 doubling up to the uniform spacing), so
/// that, like a Sturm count, it sees roots that rounding puts just after `lo`.
pub fn brute_first_root(c: &[f64; 7], lo: f64, hi: f64) -> Option<f64> {
    const N: usize = 4096;
    let cell = (hi - lo) / N as f64;
    let near = (0..200)
        .map(|k| lo + 1e-17 * 2f64.powi(k))
        .take_while(|&x| x < lo + cell);
    let uniform = (1..=N).map(|i| lo + (hi - lo) * i as f64 / N as f64);
    let mut a = lo;
    let mut fa = horner(c, a);
    for b in near.chain(uniform) {
        if b <= a {
            continue;
        }
        let fb = horner(c, b);
        if fb == 0.0 && b > lo {
            return Some(b);
        }
        if (fa < 0.0) != (fb < 0.0) && fa != 0.0 {
            let (mut x0, mut x1, mut f0) = (a, b, fa);
            for _ in 0..200 {
                let m = 0.5 * (x0 + x1);
                if m <= x0 || m >= x1 {
                    break;
                }
                let fm = horner(c, m);
                if (fm < 0.0) == (f0 < 0.0) {
                    x0 = m;
                    f0 = fm;
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

/// The heart's intersection computed with the brute-force root finder instead of the
/// `roots` module: checks the geometry (transform, box, coefficients, polish) on its own.
pub fn brute_intersect(heart: &Heart, ray: &Ray, t_min: f64, t_max: f64) -> Option<f64> {
    heart.intersect_with(ray, t_min, t_max, brute_first_root)
}

/// The value of `f` along an arbitrary world-space function, root-bracketed by sampling and
/// bisection: the first `t` in `(lo, hi]` where `func(t)` changes sign (independent of any
/// polynomial coefficients).
pub fn first_sign_change(func: impl Fn(f64) -> f64, lo: f64, hi: f64, n: usize) -> Option<f64> {
    let mut a = lo;
    let mut fa = func(a);
    for i in 1..=n {
        let b = lo + (hi - lo) * i as f64 / n as f64;
        let fb = func(b);
        if (fa < 0.0) != (fb < 0.0) {
            let (mut x0, mut x1, mut f0) = (a, b, fa);
            for _ in 0..200 {
                let m = 0.5 * (x0 + x1);
                if m <= x0 || m >= x1 {
                    break;
                }
                let fm = func(m);
                if (fm < 0.0) == (f0 < 0.0) {
                    x0 = m;
                    f0 = fm;
                } else {
                    x1 = m;
                }
            }
            return Some(0.5 * (x0 + x1));
        }
        a = b;
        fa = fb;
    }
    None
}

// ---------------------------------------------------------------------------------------
// Double-double arithmetic (about 106 bits), enough for reference roots and normals.
// ---------------------------------------------------------------------------------------

/// An unevaluated sum `hi + lo` with `|lo| ≤ ulp(hi)/2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dd {
    pub hi: f64,
    pub lo: f64,
}

#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    let e = (a - (s - bb)) + (b - bb);
    (s, e)
}

#[inline]
fn quick_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

#[inline]
fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

impl Dd {
    pub const ZERO: Dd = Dd { hi: 0.0, lo: 0.0 };
    pub fn from(x: f64) -> Dd {
        Dd { hi: x, lo: 0.0 }
    }
    pub fn to_f64(self) -> f64 {
        self.hi + self.lo
    }
    pub fn add(self, o: Dd) -> Dd {
        let (s, e) = two_sum(self.hi, o.hi);
        let (t, f) = two_sum(self.lo, o.lo);
        let (s, e) = quick_two_sum(s, e + t);
        let (hi, lo) = quick_two_sum(s, e + f);
        Dd { hi, lo }
    }
    pub fn neg(self) -> Dd {
        Dd {
            hi: -self.hi,
            lo: -self.lo,
        }
    }
    pub fn sub(self, o: Dd) -> Dd {
        self.add(o.neg())
    }
    pub fn mul(self, o: Dd) -> Dd {
        let (p, e) = two_prod(self.hi, o.hi);
        let e = e + (self.hi * o.lo + self.lo * o.hi);
        let (hi, lo) = quick_two_sum(p, e);
        Dd { hi, lo }
    }
    pub fn mulf(self, x: f64) -> Dd {
        self.mul(Dd::from(x))
    }
    pub fn div(self, o: Dd) -> Dd {
        let q1 = self.hi / o.hi;
        let r = self.sub(o.mulf(q1));
        let q2 = r.hi / o.hi;
        let r = r.sub(o.mulf(q2));
        let q3 = r.hi / o.hi;
        let (hi, lo) = quick_two_sum(q1, q2);
        Dd { hi, lo }.add(Dd::from(q3))
    }
    pub fn sqrt(self) -> Dd {
        if self.hi <= 0.0 {
            return Dd::ZERO;
        }
        let x = Dd::from(self.hi.sqrt());
        // One Newton step: x + (a − x²)/(2x).
        x.add(self.sub(x.mul(x)).div(x.mulf(2.0)))
    }
    pub fn cbrt(self) -> Dd {
        if self.hi == 0.0 {
            return Dd::ZERO;
        }
        let mut x = Dd::from(self.hi.cbrt());
        for _ in 0..2 {
            // x − (x³ − a)/(3x²)
            let x2 = x.mul(x);
            x = x.sub(x2.mul(x).sub(self).div(x2.mulf(3.0)));
        }
        x
    }
    pub fn signum(self) -> f64 {
        if self.hi > 0.0 {
            1.0
        } else if self.hi < 0.0 {
            -1.0
        } else if self.lo > 0.0 {
            1.0
        } else if self.lo < 0.0 {
            -1.0
        } else {
            0.0
        }
    }
}

/// A point in double-double.
#[derive(Clone, Copy, Debug)]
pub struct DdVec {
    pub x: Dd,
    pub y: Dd,
    pub z: Dd,
}

impl DdVec {
    /// `o + t·d` with `o`, `d` in f64 and `t` in double-double.
    pub fn on_ray(o: DVec3, d: DVec3, t: Dd) -> DdVec {
        DdVec {
            x: Dd::from(o.x).add(t.mulf(d.x)),
            y: Dd::from(o.y).add(t.mulf(d.y)),
            z: Dd::from(o.z).add(t.mulf(d.z)),
        }
    }
    pub fn to_f64(self) -> DVec3 {
        DVec3::new(self.x.to_f64(), self.y.to_f64(), self.z.to_f64())
    }
}

/// `A = 2X² + Y² + Z² − 1` and `B = 0.1X² + Y²` in double-double (0.1 is the f64 constant the
/// library uses, so both describe the very same surface).
fn dd_a_b(p: DdVec) -> (Dd, Dd) {
    let x2 = p.x.mul(p.x);
    let y2 = p.y.mul(p.y);
    let z2 = p.z.mul(p.z);
    let a = x2.mulf(2.0).add(y2).add(z2).sub(Dd::from(1.0));
    let b = x2.mulf(0.1).add(y2);
    (a, b)
}

/// `f = A³ − B·Z³` in double-double.
pub fn dd_f(p: DdVec) -> Dd {
    let (a, b) = dd_a_b(p);
    a.mul(a).mul(a).sub(b.mul(p.z).mul(p.z).mul(p.z))
}

/// `g = A − ∛B·Z` in double-double.
pub fn dd_g(p: DdVec) -> Dd {
    let (a, b) = dd_a_b(p);
    a.sub(b.cbrt().mul(p.z))
}

/// Unit `∇f` in double-double, rounded to f64 (undefined where ∇f = 0).
pub fn dd_grad_f_unit(p: DdVec) -> DVec3 {
    let (a, b) = dd_a_b(p);
    let a2 = a.mul(a);
    let z2 = p.z.mul(p.z);
    let z3 = z2.mul(p.z);
    let gx = p.x.mul(a2).mulf(12.0).sub(p.x.mul(z3).mulf(0.2));
    let gy = p.y.mul(a2).mulf(6.0).sub(p.y.mul(z3).mulf(2.0));
    let gz = p.z.mul(a2).mulf(6.0).sub(z2.mul(b).mulf(3.0));
    dd_unit(gx, gy, gz)
}

/// Unit `∇g = (4X, 2Y, 2Z) − Z·∇B/(3∛B²) − (0, 0, ∛B)` in double-double (needs `B > 0`).
pub fn dd_grad_g_unit(p: DdVec) -> DVec3 {
    let (_, b) = dd_a_b(p);
    let s = b.cbrt();
    let k = p.z.div(s.mul(s).mulf(3.0));
    let gx = p.x.mulf(4.0).sub(k.mul(p.x.mulf(0.2)));
    let gy = p.y.mulf(2.0).sub(k.mul(p.y.mulf(2.0)));
    let gz = p.z.mulf(2.0).sub(s);
    dd_unit(gx, gy, gz)
}

fn dd_unit(x: Dd, y: Dd, z: Dd) -> DVec3 {
    // Scale first so that tiny gradients do not underflow when squared.
    let m = x.hi.abs().max(y.hi.abs()).max(z.hi.abs());
    let (x, y, z) = (x.mulf(1.0 / m), y.mulf(1.0 / m), z.mulf(1.0 / m));
    let n = x.mul(x).add(y.mul(y)).add(z.mul(z)).sqrt();
    DVec3::new(x.div(n).to_f64(), y.div(n).to_f64(), z.div(n).to_f64())
}

/// The reference root of `g` along `o + t·d` inside the bracket `[ta, tb]` (where `g` changes
/// sign), by bisection in double-double to ~1e-30 of the bracket.
pub fn dd_root_g(o: DVec3, d: DVec3, ta: f64, tb: f64) -> Dd {
    let mut a = Dd::from(ta);
    let mut b = Dd::from(tb);
    let sa = dd_g(DdVec::on_ray(o, d, a)).signum();
    let sb = dd_g(DdVec::on_ray(o, d, b)).signum();
    assert!(sa * sb < 0.0, "no sign change of g in [{ta}, {tb}]");
    for _ in 0..110 {
        let m = a.add(b).mulf(0.5);
        let sm = dd_g(DdVec::on_ray(o, d, m)).signum();
        if sm == 0.0 {
            return m;
        }
        if sm == sa {
            a = m;
        } else {
            b = m;
        }
    }
    a.add(b).mulf(0.5)
}

/// The reference first root of `g` along the ray in `(lo, hi]`: located with a dense f64 scan
/// of `g` (simple roots everywhere, so a sign scan is reliable) and refined in double-double.
pub fn reference_first_root(o: DVec3, d: DVec3, lo: f64, hi: f64) -> Option<Dd> {
    reference_first_root_n(o, d, lo, hi, 20_000)
}

/// [`reference_first_root`] with an `n`-step scan.
pub fn reference_first_root_n(o: DVec3, d: DVec3, lo: f64, hi: f64, n: usize) -> Option<Dd> {
    #[allow(non_snake_case)]
    let N = n;
    let g = |t: f64| kardia::shapes::heart::factor_g(o + t * d);
    let mut a = lo;
    let mut ga = g(a);
    for i in 1..=N {
        let b = lo + (hi - lo) * i as f64 / N as f64;
        let gb = g(b);
        if (ga < 0.0) != (gb < 0.0) {
            // Widen by a hair so the f64 scan's rounding cannot hide the sign change in dd.
            let w = (b - a) * 1e-3;
            return Some(dd_root_g(o, d, a - w, b + w));
        }
        a = b;
        ga = gb;
    }
    None
}

/// Angle in radians between two unit vectors (accurate for tiny angles).
pub fn angle(a: DVec3, b: DVec3) -> f64 {
    2.0 * ((a - b).length() / (a + b).length()).atan()
}

/// First-order distance from an object-space point to the surface, `|g| / |∇g|` (meaningful
/// where `f`'s own measure is not: on the equator curve and beside the singular points).
pub fn surface_distance(p: DVec3) -> f64 {
    let g = kardia::shapes::heart::factor_g(p);
    let s2 = (0.1 * p.x * p.x + p.y * p.y).cbrt().powi(2);
    let grad = kardia::shapes::heart::scaled_gradient_g(p) / (3.0 * s2);
    if grad.length() > 0.0 && grad.is_finite() {
        g.abs() / grad.length()
    } else {
        g.abs() / (4.0 * p.x * p.x + p.y * p.y + p.z * p.z).sqrt().max(1e-300) / 2.0
    }
}
