//! Prints a typed surface as the body of a POV-Ray `polynomial { … }` object, for
//! `bench/compare.sh`: the degree, then every monomial of kardia's exact expansion as
//! `xyz(i,j,k): c` with 17 significant digits. kardia is right-handed with z up and POV-Ray
//! left-handed with y up, so kardia's `(x, y, z)` is POV-Ray's `<x, z, y>` and the monomial
//! `xⁱ yʲ zᵏ` is written `xyz(i, k, j)`.
//!
//! `cargo run --release --example povpoly -- torus 1 0.3` (a preset and its parameters) or
//! `… -- "x^2 + y^2 + z^2 = 1"` (an equation).

use kardia::shapes::implicit::{expand, preset_equation};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(first) = args.first() else {
        eprintln!("usage: povpoly PRESET [PARAMS…] | povpoly EQUATION");
        std::process::exit(2);
    };
    let params: Result<Vec<f64>, _> = args[1..].iter().map(|a| a.parse::<f64>()).collect();
    let equation = match params {
        Ok(p) => preset_equation(first, &p).unwrap_or_else(|_| first.clone()),
        Err(_) => first.clone(),
    };
    let poly = match expand(&equation) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("povpoly: {}", e.message);
            std::process::exit(1);
        }
    };
    let terms: Vec<String> = poly
        .terms
        .iter()
        .rev()
        .map(|(e, c)| format!("xyz({},{},{}): {:.17e}", e[0], e[2], e[1], c.to_f64()))
        .collect();
    println!("{},", poly.degree());
    println!("  {}", terms.join(",\n  "));
}
