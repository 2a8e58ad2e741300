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

/// [`HeartShape::chord`] of each lane's object-space ray `local[i]` with its range
/// `(t_min[i], t_max[i])`: lane `i` is `true` where `chord` gives `Some`, that chord written
/// to `out[i]`, and `false` where it gives `None` (`out[i]` is then meaningless). Every one of
/// `out`'s chords is written: the caller may take it as initialised. (`out` starts
/// uninitialised: an array of chords made only to be overwritten cost a 544-byte `memset` a
/// query, and chords returned by value a `memcpy`.)
#[inline]
pub(super) fn chords(
    at: &Placement,
    local: &[Ray; LANES],
    t_min: Lanes,
    t_max: Lanes,
    out: &mut MaybeUninit<[Chord; LANES]>,
) -> [bool; LANES] {
    #[cfg(target_arch = "x86_64")]
    if crate::cpu::avx2() {
        // SAFETY: the processor has AVX2, checked just above.
        return unsafe { chords_avx2(at, local, t_min, t_max, out) };
    }
    chords_in(at, local, t_min, t_max, out)
}

/// [`chords`] compiled for AVX2.
///
/// # Safety
/// The processor must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn chords_avx2(
    at: &Placement,
    local: &[Ray; LANES],
    t_min: Lanes,
    t_max: Lanes,
    out: &mut MaybeUninit<[Chord; LANES]>,
) -> [bool; LANES] {
    chords_in(at, local, t_min, t_max, out)
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
                    let alive = chords(&at, &local, t_min, t_max, &mut out);
                    // SAFETY: `chords` writes every chord.
                    let chosen = lanes_of(alive, unsafe { out.assume_init() });
                    for i in 0..LANES {
                        assert!(same(&want[i], &baseline[i]), "{:?}", group[i]);
                        assert!(same(&want[i], &chosen[i]), "{:?}", group[i]);
                        if want[i].is_some() {
                            checked.0 += 1;
                        } else {
                            checked.1 += 1;
                        }
                    }
                }
            }
        }
        // Both outcomes are well represented.
        assert!(checked.0 > 4000 && checked.1 > 4000, "{checked:?}");
    }
}
