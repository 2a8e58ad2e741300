//! A box that certainly holds the part of the surface inside the clip sphere, found once at
//! load time by subdividing the cube `[−r, r]³` with the polynomial in the tensor Bernstein
//! basis: where every Bernstein coefficient of a cell has one sign (beyond a rounding
//! margin), `f` cannot vanish in that cell. The box is the hull of the cells left at the
//! finest level. Rays that miss it are rejected by a slab test, and the root search runs on
//! the ray's span inside it only; the cells themselves are kept, so that the renderer can
//! leave out the pixels whose camera rays see none of them.

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

/// `C(n, k)` as `f64` (exact for `n ≤ 16`).
fn binom(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

/// Splits every coefficient line of `b` (`M³` tensor coefficients, index `(i·M + j)·M + k`)
/// along `axis` at the middle (de Casteljau): the lower half into `lo`, the upper half into
/// `hi`. `M` is fixed so that the triangle's loops unroll.
fn split_into<const M: usize>(b: &[f64], axis: usize, lo: &mut [f64], hi: &mut [f64]) {
    // The lines along `axis` start where its index is 0; the two loops run over the others.
    let (stride, outer_stride, inner_stride) = match axis {
        0 => (M * M, M, 1),
        1 => (M, M * M, 1),
        _ => (1, M * M, M),
    };
    let (b, lo, hi) = (&b[..M * M * M], &mut lo[..M * M * M], &mut hi[..M * M * M]);
    for outer in 0..M {
        for inner in 0..M {
            let base = outer * outer_stride + inner * inner_stride;
            let mut line = [0.0; M];
            for (q, v) in line.iter_mut().enumerate() {
                *v = b[base + q * stride];
            }
            // Row r of the triangle: its first entry goes to the lower half, its last to
            // the upper half (reversed).
            for r in 0..M {
                lo[base + r * stride] = line[0];
                hi[base + (M - 1 - r) * stride] = line[M - 1 - r];
                for q in 0..M - 1 - r {
                    line[q] = 0.5 * (line[q] + line[q + 1]);
                }
            }
        }
    }
}

/// True when every coefficient is beyond `margin` on one side of zero.
#[inline]
fn one_sign(b: &[f64], margin: f64) -> bool {
    b.iter().all(|&v| v > margin) || b.iter().all(|&v| v < -margin)
}

/// Where `f` may vanish inside the cube `[−r, r]³`, in object space: boxes `(min, max)`
/// whose union holds every zero there, and their hull.
#[derive(Debug, Clone, PartialEq)]
pub struct ZeroSet {
    /// A box holding every zero of `f` in the cube: the hull of [`ZeroSet::cells`], or the
    /// whole cube when the subdivision gave up.
    pub bounds: ([f64; 3], [f64; 3]),
    /// Cells of the subdivision's finest level or the one above (widened by a hair for
    /// rounding) whose union holds every zero of `f` in the cube; empty when the subdivision
    /// gave up.
    pub cells: Vec<([f64; 3], [f64; 3])>,
}

/// Where `f` may vanish in the cube `[−r, r]³` ([`ZeroSet`]; the whole cube, without cells,
/// when the subdivision gives up), or `None` when `f` is proved to have no zero there.
pub fn zero_set(f: &Compiled, r: f64) -> Option<ZeroSet> {
    let n = f.degree;
    let m = n + 1;
    let whole_cube = || ZeroSet {
        bounds: ([-r; 3], [r; 3]),
        cells: Vec::new(),
    };
    if n == 0 || !(r > 0.0 && r.is_finite()) {
        return Some(whole_cube());
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
    let hull = match m {
        2 => subdivide::<2>(a, margin, depth),
        3 => subdivide::<3>(a, margin, depth),
        4 => subdivide::<4>(a, margin, depth),
        5 => subdivide::<5>(a, margin, depth),
        6 => subdivide::<6>(a, margin, depth),
        7 => subdivide::<7>(a, margin, depth),
        8 => subdivide::<8>(a, margin, depth),
        9 => subdivide::<9>(a, margin, depth),
        10 => subdivide::<10>(a, margin, depth),
        11 => subdivide::<11>(a, margin, depth),
        12 => subdivide::<12>(a, margin, depth),
        13 => subdivide::<13>(a, margin, depth),
        14 => subdivide::<14>(a, margin, depth),
        15 => subdivide::<15>(a, margin, depth),
        16 => subdivide::<16>(a, margin, depth),
        _ => subdivide::<17>(a, margin, depth),
    };
    let Hull::Cells(cells) = hull else {
        return Some(whole_cube());
    };
    if cells.is_empty() {
        return None;
    }
    // Back to object space, widened by a hair for the rounding of the mapping.
    let pad = 1e-9 * r;
    let to_object = |(lo, size): ([f64; 3], f64)| {
        (
            lo.map(|u| (-r + 2.0 * r * u - pad).max(-r)),
            lo.map(|u| (-r + 2.0 * r * (u + size) + pad).min(r)),
        )
    };
    let cells: Vec<_> = cells.into_iter().map(to_object).collect();
    let (mut bmin, mut bmax) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for (lo, hi) in &cells {
        for ax in 0..3 {
            bmin[ax] = bmin[ax].min(lo[ax]);
            bmax[ax] = bmax[ax].max(hi[ax]);
        }
    }
    Some(ZeroSet {
        bounds: (bmin, bmax),
        cells,
    })
}

/// What the subdivision found: cells `(corner, size)` in `[0, 1]³` whose union holds every
/// zero of `f` (none when it has none), of the finest level or, inside the hull of those
/// found before, of the level above; or that it gave up.
enum Hull {
    Cells(Vec<([f64; 3], f64)>),
    GaveUp,
}

/// The subdivision of the unit cube for the tensor Bernstein coefficients `root` (`M³`, of a
/// polynomial of degree `M − 1` in each variable), down to `depth` levels: a cell whose
/// coefficients all lie beyond `margin` on one side of zero is dropped, the others are split
/// in eight.
fn subdivide<const M: usize>(root: Vec<f64>, margin: f64, depth: u32) -> Hull {
    // Depth-first over the cells, their coefficients in one stack of `M³` blocks beside
    // their corner, size and level (at most 7 pending cells a level, plus the 8 just made).
    // Every cell made counts towards `MAX_CELLS` whatever the order, so the result is that
    // of the whole subdivision.
    let len = M * M * M;
    let mut coeffs = vec![0.0; (7 * depth as usize + 8) * len];
    coeffs[..len].copy_from_slice(&root);
    let mut cells = vec![([0.0f64; 3], 1.0f64, 0u32)];
    let mut parent = vec![0.0; len];
    let mut halves = vec![0.0; 2 * len];
    let mut quarters = vec![0.0; 4 * len];
    let mut leaves = Vec::new();
    // The hull of `leaves`.
    let (mut bmin, mut bmax) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let mut examined = 0;
    while let Some((lo, size, level)) = cells.pop() {
        examined += 1;
        if examined > MAX_CELLS {
            return Hull::GaveUp;
        }
        let top = cells.len() * len;
        let b = &coeffs[top..top + len];
        if one_sign(b, margin) {
            continue;
        }
        if level == depth {
            for ax in 0..3 {
                bmin[ax] = bmin[ax].min(lo[ax]);
                bmax[ax] = bmax[ax].max(lo[ax] + size);
            }
            leaves.push((lo, size));
            continue;
        }
        if level + 1 == depth && (0..3).all(|ax| bmin[ax] <= lo[ax] && lo[ax] + size <= bmax[ax]) {
            // Its eight cells at the finest level would each be examined, and could only add
            // to the hull what it holds already: count them, skip their coefficients, and
            // keep the cell itself in their place.
            examined += 8;
            if examined > MAX_CELLS {
                return Hull::GaveUp;
            }
            leaves.push((lo, size));
            continue;
        }
        parent.copy_from_slice(b);
        let (h0, h1) = halves.split_at_mut(len);
        split_into::<M>(&parent, 0, h0, h1);
        for (h, q) in halves
            .chunks_exact(len)
            .zip(quarters.chunks_exact_mut(2 * len))
        {
            let (q0, q1) = q.split_at_mut(len);
            split_into::<M>(h, 1, q0, q1);
        }
        for (q, e) in quarters
            .chunks_exact(len)
            .zip(coeffs[top..top + 8 * len].chunks_exact_mut(2 * len))
        {
            let (e0, e1) = e.split_at_mut(len);
            split_into::<M>(q, 2, e0, e1);
        }
        // Child c has the upper half along x when bit 2 of c is set, along y bit 1, z bit 0.
        let half = 0.5 * size;
        for c in 0..8 {
            let mut corner = lo;
            for (ax, bit) in [(0, 4), (1, 2), (2, 1)] {
                if c & bit != 0 {
                    corner[ax] += half;
                }
            }
            cells.push((corner, half, level + 1));
        }
    }
    Hull::Cells(leaves)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::implicit::expand;

    fn zero_set_box(f: &Compiled, r: f64) -> Option<([f64; 3], [f64; 3])> {
        zero_set(f, r).map(|z| z.bounds)
    }

    fn boxed(eq: &str, r: f64) -> Option<([f64; 3], [f64; 3])> {
        zero_set_box(&Compiled::new(&expand(eq).unwrap()), r)
    }

    /// The subdivision as first written (every cell's coefficients in its own vectors, all
    /// eight children of a cell made by splitting whole vectors): the reference the faster
    /// [`subdivide`] must reproduce exactly.
    fn reference_box(f: &Compiled, r: f64) -> Option<([f64; 3], [f64; 3])> {
        fn split(b: &[f64], m: usize, axis: usize) -> (Vec<f64>, Vec<f64>) {
            let stride = [m * m, m, 1][axis];
            let (mut lo, mut hi) = (b.to_vec(), b.to_vec());
            for base in (0..b.len()).filter(|base| (base / stride).is_multiple_of(m)) {
                let mut line: Vec<f64> = (0..m).map(|q| b[base + q * stride]).collect();
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
        let (n, m) = (f.degree, f.degree + 1);
        let mut a = vec![0.0; m * m * m];
        let mut a_abs = vec![0.0; m * m * m];
        for t in &f.terms {
            let part = |e: u8| -> Vec<f64> {
                let e = e as usize;
                (0..=e)
                    .map(|q| binom(e, q) * (-r).powi((e - q) as i32) * (2.0 * r).powi(q as i32))
                    .collect()
            };
            let (px, py, pz) = (part(t.e[0]), part(t.e[1]), part(t.e[2]));
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
        for a in [&mut a, &mut a_abs] {
            for stride in [m * m, m, 1] {
                let src = a.clone();
                for (idx, out) in a.iter_mut().enumerate() {
                    let p = (idx / stride) % m;
                    let base = idx - p * stride;
                    *out = (0..=p)
                        .map(|q| binom(p, q) / binom(n, q) * src[base + q * stride])
                        .sum();
                }
            }
        }
        let margin = 1e-9 * a_abs.iter().fold(0.0f64, |s, v| s.max(v.abs()));
        let depth = depth_for(n);
        let mut stack = vec![(a, [0.0; 3], 1.0, 0)];
        let (mut bmin, mut bmax) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        let mut examined = 0;
        while let Some((b, lo, size, level)) = stack.pop() {
            examined += 1;
            if examined > MAX_CELLS {
                return Some(([-r; 3], [r; 3]));
            }
            if one_sign(&b, margin) {
                continue;
            }
            if level == depth {
                for ax in 0..3 {
                    bmin[ax] = bmin[ax].min(lo[ax]);
                    bmax[ax] = bmax[ax].max(lo[ax] + size);
                }
                continue;
            }
            let half = 0.5 * size;
            let mut parts = vec![(b, lo)];
            for axis in 0..3 {
                let mut next = Vec::new();
                for (b, lo) in parts {
                    let (l, h) = split(&b, m, axis);
                    let mut lo_h = lo;
                    lo_h[axis] += half;
                    next.push((l, lo));
                    next.push((h, lo_h));
                }
                parts = next;
            }
            stack.extend(parts.into_iter().map(|(b, lo)| (b, lo, half, level + 1)));
        }
        if bmin[0] > bmax[0] {
            return None;
        }
        let pad = 1e-9 * r;
        Some((
            bmin.map(|u| (-r + 2.0 * r * u - pad).max(-r)),
            bmax.map(|u| (-r + 2.0 * r * u + pad).min(r)),
        ))
    }

    #[test]
    fn the_subdivision_gives_the_reference_box_exactly() {
        // Every degree from 1 to 16 and the presets: surfaces that cross the cube, miss it
        // or are clipped by it, bit for bit.
        let cases = [
            ("x + 2*y - z = 0.3", 1.0),
            ("x^2 + y^2 - z^2 = 0.2", 1.5),
            ("x^3 + y^3 + z^3 = 1", 2.0),
            ("(x^2 + y^2 + z^2 + 0.91)^2 - 4*(x^2 + y^2) = 0", 1.4),
            ("x^2 + y^2 + z^2 = 100", 2.0),
            ("x^5 - y*z^3 + x*y = 0.01", 1.0),
            ("(2*x^2 + y^2 + z^2 - 1)^3 - (0.1*x^2 + y^2)*z^3 = 0", 1.83),
            ("x^7 + y^7 + z^7 = 1", 1.2),
            ("(x^2 + y^2 + z^2)^4 - x*y*z = 0.5", 1.5),
            ("x^9 - y^9 + z = 0.1", 1.0),
            ("(x^2 + y^2 + z^2)^5 = 1", 1.5),
            ("x^11 + y^2 + z^2 = 0.5", 1.0),
            ("(x^2 + y^2 + z^2)^6 - x^3 = 1", 1.5),
            ("x^13 + y^13 + z^13 = 0.5", 1.0),
            ("(x^2 + y^2 + z^2)^7 = 1", 1.5),
            ("x^15 + y*z = 0.2", 1.0),
            ("(x^2 + y^2 + z^2)^8 = 1", 1.5),
            // Large zero sets, about as many cells as the subdivision examines at most.
            ("(x^2 - 0.01)*(x^2 - 0.64) = 0", 1.0),
            ("(x^2 - 0.01)*(x^2 - 0.36)*y = 0.001", 1.0),
            ("(x^2 - 0.01)*(y^2 - 0.25)*(z^2 - 0.64) = 0", 1.0),
        ];
        for (eq, r) in cases {
            let f = Compiled::new(&expand(eq).unwrap());
            assert_eq!(zero_set_box(&f, r), reference_box(&f, r), "{eq}");
        }
        // Six planes |x| ≤ 0.8: more cells than the limit, so the box is the whole cube.
        let f = Compiled::new(&expand("(x^2 - 0.01)*(x^2 - 0.25)*(x^2 - 0.64) = 0").unwrap());
        assert_eq!(zero_set_box(&f, 1.0), Some(([-1.0; 3], [1.0; 3])));
        assert_eq!(reference_box(&f, 1.0), Some(([-1.0; 3], [1.0; 3])));
        let presets: [(&str, &[f64]); 8] = [
            ("torus", &[1.0, 0.3]),
            ("barth_sextic", &[]),
            ("chmutov", &[6.0]),
            ("chmutov", &[8.0]),
            ("taubin_heart", &[]),
            ("kummer", &[1.3]),
            ("clebsch", &[]),
            ("heart", &[]),
        ];
        for (name, params) in presets {
            let p = crate::shapes::implicit::preset(name, params).unwrap();
            let f = Compiled::new(&expand(&p.equation).unwrap());
            let r = p.bound;
            assert_eq!(zero_set_box(&f, r), reference_box(&f, r), "{name}");
        }
    }

    #[test]
    fn the_cells_hold_every_zero_and_their_hull_is_the_box() {
        let mut uniform = crate::testing::uniform_stream(0x9e37_79b9_7f4a_7c15);
        // Each surface with its radius and whether its cells leave out much of their hull
        // (Chmutov's octic and the degree-16 sphere fill it at the depths used for them).
        let cases: Vec<(String, f64, bool)> = [
            ("torus", &[1.0, 0.3][..], true),
            ("barth_sextic", &[], true),
            ("chmutov", &[8.0], false),
            ("taubin_heart", &[], true),
            ("clebsch", &[], true),
        ]
        .into_iter()
        .map(|(name, params, tight)| {
            let p = crate::shapes::implicit::preset(name, params).unwrap();
            (p.equation, p.bound, tight)
        })
        .chain([
            ("4*(x - 0.5)^2 + 16*y^2 + 4*z^2 = 1".to_string(), 2.0, true),
            ("(x^2 + y^2 + z^2)^8 = 1".to_string(), 1.5, false),
        ])
        .collect();
        for (eq, r, tight) in cases {
            let f = Compiled::new(&expand(&eq).unwrap());
            let zeros = zero_set(&f, r).unwrap();
            assert!(!zeros.cells.is_empty(), "{eq}");
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for (a, b) in &zeros.cells {
                for ax in 0..3 {
                    (lo[ax], hi[ax]) = (lo[ax].min(a[ax]), hi[ax].max(b[ax]));
                }
            }
            assert_eq!((lo, hi), zeros.bounds, "{eq}");
            // The cells overlap only on their faces and, where they can, cover much less than
            // their hull.
            let volume =
                |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|ax| b[ax] - a[ax]).product::<f64>();
            let covered: f64 = zeros.cells.iter().map(|(a, b)| volume(a, b)).sum();
            let share = covered / volume(&lo, &hi);
            assert!(share <= 1.0 + 1e-6, "{eq}: {share}");
            assert!(!tight || share < 0.6, "{eq}: {share}");
            // Zeros found by bisection on random segments of the cube lie in a cell.
            let mut found = 0;
            for _ in 0..4000 {
                let mut a: [f64; 3] = std::array::from_fn(|_| r * (2.0 * uniform() - 1.0));
                let mut b: [f64; 3] = std::array::from_fn(|_| r * (2.0 * uniform() - 1.0));
                let (mut fa, fb) = (f.eval(a), f.eval(b));
                if fa.signum() == fb.signum() {
                    continue;
                }
                for _ in 0..60 {
                    let m: [f64; 3] = std::array::from_fn(|ax| 0.5 * (a[ax] + b[ax]));
                    let fm = f.eval(m);
                    if fm.signum() == fa.signum() {
                        (a, fa) = (m, fm);
                    } else {
                        b = m;
                    }
                }
                found += 1;
                let inside = |(c0, c1): &([f64; 3], [f64; 3])| {
                    (0..3).all(|ax| c0[ax] <= a[ax] && a[ax] <= c1[ax])
                };
                assert!(
                    zeros.cells.iter().any(inside),
                    "{eq}: zero {a:?} in no cell"
                );
            }
            assert!(found > 20, "{eq}: {found}");
        }
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
