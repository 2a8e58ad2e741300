//! A box that certainly holds the part of the surface inside the clip sphere, found once at
//! load time by subdividing the cube `[−r, r]³` with the polynomial in the tensor Bernstein
//! basis: where every Bernstein coefficient of a cell has one sign (beyond a rounding
//! margin), `f` cannot vanish in that cell. The box is the hull of the cells left at the
//! finest level. Rays that miss it are rejected by a slab test, and the root search runs on
//! the ray's span inside it only.

use super::poly::Compiled;

/// Subdivision depth (cells per axis `2^depth`) for a polynomial of degree `n`: deeper for
/// low degrees, where a cell's `(n+1)³` coefficients are few.
fn depth_for(n: usize) -> u32 {
    match n {
        0..=6 => 5,
        7..=10 => 4,
        _ => 3,
    }
}

/// Most cells examined before giving up on a tighter box (bounds the load time).
const MAX_CELLS: usize = 20_000;

/// Tensor coefficients `(n+1)³` of one cell, index `(i·m + j)·m + k`.
struct Cell {
    b: Vec<f64>,
    lo: [f64; 3],
    size: f64,
}

/// `C(n, k)` as `f64` (exact for `n ≤ 16`).
fn binom(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

/// Splits the coefficient lines along `axis` at the middle (de Casteljau): the lower and
/// upper halves.
fn split(b: &[f64], m: usize, axis: usize) -> (Vec<f64>, Vec<f64>) {
    let stride = [m * m, m, 1][axis];
    let mut lo = b.to_vec();
    let mut hi = b.to_vec();
    let mut line = vec![0.0; m];
    for base in 0..b.len() {
        // Visit each line once, from its first element.
        if !(base / stride).is_multiple_of(m) {
            continue;
        }
        for (q, v) in line.iter_mut().enumerate() {
            *v = b[base + q * stride];
        }
        // Row r of the triangle: its first entry goes to the lower half, its last to the
        // upper half (reversed).
        for r in 0..m {
            lo[base + r * stride] = line[0];
            hi[base + (m - 1 - r) * stride] = line[m - 1 - r];
            for q in 0..m - 1 - r {
                line[q] = 0.5 * (line[q] + line[q + 1]);
            }
        }
    }
    (lo, hi)
}

/// A box `(min, max)` in object space holding every zero of `f` in the cube `[−r, r]³` (the
/// whole cube when the subdivision gives up), or `None` when `f` is proved to have no zero
/// there at all.
pub fn zero_set_box(f: &Compiled, r: f64) -> Option<([f64; 3], [f64; 3])> {
    let n = f.degree;
    let m = n + 1;
    if n == 0 || !(r > 0.0 && r.is_finite()) {
        return Some(([-r; 3], [r; 3]));
    }
    // f(−r + 2r·u, …) as a tensor polynomial in u, v, w ∈ [0, 1] (power basis), and the same
    // with every term's magnitude (for the rounding margin).
    let mut a = vec![0.0; m * m * m];
    let mut a_abs = vec![0.0; m * m * m];
    for t in &f.terms {
        let [ei, ej, ek] = t.e.map(|e| e as usize);
        let part = |e: usize| -> Vec<f64> {
            (0..=e)
                .map(|q| binom(e, q) * (-r).powi((e - q) as i32) * (2.0 * r).powi(q as i32))
                .collect()
        };
        let (px, py, pz) = (part(ei), part(ej), part(ek));
        for (i, x) in px.iter().enumerate() {
            for (j, y) in py.iter().enumerate() {
                for (k, z) in pz.iter().enumerate() {
                    let v = t.c * x * y * z;
                    a[(i * m + j) * m + k] += v;
                    a_abs[(i * m + j) * m + k] += v.abs();
                }
            }
        }
    }
    // Power basis → Bernstein basis along each axis: b_p = Σ_{q≤p} C(p,q)/C(n,q) a_q.
    let to_bernstein = |a: &mut Vec<f64>| {
        for axis in 0..3 {
            let stride = [m * m, m, 1][axis];
            let src = a.clone();
            for (idx, out) in a.iter_mut().enumerate() {
                let p = (idx / stride) % m;
                let base = idx - p * stride;
                *out = (0..=p)
                    .map(|q| binom(p, q) / binom(n, q) * src[base + q * stride])
                    .sum();
            }
        }
    };
    to_bernstein(&mut a);
    to_bernstein(&mut a_abs);
    let scale = a_abs.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    // Conversion and subdivision are sums of a few hundred rounded terms of at most `scale`.
    let margin = 1e-9 * scale;
    let depth = depth_for(n);
    let mut stack = vec![(
        Cell {
            b: a,
            lo: [0.0; 3],
            size: 1.0,
        },
        0u32,
    )];
    let (mut bmin, mut bmax) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let mut examined = 0;
    while let Some((cell, level)) = stack.pop() {
        examined += 1;
        if examined > MAX_CELLS {
            return Some(([-r; 3], [r; 3]));
        }
        if cell.b.iter().all(|&v| v > margin) || cell.b.iter().all(|&v| v < -margin) {
            continue;
        }
        if level == depth {
            for ax in 0..3 {
                bmin[ax] = bmin[ax].min(cell.lo[ax]);
                bmax[ax] = bmax[ax].max(cell.lo[ax] + cell.size);
            }
            continue;
        }
        let half = 0.5 * cell.size;
        let mut parts = vec![(cell.b, cell.lo)];
        for axis in 0..3 {
            let mut next = Vec::with_capacity(parts.len() * 2);
            for (b, lo) in parts {
                let (l, h) = split(&b, m, axis);
                let mut lo_h = lo;
                lo_h[axis] += half;
                next.push((l, lo));
                next.push((h, lo_h));
            }
            parts = next;
        }
        for (b, lo) in parts {
            stack.push((Cell { b, lo, size: half }, level + 1));
        }
    }
    if bmin[0] > bmax[0] {
        return None;
    }
    // Back to object space, widened by a hair for the rounding of the mapping.
    let pad = 1e-9 * r;
    Some((
        bmin.map(|u| (-r + 2.0 * r * u - pad).max(-r)),
        bmax.map(|u| (-r + 2.0 * r * u + pad).min(r)),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::implicit::expand;

    fn boxed(eq: &str, r: f64) -> Option<([f64; 3], [f64; 3])> {
        zero_set_box(&Compiled::new(&expand(eq).unwrap()), r)
    }

    #[test]
    fn boxes_hold_the_surface_and_are_tight() {
        // An off-centre ellipsoid: x ∈ [0, 1], y ∈ [−0.25, 0.25], z ∈ [−0.5, 0.5].
        let (lo, hi) = boxed("4*(x - 0.5)^2 + 16*y^2 + 4*z^2 = 1", 2.0).unwrap();
        for (ax, (want_lo, want_hi)) in [(0.0, 1.0), (-0.25, 0.25), (-0.5, 0.5)]
            .into_iter()
            .enumerate()
        {
            assert!(lo[ax] <= want_lo && hi[ax] >= want_hi, "{lo:?} {hi:?}");
            // Cells are 4/32 wide: at most one cell of slack each side.
            assert!(
                lo[ax] >= want_lo - 0.126 && hi[ax] <= want_hi + 0.126,
                "{lo:?} {hi:?}"
            );
        }
        // Nothing inside the cube.
        assert_eq!(boxed("x^2 + y^2 + z^2 = 100", 2.0), None);
        // Degree 16: the unit sphere written as (x²+y²+z²)⁸ = 1.
        let (lo, hi) = boxed("(x^2 + y^2 + z^2)^8 = 1", 1.5).unwrap();
        assert!(lo.iter().all(|&v| v <= -1.0) && hi.iter().all(|&v| v >= 1.0));
        assert!(lo.iter().all(|&v| v >= -1.5) && hi.iter().all(|&v| v <= 1.5));
    }
}
