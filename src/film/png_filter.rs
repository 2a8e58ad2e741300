//! PNG scanline filtering with the png crate's adaptive choice, four filters in one pass.
//!
//! Each row of an 8-bit PNG is stored as a filter type byte and the row's bytes minus a
//! prediction from its neighbours (the byte one pixel to the left `a`, the byte above `b`, the
//! byte above-left `c`; zero outside the image): Sub predicts `a`, Up `b`, Average
//! `⌊(a + b) / 2⌋`, Paeth whichever of `a`, `b`, `c` is nearest to `a + b − c`. The png crate's
//! `Filter::Adaptive` (0.18) tries Up, Sub, Average and Paeth in that order, costs each
//! filtered row as the sum of its bytes read as signed (`|b as i8|`), stops at the first of
//! cost zero, and otherwise keeps the last of the cheapest (a later filter wins a tie).
//! [`AdaptiveRowFilter`] makes the same choice, so the filtered rows, and the file compressed
//! from them, are the same bytes; it computes the four candidates in one pass over the row,
//! 32 bytes at a time where the processor has AVX2 ([`crate::cpu::avx2`]), otherwise in loops
//! that the compiler vectorises with the baseline instructions (the same bytes either way:
//! tested).

/// The PNG filter type bytes, in the order the adaptive choice tries them.
const TRIED: [u8; 4] = [UP, SUB, AVERAGE, PAETH];
const SUB: u8 = 1;
const UP: u8 = 2;
const AVERAGE: u8 = 3;
const PAETH: u8 = 4;

/// Which copy of the four-filter pass runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kernel {
    /// Plain Rust, each filter in a loop of its own (vectorised by the compiler for the
    /// baseline processor), on any processor.
    Scalar,
    /// 32 bytes at a time; only where the processor has AVX2.
    #[cfg(target_arch = "x86_64")]
    Avx2,
}

/// Filters the rows of one PNG image, one after another, as the png crate's adaptive filter
/// does. Holds the four candidate rows, so filtering allocates nothing.
pub(crate) struct AdaptiveRowFilter {
    bytes_per_pixel: usize,
    /// The row filtered by Up, Sub, Average and Paeth (the order of [`TRIED`]).
    candidates: [Vec<u8>; 4],
    kernel: Kernel,
}

impl AdaptiveRowFilter {
    /// A filter for rows of `row_len` bytes with `bytes_per_pixel` bytes a pixel (1–8: 3 for
    /// 8-bit RGB, 4 for RGBA), using AVX2 where [`crate::cpu::avx2`] allows it.
    pub(crate) fn new(bytes_per_pixel: usize, row_len: usize) -> Self {
        #[cfg(target_arch = "x86_64")]
        if crate::cpu::avx2() {
            return Self::with_kernel(bytes_per_pixel, row_len, Kernel::Avx2);
        }
        Self::with_kernel(bytes_per_pixel, row_len, Kernel::Scalar)
    }

    /// A filter that takes the baseline copy on any processor (for tests of it).
    #[cfg(test)]
    pub(crate) fn scalar(bytes_per_pixel: usize, row_len: usize) -> Self {
        Self::with_kernel(bytes_per_pixel, row_len, Kernel::Scalar)
    }

    fn with_kernel(bytes_per_pixel: usize, row_len: usize, kernel: Kernel) -> Self {
        assert!((1..=8).contains(&bytes_per_pixel));
        AdaptiveRowFilter {
            bytes_per_pixel,
            candidates: std::array::from_fn(|_| vec![0; row_len]),
            kernel,
        }
    }

    /// The filter type byte (1–4) the png crate's adaptive filter picks for `current` under
    /// `previous` (the row above; all zeros for the first row), and the filtered row. Both
    /// rows are `row_len` bytes.
    pub(crate) fn filter(&mut self, previous: &[u8], current: &[u8]) -> (u8, &[u8]) {
        let len = self.candidates[0].len();
        assert!(previous.len() == len && current.len() == len);
        let [up, sub, average, paeth] = &mut self.candidates;
        let costs = match self.kernel {
            Kernel::Scalar => all_filters_scalar(
                self.bytes_per_pixel,
                previous,
                current,
                [up, sub, average, paeth],
            ),
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `Kernel::Avx2` is chosen only when the processor has AVX2.
            Kernel::Avx2 => unsafe {
                all_filters_avx2(
                    self.bytes_per_pixel,
                    previous,
                    current,
                    [up, sub, average, paeth],
                )
            },
        };
        let chosen = adaptive_choice(costs);
        (TRIED[chosen], &self.candidates[chosen])
    }
}

/// The index (into [`TRIED`]) of the filter the png crate's adaptive loop keeps for these
/// costs: the first of cost zero, if any (it stops there), else the last of the cheapest
/// (it keeps a filter whose cost is `<=` the best so far).
fn adaptive_choice(costs: [u64; 4]) -> usize {
    if let Some(free) = costs.iter().position(|&cost| cost == 0) {
        return free;
    }
    let mut best = 0;
    for (i, &cost) in costs.iter().enumerate().skip(1) {
        if cost <= costs[best] {
            best = i;
        }
    }
    best
}

/// The Paeth predictor as the PNG specification states it: of `a`, `b`, `c` the one nearest
/// to `a + b − c`, ties going to `a`, then `b`.
#[inline(always)]
fn paeth_predictor(a: u8, b: u8, c: u8) -> u8 {
    let p = i16::from(a) + i16::from(b) - i16::from(c);
    let pa = (p - i16::from(a)).abs();
    let pb = (p - i16::from(b)).abs();
    let pc = (p - i16::from(c)).abs();
    if pa <= pb && pa <= pc {
        a
    } else if pb <= pc {
        b
    } else {
        c
    }
}

/// [`paeth_predictor`] in unsigned bytes, as [`all_filters_avx2`] computes it, for the
/// baseline copy's loops: `|b − c|` and `|a − c|` as the larger less the smaller (the
/// compiler vectorises that form for the baseline processor; `u8::abs_diff` ran the filter
/// 2.1× slower), `|a + b − 2c|` their sum where `b − c` and `a − c` share a sign (saturated:
/// it is then at least both, and 255 compares with them the same) and their difference
/// otherwise. The same answer for every `a`, `b`, `c` (tested).
#[inline(always)]
fn paeth_predictor_in_bytes(a: u8, b: u8, c: u8) -> u8 {
    let distance = |p: u8, q: u8| p.max(q) - p.min(q);
    let pa = distance(b, c);
    let pb = distance(a, c);
    let pc = if (b >= c) == (a >= c) {
        pa.saturating_add(pb)
    } else {
        distance(pa, pb)
    };
    if pa <= pb && pa <= pc {
        a
    } else if pb <= pc {
        b
    } else {
        c
    }
}

/// The cost the adaptive choice gives a filtered byte: its value read as signed, made positive.
#[inline(always)]
fn cost(byte: u8) -> u64 {
    u64::from((byte as i8).unsigned_abs())
}

/// Filters bytes `range` of `current` (under `previous`) by all four filters into `out`
/// (Up, Sub, Average, Paeth) and returns the four costs of those bytes.
#[inline(always)]
fn filter_bytes_scalar(
    bytes_per_pixel: usize,
    previous: &[u8],
    current: &[u8],
    out: &mut [&mut Vec<u8>; 4],
    range: std::ops::Range<usize>,
) -> [u64; 4] {
    let mut costs = [0u64; 4];
    for i in range {
        let x = current[i];
        let b = previous[i];
        let (a, c) = if i >= bytes_per_pixel {
            (current[i - bytes_per_pixel], previous[i - bytes_per_pixel])
        } else {
            (0, 0)
        };
        let average = ((u16::from(a) + u16::from(b)) / 2) as u8;
        let filtered = [
            x.wrapping_sub(b),
            x.wrapping_sub(a),
            x.wrapping_sub(average),
            x.wrapping_sub(paeth_predictor(a, b, c)),
        ];
        for k in 0..4 {
            out[k][i] = filtered[k];
            costs[k] += cost(filtered[k]);
        }
    }
    costs
}

/// The sum of [`cost`] over `bytes`, in runs of 32 the compiler vectorises.
fn cost_of(bytes: &[u8]) -> u64 {
    let mut runs = bytes.chunks_exact(32);
    let mut sum = 0;
    for run in &mut runs {
        // At most 32 · 128: no overflow in u32.
        sum += u64::from(
            run.iter()
                .map(|&b| u32::from((b as i8).unsigned_abs()))
                .sum::<u32>(),
        );
    }
    sum + runs.remainder().iter().map(|&b| cost(b)).sum::<u64>()
}

/// `out[i] = x[i] − predict(a[i], b[i], c[i])` (wrapping) for the bytes `x` and their left,
/// upper and upper-left neighbours `(x, a, b, c)`, in runs of 32 the compiler vectorises.
#[inline(always)]
fn filter_runs(
    out: &mut [u8],
    (x, a, b, c): (&[u8], &[u8], &[u8], &[u8]),
    predict: impl Fn(u8, u8, u8) -> u8,
) {
    const RUN: usize = 32;
    let n = x.len();
    assert!(out.len() == n && a.len() == n && b.len() == n && c.len() == n);
    let whole = n / RUN * RUN;
    for start in (0..whole).step_by(RUN) {
        let run = start..start + RUN;
        let (out, x, a, b, c) = (
            &mut out[run.clone()],
            &x[run.clone()],
            &a[run.clone()],
            &b[run.clone()],
            &c[run],
        );
        for i in 0..RUN {
            out[i] = x[i].wrapping_sub(predict(a[i], b[i], c[i]));
        }
    }
    for i in whole..n {
        out[i] = x[i].wrapping_sub(predict(a[i], b[i], c[i]));
    }
}

/// Filters `current` under `previous` by Up, Sub, Average and Paeth into `out` (each as long
/// as the rows) and returns the four costs: the first pixel one byte at a time, the rest of
/// each filter in a loop of its own over runs of 32 bytes, which the compiler vectorises with
/// the baseline instructions.
fn all_filters_scalar(
    bytes_per_pixel: usize,
    previous: &[u8],
    current: &[u8],
    mut out: [&mut Vec<u8>; 4],
) -> [u64; 4] {
    let len = current.len();
    assert!(previous.len() == len && out.iter().all(|o| o.len() == len));
    let bpp = bytes_per_pixel.min(len);
    filter_bytes_scalar(bpp, previous, current, &mut out, 0..bpp);
    let [up, sub, average, paeth] = out;
    // Bytes bpp.. from the byte `x`, its left `a`, upper `b` and upper-left `c`.
    let x = &current[bpp..];
    let a = &current[..len - bpp];
    let b = &previous[bpp..];
    let c = &previous[..len - bpp];
    let neighbours = (x, a, b, c);
    filter_runs(&mut up[bpp..], neighbours, |_, b, _| b);
    filter_runs(&mut sub[bpp..], neighbours, |a, _, _| a);
    filter_runs(&mut average[bpp..], neighbours, |a, b, _| {
        (a & b) + ((a ^ b) >> 1)
    });
    filter_runs(&mut paeth[bpp..], neighbours, paeth_predictor_in_bytes);
    [up, sub, average, paeth].map(|row| cost_of(row))
}

/// [`all_filters_scalar`] 32 bytes at a time from the second pixel on (its left and
/// upper-left neighbours are then inside the row, loaded unaligned from `bytes_per_pixel`
/// bytes back); the first pixel and the tail one byte at a time. Paeth in 8-bit lanes:
/// `|b − c|` and `|a − c|` are exact as unsigned bytes, and `|a + b − 2c|` is their saturated
/// sum where `b − c` and `a − c` share a sign and their difference otherwise; saturating at 255
/// changes no comparison with the other two, which are at most 255.
///
/// # Safety
/// The processor must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn all_filters_avx2(
    bytes_per_pixel: usize,
    previous: &[u8],
    current: &[u8],
    mut out: [&mut Vec<u8>; 4],
) -> [u64; 4] {
    use std::arch::x86_64::*;
    let len = current.len();
    assert!(previous.len() == len && out.iter().all(|o| o.len() == len));
    let bpp = bytes_per_pixel.min(len);
    let mut costs = filter_bytes_scalar(bpp, previous, current, &mut out, 0..bpp);
    let zero = _mm256_setzero_si256();
    let low_bit = _mm256_set1_epi8(1);
    let mut sums = [zero; 4];
    let mut i = bpp;
    let cur = current.as_ptr();
    let prev = previous.as_ptr();
    let outs = [
        out[0].as_mut_ptr(),
        out[1].as_mut_ptr(),
        out[2].as_mut_ptr(),
        out[3].as_mut_ptr(),
    ];
    while i + 32 <= len {
        // SAFETY: i − bpp ≥ 0 and i + 32 ≤ len: every load and store is inside its row.
        let (x, a, b, c) = unsafe {
            (
                _mm256_loadu_si256(cur.add(i).cast()),
                _mm256_loadu_si256(cur.add(i - bpp).cast()),
                _mm256_loadu_si256(prev.add(i).cast()),
                _mm256_loadu_si256(prev.add(i - bpp).cast()),
            )
        };
        // ⌊(a + b) / 2⌋: the rounded-up average less the bit that rounding added.
        let average = _mm256_sub_epi8(
            _mm256_avg_epu8(a, b),
            _mm256_and_si256(_mm256_xor_si256(a, b), low_bit),
        );
        let abs_diff = |p: __m256i, q: __m256i| {
            _mm256_or_si256(_mm256_subs_epu8(p, q), _mm256_subs_epu8(q, p))
        };
        let at_least = |p: __m256i, q: __m256i| _mm256_cmpeq_epi8(_mm256_max_epu8(p, q), p);
        let at_most = |p: __m256i, q: __m256i| _mm256_cmpeq_epi8(_mm256_min_epu8(p, q), p);
        let pa = abs_diff(b, c);
        let pb = abs_diff(a, c);
        let same_sign = _mm256_cmpeq_epi8(at_least(b, c), at_least(a, c));
        let pc = _mm256_blendv_epi8(abs_diff(pa, pb), _mm256_adds_epu8(pa, pb), same_sign);
        let take_a = _mm256_and_si256(at_most(pa, pb), at_most(pa, pc));
        let b_or_c = _mm256_blendv_epi8(c, b, at_most(pb, pc));
        let paeth = _mm256_blendv_epi8(b_or_c, a, take_a);
        let filtered = [
            _mm256_sub_epi8(x, b),
            _mm256_sub_epi8(x, a),
            _mm256_sub_epi8(x, average),
            _mm256_sub_epi8(x, paeth),
        ];
        for k in 0..4 {
            // SAFETY: as for the loads; each output is as long as the rows.
            unsafe { _mm256_storeu_si256(outs[k].add(i).cast(), filtered[k]) };
            let magnitude = _mm256_abs_epi8(filtered[k]);
            sums[k] = _mm256_add_epi64(sums[k], _mm256_sad_epu8(magnitude, zero));
        }
        i += 32;
    }
    let tail = filter_bytes_scalar(bpp, previous, current, &mut out, i..len);
    for k in 0..4 {
        let mut lanes = [0u64; 4];
        // SAFETY: four u64 lanes into an array of four.
        unsafe { _mm256_storeu_si256(lanes.as_mut_ptr().cast(), sums[k]) };
        costs[k] += lanes.iter().sum::<u64>() + tail[k];
    }
    costs
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The four filters (in the order of [`TRIED`]) one at a time, each from its definition.
    fn definitions(bpp: usize, previous: &[u8], current: &[u8]) -> [Vec<u8>; 4] {
        TRIED.map(|kind| {
            (0..current.len())
                .map(|i| {
                    let a = if i >= bpp { current[i - bpp] } else { 0 };
                    let c = if i >= bpp { previous[i - bpp] } else { 0 };
                    let b = previous[i];
                    let predicted = match kind {
                        SUB => a,
                        UP => b,
                        AVERAGE => ((a as u32 + b as u32) / 2) as u8,
                        _ => paeth_predictor(a, b, c),
                    };
                    current[i].wrapping_sub(predicted)
                })
                .collect()
        })
    }

    /// png's adaptive loop as it is written (try in order, keep on `<=`, stop at zero) over
    /// [`definitions`]: the reference for the choice.
    fn reference(bpp: usize, previous: &[u8], current: &[u8]) -> (u8, Vec<u8>) {
        let rows = definitions(bpp, previous, current);
        let mut best = (u64::MAX, 0usize);
        for (k, row) in rows.iter().enumerate() {
            let cost: u64 = row.iter().map(|&b| cost(b)).sum();
            if cost <= best.0 {
                best = (cost, k);
                if cost == 0 {
                    break;
                }
            }
        }
        (TRIED[best.1], rows[best.1].clone())
    }

    fn kernels() -> Vec<Kernel> {
        let mut kernels = vec![Kernel::Scalar];
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            kernels.push(Kernel::Avx2);
        } else {
            eprintln!("NOTE: this processor has no AVX2: only the scalar filter kernel is tested");
        }
        kernels
    }

    #[test]
    fn the_paeth_predictor_is_the_specifications() {
        // Against the three-way distance test written out in full, every (a, b, c).
        for a in 0..=255u8 {
            for b in 0..=255u8 {
                for c in 0..=255u8 {
                    let p = a as i32 + b as i32 - c as i32;
                    let d = |v: u8| (p - v as i32).abs();
                    let nearest = [a, b, c].into_iter().min_by_key(|&v| d(v)).unwrap();
                    assert_eq!(paeth_predictor(a, b, c), nearest, "{a} {b} {c}");
                    assert_eq!(paeth_predictor_in_bytes(a, b, c), nearest, "{a} {b} {c}");
                }
            }
        }
    }

    #[test]
    fn every_kernel_filters_every_neighbourhood_as_the_definitions_do() {
        // One byte a pixel. The row above alternates c (even bytes) and b (odd bytes); the
        // row's even bytes count 0, 1, 2, …: so the odd bytes 1 to 511 see every left
        // neighbour a with that (b, c), and over all (b, c) every triple is met, inside the
        // kernel's 32-byte lanes (the row is 32 bytes longer than needed, for the tail).
        const LEN: usize = 545;
        let current: Vec<u8> = (0..LEN)
            .map(|i| {
                if i % 2 == 0 {
                    (i / 2) as u8
                } else {
                    (i * 7 + 3) as u8
                }
            })
            .collect();
        for kernel in kernels() {
            let mut filter = AdaptiveRowFilter::with_kernel(1, LEN, kernel);
            for b in 0..=255u8 {
                for c in 0..=255u8 {
                    let previous: Vec<u8> =
                        (0..LEN).map(|i| if i % 2 == 0 { c } else { b }).collect();
                    let (kind, row) = filter.filter(&previous, &current);
                    let (want_kind, want_row) = reference(1, &previous, &current);
                    assert_eq!(
                        (kind, row),
                        (want_kind, &want_row[..]),
                        "{kernel:?} b {b} c {c}"
                    );
                    let want = definitions(1, &previous, &current);
                    assert_eq!(filter.candidates, want, "{kernel:?} b {b} c {c}");
                }
            }
        }
    }

    #[test]
    fn every_kernel_chooses_as_png_on_random_rows_with_ties() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(36);
        for kernel in kernels() {
            for bpp in [1, 3, 4, 6, 8] {
                for len in (bpp..=200).step_by(bpp) {
                    let mut filter = AdaptiveRowFilter::with_kernel(bpp, len, kernel);
                    // A small alphabet makes equal costs (and zero costs) common.
                    for alphabet in [1u32, 2, 3, 256] {
                        let mut previous = vec![0u8; len];
                        for _ in 0..8 {
                            let current: Vec<u8> = (0..len)
                                .map(|_| (rng.random_range(0..alphabet) * 97 % 256) as u8)
                                .collect();
                            let (kind, row) = filter.filter(&previous, &current);
                            let want = reference(bpp, &previous, &current);
                            assert_eq!(
                                (kind, row),
                                (want.0, &want.1[..]),
                                "{kernel:?} {bpp} {len}"
                            );
                            previous = current;
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn ties_go_to_the_last_cheapest_and_zero_stops_the_search() {
        assert_eq!(adaptive_choice([5, 5, 5, 5]), 3);
        assert_eq!(adaptive_choice([4, 5, 4, 6]), 2);
        assert_eq!(adaptive_choice([0, 0, 3, 0]), 0);
        assert_eq!(adaptive_choice([2, 0, 0, 1]), 1);
        assert_eq!(adaptive_choice([9, 8, 7, 6]), 3);
    }
}
