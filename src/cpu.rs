//! Which vector instructions the hot loops may use.
//!
//! Every routine with an AVX2 or FMA copy gives the same bits as its baseline x86-64 copy, so
//! the choice changes speed, never a picture. Setting the environment variable
//! `KARDIA_CPU=baseline` makes every routine take its baseline copy: for checking that promise
//! on a machine that has AVX2 (the integration tests render both ways and compare the bytes),
//! and for timing the two paths against each other. Any other value, or none, means "what the
//! processor has". The answer is read once per process.

use std::sync::atomic::{AtomicU8, Ordering};

/// The environment variable that selects the baseline code path (value `baseline`).
pub const ENV_VAR: &str = "KARDIA_CPU";

const KNOWN: u8 = 1;
const AVX2: u8 = 2;
const FMA: u8 = 4;

static FEATURES: AtomicU8 = AtomicU8::new(0);

#[inline(always)]
fn features() -> u8 {
    match FEATURES.load(Ordering::Relaxed) {
        0 => detect(),
        known => known,
    }
}

#[cold]
fn detect() -> u8 {
    let features = KNOWN | if baseline_requested() { 0 } else { detected() };
    FEATURES.store(features, Ordering::Relaxed);
    features
}

fn baseline_requested() -> bool {
    std::env::var_os(ENV_VAR).is_some_and(|v| v.eq_ignore_ascii_case("baseline"))
}

#[cfg(target_arch = "x86_64")]
fn detected() -> u8 {
    let mut features = 0;
    if std::arch::is_x86_feature_detected!("avx2") {
        features |= AVX2;
    }
    if std::arch::is_x86_feature_detected!("fma") {
        features |= FMA;
    }
    features
}

#[cfg(not(target_arch = "x86_64"))]
fn detected() -> u8 {
    0
}

/// True when the AVX2 copies may run: the processor has AVX2 and `KARDIA_CPU=baseline` is
/// not set. Callers still guard their AVX2 code with `#[cfg(target_arch = "x86_64")]`.
#[inline(always)]
pub fn avx2() -> bool {
    features() & AVX2 != 0
}

/// True when the FMA copies may run: the processor has FMA and `KARDIA_CPU=baseline` is not
/// set.
#[inline(always)]
pub fn fma() -> bool {
    features() & FMA != 0
}

/// "avx2+fma", "avx2", "fma" or "baseline": the code path this process takes, for summaries
/// and bug reports.
pub fn path_name() -> &'static str {
    match (avx2(), fma()) {
        (true, true) => "avx2+fma",
        (true, false) => "avx2",
        (false, true) => "fma",
        (false, false) => "baseline",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_answer_matches_the_processor_unless_baseline_is_asked() {
        // The test process may run with KARDIA_CPU=baseline (the CI's second pass does not,
        // but a developer may): the answer must follow the variable either way.
        if baseline_requested() {
            assert_eq!(path_name(), "baseline");
        } else {
            #[cfg(target_arch = "x86_64")]
            {
                assert_eq!(avx2(), std::arch::is_x86_feature_detected!("avx2"));
                assert_eq!(fma(), std::arch::is_x86_feature_detected!("fma"));
            }
        }
        // Read once: a second call gives the same answer from the cache.
        assert_eq!(features(), features());
        assert_ne!(features() & KNOWN, 0);
    }
}
