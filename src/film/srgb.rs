//! 8-bit sRGB: linear channel values to codes by the sRGB transfer curve (exactly: by table,
//! the same answer as evaluating the curve for every input) and codes back to linear values.
//! A row of the film converts eight channels at a time where the processor has AVX2.

use super::Vec3;

/// Writes premultiplied `pixels` with coverage `alpha` (`None`: opaque) as straight-alpha
/// 8-bit sRGBA bytes (see [`Image::to_srgba8`](super::Image::to_srgba8)) into `out`, which
/// holds four bytes a pixel.
pub(crate) fn srgba8_into(pixels: &[Vec3], alpha: Option<&[f32]>, out: &mut [u8]) {
    let table = srgb8_table();
    for (i, (o, p)) in out.chunks_exact_mut(4).zip(pixels).enumerate() {
        let a = alpha.map_or(1.0, |a| a[i] as f64);
        let a8 = (a * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8;
        if a8 == 0 {
            o.copy_from_slice(&[0; 4]);
            continue;
        }
        let straight = |c: f32| if a >= 1.0 { c as f64 } else { c as f64 / a };
        o[0] = table.code(straight(p.x));
        o[1] = table.code(straight(p.y));
        o[2] = table.code(straight(p.z));
        o[3] = a8;
    }
}

/// Writes `pixels` as 8-bit sRGB bytes (`R, G, B` each, as [`linear_to_srgb8`] of each
/// channel) into `out`, which holds three bytes a pixel.
pub(crate) fn srgb8_into(pixels: &[Vec3], out: &mut [u8]) {
    let channels: &[f32] = bytemuck::cast_slice(pixels);
    let out = &mut out[..channels.len()];
    let table = srgb8_table();
    #[cfg(target_arch = "x86_64")]
    if crate::cpu::avx2() {
        // SAFETY: the processor has AVX2, checked just above.
        return unsafe { table.channels_avx2(channels, out) };
    }
    table.channels(channels, out);
}

/// One linear channel value as an 8-bit sRGB code: clamped to `[0, 1]` (NaN → 0), encoded
/// with the sRGB transfer curve, rounded to nearest.
pub fn linear_to_srgb8(v: f64) -> u8 {
    srgb8_table().code(v)
}

/// Buckets of equal width over `[0, 1]`; narrower than the closest pair of code
/// boundaries (1 / (12.92·255) near black), so no bucket holds two of them.
const SRGB_BUCKETS: usize = 4096;

/// Look-up tables for [`linear_to_srgb8`].
struct Srgb8Table {
    /// `first_linear[c]`: the smallest linear value whose code is `c` (index 0 unused).
    first_linear: [f64; 256],
    /// `first_f32[c]`: the smallest `f32` whose code is `c` (index 0 unused; index 256 is
    /// +∞, reached by nothing).
    first_f32: [f32; 257],
    /// The code of each bucket's lower edge, plus one entry for 1.0 itself (0–255, as `i32`:
    /// the width the AVX2 gathers read).
    bucket_code: [i32; SRGB_BUCKETS + 1],
}

impl Srgb8Table {
    /// [`linear_to_srgb8`]: the same answer as `srgb8_by_formula` for every input (tested),
    /// without a `powf`: the bucket of `v` gives the code at the bucket's lower edge, and one
    /// comparison with the next code's first value says whether `v` has reached it.
    #[inline]
    fn code(&self, v: f64) -> u8 {
        // Black (most of a typical background) and NaN need no look-up.
        if v.is_nan() || v <= 0.0 {
            return 0;
        }
        let v = v.min(1.0);
        let code = self.bucket_code[(v * SRGB_BUCKETS as f64) as usize] as u8;
        if code < 255 && v >= self.first_linear[code as usize + 1] {
            code + 1
        } else {
            code
        }
    }

    /// [`Srgb8Table::code`] of an `f32`, in `f32`: its bucket is the same (scaling by a power
    /// of two is exact in both), and an `f32` reaches a code's first linear value exactly
    /// when it reaches the smallest `f32` at or above it.
    #[inline(always)]
    fn code_f32(&self, v: f32) -> u8 {
        if v.is_nan() || v <= 0.0 {
            return 0;
        }
        let v = v.min(1.0);
        let code = self.bucket_code[(v * SRGB_BUCKETS as f32) as usize] as u8;
        code + u8::from(v >= self.first_f32[code as usize + 1])
    }

    /// `out[i]` = the code of `channels[i]`, one at a time (`out` as long as `channels`).
    fn channels(&self, channels: &[f32], out: &mut [u8]) {
        assert_eq!(channels.len(), out.len());
        for (o, &v) in out.iter_mut().zip(channels) {
            *o = self.code_f32(v);
        }
    }

    /// [`Srgb8Table::channels`] eight at a time: the same steps as [`Srgb8Table::code_f32`] on
    /// eight lanes (the bucket's code and the next code's first value gathered from the
    /// tables), eight zeros (a black stretch) in one test.
    ///
    /// # Safety
    /// The processor must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn channels_avx2(&self, channels: &[f32], out: &mut [u8]) {
        use std::arch::x86_64::*;
        assert_eq!(channels.len(), out.len());
        let whole = channels.len() / 8 * 8;
        let zero = _mm256_setzero_ps();
        let one = _mm256_set1_ps(1.0);
        let scale = _mm256_set1_ps(SRGB_BUCKETS as f32);
        let next = _mm256_set1_epi32(1);
        for (v, o) in channels[..whole]
            .chunks_exact(8)
            .zip(out[..whole].chunks_exact_mut(8))
        {
            let v = _mm256_loadu_ps(v.as_ptr());
            let bits = _mm256_castps_si256(v);
            if _mm256_testz_si256(bits, bits) == 1 {
                o.fill(0);
                continue;
            }
            // Zero, negative and NaN (max(NaN, 0) is the second operand) become 0, whose
            // code is 0; every index is within the table.
            let v = _mm256_min_ps(_mm256_max_ps(v, zero), one);
            let bucket = _mm256_cvttps_epi32(_mm256_mul_ps(v, scale));
            let code = _mm256_i32gather_epi32::<4>(self.bucket_code.as_ptr(), bucket);
            let first =
                _mm256_i32gather_ps::<4>(self.first_f32.as_ptr(), _mm256_add_epi32(code, next));
            // All ones (−1) where reached: subtracting it adds one.
            let reached = _mm256_castps_si256(_mm256_cmp_ps::<_CMP_GE_OQ>(v, first));
            let code = _mm256_sub_epi32(code, reached);
            let words = _mm_packus_epi32(
                _mm256_castsi256_si128(code),
                _mm256_extracti128_si256::<1>(code),
            );
            _mm_storel_epi64(o.as_mut_ptr().cast(), _mm_packus_epi16(words, words));
        }
        self.channels(&channels[whole..], &mut out[whole..]);
    }
}

fn srgb8_table() -> &'static Srgb8Table {
    static TABLE: std::sync::OnceLock<Srgb8Table> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let mut first_linear = [0.0; 256];
        for (code, first) in first_linear.iter_mut().enumerate().skip(1) {
            *first = first_with_code(code);
        }
        // The formula is monotone (the test sweeps it), so the code of a bucket's lower edge
        // is the number of codes whose first value it has reached.
        let mut bucket_code = [0; SRGB_BUCKETS + 1];
        let mut code = 0;
        for (i, out) in bucket_code.iter_mut().enumerate() {
            let edge = i as f64 / SRGB_BUCKETS as f64;
            while code < 255 && first_linear[code + 1] <= edge {
                code += 1;
            }
            *out = code as i32;
        }
        let mut first_f32 = [f32::INFINITY; 257];
        for (first, &linear) in first_f32.iter_mut().zip(&first_linear).skip(1) {
            let nearest = linear as f32;
            *first = if f64::from(nearest) < linear {
                nearest.next_up()
            } else {
                nearest
            };
        }
        Srgb8Table {
            first_linear,
            first_f32,
            bucket_code,
        }
    })
}

/// The smallest linear value in `[0, 1]` that the formula maps to `code` (1–255) or above.
/// Non-negative doubles order like their bit patterns: from the curve's inverse at the code's
/// lower rounding edge (a few ulps off), steps of doubling length find bit patterns on both
/// sides, and a bisection between them the first one.
fn first_with_code(code: usize) -> f64 {
    let reaches = |bits: u64| srgb8_by_formula(f64::from_bits(bits)) as usize >= code;
    let edge = (code as f64 - 0.5) / 255.0;
    let guess = if edge <= 0.040_45 {
        edge / 12.92
    } else {
        ((edge + 0.055) / 1.055).powf(2.4)
    };
    let top = 1f64.to_bits();
    let start = guess.clamp(0.0, 1.0).to_bits();
    // `lo` never reaches the code (0 does not: its code is 0), `hi` always does (1 does).
    let (mut lo, mut hi) = (start, start);
    let mut step = 1;
    if reaches(start) {
        while lo > 0 && reaches(lo) {
            hi = lo;
            lo = lo.saturating_sub(step);
            step *= 2;
        }
    } else {
        while hi < top && !reaches(hi) {
            lo = hi;
            hi = (hi + step).min(top);
            step *= 2;
        }
    }
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if reaches(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    f64::from_bits(hi)
}

/// The sRGB transfer curve evaluated directly; the definition [`linear_to_srgb8`] follows.
fn srgb8_by_formula(v: f64) -> u8 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// An 8-bit sRGB code back to a linear value in `[0, 1]` (the inverse of
/// [`linear_to_srgb8`] up to rounding).
pub fn srgb8_to_linear(c: u8) -> f64 {
    let s = c as f64 / 255.0;
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_every_code() {
        for c in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(c)), c);
        }
        assert_eq!(linear_to_srgb8(-1.0), 0);
        assert_eq!(linear_to_srgb8(f64::NAN), 0);
        assert_eq!(linear_to_srgb8(7.0), 255);
        assert_eq!(linear_to_srgb8(0.5), 188);
    }

    #[test]
    fn table_matches_the_formula() {
        let table = srgb8_table();
        for i in 0..SRGB_BUCKETS {
            let (lo, hi) = (table.bucket_code[i], table.bucket_code[i + 1]);
            assert!(
                (0..=1).contains(&(hi - lo)),
                "bucket {i} spans codes {lo}..={hi}"
            );
        }
        for (i, &code) in table.bucket_code.iter().enumerate() {
            let edge = i as f64 / SRGB_BUCKETS as f64;
            assert_eq!(code, i32::from(srgb8_by_formula(edge)), "bucket {i}");
        }
        for code in 1..=255usize {
            let first = table.first_linear[code];
            let before = f64::from_bits(first.to_bits() - 1);
            assert_eq!(linear_to_srgb8(first) as usize, code);
            assert_eq!(linear_to_srgb8(before) as usize, code - 1);
            assert_eq!(srgb8_by_formula(before) as usize, code - 1);
        }
        // A dense sweep plus pseudo-random values, including outside [0, 1].
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for i in 0..2_000_000u64 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = if i % 2 == 0 {
                i as f64 / 1_000_000.0 - 0.5
            } else {
                (x >> 11) as f64 / (1u64 << 53) as f64
            };
            assert_eq!(linear_to_srgb8(v), srgb8_by_formula(v), "at {v:e}");
        }
    }

    /// `f32` values where the `f32` path could part from the `f64` one: each side of every
    /// code's first value and of every bucket's edge, a stride through every `f32` from 0 to
    /// a little past 1, and the special values.
    fn awkward_f32s() -> Vec<f32> {
        let table = srgb8_table();
        let near = |v: f32, ulps: u32| {
            let bits = v.to_bits();
            (bits.saturating_sub(ulps)..=bits + ulps).map(f32::from_bits)
        };
        let mut values: Vec<f32> = Vec::new();
        for &first in &table.first_linear[1..] {
            values.extend(near(first as f32, 64));
        }
        for i in 0..=SRGB_BUCKETS {
            values.extend(near(i as f32 / SRGB_BUCKETS as f32, 4));
        }
        values.extend((0..=1.5f32.to_bits()).step_by(1013).map(f32::from_bits));
        values.extend([
            0.0,
            -0.0,
            -1e-30,
            -1.0,
            f32::NAN,
            -f32::NAN,
            f32::from_bits(0x7fc0_1234),
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            f32::MAX,
            1.0,
            1.0f32.next_up(),
            1.0f32.next_down(),
        ]);
        values
    }

    #[test]
    fn f32_channels_convert_as_their_f64_values() {
        let table = srgb8_table();
        let values = awkward_f32s();
        assert!(values.len() > 1_000_000, "{}", values.len());
        let mut one_at_a_time = vec![7u8; values.len()];
        table.channels(&values, &mut one_at_a_time);
        for (&v, &code) in values.iter().zip(&one_at_a_time) {
            assert_eq!(
                code,
                table.code(f64::from(v)),
                "at {v:e} ({:#x})",
                v.to_bits()
            );
        }
        // Every start and length, so that the eight-wide stretches and the tail both meet
        // every kind of value; black stretches among them.
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            let mut wide = vec![7u8; values.len()];
            // SAFETY: the processor has AVX2, checked just above.
            unsafe { table.channels_avx2(&values, &mut wide) };
            assert_eq!(wide, one_at_a_time);
            let mut mixed = values[..4000].to_vec();
            mixed[100..140].fill(0.0);
            mixed[203..211].fill(0.0);
            for start in 0..9 {
                for len in 0..40 {
                    let part = &mixed[start * 37..start * 37 + len * 11];
                    let (mut a, mut b) = (vec![9u8; part.len()], vec![9u8; part.len()]);
                    table.channels(part, &mut a);
                    // SAFETY: as above.
                    unsafe { table.channels_avx2(part, &mut b) };
                    assert_eq!(a, b, "start {start}, length {}", part.len());
                }
            }
        }
    }

    #[test]
    fn a_row_converts_as_each_channel_alone() {
        // The black pixel's shortcut against the per-channel conversion: zeros of both
        // signs, negatives, NaN and small positives in every channel and mixed.
        let values = [
            0.0,
            -0.0,
            -1.0,
            f32::NAN,
            f32::MIN_POSITIVE,
            1e-7,
            0.002,
            0.5,
            3.0,
        ];
        let mut pixels = Vec::new();
        for &x in &values {
            for &y in &values {
                for &z in &values {
                    pixels.push(Vec3::new(x, y, z));
                }
            }
        }
        let mut out = vec![7u8; pixels.len() * 3];
        srgb8_into(&pixels, &mut out);
        for (p, o) in pixels.iter().zip(out.chunks_exact(3)) {
            let each = [p.x, p.y, p.z].map(|v| linear_to_srgb8(f64::from(v)));
            assert_eq!(o, &each[..], "at {p:?}");
        }
        assert!(out.iter().any(|&c| c > 0) && out.contains(&0));
    }
}
