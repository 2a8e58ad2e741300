//! `kardia roots` as a user runs it: the built binary, its stdout, stderr and exit code.

use std::process::{Command, Output};

fn kardia_roots(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kardia"))
        .arg("roots")
        .args(args)
        .output()
        .expect("run kardia")
}

/// The printed roots, each parsed, and the exit code.
fn roots_of(args: &[&str]) -> (Vec<f64>, i32) {
    let out = kardia_roots(args);
    let text = String::from_utf8(out.stdout).unwrap();
    let roots = text.lines().map(|l| l.parse().unwrap()).collect();
    (roots, out.status.code().unwrap())
}

fn assert_close(found: &[f64], expected: &[f64]) {
    assert_eq!(found.len(), expected.len(), "{found:?} vs {expected:?}");
    for (f, e) in found.iter().zip(expected) {
        assert!(
            (f - e).abs() <= 1e-12 * e.abs().max(1.0),
            "{found:?} vs {expected:?}"
        );
    }
}

#[test]
fn prints_every_root_ascending_with_negative_numbers_as_written() {
    let (roots, code) = roots_of(&["--in", "-10,10", "-6", "11", "-6", "1"]);
    assert_eq!(code, 0);
    assert_close(&roots, &[1.0, 2.0, 3.0]);
    let (roots, _) = roots_of(&["--in", "-10,-1.5", "6", "11", "6", "1"]);
    assert_close(&roots, &[-3.0, -2.0]);
}

#[test]
fn accepts_a_double_dash_and_an_equals_sign() {
    let (roots, code) = roots_of(&["--in", "-10,10", "--", "-6", "11", "-6", "1"]);
    assert_eq!(code, 0);
    assert_close(&roots, &[1.0, 2.0, 3.0]);
    let (roots, _) = roots_of(&["--in=-10,10", "-6", "11", "-6", "1"]);
    assert_close(&roots, &[1.0, 2.0, 3.0]);
}

#[test]
fn first_prints_only_the_smallest_with_either_solver() {
    for solver in [None, Some("sturm"), Some("yuksel")] {
        let mut args = vec!["--first", "--in", "-10,10"];
        if let Some(s) = solver {
            args.extend(["--solver", s]);
        }
        args.extend(["-6", "11", "-6", "1"]);
        let (roots, code) = roots_of(&args);
        assert_eq!(code, 0);
        assert_close(&roots, &[1.0]);
    }
}

#[test]
fn prints_seventeen_significant_digits() {
    let out = kardia_roots(&["--in", "0,2", "--", "-2", "0", "1"]);
    let text = String::from_utf8(out.stdout).unwrap();
    let line = text.trim();
    let digits = line
        .split(['e', 'E'])
        .next()
        .unwrap()
        .chars()
        .filter(char::is_ascii_digit)
        .count();
    assert_eq!(digits, 17, "{line}");
    assert_eq!(line.parse::<f64>().unwrap(), 2f64.sqrt());
}

#[test]
fn a_multiple_root_is_printed_once_and_hi_is_included() {
    // (t − 1)²·(t − 2) on (0, 2]
    let (roots, _) = roots_of(&["--in", "0,2", "--", "-2", "5", "-4", "1"]);
    assert_close(&roots, &[1.0, 2.0]);
}

#[test]
fn no_roots_prints_nothing_and_succeeds() {
    let out = kardia_roots(&["--in", "-10,10", "1", "0", "1"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(out.stdout.is_empty());
    assert!(out.stderr.is_empty());
    let out = kardia_roots(&["--in", "0,1", "0", "0", "0"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(out.stdout.is_empty());
}

#[test]
fn bad_input_is_one_line_on_stderr_and_exit_code_2() {
    let eighteen: Vec<String> = (0..18).map(|k| k.to_string()).collect();
    let mut too_many = vec!["--in", "0,1"];
    too_many.extend(eighteen.iter().map(String::as_str));
    let cases: Vec<Vec<&str>> = vec![
        vec!["--in", "0,1", "1", "x"],
        vec!["--in", "0,1", "1", "nan"],
        vec!["--in", "a,1", "1", "1"],
        vec!["--in", "0;1", "1", "1"],
        vec!["--in", "1,1", "1", "1"],
        vec!["--in", "2,1", "1", "1"],
        vec!["--in", "0,1"],
        vec!["1", "2"],
        too_many,
    ];
    for args in cases {
        let out = kardia_roots(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(out.stdout.is_empty(), "{args:?}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    }
    // Clap's own rejections also exit with 2.
    let out = kardia_roots(&["--in", "0,1", "--solver", "nope", "1", "1"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn seventeen_coefficients_are_accepted() {
    let mut args = vec!["--in", "-2,2", "-1"];
    args.extend(["0"; 15]);
    args.push("1");
    let (roots, code) = roots_of(&args);
    assert_eq!(code, 0);
    assert_close(&roots, &[-1.0, 1.0]);
}
