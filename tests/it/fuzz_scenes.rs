//! A deterministic sample of the scene fuzzer (see `fuzz_support` and docs/reliability.md):
//! mutated scenes are parsed and, when they parse, rendered at 12×9 with 1 sample per pixel
//! in this build (the dev profile: debug assertions and overflow checks on). No case may
//! panic, give a malformed error, a NaN or infinite pixel, or take longer than the bound.

use crate::fuzz_support::{confirm_slow, run, Fuzzer};
use std::time::Duration;

/// Cases in the CI sample, split over the test threads in chunks.
const CASES: u64 = 20_000;
const CHUNKS: u64 = 4;
/// Seed of the CI sample (the long campaign takes its own).
const SEED: u64 = 14;
/// Time bound per case (generous: the machine may be loaded; the campaign reports the
/// slowest case).
const BOUND: Duration = Duration::from_secs(5);

fn chunk(k: u64) {
    let fuzzer = Fuzzer::new();
    let per = CASES / CHUNKS;
    let mut tally = run(&fuzzer, SEED, k * per, per, BOUND);
    confirm_slow(&mut tally, SEED, BOUND);
    assert!(
        tally.clean(),
        "{} panics, {} non-finite, {} malformed errors, {} slow of {} cases; first failures:\n{:#?}",
        tally.panics,
        tally.non_finite,
        tally.bad_errors,
        tally.slow,
        tally.cases,
        tally.failures
    );
    // The sample must reach the renderer, not only the parser's errors.
    assert!(
        tally.rendered * 20 > tally.cases,
        "only {} of {} cases rendered",
        tally.rendered,
        tally.cases
    );
}

#[test]
fn sample_0() {
    chunk(0);
}

#[test]
fn sample_1() {
    chunk(1);
}

#[test]
fn sample_2() {
    chunk(2);
}

#[test]
fn sample_3() {
    chunk(3);
}

/// The campaign's mutations are deterministic: the same seed and index give the same text.
#[test]
fn cases_are_reproducible() {
    let fuzzer = Fuzzer::new();
    for i in [0, 1, 999, 123_456] {
        assert_eq!(fuzzer.case(7, i), fuzzer.case(7, i));
    }
    assert_ne!(fuzzer.case(7, 1), fuzzer.case(8, 1));
}

/// Equations with extreme numbers and exponents (the campaign mutates the numbers inside
/// quotes too): each is refused with a well-formed error or renders finite pixels.
#[test]
fn extreme_equations_are_refused_or_render_finite() {
    use crate::fuzz_support::{run_case, Verdict};
    for (equation, refused) in [
        ("1e308*x^2 + 1e308*x^2 - 1", Some("too large")),
        ("x^2 + y^2 + z^2 - 1e-320", None),
        ("x^16*1e300 + y^2 + z^2 - 1", None),
        ("(x+1e300)^16 - 1", Some("too large")),
        ("x^2 + y^2 + z^2 - 1/5e-324", Some("too large")),
        ("x^65536 - 1", Some("degree 65536")),
        // 2^3^4 = 2^81: its degree was cut to 64 bits in the message ("degree 0").
        ("x^(2^3^4) - 1", Some("degree 2417851639229258349412352")),
        ("5e-324*x^2 + 5e-324*y^2 + 5e-324*z^2 - 5e-324", None),
        ("x^2 + y^2 + z^2 - 1e-300", None),
    ] {
        let text = format!(
            "CAMERA (6,0,0) (0,0,0) (0,0,1) 40\nLIGHT (5,5,5) (1,1,1)\n\
             IMPLICIT \"{equation}\" (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.3, 0.3, 0.8) BOUND 2\n"
        );
        let verdict = run_case(&text, 1).verdict;
        match refused {
            None => assert_eq!(verdict, Verdict::Rendered, "{equation}"),
            Some(why) => {
                assert_eq!(verdict, Verdict::Refused, "{equation}");
                let e = kardia::scene::parse(&text, "t", &Default::default()).unwrap_err();
                assert!(e.message().contains(why), "{equation}: {e}");
            }
        }
    }
}
