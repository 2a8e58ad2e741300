//! First-root queries for [`LANES`] polynomials at once ([`Solver::first_root_lanes`]): the
//! usual path's fixed part (the fixed-size preparation, the expansion in the Bernstein basis
//! and the whole interval's sign test) computed lane by lane in the same operations and the
//! same order as the scalar query, without branches, so that the compiler keeps the lanes in
//! vector registers; each lane the test does not settle then goes on alone where the scalar
//! query would (the search over pieces, the strategy's own isolation), except that the
//! refinements of the lanes' brackets take their steps in turn
//! (`refine::refine_simple_lanes`), so that the lanes' chains of dependent operations
//! overlap. Every lane's answer is the scalar [`Solver::first_root`] bit for bit (tested):
//! every step is an IEEE operation (no fused multiply-add is ever formed, as in the scalar
//! code), and each `if` of the scalar code becomes a choice between two computed values.
//!
//! The queries have two copies, chosen at run time: for AVX2 (four `f64` lanes a register)
//! when the processor has it, and for the x86-64 baseline (SSE2, two lanes), which every
//! other processor runs and the tests also run. In the AVX2 copy the lanes' part is written
//! in intrinsics (`front_avx2`), each lane's rest is `rest_in` compiled for AVX2, and the
//! brackets are refined four lanes a register (`refine::refine_simple_lanes_avx2`); the
//! baseline copy compiles `front_in` and `rest_in` as they are. Both give the scalar query's
//! answers bit for bit (tested).

use super::bernstein::{self, Fast, INV_BINOMIAL};
use super::prep::{Fixed, MAX_COEFFS};
use super::refine::refine_simple_lanes;
#[cfg(target_arch = "x86_64")]
use super::refine::refine_simple_lanes_avx2;
use super::{settle, Solver};
use crate::geometry::LANES;

/// One `f64` per lane.
type Lanes = [f64; LANES];

/// What the lanes' part found for one lane.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Status {
    /// Not asked, refused (invalid input), or no root by the whole interval's test.
    NoRoot,
    /// Not the usual case of the fixed-size preparation: the scalar query.
    Other,
    /// An end coefficient too close to zero: the strategy's own isolation.
    Undecided,
    /// The whole interval's test did not settle it: the search goes on from its result
    /// (`Some(v)`: `v` sign variations, `None`: an uncertain sign).
    Search(Option<u32>),
}

/// The lanes' part of the queries: each lane's prepared polynomial (coefficients, scale,
/// interval), its Bernstein coefficients on the whole interval and the search's bounds, where
/// the status says they were computed.
struct Front<const D: usize> {
    c: [Lanes; D],
    scale: Lanes,
    lo: Lanes,
    hi: Lanes,
    /// Each lane's Bernstein coefficients, in its first `D` entries (whole vector stores:
    /// the search copies them with vector loads, which wait long on narrower stores).
    b: [[f64; PADDED]; LANES],
    size: Lanes,
    unit: Lanes,
    status: [Status; LANES],
}

/// [`MAX_COEFFS`] rounded up to whole groups of [`LANES`]: the length of [`Front::b`]'s rows.
const PADDED: usize = MAX_COEFFS.div_ceil(LANES) * LANES;

/// The binary exponent of a finite non-zero `x` (as `prep::exponent`, in 64 bits, which the
/// lanes compute without conversions).
#[inline(always)]
fn exponent(x: f64) -> i64 {
    ((x.to_bits() >> 52) & 0x7ff) as i64 - 1023
}

/// `2^k` for a normal exponent `k` (`−1022 ≤ k ≤ 1023`); meaningless otherwise.
#[inline(always)]
fn pow2(k: i64) -> f64 {
    f64::from_bits(((k + 1023) as u64) << 52)
}

/// `a` where `pick`, else `b`.
#[inline(always)]
fn choose(pick: bool, a: f64, b: f64) -> f64 {
    if pick {
        a
    } else {
        b
    }
}

/// The lanes' part (see the module documentation): `prep::prepare_fixed`, then
/// `bernstein::bernstein_fixed` and the first test of `bernstein::search`, lane by lane.
#[inline(always)]
fn front_in<const D: usize>(
    coeffs: &[Lanes; D],
    lo: Lanes,
    hi: Lanes,
    active: [bool; LANES],
) -> Front<D> {
    let n = D - 1;
    let mut c = *coeffs;
    // The preparation's tests: valid, then the usual case (see `prepare_fixed`; its shortcut
    // for an interval reaching 1 tests the same as its general rule, which is used here for
    // every lane).
    let mut valid = [false; LANES];
    let mut usual = [false; LANES];
    let mut er = [0i64; LANES];
    for l in 0..LANES {
        let finite = c.iter().fold(true, |ok, cj| ok & cj[l].is_finite());
        valid[l] = active[l] & (lo[l] < hi[l]) & finite;
        let r = lo[l].abs().max(hi[l].abs());
        let cn = c[n][l];
        let (an, mut pow, mut negligible) = (cn.abs(), 1.0, false);
        for i in (0..n).rev() {
            pow *= r;
            negligible |= (c[i][l] != 0.0) & (an * pow <= f64::EPSILON * c[i][l].abs());
        }
        let e_r = exponent(r) + 1;
        let e_n = exponent(cn);
        let mut reaches = false;
        for k in 1..D {
            let ck = c[n - k][l];
            reaches |= (ck != 0.0) & (exponent(ck) - e_n + 1 > k as i64 * (e_r - 1));
        }
        let (first, last) = (-(n as i64) * e_r - e_n, -e_n);
        let normal = |k: i64| (-1022..=1023).contains(&k);
        usual[l] = (cn != 0.0)
            & r.is_finite()
            & !negligible
            & (-1000..=999).contains(&e_r)
            & reaches
            & normal(first)
            & normal(last);
        er[l] = e_r;
        // The rescaling (meaningless in a lane that is not usual, and then not used).
        for (j, cj) in c.iter_mut().enumerate() {
            cj[l] *= pow2(j as i64 * e_r + first);
        }
    }
    let mut scale = [0.0; LANES];
    let (mut p_lo, mut p_hi) = ([0.0; LANES], [0.0; LANES]);
    for l in 0..LANES {
        let inv = pow2(-er[l]);
        scale[l] = pow2(er[l]);
        p_lo[l] = lo[l] * inv;
        p_hi[l] = hi[l] * inv;
    }
    // `bernstein_fixed` on `[p_lo, p_hi]`.
    let mut reversed = [false; LANES];
    let (mut x0, mut h) = ([0.0; LANES], [0.0; LANES]);
    for l in 0..LANES {
        reversed[l] = p_hi[l].abs() < p_lo[l].abs();
        x0[l] = choose(reversed[l], p_hi[l], p_lo[l]);
        h[l] = choose(reversed[l], p_lo[l] - p_hi[l], p_hi[l] - p_lo[l]);
    }
    let mut d = c;
    // The Taylor shift where `x0 ≠ 0` (none from zero, the heart's usual query).
    if (0..LANES).any(|l| x0[l] != 0.0) {
        let mut shifted = d;
        for i in 0..n {
            for j in (i..n).rev() {
                for l in 0..LANES {
                    shifted[j][l] += x0[l] * shifted[j + 1][l];
                }
            }
        }
        for (dj, sj) in d.iter_mut().zip(&shifted) {
            for l in 0..LANES {
                dj[l] = choose(x0[l] != 0.0, sj[l], dj[l]);
            }
        }
    }
    let mut hk = [1.0; LANES];
    for (dj, ib) in d.iter_mut().zip(&INV_BINOMIAL[n]) {
        for l in 0..LANES {
            dj[l] *= hk[l] * ib;
            hk[l] *= h[l];
        }
    }
    for i in 1..D {
        for j in (i..D).rev() {
            let before = d[j - 1];
            for (x, y) in d[j].iter_mut().zip(before) {
                *x += y;
            }
        }
    }
    let mut b = d;
    for (j, bj) in b.iter_mut().enumerate() {
        for l in 0..LANES {
            bj[l] = choose(reversed[l], d[n - j][l], d[j][l]);
        }
    }
    let mut b_lanes = [[0.0; PADDED]; LANES];
    for (l, row) in b_lanes.iter_mut().enumerate() {
        for (j, bj) in b.iter().enumerate() {
            row[j] = bj[l];
        }
    }
    // `search`'s bounds and its first test.
    let mut size = [0.0; LANES];
    let mut unit = [0.0; LANES];
    let mut status = [Status::NoRoot; LANES];
    for l in 0..LANES {
        let w = p_hi[l] - p_lo[l];
        let r = p_lo[l].abs() + w;
        size[l] = c.iter().rev().fold(0.0, |s, cj| s * r + cj[l].abs());
        unit[l] = (n + 1) as f64 * f64::EPSILON * size[l];
        let margin = 64.0 * unit[l];
        let ends_unclear =
            !unit[l].is_finite() | (b[0][l].abs() <= margin) | (b[n][l].abs() <= margin);
        let mut uncertain = false;
        let mut changes = 0u32;
        for j in 0..n {
            uncertain |= b[j + 1][l].abs() <= margin;
            changes += u32::from((b[j][l] < 0.0) != (b[j + 1][l] < 0.0));
        }
        status[l] = if !valid[l] {
            Status::NoRoot
        } else if !usual[l] {
            Status::Other
        } else if ends_unclear {
            Status::Undecided
        } else if uncertain {
            Status::Search(None)
        } else if changes == 0 {
            Status::NoRoot
        } else {
            Status::Search(Some(changes.min(2)))
        };
    }
    Front {
        c,
        scale,
        lo: p_lo,
        hi: p_hi,
        b: b_lanes,
        size,
        unit,
        status,
    }
}

/// Which compiled copy of the lanes' part runs.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Code {
    /// AVX2 where the processor has it, else the baseline.
    Detected,
    /// The baseline copy (what processors without AVX2 run).
    Baseline,
}

/// See [`Solver::first_root_lanes`]; `code` picks the copy of the lanes' part.
#[inline]
pub(super) fn first_roots<const D: usize>(
    solver: Solver,
    coeffs: &[[f64; D]; LANES],
    lo: Lanes,
    hi: Lanes,
    active: [bool; LANES],
    code: Code,
) -> [Option<f64>; LANES] {
    first_roots_by_power(solver, &by_power(coeffs), lo, hi, active, code)
}

/// The lanes' coefficients by power: `[j][l]` is lane `l`'s coefficient of `tʲ`.
#[inline(always)]
pub(super) fn by_power<const D: usize>(coeffs: &[[f64; D]; LANES]) -> [Lanes; D] {
    std::array::from_fn(|j| std::array::from_fn(|l| coeffs[l][j]))
}

/// See [`Solver::first_root_lanes_by_power`]; `code` picks the copy of the lanes' part.
#[inline]
pub(super) fn first_roots_by_power<const D: usize>(
    solver: Solver,
    coeffs: &[Lanes; D],
    lo: Lanes,
    hi: Lanes,
    active: [bool; LANES],
    code: Code,
) -> [Option<f64>; LANES] {
    if !(2..=MAX_COEFFS).contains(&D) {
        return std::array::from_fn(|l| {
            active[l]
                .then(|| solver.first_root(&lane(coeffs, l), lo[l], hi[l]))
                .flatten()
        });
    }
    if !active.iter().any(|&a| a) {
        return [None; LANES];
    }
    #[cfg(target_arch = "x86_64")]
    if code == Code::Detected && crate::cpu::avx2() {
        // SAFETY: the processor has AVX2, checked just above. The two parts stay separate
        // functions: one function for both measured 8 % slower on the heart (16 pairs).
        unsafe {
            let front = front_avx2(coeffs, lo, hi, active);
            return rest_avx2(solver, coeffs, lo, hi, &front);
        }
    }
    rest_in::<D, false>(solver, coeffs, lo, hi, &front_in(coeffs, lo, hi, active))
}

/// Lane `l`'s coefficients, ascending.
#[inline(always)]
fn lane<const D: usize>(coeffs: &[Lanes; D], l: usize) -> [f64; D] {
    std::array::from_fn(|j| coeffs[j][l])
}

/// [`front_in`] in AVX2 intrinsics: four lanes a register, each operation the IEEE (or
/// 64-bit integer) operation `front_in` takes for each lane, in the same order, so every
/// lane's result that `rest_in` reads is the same bits (tested); each `if` of `front_in` is
/// a blend on the comparison's mask, and the status is decided from the masks at the end.
///
/// # Safety
/// The processor must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn front_avx2<const D: usize>(
    coeffs: &[Lanes; D],
    lo: Lanes,
    hi: Lanes,
    active: [bool; LANES],
) -> Front<D> {
    use std::arch::x86_64::*;
    let n = D - 1;
    // The lane operations are `roots::avx2`'s macros, and these.
    macro_rules! load {
        ($v:expr $(,)?) => {
            _mm256_loadu_pd($v.as_ptr())
        };
    }
    macro_rules! int {
        ($k:expr $(,)?) => {
            _mm256_set1_epi64x($k)
        };
    }
    macro_rules! mask_of {
        ($m:expr $(,)?) => {
            _mm256_castsi256_pd($m)
        };
    }
    // `exponent` and `pow2`, lane by lane in 64-bit integers.
    macro_rules! exponent {
        ($x:expr) => {
            _mm256_sub_epi64(
                _mm256_and_si256(
                    _mm256_srli_epi64::<52>(_mm256_castpd_si256($x)),
                    int!(0x7ff),
                ),
                int!(1023),
            )
        };
    }
    macro_rules! pow2 {
        ($k:expr $(,)?) => {
            _mm256_castsi256_pd(_mm256_slli_epi64::<52>(_mm256_add_epi64($k, int!(1023))))
        };
    }
    // `lo_k ≤ k ≤ hi_k` for 64-bit lanes.
    macro_rules! within {
        ($k:expr, $lo_k:expr, $hi_k:expr $(,)?) => {
            mask_of!(_mm256_and_si256(
                _mm256_cmpgt_epi64($k, int!($lo_k - 1)),
                _mm256_cmpgt_epi64(int!($hi_k + 1), $k),
            ))
        };
    }
    macro_rules! store {
        ($v:expr) => {{
            let mut out = [0.0; LANES];
            _mm256_storeu_pd(out.as_mut_ptr(), $v);
            out
        }};
    }
    let zero = _mm256_setzero_pd();
    let (lo_v, hi_v) = (load!(&lo), load!(&hi));
    // Loops, not closures (`from_fn`, `map`, `fold`): a closure is compiled without AVX2
    // and not inlined here.
    let mut c = [_mm256_setzero_pd(); D];
    for (cj, given) in c.iter_mut().zip(coeffs) {
        *cj = load!(given);
    }
    // The preparation's tests: valid, then the usual case.
    let active_mask = mask_of!(_mm256_set_epi64x(
        -i64::from(active[3]),
        -i64::from(active[2]),
        -i64::from(active[1]),
        -i64::from(active[0]),
    ));
    let mut all_finite = active_mask;
    for &cj in &c {
        all_finite = and!(all_finite, finite!(cj));
    }
    let valid = and!(all_finite, lt!(lo_v, hi_v));
    // `lo.abs().max(hi.abs())`: neither is NaN in a valid lane (`lo < hi`).
    let r = _mm256_max_pd(abs!(lo_v), abs!(hi_v));
    let cn = c[n];
    let an = abs!(cn);
    let (mut pow, mut negligible) = (splat!(1.0), zero);
    for i in (0..n).rev() {
        pow = mul!(pow, r);
        negligible = or!(
            negligible,
            and!(
                ne!(c[i], zero),
                le!(mul!(an, pow), mul!(splat!(f64::EPSILON), abs!(c[i]))),
            ),
        );
    }
    let e_r = _mm256_add_epi64(exponent!(r), int!(1));
    let e_n = exponent!(cn);
    let e_r_less = _mm256_sub_epi64(e_r, int!(1));
    let (mut k_times, mut reaches) = (_mm256_setzero_si256(), zero);
    for k in 1..D {
        let ck = c[n - k];
        // k·(e_r − 1), by k additions.
        k_times = _mm256_add_epi64(k_times, e_r_less);
        let span = _mm256_add_epi64(_mm256_sub_epi64(exponent!(ck), e_n), int!(1));
        reaches = or!(
            reaches,
            and!(ne!(ck, zero), mask_of!(_mm256_cmpgt_epi64(span, k_times))),
        );
    }
    // first = −n·e_r − e_n, last = −e_n.
    let mut n_e_r = _mm256_setzero_si256();
    for _ in 0..n {
        n_e_r = _mm256_add_epi64(n_e_r, e_r);
    }
    let first = _mm256_sub_epi64(_mm256_sub_epi64(_mm256_setzero_si256(), n_e_r), e_n);
    let last = _mm256_sub_epi64(_mm256_setzero_si256(), e_n);
    let usual = and!(
        and!(
            and!(ne!(cn, zero), finite!(r)),
            _mm256_andnot_pd(negligible, within!(e_r, -1000, 999)),
        ),
        and!(
            reaches,
            and!(within!(first, -1022, 1023), within!(last, -1022, 1023)),
        ),
    );
    // The rescaling: cⱼ·2^(j·e_r + first).
    let mut k = first;
    for cj in c.iter_mut() {
        *cj = mul!(*cj, pow2!(k));
        k = _mm256_add_epi64(k, e_r);
    }
    let scale = pow2!(e_r);
    let inv = pow2!(_mm256_sub_epi64(_mm256_setzero_si256(), e_r));
    let (p_lo, p_hi) = (mul!(lo_v, inv), mul!(hi_v, inv));
    // `bernstein_fixed` on `[p_lo, p_hi]`.
    let reversed = lt!(abs!(p_hi), abs!(p_lo));
    let x0 = pick!(reversed, p_hi, p_lo);
    let h = pick!(reversed, sub!(p_lo, p_hi), sub!(p_hi, p_lo));
    let mut d = c;
    let shift = ne!(x0, zero);
    if _mm256_movemask_pd(shift) != 0 {
        let mut shifted = d;
        for i in 0..n {
            for j in (i..n).rev() {
                shifted[j] = add!(shifted[j], mul!(x0, shifted[j + 1]));
            }
        }
        for (dj, sj) in d.iter_mut().zip(shifted) {
            *dj = pick!(shift, sj, *dj);
        }
    }
    let mut hk = splat!(1.0);
    for (dj, &ib) in d.iter_mut().zip(&INV_BINOMIAL[n]) {
        *dj = mul!(*dj, mul!(hk, splat!(ib)));
        hk = mul!(hk, h);
    }
    for i in 1..D {
        for j in (i..D).rev() {
            d[j] = add!(d[j], d[j - 1]);
        }
    }
    let mut b = d;
    for j in 0..D {
        b[j] = pick!(reversed, d[n - j], d[j]);
    }
    // `search`'s bounds and its first test.
    let w = sub!(p_hi, p_lo);
    let reach = add!(abs!(p_lo), w);
    let mut size = zero;
    for &cj in c.iter().rev() {
        size = add!(mul!(size, reach), abs!(cj));
    }
    let unit = mul!(splat!((n + 1) as f64 * f64::EPSILON), size);
    let margin = mul!(splat!(64.0), unit);
    let ends_unclear = or!(
        _mm256_andnot_pd(finite!(unit), _mm256_castsi256_pd(int!(-1))),
        or!(le!(abs!(b[0]), margin), le!(abs!(b[n]), margin)),
    );
    let (mut uncertain, mut changes) = (zero, _mm256_setzero_si256());
    for j in 0..n {
        uncertain = or!(uncertain, le!(abs!(b[j + 1]), margin));
        let differ = _mm256_xor_pd(lt!(b[j], zero), lt!(b[j + 1], zero));
        // A mask lane is −1: subtracting it counts.
        changes = _mm256_sub_epi64(changes, _mm256_castpd_si256(differ));
    }
    let (valid, usual, ends_unclear, uncertain) = (
        _mm256_movemask_pd(valid),
        _mm256_movemask_pd(usual),
        _mm256_movemask_pd(ends_unclear),
        _mm256_movemask_pd(uncertain),
    );
    let mut counts = [0i64; LANES];
    _mm256_storeu_si256(counts.as_mut_ptr().cast(), changes);
    let mut status = [Status::NoRoot; LANES];
    for (l, lane_status) in status.iter_mut().enumerate() {
        let set = |m: i32| m >> l & 1 == 1;
        *lane_status = if !set(valid) {
            Status::NoRoot
        } else if !set(usual) {
            Status::Other
        } else if set(ends_unclear) {
            Status::Undecided
        } else if set(uncertain) {
            Status::Search(None)
        } else if counts[l] == 0 {
            Status::NoRoot
        } else {
            Status::Search(Some((counts[l] as u32).min(2)))
        };
    }
    let mut c_out = [[0.0; LANES]; D];
    for j in 0..D {
        _mm256_storeu_pd(c_out[j].as_mut_ptr(), c[j]);
    }
    // The lanes' coefficients transposed four powers at a time (a 4 × 4 transpose in
    // registers), each lane's row stored in whole vectors.
    let mut b_out = [[0.0; PADDED]; LANES];
    for j in (0..D).step_by(LANES) {
        let mut rows = [zero; LANES];
        for (k, r) in rows.iter_mut().enumerate() {
            if j + k < D {
                *r = b[j + k];
            }
        }
        let (t0, t1) = (
            _mm256_unpacklo_pd(rows[0], rows[1]),
            _mm256_unpackhi_pd(rows[0], rows[1]),
        );
        let (t2, t3) = (
            _mm256_unpacklo_pd(rows[2], rows[3]),
            _mm256_unpackhi_pd(rows[2], rows[3]),
        );
        let lanes = [
            _mm256_permute2f128_pd::<0x20>(t0, t2),
            _mm256_permute2f128_pd::<0x20>(t1, t3),
            _mm256_permute2f128_pd::<0x31>(t0, t2),
            _mm256_permute2f128_pd::<0x31>(t1, t3),
        ];
        for (out, lane) in b_out.iter_mut().zip(lanes) {
            _mm256_storeu_pd(out[j..].as_mut_ptr(), lane);
        }
    }
    Front {
        c: c_out,
        scale: store!(scale),
        lo: store!(p_lo),
        hi: store!(p_hi),
        b: b_out,
        size: store!(size),
        unit: store!(unit),
        status,
    }
}

/// [`rest_in`] compiled for AVX2: the same operations (AVX2 brings no fused multiply-add),
/// so the same bits, with the searches' de Casteljau rows in wider registers.
///
/// # Safety
/// The processor must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn rest_avx2<const D: usize>(
    solver: Solver,
    coeffs: &[Lanes; D],
    lo: Lanes,
    hi: Lanes,
    front: &Front<D>,
) -> [Option<f64>; LANES] {
    rest_in::<D, true>(solver, coeffs, lo, hi, front)
}

/// The part of [`first_roots`] after the lanes' front: each lane on from it, as the scalar
/// query goes on (see `observed`), up to the refinement of the search's bracket; then the
/// lanes' brackets refined together (with `AVX2`, which only code compiled for AVX2 may
/// set, in one vector a step: `refine::refine_simple_lanes_avx2`).
#[inline(always)]
fn rest_in<const D: usize, const AVX2: bool>(
    solver: Solver,
    coeffs: &[Lanes; D],
    lo: Lanes,
    hi: Lanes,
    front: &Front<D>,
) -> [Option<f64>; LANES] {
    let fixed: [Fixed<D>; LANES] = std::array::from_fn(|l| Fixed::<D> {
        c: std::array::from_fn(|j| front.c[j][l]),
        scale: front.scale[l],
        lo: front.lo[l],
        hi: front.hi[l],
    });
    let mut answers = [None; LANES];
    let mut brackets = [None; LANES];
    for l in 0..LANES {
        let p = &fixed[l];
        answers[l] = match front.status[l] {
            Status::NoRoot => None,
            Status::Other => solver.first_root(&lane(coeffs, l), lo[l], hi[l]),
            Status::Undecided => settle(solver, Fast::Undecided, || p.to_prepared(), &mut ()),
            Status::Search(whole) => {
                let b: &[f64; D] = front.b[l][..D].try_into().expect("D ≤ PADDED");
                match bernstein::bracket_from(p, b, front.size[l], front.unit[l], whole, &mut ()) {
                    Ok(bracket) => {
                        brackets[l] = Some(bracket);
                        None
                    }
                    Err(fast) => settle(solver, fast, || p.to_prepared(), &mut ()),
                }
            }
        };
    }
    if brackets.iter().any(Option::is_some) {
        #[cfg(target_arch = "x86_64")]
        let roots = if AVX2 {
            // SAFETY: `AVX2` is set only by `rest_avx2`, which runs only where the
            // processor has AVX2. The lanes' prepared coefficients by power are `front.c`.
            unsafe { refine_simple_lanes_avx2(&front.c, brackets) }
        } else {
            refine_simple_lanes(std::array::from_fn(|l| &fixed[l].c), brackets)
        };
        #[cfg(not(target_arch = "x86_64"))]
        let roots = refine_simple_lanes(std::array::from_fn(|l| &fixed[l].c), brackets);
        for l in 0..LANES {
            if brackets[l].is_some() {
                // `settle` of the scalar query's `Fast::Root`.
                answers[l] = Some(roots[l] * fixed[l].scale);
            }
        }
    }
    answers
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::uniform_stream;

    /// One random query of `D` coefficients: from real roots (some clustered or double, some
    /// at the interval's ends), or random coefficients of mixed sizes with zeros, negligible
    /// leading terms and non-finite values; on intervals from zero, around zero, far out,
    /// reversed, empty or unbounded.
    fn query<const D: usize>(next: &mut impl FnMut() -> f64) -> ([f64; D], f64, f64) {
        let mut c = [0.0; D];
        if next() < 0.5 {
            c[0] = 1.0;
            let base = next() * 2.0 - 0.5;
            for k in 1..D {
                let r = match (next() * 6.0) as u32 {
                    0 => base,
                    1 => base + (next() - 0.5) * 1e-7,
                    2 => 0.0,
                    _ => next() * 3.0 - 1.0,
                };
                // c ← c·(t − r), lowest power first.
                for j in (0..k).rev() {
                    c[j + 1] += c[j];
                    c[j] *= -r;
                }
            }
            if next() < 0.3 {
                c[0] += (next() - 0.5) * 1e-3;
            }
        } else {
            for cj in c.iter_mut() {
                let size = 2f64.powi((next() * 60.0) as i32 - 30);
                *cj = match (next() * 30.0) as u32 {
                    0 => 0.0,
                    1 => size,
                    2 => f64::NAN,
                    3 => f64::INFINITY,
                    _ => (next() - 0.5) * size,
                };
            }
            if next() < 0.1 {
                c[D - 1] *= 1e-20;
            }
        }
        let (lo, hi) = match (next() * 8.0) as u32 {
            0 | 1 => (0.0, 1.0),
            2 => (next() * 0.9, 1.0),
            3 => (-1.0 - next(), next()),
            4 => (next(), next()),
            5 => (0.0, f64::INFINITY),
            6 => (-2.0 * next(), -next() * 0.1),
            _ => {
                let lo = (next() - 0.7) * 2f64.powi((next() * 40.0) as i32 - 20);
                (lo, lo + next() * 2f64.powi((next() * 40.0) as i32 - 20))
            }
        };
        (c, lo, hi)
    }

    /// Both copies of the lanes' code against the scalar query on `groups` groups of random
    /// queries of `D` coefficients; counts of (roots, no roots) found.
    fn check<const D: usize>(seed: u64, groups: usize) -> (usize, usize) {
        let mut next = uniform_stream(seed);
        let mut found = (0, 0);
        for g in 0..groups {
            let mut coeffs = [[0.0; D]; LANES];
            let (mut lo, mut hi) = ([0.0; LANES], [0.0; LANES]);
            for l in 0..LANES {
                (coeffs[l], lo[l], hi[l]) = query::<D>(&mut next);
            }
            let active: [bool; LANES] = std::array::from_fn(|l| g % 7 != 0 || l % 2 == 0);
            same_fronts(&by_power(&coeffs), lo, hi, active);
            for &(solver, _) in Solver::ALL {
                let detected = solver.first_root_lanes(&coeffs, lo, hi, active);
                let baseline = solver.first_root_lanes_baseline(&coeffs, lo, hi, active);
                let by_power = solver.first_root_lanes_by_power(&by_power(&coeffs), lo, hi, active);
                for l in 0..LANES {
                    let want = active[l]
                        .then(|| solver.first_root(&coeffs[l], lo[l], hi[l]))
                        .flatten();
                    let bits = |x: Option<f64>| x.map(f64::to_bits);
                    let what = (solver, coeffs[l], lo[l], hi[l]);
                    assert_eq!(bits(detected[l]), bits(want), "{what:?}");
                    assert_eq!(bits(baseline[l]), bits(want), "{what:?}");
                    assert_eq!(bits(by_power[l]), bits(want), "{what:?}");
                    if active[l] {
                        if want.is_some() {
                            found.0 += 1;
                        } else {
                            found.1 += 1;
                        }
                    }
                }
            }
        }
        found
    }

    /// The two fronts (intrinsics and `front_in`) agree on every status and, where the rest
    /// reads them (a lane that searches), on every value, bit for bit.
    fn same_fronts<const D: usize>(
        coeffs: &[Lanes; D],
        lo: Lanes,
        hi: Lanes,
        active: [bool; LANES],
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            let plain = front_in(coeffs, lo, hi, active);
            // SAFETY: the processor has AVX2, checked just above.
            let fast = unsafe { front_avx2(coeffs, lo, hi, active) };
            assert_eq!(plain.status, fast.status, "{coeffs:?} {lo:?} {hi:?}");
            let bits = |v: &Lanes, l: usize| v[l].to_bits();
            for l in 0..LANES {
                if matches!(plain.status[l], Status::Undecided | Status::Search(_)) {
                    let what = (coeffs, lo, hi, l);
                    for j in 0..D {
                        assert_eq!(bits(&plain.c[j], l), bits(&fast.c[j], l), "{what:?}");
                        let b = |f: &Front<D>| f.b[l][j].to_bits();
                        assert_eq!(b(&plain), b(&fast), "{what:?}");
                    }
                    for (a, b) in [
                        (&plain.scale, &fast.scale),
                        (&plain.lo, &fast.lo),
                        (&plain.hi, &fast.hi),
                        (&plain.size, &fast.size),
                        (&plain.unit, &fast.unit),
                    ] {
                        assert_eq!(bits(a, l), bits(b, l), "{what:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn every_lane_is_the_scalar_query_bit_for_bit() {
        macro_rules! lengths {
            ($($d:literal)*) => {
                $(
                    let (roots, none) = check::<$d>(0x9e37_79b9_7f4a_7c15 ^ $d, 1500);
                    // Both outcomes are well represented.
                    assert!(roots > 1500 && none > 1500, "{}: {roots} {none}", $d);
                )*
            };
        }
        lengths!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17);
    }

    #[test]
    fn the_baseline_copy_runs_every_status() {
        // The scalar copy by itself (what a processor without AVX2 runs), on queries that
        // end in each status of the lanes' part.
        let coeffs = [
            [2.0, -3.0, 1.0],      // (t − 1)(t − 2) on (0, 1.5]: one variation, the root 1
            [8.0, 1.0, 1.0],       // 8 + t + t²: no variation
            [1.0, -2.0, 1.0],      // a double root: the search goes on
            [2.0, -3.0, f64::NAN], // refused
        ];
        let (lo, hi) = ([0.0; LANES], [1.5, 3.0, 3.0, 3.0]);
        let front = front_in(&by_power(&coeffs), lo, hi, [true; LANES]);
        assert_eq!(front.status[0], Status::Search(Some(1)));
        assert_eq!(front.status[1], Status::NoRoot);
        assert!(matches!(
            front.status[2],
            Status::Search(_) | Status::Undecided
        ));
        assert_eq!(front.status[3], Status::NoRoot);
        let got = Solver::Sturm.first_root_lanes_baseline(&coeffs, lo, hi, [true; LANES]);
        assert!((got[0].unwrap() - 1.0).abs() <= 2.0 * f64::EPSILON);
        assert_eq!(got[1], None);
        assert!((got[2].unwrap() - 1.0).abs() <= 1e-6);
        assert_eq!(got[3], None);
        // The unusual case (a zero leading coefficient) and the end of an interval at a root.
        let coeffs = [[2.0, -3.0, 0.0], [2.0, -3.0, 1.0], [1.0; 3], [1.0; 3]];
        let (lo, hi) = ([0.0, 1.0, 0.0, 0.0], [3.0; LANES]);
        let front = front_in(&by_power(&coeffs), lo, hi, [true, true, false, false]);
        assert_eq!(front.status[0], Status::Other);
        assert_eq!(front.status[1], Status::Undecided);
        assert_eq!(front.status[2], Status::NoRoot);
        let active = [true, true, false, true];
        let got = Solver::Yuksel.first_root_lanes_baseline(&coeffs, lo, hi, active);
        assert_eq!(got[0], Some(2.0 / 3.0));
        assert!((got[1].unwrap() - 2.0).abs() <= 4.0 * f64::EPSILON);
        assert_eq!(got[2], None);
        assert_eq!(got[3], None);
    }
}
