//! The heart's chords ([`HeartShape::chord`]) for [`LANES`] rays at once: the same
//! operations in the same order, lane by lane, without branches, so that the compiler keeps
//! the lanes in vector registers. The answer is the scalar one bit for bit (tested): every
//! step is an IEEE operation (no fused multiply-add is ever formed), and each `if` of the
//! scalar code becomes a choice between two already computed values.
//!
//! The code is compiled twice: for AVX2 (four `f64` lanes a register), chosen at run time
//! when the processor has it, and for the x86-64 baseline (SSE2, two lanes), which every
//! other processor runs and the tests also run.

use super::surface::{sextic_coefficients, BOUNDS, BOUNDS_MARGIN};
use super::{
    ellipsoid_span, upper_ellipsoid, Chord, HeartShape, LOWER_ELLIPSOID, POLISH_WINDOW,
    SELF_HIT_GUARD,
};
use crate::geometry::{DVec3, Ray};
use crate::shapes::placed::Placement;
use crate::shapes::LANES;
use std::mem::MaybeUninit;

/// One `f64` per lane.
type Lanes = [f64; LANES];

/// The lanes' sextics by power (`[j][i]` is lane `i`'s coefficient of `sʲ`, the chord's
/// [`Chord::coeffs`] laid out for [`Solver::first_root_lanes_by_power`](crate::roots::Solver)).
pub(super) type ByPower = [Lanes; 7];

/// [`HeartShape::chord`] of each lane's object-space ray `local[i]` with its range
/// `(t_min[i], t_max[i])`: lane `i` is `true` where `chord` gives `Some`, that chord written
/// to `out[i]` and its sextic to `by_power[·][i]`, and `false` where it gives `None` (`out[i]`
/// and `by_power[·][i]` are then meaningless). When some lane is `true`, every one of `out`'s
/// chords is written and the caller may take it as initialised; when none is, `out` and
/// `by_power` may be left as they were (a query whose rays all miss the heart's bounds skips
/// the sextics). (`out` starts uninitialised: an array of chords made only to be overwritten
/// cost a 544-byte `memset` a query, and chords returned by value a `memcpy`.)
#[inline]
pub(super) fn chords(
    at: &Placement,
    local: &[Ray; LANES],
    t_min: Lanes,
    t_max: Lanes,
    out: &mut MaybeUninit<[Chord; LANES]>,
    by_power: &mut ByPower,
) -> [bool; LANES] {
    #[cfg(target_arch = "x86_64")]
    if crate::cpu::avx2() {
        // SAFETY: the processor has AVX2, checked just above.
        return unsafe { chords_avx2(at, local, None, t_min, t_max, out, by_power) };
    }
    chords_baseline(at, local, t_min, t_max, out, by_power)
}

/// [`chords`] of the world rays `world`, mapped into object space by `at`'s frame
/// ([`Frame::ray_to_object`](crate::geometry::Frame::ray_to_object), the same bits; with AVX2 in vector registers, without the
/// object-space rays written out).
#[inline]
pub(super) fn chords_of_world(
    at: &Placement,
    world: &[Ray; LANES],
    t_min: Lanes,
    t_max: Lanes,
    out: &mut MaybeUninit<[Chord; LANES]>,
    by_power: &mut ByPower,
) -> [bool; LANES] {
    #[cfg(target_arch = "x86_64")]
    if crate::cpu::avx2() {
        // SAFETY: the processor has AVX2, checked just above.
        return unsafe { chords_avx2(at, world, Some(at.frame()), t_min, t_max, out, by_power) };
    }
    let frame = at.frame();
    let local = std::array::from_fn(|i| frame.ray_to_object(&world[i]));
    chords_baseline(at, &local, t_min, t_max, out, by_power)
}

/// [`chords`] by [`chords_in`], the sextics then laid out by power.
#[inline(always)]
fn chords_baseline(
    at: &Placement,
    local: &[Ray; LANES],
    t_min: Lanes,
    t_max: Lanes,
    out: &mut MaybeUninit<[Chord; LANES]>,
    by_power: &mut ByPower,
) -> [bool; LANES] {
    let alive = chords_in(at, local, t_min, t_max, out);
    // SAFETY: `chords_in` writes every chord.
    let written = unsafe { out.assume_init_ref() };
    for (j, row) in by_power.iter_mut().enumerate() {
        for (i, c) in row.iter_mut().enumerate() {
            *c = written[i].coeffs[j];
        }
    }
    alive
}

/// [`chords`] in AVX2 intrinsics, four lanes a register: each operation the one
/// [`chords_in`] takes for each lane (the scalar chord's), in the same order, so that every
/// live lane's chord is the same bits (tested); each `if` is a blend on the comparison's
/// mask, and each `f64::max`/`f64::min` keeps its rule for a NaN operand. A lane's zero
/// may differ in sign from the scalar code's only where it is added to the box entry
/// `t0 > 0`, which makes it the same `t0`. With `to_object`, `rays` are world rays, mapped
/// into object space as [`Frame::ray_to_object`](crate::geometry::Frame::ray_to_object) maps them (the same operations); without
/// it, they are the object-space rays.
///
/// # Safety
/// The processor must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn chords_avx2(
    at: &Placement,
    rays: &[Ray; LANES],
    to_object: Option<&crate::geometry::Frame>,
    t_min: Lanes,
    t_max: Lanes,
    out: &mut MaybeUninit<[Chord; LANES]>,
    by_power: &mut ByPower,
) -> [bool; LANES] {
    use std::arch::x86_64::*;
    const _: () = assert!(LANES == 4, "four f64 lanes a 256-bit register");
    let set = _mm256_set1_pd;
    let zero = _mm256_setzero_pd();
    let sign = set(-0.0);
    let infinity = set(f64::INFINITY);
    let (add, sub, mul, div) = (_mm256_add_pd, _mm256_sub_pd, _mm256_mul_pd, _mm256_div_pd);
    // `if c {a} else {b}`.
    let pick = |c: __m256d, a: __m256d, b: __m256d| _mm256_blendv_pd(b, a, c);
    let is_nan = |x: __m256d| _mm256_cmp_pd::<_CMP_UNORD_Q>(x, x);
    let abs = |x: __m256d| _mm256_andnot_pd(sign, x);
    let finite = |x: __m256d| _mm256_cmp_pd::<_CMP_LT_OQ>(abs(x), infinity);
    // `a > b ? a : b` (glam's `max_element` rule: `larger`) and `a < b ? a : b`.
    let larger = |a: __m256d, b: __m256d| _mm256_max_pd(a, b);
    // `f64::max` and `f64::min`: a NaN operand gives the other one.
    let fmax = |a: __m256d, b: __m256d| pick(is_nan(b), a, _mm256_max_pd(a, b));
    let fmin = |a: __m256d, b: __m256d| pick(is_nan(b), a, _mm256_min_pd(a, b));
    let gt = |a: __m256d, b: __m256d| _mm256_cmp_pd::<_CMP_GT_OQ>(a, b);
    let lt = |a: __m256d, b: __m256d| _mm256_cmp_pd::<_CMP_LT_OQ>(a, b);
    let ge = |a: __m256d, b: __m256d| _mm256_cmp_pd::<_CMP_GE_OQ>(a, b);
    let le = |a: __m256d, b: __m256d| _mm256_cmp_pd::<_CMP_LE_OQ>(a, b);
    let and = _mm256_and_pd;
    let origin = |axis: usize| {
        let [a, b, c, d] = rays.each_ref().map(|r| r.origin[axis]);
        _mm256_set_pd(d, c, b, a)
    };
    let direction = |axis: usize| {
        let [a, b, c, d] = rays.each_ref().map(|r| r.dir[axis]);
        _mm256_set_pd(d, c, b, a)
    };
    let (mut ox, mut oy, mut oz) = (origin(0), origin(1), origin(2));
    let (mut dx, mut dy, mut dz) = (direction(0), direction(1), direction(2));
    if let Some(frame) = to_object {
        // `m_inv * (origin − position)` and `m_inv * dir`, as glam's `DMat3 * DVec3`
        // computes each component: `(x_axis·v.x + y_axis·v.y) + z_axis·v.z`.
        let m = frame.m_inv;
        let times = |[vx, vy, vz]: [__m256d; 3]| {
            let row = |r: usize| {
                add(
                    add(mul(set(m.x_axis[r]), vx), mul(set(m.y_axis[r]), vy)),
                    mul(set(m.z_axis[r]), vz),
                )
            };
            (row(0), row(1), row(2))
        };
        let p = frame.position;
        (ox, oy, oz) = times([sub(ox, set(p.x)), sub(oy, set(p.y)), sub(oz, set(p.z))]);
        (dx, dy, dz) = times([dx, dy, dz]);
    }
    let load = |x: &Lanes| _mm256_loadu_pd(x.as_ptr());

    // |d| and the self-hit guard.
    let scale = larger(abs(dx), larger(abs(dy), abs(dz)));
    let (sx, sy, sz) = (div(dx, scale), div(dy, scale), div(dz, scale));
    let dir_len = mul(
        scale,
        _mm256_sqrt_pd(add(add(mul(sx, sx), mul(sy, sy)), mul(sz, sz))),
    );
    let mut alive = and(
        and(gt(dir_len, zero), finite(dir_len)),
        and(finite(ox), and(finite(oy), finite(oz))),
    );
    let reach = add(
        larger(abs(ox), larger(abs(oy), abs(oz))),
        set(at.position_reach()),
    );
    let guard = fmax(set(SELF_HIT_GUARD), mul(set(1024.0 * f64::EPSILON), reach));
    let t_lo = fmax(load(&t_min), div(guard, dir_len));
    let (mut t0, mut t1) = (t_lo, load(&t_max));
    BOUNDS.clip_avx2(&[ox, oy, oz], &[dx, dy, dz], &mut t0, &mut t1, &mut alive);

    // The lower half's ellipsoid and the half-space above it, from the box entry.
    let z_floor = set(-BOUNDS_MARGIN);
    let (px, py, pz) = (
        add(ox, mul(t0, dx)),
        add(oy, mul(t0, dy)),
        add(oz, mul(t0, dz)),
    );
    let len = sub(t1, t0);
    // Above Z = −margin.
    let q = div(sub(z_floor, pz), dz);
    let rising = fmax(q, zero);
    let (up, down) = (gt(dz, zero), lt(dz, zero));
    let above_ok = pick(
        up,
        le(rising, len),
        pick(down, ge(q, zero), ge(pz, z_floor)),
    );
    let above0 = pick(up, rising, zero);
    let above1 = pick(up, len, pick(down, fmin(q, len), len));
    // `ellipsoid_span` and `quadratic_span`, operation for operation.
    let one = set(1.0);
    let two = set(2.0);
    let span = |(centre_z, r2): (f64, f64), lo: __m256d, hi: __m256d| {
        let pz = sub(pz, set(centre_z));
        let a = add(add(mul(mul(two, dx), dx), mul(dy, dy)), mul(dz, dz));
        let hb = add(add(mul(mul(two, px), dx), mul(py, dy)), mul(pz, dz));
        let k = sub(
            add(add(mul(mul(two, px), px), mul(py, py)), mul(pz, pz)),
            set(r2),
        );
        let disc = sub(mul(hb, hb), mul(a, k));
        let signum = pick(is_nan(hb), hb, _mm256_or_pd(and(hb, sign), one));
        let q = _mm256_xor_pd(add(hb, mul(signum, _mm256_sqrt_pd(disc))), sign);
        let (u0, u1) = (div(q, a), div(k, q));
        let swap = gt(u0, u1);
        let (u0, u1) = (pick(swap, u1, u0), pick(swap, u0, u1));
        let both_finite = and(finite(u0), finite(u1));
        let (u0, u1) = (pick(both_finite, u0, zero), pick(both_finite, u1, len));
        let (u0, u1) = (fmax(u0, lo), fmin(u1, hi));
        (and(ge(disc, zero), le(u0, u1)), u0, u1)
    };
    // Inside the lower half's ellipsoid; inside the upper half's above the floor.
    let (inside_ok, u0, u1) = span(LOWER_ELLIPSOID, zero, len);
    let (upper_ok, above0, above1) = span(upper_ellipsoid(), above0, above1);
    let above_ok = and(above_ok, upper_ok);
    let both = and(above_ok, inside_ok);
    let v0 = pick(both, fmin(above0, u0), pick(above_ok, above0, u0));
    let v1 = pick(both, fmax(above1, u1), pick(above_ok, above1, u1));
    alive = and(alive, _mm256_or_pd(inside_ok, above_ok));
    let (t0, t1) = (add(t0, v0), add(t0, v1));
    let len = sub(t1, t0);
    alive = and(alive, and(gt(len, zero), finite(len)));
    let mask = _mm256_movemask_pd(alive);
    let alive_lanes = std::array::from_fn(|i| mask & (1 << i) != 0);
    if mask == 0 {
        return alive_lanes;
    }

    // The chord and its sextic, every lane (a dead lane's values are never read).
    let (x0, y0, z0) = (
        add(ox, mul(t0, dx)),
        add(oy, mul(t0, dy)),
        add(oz, mul(t0, dz)),
    );
    let (x1, y1, z1) = (mul(dx, len), mul(dy, len), mul(dz, len));
    let window = div(set(POLISH_WINDOW), mul(dir_len, len));
    // `sextic_coefficients`, operation for operation.
    let (three, four, six) = (set(3.0), set(4.0), set(6.0));
    let (tenth, fifth) = (set(0.1), set(0.2));
    let a = sub(
        add(add(mul(mul(two, x0), x0), mul(y0, y0)), mul(z0, z0)),
        one,
    );
    let b = add(
        add(mul(mul(four, x0), x1), mul(mul(two, y0), y1)),
        mul(mul(two, z0), z1),
    );
    let c = add(add(mul(mul(two, x1), x1), mul(y1, y1)), mul(z1, z1));
    let d_ = add(mul(mul(tenth, x0), x0), mul(y0, y0));
    let e = add(mul(mul(fifth, x0), x1), mul(mul(two, y0), y1));
    let f = add(mul(mul(tenth, x1), x1), mul(y1, y1));
    let g = mul(mul(z0, z0), z0);
    let h = mul(mul(mul(three, z0), z0), z1);
    let i = mul(mul(mul(three, z0), z1), z1);
    let k = mul(mul(z1, z1), z1);
    let coeffs = [
        sub(mul(mul(a, a), a), mul(d_, g)),
        sub(sub(mul(mul(mul(three, a), a), b), mul(d_, h)), mul(e, g)),
        sub(
            sub(
                sub(
                    add(mul(mul(mul(three, a), a), c), mul(mul(mul(three, a), b), b)),
                    mul(d_, i),
                ),
                mul(e, h),
            ),
            mul(f, g),
        ),
        sub(
            sub(
                sub(
                    add(mul(mul(mul(six, a), b), c), mul(mul(b, b), b)),
                    mul(d_, k),
                ),
                mul(e, i),
            ),
            mul(f, h),
        ),
        sub(
            sub(
                add(mul(mul(mul(three, b), b), c), mul(mul(mul(three, a), c), c)),
                mul(e, k),
            ),
            mul(f, i),
        ),
        sub(mul(mul(mul(three, b), c), c), mul(f, k)),
        mul(mul(c, c), c),
    ];
    for (row, c) in by_power.iter_mut().zip(coeffs) {
        _mm256_storeu_pd(row.as_mut_ptr(), c);
    }
    let store = |v: __m256d| {
        let mut a = [0.0; LANES];
        _mm256_storeu_pd(a.as_mut_ptr(), v);
        a
    };
    let (t_lo, t0, len, window) = (store(t_lo), store(t0), store(len), store(window));
    let (x0, y0, z0) = (store(x0), store(y0), store(z0));
    let (x1, y1, z1) = (store(x1), store(y1), store(z1));
    // Each chord written once, straight into `out`.
    let first = out.as_mut_ptr().cast::<Chord>();
    for i in 0..LANES {
        let chord = Chord {
            t_lo: t_lo[i],
            t0: t0[i],
            len: len[i],
            o: DVec3::new(x0[i], y0[i], z0[i]),
            d: DVec3::new(x1[i], y1[i], z1[i]),
            coeffs: std::array::from_fn(|j| by_power[j][i]),
            window: window[i],
        };
        // SAFETY: `i < LANES`: inside the array `out` points to.
        unsafe { first.add(i).write(chord) };
    }
    alive_lanes
}

/// `a` if `a > b`, else `b`: glam's `max_element` rule, which the scalar code uses.
#[inline(always)]
fn larger(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// The body of [`chords`] (and, called directly, its baseline copy), in the scalar code's order (see [`HeartShape::chord`],
/// [`Aabb::clip`](crate::geometry::Aabb::clip) and `clip_lower_half`).
#[inline(always)]
fn chords_in(
    at: &Placement,
    local: &[Ray; LANES],
    t_min: Lanes,
    t_max: Lanes,
    out: &mut MaybeUninit<[Chord; LANES]>,
) -> [bool; LANES] {
    let (mut ox, mut oy, mut oz) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
    let (mut dx, mut dy, mut dz) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
    for (i, r) in local.iter().enumerate() {
        (ox[i], oy[i], oz[i]) = (r.origin.x, r.origin.y, r.origin.z);
        (dx[i], dy[i], dz[i]) = (r.dir.x, r.dir.y, r.dir.z);
    }
    let reach_of_position = at.position_reach();
    let mut alive = [true; LANES];
    let mut dir_len = [0.0; LANES];
    let mut t0 = [0.0; LANES];
    let mut t1 = [0.0; LANES];
    let mut t_lo = [0.0; LANES];
    for i in 0..LANES {
        // |d| and the self-hit guard.
        let scale = larger(dx[i].abs(), larger(dy[i].abs(), dz[i].abs()));
        let (sx, sy, sz) = (dx[i] / scale, dy[i] / scale, dz[i] / scale);
        let len = scale * (sx * sx + sy * sy + sz * sz).sqrt();
        dir_len[i] = len;
        alive[i] = (len > 0.0)
            & len.is_finite()
            & ox[i].is_finite()
            & oy[i].is_finite()
            & oz[i].is_finite();
        let reach = larger(ox[i].abs(), larger(oy[i].abs(), oz[i].abs())) + reach_of_position;
        let guard = SELF_HIT_GUARD.max(1024.0 * f64::EPSILON * reach);
        t_lo[i] = t_min[i].max(guard / len);
        t0[i] = t_lo[i];
        t1[i] = t_max[i];
    }
    BOUNDS.clip_lanes(&[ox, oy, oz], &[dx, dy, dz], &mut t0, &mut t1, &mut alive);
    // The lower half's ellipsoid and the half-space above it, from the box entry.
    let z_floor = -BOUNDS_MARGIN;
    let upper = upper_ellipsoid();
    for i in 0..LANES {
        let (px, py, pz) = (
            ox[i] + t0[i] * dx[i],
            oy[i] + t0[i] * dy[i],
            oz[i] + t0[i] * dz[i],
        );
        let (ex, ey, ez) = (dx[i], dy[i], dz[i]);
        let len = t1[i] - t0[i];
        // Above Z = −margin.
        let q = (z_floor - pz) / ez;
        let rising = q.max(0.0);
        let (above_ok, above0, above1) = if ez > 0.0 {
            (rising <= len, rising, len)
        } else if ez < 0.0 {
            (q >= 0.0, 0.0, q.min(len))
        } else {
            (pz >= z_floor, 0.0, len)
        };
        // Inside the lower half's ellipsoid; inside the upper half's above the floor.
        let (p, e) = ([px, py, pz], [ex, ey, ez]);
        let (inside_ok, u0, u1) = ellipsoid_span(p, e, LOWER_ELLIPSOID, len, (0.0, len));
        let (upper_ok, w0, w1) = ellipsoid_span(p, e, upper, len, (above0, above1));
        let above_ok = above_ok & upper_ok;
        let (above0, above1) = (w0, w1);
        let both = above_ok & inside_ok;
        let v0 = if both {
            above0.min(u0)
        } else if above_ok {
            above0
        } else {
            u0
        };
        let v1 = if both {
            above1.max(u1)
        } else if above_ok {
            above1
        } else {
            u1
        };
        alive[i] &= inside_ok | above_ok;
        let (c0, c1) = (t0[i] + v0, t0[i] + v1);
        t0[i] = c0;
        t1[i] = c1;
    }
    // The chord and its sextic, every lane (a dead lane's values are never read).
    // Each chord written once, straight into `out`.
    let first = out.as_mut_ptr().cast::<Chord>();
    for i in 0..LANES {
        let len = t1[i] - t0[i];
        alive[i] &= (len > 0.0) & len.is_finite();
        let o = DVec3::new(ox[i], oy[i], oz[i]) + t0[i] * DVec3::new(dx[i], dy[i], dz[i]);
        let d = DVec3::new(dx[i], dy[i], dz[i]) * len;
        let chord = Chord {
            t_lo: t_lo[i],
            t0: t0[i],
            len,
            o,
            d,
            coeffs: sextic_coefficients(o, d),
            window: POLISH_WINDOW / (dir_len[i] * len),
        };
        // SAFETY: `i < LANES`: inside the array `out` points to.
        unsafe { first.add(i).write(chord) };
    }
    alive
}

impl HeartShape {
    /// [`HeartShape::chord`] of each lane, one at a time (the reference the lanes must match).
    #[cfg(test)]
    fn chords_one_by_one(
        at: &Placement,
        local: &[Ray; LANES],
        t_min: Lanes,
        t_max: Lanes,
    ) -> [Option<Chord>; LANES] {
        std::array::from_fn(|i| Self::chord(at, &local[i], t_min[i], t_max[i]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Frame;

    /// Rays of every kind the heart meets: from afar at the box, grazing, from inside the box
    /// and on the surface, along the axes (zero components), degenerate (zero, NaN,
    /// infinite), each with a random `t_max`, some of them idle (`t_max = −∞`).
    fn rays(seed: u64, count: usize) -> Vec<(Ray, f64)> {
        let mut uniform = crate::testing::uniform_stream(seed);
        let mut out = Vec::new();
        for k in 0..count {
            let mut v = || DVec3::new(uniform(), uniform(), uniform()) * 2.0 - DVec3::ONE;
            let target = v() * 1.3;
            let origin = match k % 4 {
                0 => v() * 8.0,
                1 => v() * 1.2,
                2 => target + v() * 1e-3,
                _ => DVec3::new(0.0, 0.0, 5.0 * v().x),
            };
            let mut dir = target - origin;
            match k % 13 {
                3 => dir.x = 0.0,
                5 => dir.z = 0.0,
                7 => (dir.x, dir.y) = (0.0, 0.0),
                11 => dir *= 1e-200,
                _ => {}
            }
            let t_max = match k % 9 {
                0 => f64::INFINITY,
                4 => f64::NEG_INFINITY,
                _ => 4.0 * uniform(),
            };
            out.push((Ray::new(origin, dir), t_max));
        }
        out.push((Ray::new(DVec3::ZERO, DVec3::ZERO), 1.0));
        out.push((Ray::new(DVec3::splat(f64::NAN), DVec3::X), 1.0));
        out.push((Ray::new(DVec3::ZERO, DVec3::splat(f64::INFINITY)), 1.0));
        out.push((Ray::new(DVec3::new(f64::INFINITY, 0.0, 0.0), DVec3::X), 1.0));
        out
    }

    fn same(a: &Option<Chord>, b: &Option<Chord>) -> bool {
        let bits = |c: &Chord| {
            let mut v = vec![c.t_lo, c.t0, c.len, c.window, c.o.x, c.o.y, c.o.z];
            v.extend([c.d.x, c.d.y, c.d.z]);
            v.extend(c.coeffs);
            v.into_iter().map(f64::to_bits).collect::<Vec<_>>()
        };
        match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => bits(a) == bits(b),
            _ => false,
        }
    }

    #[test]
    fn every_code_path_gives_the_scalar_chords_bit_for_bit() {
        let frames = [
            Frame::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z).unwrap(),
            Frame::new(
                DVec3::new(3.0, -1.0, 2.0),
                DVec3::new(0.7, 0.2, 0.0),
                DVec3::new(-0.1, 1.3, 0.4),
                DVec3::new(0.0, -0.3, 0.9),
            )
            .unwrap(),
        ];
        let mut checked = (0, 0);
        for frame in frames {
            let at = Placement::new(frame);
            for t_min in [0.0f64, 1e-9, 0.5] {
                let all = rays(0x9e37_79b9 ^ t_min.to_bits(), 4000);
                for group in all.chunks_exact(LANES) {
                    let local: [Ray; LANES] =
                        std::array::from_fn(|i| at.ray_to_object(&group[i].0));
                    let t_max: Lanes = std::array::from_fn(|i| group[i].1);
                    let t_min = [t_min; LANES];
                    let want = HeartShape::chords_one_by_one(&at, &local, t_min, t_max);
                    let lanes_of =
                        |alive: [bool; LANES], out: [Chord; LANES]| -> [Option<Chord>; LANES] {
                            std::array::from_fn(|i| alive[i].then_some(out[i]))
                        };
                    let mut out = MaybeUninit::uninit();
                    let alive = chords_in(&at, &local, t_min, t_max, &mut out);
                    // SAFETY: `chords_in` writes every chord.
                    let baseline = lanes_of(alive, unsafe { out.assume_init() });
                    let mut out = MaybeUninit::uninit();
                    let mut by_power = [[f64::NAN; LANES]; 7];
                    let alive = chords(&at, &local, t_min, t_max, &mut out, &mut by_power);
                    let chosen = if alive == [false; LANES] {
                        [None; LANES]
                    } else {
                        // SAFETY: `chords` writes every chord when a lane is alive.
                        lanes_of(alive, unsafe { out.assume_init() })
                    };
                    // Each lane's chord as wanted, and its sextic laid out by power as the
                    // chord's own coefficients.
                    let agree = |want: &[Option<Chord>; LANES],
                                 chosen: &[Option<Chord>; LANES],
                                 by_power: &[[f64; LANES]; 7],
                                 from: &str| {
                        for i in 0..LANES {
                            assert!(same(&want[i], &chosen[i]), "{from} {:?}", group[i]);
                            if let Some(chord) = &chosen[i] {
                                let column = by_power.map(|row| row[i].to_bits());
                                assert_eq!(column, chord.coeffs.map(f64::to_bits));
                            }
                        }
                    };
                    for i in 0..LANES {
                        assert!(same(&want[i], &baseline[i]), "{:?}", group[i]);
                    }
                    agree(&want, &chosen, &by_power, "object");
                    // From the world rays, mapped by the frame (as a placement that is not
                    // the identity maps them).
                    let world: [Ray; LANES] = std::array::from_fn(|i| group[i].0);
                    let mapped: [Ray; LANES] =
                        std::array::from_fn(|i| at.frame().ray_to_object(&world[i]));
                    let want = HeartShape::chords_one_by_one(&at, &mapped, t_min, t_max);
                    let mut out = MaybeUninit::uninit();
                    let mut by_power = [[f64::NAN; LANES]; 7];
                    let alive = chords_of_world(&at, &world, t_min, t_max, &mut out, &mut by_power);
                    let chosen = if alive == [false; LANES] {
                        [None; LANES]
                    } else {
                        // SAFETY: `chords_of_world` writes every chord when a lane is alive.
                        lanes_of(alive, unsafe { out.assume_init() })
                    };
                    agree(&want, &chosen, &by_power, "world");
                    let hits = want.iter().filter(|w| w.is_some()).count();
                    checked.0 += hits;
                    checked.1 += LANES - hits;
                }
            }
        }
        // Both outcomes are well represented.
        assert!(checked.0 > 4000 && checked.1 > 4000, "{checked:?}");
    }
}
