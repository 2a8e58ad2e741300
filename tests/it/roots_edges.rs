//! `kardia roots` at the edges of `f64` (issue 40): every spelling of a number on the command
//! line, and roots at every scale — near 0 inside intervals of any width, at 10⁻³⁰⁰ and
//! 10³⁰⁰, with coefficients from 10⁻³⁰⁰ to 10³⁰⁰ in one polynomial, at the interval's ends.
//!
//! The accuracy checked is the one the docs promise (docs/roots.md): a simple root `r` of the
//! `f64` polynomial within `64·(n+1)·ε·A(|r|)/|p′(r)| + 4·ε·|r|`, `A(x) = Σ|cⱼ|·xʲ` (a few ulps
//! times its condition). Every polynomial here is either exact in `f64` (so its roots are
//! known exactly), or built from roots far enough apart that the rounding of its coefficients
//! moves them by far less than `1e-12` relative. `--first` (both solvers, through
//! `Solver::first_root_at_any_scale`, which the CLI calls) must agree with the first of the
//! full list in every case.

use kardia::roots::{sturm_roots, Solver};
use proptest::prelude::*;
use std::process::Command;

/// Coefficients (ascending) of `lead·Π (t − r)` over `roots`, multiplied out in `f64`.
fn from_roots(lead: f64, roots: &[f64]) -> Vec<f64> {
    let mut c = vec![lead];
    for &r in roots {
        let mut next = vec![0.0; c.len() + 1];
        for (j, &a) in c.iter().enumerate() {
            next[j + 1] += a;
            next[j] -= r * a;
        }
        c = next;
    }
    c
}

/// `Σ|cⱼ|·|t|ʲ` and `p′(t)`, in `f64` scaled by `2^-k` per term so that nothing over- or
/// underflows for the roots tested here (`t` a power of two times a moderate number).
fn size_and_slope(c: &[f64], t: f64) -> (f64, f64) {
    if t == 0.0 {
        return (c[0].abs(), c[1]);
    }
    // Exact-enough evaluation with a common power-of-two scale: terms |c_j|·|t|^j can span
    // far more than f64 holds, so each is formed in logarithms first.
    let logs: Vec<f64> = c
        .iter()
        .enumerate()
        .filter(|(_, x)| **x != 0.0)
        .map(|(j, x)| x.abs().log2() + j as f64 * t.abs().log2())
        .collect();
    let top = logs
        .iter()
        .cloned()
        .fold(f64::NEG_INFINITY, f64::max)
        .ceil();
    let mut size = 0.0;
    let mut slope = 0.0;
    for (j, &x) in c.iter().enumerate() {
        if x == 0.0 {
            continue;
        }
        let term = (x.abs().log2() + j as f64 * t.abs().log2() - top).exp2();
        size += term;
        if j > 0 {
            // j·c_j·t^(j−1) = j·(c_j·t^j)/t, sign included
            let sign = x.signum()
                * if t < 0.0 && (j - 1) % 2 == 1 {
                    -1.0
                } else {
                    1.0
                };
            slope += sign * j as f64 * term;
        }
    }
    // Both scaled by 2^-top (the slope also by t: compare size/|slope·/t| as a ratio).
    (size, slope / t.abs())
}

/// The promised bound on the error of a simple root `r` of `c`.
fn promised(c: &[f64], r: f64) -> f64 {
    let n = c.len() - 1;
    let (size, slope) = size_and_slope(c, r);
    64.0 * (n + 1) as f64 * f64::EPSILON * size / slope.abs() + 4.0 * f64::EPSILON * r.abs()
}

/// Checks the full list and `--first` (both solvers) of `c` on `(lo, hi]` against the
/// expected roots, each to `tol(root)`.
fn check_with(c: &[f64], lo: f64, hi: f64, expected: &[f64], tol: &dyn Fn(f64) -> f64) {
    let found = sturm_roots(c, lo, hi);
    assert_eq!(
        found.len(),
        expected.len(),
        "{c:?} on ({lo}, {hi}]: {found:?} vs {expected:?}"
    );
    for (f, e) in found.iter().zip(expected) {
        assert!(
            (f - e).abs() <= tol(*e),
            "{c:?} on ({lo}, {hi}]: {found:?} vs {expected:?}"
        );
    }
    for (solver, name) in Solver::ALL {
        let first = solver.first_root_at_any_scale(c, lo, hi);
        match (first, expected.first()) {
            (None, None) => {}
            (Some(f), Some(e)) => assert!(
                (f - e).abs() <= tol(*e),
                "{name} --first {f:e} vs {e:e}: {c:?} on ({lo}, {hi}]"
            ),
            _ => panic!("{name} --first {first:?} vs {expected:?}: {c:?} on ({lo}, {hi}]"),
        }
    }
}

/// [`check_with`] at the promised accuracy (the polynomial exact, its roots `expected`).
fn check_exact(c: &[f64], lo: f64, hi: f64, expected: &[f64]) {
    check_with(c, lo, hi, expected, &|r| promised(c, r));
}

/// [`check_with`] to `1e-12` relative (the roots of a rounded product).
fn check_relative(c: &[f64], lo: f64, hi: f64, expected: &[f64]) {
    check_with(c, lo, hi, expected, &|r| 1e-12 * r.abs());
}

#[test]
fn the_double_roots_near_zero_in_a_wide_interval() {
    // The issue's case: (1e140·t² − 3)² + 1e140·t⁹, double roots ±√3·1e-70 and a simple root
    // near −1e28 (t⁵ = −1e140).
    let c = [9.0, 0.0, -6e140, 0.0, 1e280, 0.0, 0.0, 0.0, 0.0, 1e140];
    let r = 3f64.sqrt() * 1e-70;
    for (lo, hi) in [(-1.5e28, 2.25e28), (-1e20, 1e20), (-1e300, 1e300)] {
        let expected: Vec<f64> = [-1e28, -r, r].into_iter().filter(|&t| t > lo).collect();
        check_relative(&c, lo, hi, &expected);
    }
    check_relative(&c, f64::NEG_INFINITY, f64::INFINITY, &[-1e28, -r, r]);
}

#[test]
fn geometric_roots_four_to_the_plus_minus_i() {
    // 4^i for i in −7..=8 (exact coefficients: sums of powers of two of one sign, rounded
    // only where they exceed 53 bits; the roots are well-conditioned), on intervals from
    // tight to 1e300 wide.
    let roots: Vec<f64> = (-7..=8).map(|i| 4f64.powi(i)).collect();
    let c = from_roots(1.0, &roots);
    for (lo, hi) in [(0.0, 1e5), (-1.0, 1e5), (-1e300, 1e300)] {
        check_relative(&c, lo, hi, &roots);
    }
    // Alternating signs, and the same scaled by 2^±100 (the scaling is exact).
    let alternating: Vec<f64> = (-4..=4)
        .map(|i| 4f64.powi(i) * if i % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    let mut sorted = alternating.clone();
    sorted.sort_by(f64::total_cmp);
    for k in [-100, 0, 100] {
        let s = 2f64.powi(k);
        let scaled: Vec<f64> = alternating.iter().map(|r| r * s).collect();
        let c = from_roots(1.0, &scaled);
        let expected: Vec<f64> = sorted.iter().map(|r| r * s).collect();
        check_relative(&c, -1e3 * s, 1e3 * s, &expected);
        check_relative(&c, f64::NEG_INFINITY, f64::INFINITY, &expected);
    }
}

#[test]
fn wilkinson_like_products_at_every_scale() {
    // Π (t − i) for i = 1..=n has exact integer coefficients for n ≤ 16 (16! < 2⁵³): its
    // roots are exactly 1..=n, and the promised accuracy is their (large) condition. Scaled
    // by 2^k (exactly, as far as the coefficients stay normal numbers) they sit at 2^k·i,
    // also inside intervals far wider than they.
    for n in [6i32, 10, 14] {
        let far = 960 / n - 4;
        for k in [-far, -60, 0, 60, far] {
            let s = 2f64.powi(k);
            let expected: Vec<f64> = (1..=n).map(|i| f64::from(i) * s).collect();
            let c = from_roots(1.0, &expected);
            for (lo, hi) in [(0.0, 2.0 * f64::from(n) * s), (-1.0, 1.0), (-1e300, 1e300)] {
                let inside: Vec<f64> = expected
                    .iter()
                    .cloned()
                    .filter(|&r| r > lo && r <= hi)
                    .collect();
                check_exact(&c, lo, hi, &inside);
            }
        }
    }
}

#[test]
fn roots_of_opposite_signs_near_zero_are_never_merged() {
    // (t − a)²·(t + a) and (t − a)(t + a)(t − 2a) with a = 2^-k: exact coefficients, roots
    // at ±a found apart on intervals up to 1e300 wide.
    for k in [30, 200, 300] {
        let a = 2f64.powi(-k);
        let double = from_roots(1.0, &[a, a, -a]);
        let simple = from_roots(1.0, &[a, -a, 2.0 * a]);
        for (lo, hi) in [(-1.0, 1.0), (-3.0, 1e30), (-1e300, 1e300)] {
            check_relative(&double, lo, hi, &[-a, a]);
            check_exact(&simple, lo, hi, &[-a, a, 2.0 * a]);
        }
    }
}

#[test]
fn a_cluster_near_zero_is_resolved_relative_to_its_size() {
    // Roots a, 2a, 3a (a = 2^-300) and a root at 1 (the product's coefficients lose the
    // tiny parts of the large ones, which moves no root by more than a relative 1e-15).
    let a = 2f64.powi(-300);
    let c = from_roots(1.0, &[a, 2.0 * a, 3.0 * a, 1.0]);
    check_relative(&c, -1.0, 2.0, &[a, 2.0 * a, 3.0 * a, 1.0]);
    check_relative(&c, -1e200, 1e200, &[a, 2.0 * a, 3.0 * a, 1.0]);
    // A root exactly at 0 next to tiny ones: t·(t − a)(t − 2a).
    let c = from_roots(1.0, &[0.0, a, 2.0 * a]);
    check_exact(&c, -1.0, 1.0, &[0.0, a, 2.0 * a]);
    check_exact(&c, 0.0, 1.0, &[a, 2.0 * a]);
}

#[test]
fn a_tiny_root_in_a_sturm_bracket_around_zero() {
    // Found by the property test below: the Sturm bracket of the root 2.34e-91 reaches from
    // −0.8 to 0.07 (in the prepared variable, where the root is 3.8e-177); false position
    // alone stopped near 1e-153.
    let roots = [-5.1828501404752125e85, 2.3414133846120175e-91];
    let c = from_roots(1.0, &roots);
    check_relative(&c, -2.0 * roots[0].abs(), 1.2406340138763684e180, &roots);
}

#[test]
fn huge_and_tiny_coefficients_in_one_polynomial() {
    // 1e-300·t² − t + 1e-300: roots 1e-300 and 1e300 (to a relative 1e-600).
    let c = [1e-300, -1.0, 1e-300];
    check_relative(&c, f64::NEG_INFINITY, f64::INFINITY, &[1e-300, 1e300]);
    check_relative(&c, -1.0, 1.5e300, &[1e-300, 1e300]);
    check_relative(&c, 0.0, 1.0, &[1e-300]);
    // 1e-300·t¹⁶ − 1e300: t = ±1e37.5.
    let mut c = vec![-1e300];
    c.extend([0.0; 15]);
    c.push(1e-300);
    let r = 10f64.powf(37.5);
    check_relative(&c, f64::NEG_INFINITY, f64::INFINITY, &[-r, r]);
    check_relative(&c, -1e300, 1e300, &[-r, r]);
    // 1e300·t² − 1e-300: t = ±1e-300.
    check_relative(&[-1e-300, 0.0, 1e300], -1.0, 1.0, &[-1e-300, 1e-300]);
    // 1e-300 + t + 1e300·t¹⁶: t ≈ −1e-300 and t = −1e-20 (t¹⁵ = −1e-300), nothing else real.
    let mut c = vec![1e-300, 1.0];
    c.extend([0.0; 14]);
    c.push(1e300);
    check_relative(&c, -1.0, 1.0, &[-1e-20, -1e-300]);
}

#[test]
fn roots_at_the_ends_of_the_interval() {
    // lo is excluded and hi included, at every scale, for simple and double roots.
    for k in [-300, 0, 300] {
        let s = 2f64.powi(k);
        let c = from_roots(1.0, &[s, 2.0 * s, 3.0 * s]);
        check_exact(&c, s, 3.0 * s, &[2.0 * s, 3.0 * s]);
        check_exact(&c, 0.0, s, &[s]);
        let c = from_roots(1.0, &[s, s, -1.0]);
        check_relative(&c, -0.5, s, &[s]);
        check_relative(&c, s, 2.0 * s, &[]);
    }
}

/// `kardia roots ARGS` as a user runs it: stdout lines, stderr and the exit code.
fn kardia_roots(args: &[&str]) -> (Vec<String>, String, i32) {
    let out = Command::new(env!("CARGO_BIN_EXE_kardia"))
        .arg("roots")
        .args(args)
        .output()
        .expect("run kardia");
    let text = String::from_utf8(out.stdout).unwrap();
    (
        text.lines().map(str::to_string).collect(),
        String::from_utf8(out.stderr).unwrap(),
        out.status.code().unwrap(),
    )
}

#[test]
fn the_issue_commands_print_the_right_roots() {
    let poly = [
        "9", "0", "-6e140", "0", "1e280", "0", "0", "0", "0", "1e140",
    ];
    for interval in ["-1.5e28,2.25e28", "-1e20,1e20"] {
        let mut args = vec!["--in", interval, "--"];
        args.extend(poly);
        let (lines, err, code) = kardia_roots(&args);
        assert_eq!(code, 0, "{err}");
        let tail = &lines[lines.len() - 2..];
        assert_eq!(tail, ["-1.7320508075688771e-70", "1.7320508075688771e-70"]);
        args.insert(0, "--first");
        let (first, _, _) = kardia_roots(&args);
        assert_eq!(first, lines[..1]);
    }
    // Negative numbers with exponents anywhere, without `--`, and options after them.
    let (lines, err, code) = kardia_roots(&["--in", "-1,1000", "1", "-2.5e-3"]);
    assert_eq!((code, lines.len()), (0, 1), "{err}");
    assert!((lines[0].parse::<f64>().unwrap() - 400.0).abs() < 1e-12);
    let (lines, _, _) = kardia_roots(&["-1E+5", "1", "--in", "-1e6,1e6", "--first"]);
    assert_eq!(lines.len(), 1);
    assert!((lines[0].parse::<f64>().unwrap() - 1e5).abs() <= 1e-10);
    let (lines, _, _) = kardia_roots(&["--in=-1,1", "-.5", "1"]);
    assert_eq!(lines, ["5.0000000000000000e-1"]);
    let (lines, _, _) = kardia_roots(&["--in", "-1,1", "-0", "1"]);
    assert_eq!(lines.len(), 1);
    assert_eq!(lines[0].parse::<f64>().unwrap(), 0.0);
    // A root read back in the form it was printed: t ∓ r has the root ±r.
    let r = 1.732_050_807_568_877e-70;
    for (c0, root) in [
        ("1.7320508075688771e-70", -r),
        ("-1.7320508075688771e-70", r),
    ] {
        let (lines, err, code) = kardia_roots(&["--in", "-1,1", c0, "1"]);
        assert_eq!((code, lines.len()), (0, 1), "{err}");
        assert!((lines[0].parse::<f64>().unwrap() - root).abs() <= 4e-16 * r);
    }
}

#[test]
fn infinities_and_nans_are_refused_with_a_message() {
    for (args, says) in [
        (vec!["--in", "-1,1", "1", "inf"], "not finite"),
        (vec!["--in", "-1,1", "-inf", "1"], "not finite"),
        (vec!["--in", "-1,1", "1", "-1e999"], "beyond the largest"),
        (vec!["--in", "-1,1", "-nan", "1"], "NaN"),
        (vec!["--in", "nan,1", "1", "1"], "NaN"),
        (vec!["--in", "-1e999,1", "1", "1"], "write inf"),
        (vec!["--in", "0,1", "1", "1", "--in", "0,2"], "twice"),
    ] {
        let (lines, err, code) = kardia_roots(&args);
        assert_eq!(code, 2, "{args:?}");
        assert!(lines.is_empty(), "{args:?}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    // Infinite interval ends written as such are an unbounded interval.
    let (lines, _, code) = kardia_roots(&["--in", "-inf,inf", "-2", "1"]);
    assert_eq!((code, lines), (0, vec!["2.0000000000000000e0".to_string()]));
}

/// Well-separated roots (pairwise apart by at least half the larger) of magnitudes from
/// 1e-100 to 1e100, either sign, with every coefficient of their product inside `f64`'s
/// normal range.
fn separated_roots() -> impl Strategy<Value = Vec<f64>> {
    prop::collection::vec((-100.0f64..100.0, any::<bool>()), 1..=5)
        .prop_map(|v| {
            v.into_iter()
                .map(|(e, neg)| 10f64.powf(e) * if neg { -1.0 } else { 1.0 })
                .collect::<Vec<f64>>()
        })
        .prop_filter("separated, coefficients in range", |roots| {
            let apart = roots.iter().enumerate().all(|(i, a)| {
                roots[..i]
                    .iter()
                    .all(|b| (a - b).abs() >= 0.5 * a.abs().max(b.abs()))
            });
            let up: f64 = roots.iter().map(|r| r.abs().log10().max(0.0)).sum();
            let down: f64 = roots.iter().map(|r| r.abs().log10().min(0.0)).sum();
            apart && up < 280.0 && down > -280.0
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 500, ..ProptestConfig::default() })]

    /// Every root to 1e-12 relative, on an infinite interval and on wide finite ones, with
    /// `--first` the first of them.
    #[test]
    fn separated_roots_from_1e_minus_100_to_1e100(
        roots in separated_roots(),
        lead in -20.0f64..20.0,
        reach in 0.0f64..1.0,
    ) {
        let c = from_roots(10f64.powf(lead), &roots);
        let mut sorted = roots.clone();
        sorted.sort_by(f64::total_cmp);
        let far = sorted.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        // From just beyond the farthest root to 1e300.
        let wide = far * 2.0 * (1e300 / (far * 2.0)).powf(reach);
        for (lo, hi) in [(f64::NEG_INFINITY, f64::INFINITY), (-wide, wide), (-2.0 * far, wide)] {
            let found = sturm_roots(&c, lo, hi);
            prop_assert_eq!(found.len(), sorted.len(), "{:?} on ({}, {}]: {:?} vs {:?}", c, lo, hi, found, sorted);
            for (f, e) in found.iter().zip(&sorted) {
                prop_assert!((f - e).abs() <= 1e-12 * e.abs(), "{:?} on ({}, {}]: {:?} vs {:?}", c, lo, hi, found, sorted);
            }
            for (solver, _) in Solver::ALL {
                let first = solver.first_root_at_any_scale(&c, lo, hi);
                prop_assert!(first.is_some_and(|f| (f - sorted[0]).abs() <= 1e-12 * sorted[0].abs()),
                    "{:?} --first {:?} vs {:?}", solver, first, sorted);
            }
        }
    }
}
