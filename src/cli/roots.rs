//! `kardia roots`: the distinct real roots of a polynomial in an interval.
//!
//! Every number Rust reads as an `f64` is a coefficient, in any position and without `--`
//! (`-2.5e-3`, `-1E+5`, `-.5`, `-0`): the coefficients take hyphen values, and options written
//! after them (`1 -2 1 --first --in 0,3`) are picked out of the values and read again by the
//! same argument definitions.

use clap::{Args, Command, FromArgMatches};

use crate::roots::{sturm_roots, Solver};

/// Arguments of `kardia roots`.
#[derive(Debug, Args)]
pub struct RootsArgs {
    /// The interval `LO,HI`: roots `t` with `LO < t ≤ HI` are printed (`-inf`/`inf` allowed).
    #[arg(long = "in", value_name = "LO,HI", allow_hyphen_values = true)]
    pub interval: Option<String>,

    /// Print only the smallest root.
    #[arg(long)]
    pub first: bool,

    /// Root-isolation strategy for `--first` (all roots always use the Sturm method).
    #[arg(long, value_name = "NAME")]
    pub solver: Option<Solver>,

    /// Coefficients c0 c1 … cn in ascending powers (1 to 17 finite numbers).
    #[arg(allow_hyphen_values = true, value_name = "COEFF")]
    pub coeffs: Vec<String>,
}

/// `LO,HI` as two numbers with `LO < HI` (either may be infinite).
fn parse_interval(s: &str) -> Result<(f64, f64), String> {
    let (lo, hi) = s
        .split_once(',')
        .ok_or_else(|| format!("interval '{s}' is not LO,HI"))?;
    let (lo, hi) = (parse_end(lo)?, parse_end(hi)?);
    if lo >= hi {
        return Err(format!("interval '{s}' needs LO < HI"));
    }
    Ok((lo, hi))
}

/// A number as Rust parses `f64`, NaN refused (infinite allowed).
fn parse_number(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_nan() {
        return Err(format!("'{s}' is not a number (NaN)"));
    }
    Ok(v)
}

/// Whether `s` spells an infinity (`inf`, `-Infinity`, …) rather than a finite number too
/// large for `f64` (`1e999`).
fn spells_infinity(s: &str) -> bool {
    let s = s.trim().trim_start_matches(['+', '-']);
    s.eq_ignore_ascii_case("inf") || s.eq_ignore_ascii_case("infinity")
}

/// An interval end: a number, `±inf` for an unbounded end.
fn parse_end(s: &str) -> Result<f64, String> {
    let v = parse_number(s)?;
    if v.is_infinite() && !spells_infinity(s) {
        return Err(format!(
            "'{s}' is beyond the largest f64 (about 1.8e308); write inf for an unbounded end"
        ));
    }
    Ok(v)
}

/// A coefficient: a finite number.
fn parse_coefficient(s: &str) -> Result<f64, String> {
    let v = parse_number(s)?;
    if v.is_infinite() {
        return Err(if spells_infinity(s) {
            format!("coefficient '{s}' is not finite")
        } else {
            format!("coefficient '{s}' is beyond the largest f64 (about 1.8e308)")
        });
    }
    Ok(v)
}

/// Whether a value the coefficients took is an option written after them (`--first`,
/// `--in=…`, `-h`), not a coefficient: it is not a number and looks like an option.
fn is_option(s: &str) -> bool {
    ((s.starts_with("--") && s.len() > 2) || s == "-h") && s.parse::<f64>().is_err()
}

/// Why the command line was not accepted: clap's own error (printed as clap prints it, help
/// included) or a one-line message.
enum Refusal {
    Clap(clap::Error),
    Message(String),
}

/// `args` with the options that the coefficients took as values moved back to the options.
/// A `--` among the coefficients makes every value after it a coefficient.
fn gather(mut args: RootsArgs) -> Result<RootsArgs, Refusal> {
    let Some(at) = args.coeffs.iter().position(|s| s == "--" || is_option(s)) else {
        return Ok(args);
    };
    let tail = args.coeffs.split_off(at);
    if tail[0] == "--" {
        args.coeffs.extend(tail.into_iter().skip(1));
        return Ok(args);
    }
    let command = RootsArgs::augment_args(Command::new("roots").no_binary_name(true));
    let matches = command.try_get_matches_from(&tail).map_err(Refusal::Clap)?;
    let rest = gather(RootsArgs::from_arg_matches(&matches).map_err(Refusal::Clap)?)?;
    if args.interval.is_some() && rest.interval.is_some() {
        return Err(Refusal::Message("--in is given twice".into()));
    }
    if args.solver.is_some() && rest.solver.is_some() {
        return Err(Refusal::Message("--solver is given twice".into()));
    }
    args.coeffs.extend(rest.coeffs);
    Ok(RootsArgs {
        interval: args.interval.or(rest.interval),
        first: args.first || rest.first,
        solver: args.solver.or(rest.solver),
        coeffs: args.coeffs,
    })
}

/// Validated input: `(lo, hi, coefficients)`, or a one-line message.
fn validate(args: &RootsArgs) -> Result<(f64, f64, Vec<f64>), String> {
    let interval = args.interval.as_deref().ok_or("missing --in LO,HI")?;
    let (lo, hi) = parse_interval(interval)?;
    if args.coeffs.is_empty() || args.coeffs.len() > 17 {
        return Err(format!(
            "expected 1 to 17 coefficients, got {}",
            args.coeffs.len()
        ));
    }
    let coeffs = args
        .coeffs
        .iter()
        .map(|c| parse_coefficient(c))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((lo, hi, coeffs))
}

/// Runs `kardia roots`: prints each root on its own line with 17 significant digits;
/// returns 0, or 2 after an error on stderr for bad input (one line, or clap's usage error
/// for an option written after the coefficients).
pub fn run(args: RootsArgs) -> i32 {
    let args = match gather(args) {
        Ok(args) => args,
        Err(Refusal::Clap(e)) => {
            // `--help` among the coefficients prints the help and succeeds, as before them.
            let _ = e.print();
            return e.exit_code();
        }
        Err(Refusal::Message(msg)) => {
            eprintln!("kardia roots: {msg}");
            return 2;
        }
    };
    let (lo, hi, coeffs) = match validate(&args) {
        Ok(v) => v,
        Err(msg) => {
            eprintln!("kardia roots: {msg}");
            return 2;
        }
    };
    let roots = if args.first {
        args.solver
            .unwrap_or(Solver::Sturm)
            .first_root_at_any_scale(&coeffs, lo, hi)
            .into_iter()
            .collect()
    } else {
        sturm_roots(&coeffs, lo, hi)
    };
    for r in roots {
        outln!("{r:.16e}");
    }
    0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_spelling_of_a_finite_number_is_a_coefficient() {
        for (s, v) in [
            ("-2.5e-3", -2.5e-3),
            ("-1E+5", -1e5),
            ("-.5", -0.5),
            ("-0", 0.0),
            ("+3", 3.0),
            ("1.", 1.0),
            ("-1.7320508075688771e-70", -1.732_050_807_568_877e-70),
            ("4.9e-324", 4.9e-324),
        ] {
            assert_eq!(parse_coefficient(s), Ok(v), "{s}");
            assert!(!is_option(s), "{s}");
        }
        assert!(parse_coefficient("-0").unwrap().is_sign_negative());
        for bad in [
            "inf", "-inf", "Infinity", "1e999", "nan", "-NaN", "x", "1e", "--first",
        ] {
            assert!(parse_coefficient(bad).is_err(), "{bad}");
        }
        assert!(parse_coefficient("1e999").unwrap_err().contains("beyond"));
        assert!(parse_coefficient("-inf")
            .unwrap_err()
            .contains("not finite"));
    }

    #[test]
    fn an_interval_end_may_be_infinite_when_written_so() {
        assert_eq!(
            parse_interval("-inf,1e-300"),
            Ok((f64::NEG_INFINITY, 1e-300))
        );
        assert_eq!(parse_interval("-1E+5,inf"), Ok((-1e5, f64::INFINITY)));
        assert!(parse_interval("-1e999,0")
            .unwrap_err()
            .contains("write inf"));
        assert!(parse_interval("nan,1").is_err());
    }

    #[test]
    fn options_after_the_coefficients_are_options() {
        let args = |v: &[&str]| RootsArgs {
            interval: None,
            first: false,
            solver: None,
            coeffs: v.iter().map(|s| s.to_string()).collect(),
        };
        let got = gather(args(&["1", "-2.5e-3", "--first", "--in=-1,1", "-3"]))
            .ok()
            .unwrap();
        assert_eq!(got.coeffs, ["1", "-2.5e-3", "-3"]);
        assert_eq!(got.interval.as_deref(), Some("-1,1"));
        assert!(got.first);
        let got = gather(args(&["1", "--", "--first"])).ok().unwrap();
        assert_eq!(got.coeffs, ["1", "--first"]);
        assert!(!got.first);
        let mut twice = args(&["1", "--in", "0,1"]);
        twice.interval = Some("0,2".into());
        assert!(matches!(gather(twice), Err(Refusal::Message(_))));
        assert!(matches!(
            gather(args(&["1", "--solver", "nope"])),
            Err(Refusal::Clap(_))
        ));
    }
}
