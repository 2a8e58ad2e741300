//! `kardia roots`: the distinct real roots of a polynomial in an interval.

use clap::Args;

use crate::roots::{sturm_roots, Solver};

/// Arguments of `kardia roots`.
#[derive(Debug, Args)]
pub struct RootsArgs {
    /// The interval `LO,HI`: roots `t` with `LO < t ≤ HI` are printed.
    #[arg(long = "in", value_name = "LO,HI", allow_hyphen_values = true)]
    pub interval: Option<String>,

    /// Print only the smallest root.
    #[arg(long)]
    pub first: bool,

    /// Root-isolation strategy for `--first` (all roots always use the Sturm method).
    #[arg(long, value_name = "NAME")]
    pub solver: Option<Solver>,

    /// Coefficients c0 c1 … cn in ascending powers (1 to 17 of them).
    #[arg(allow_negative_numbers = true, value_name = "COEFF")]
    pub coeffs: Vec<String>,
}

/// `LO,HI` as two numbers with `LO < HI`.
fn parse_interval(s: &str) -> Result<(f64, f64), String> {
    let (lo, hi) = s
        .split_once(',')
        .ok_or_else(|| format!("interval '{s}' is not LO,HI"))?;
    let (lo, hi) = (parse_number(lo)?, parse_number(hi)?);
    if lo >= hi {
        return Err(format!("interval '{s}' needs LO < HI"));
    }
    Ok((lo, hi))
}

/// A number as Rust parses `f64` (`inf` allowed, NaN refused).
fn parse_number(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_nan() {
        return Err(format!("'{s}' is not a number"));
    }
    Ok(v)
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
        .map(|c| parse_number(c))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((lo, hi, coeffs))
}

/// Runs `kardia roots`: prints each root on its own line with 17 significant digits;
/// returns 0, or 2 after a one-line error on stderr for bad input.
pub fn run(args: RootsArgs) -> i32 {
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
            .first_root(&coeffs, lo, hi)
            .into_iter()
            .collect()
    } else {
        sturm_roots(&coeffs, lo, hi)
    };
    for r in roots {
        println!("{r:.16e}");
    }
    0
}
