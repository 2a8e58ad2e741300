//! Named surfaces usable instead of a quoted equation (`IMPLICIT torus 1 0.3 …`): each is an
//! equation text in the ordinary language plus a default clip radius.
//!
//! Numbers are written into the text with Rust's shortest round-trip formatting, so the
//! parser reads back exactly the `f64` parameter given; derived constants (λ of the Kummer
//! family) are written as the expressions that define them, so they are expanded exactly.

/// The paper's heart, as the `heart` preset writes it.
pub const HEART_EQUATION: &str = "(2*x^2 + y^2 + z^2 - 1)^3 - (0.1*x^2 + y^2)*z^3";

/// A radius (object space, about the origin) that holds the whole paper heart, whose
/// extents are |X| ≤ 0.7193, |Y| ≤ 1.1390, −1 ≤ Z ≤ 1.2367: √(0.72² + 1.14² + 1.24²) < 1.83.
pub const HEART_RADIUS: f64 = 1.83;

/// A preset resolved with its parameters: the equation and its default clip radius.
#[derive(Debug, Clone, PartialEq)]
pub struct Preset {
    /// Equation text in the ordinary equation language.
    pub equation: String,
    /// Default `BOUND` (object-space clip radius) when the scene gives none.
    pub bound: f64,
}

/// A number as equation text, parenthesised when negative.
fn num(v: f64) -> String {
    if v < 0.0 {
        format!("({v})")
    } else {
        format!("{v}")
    }
}

/// The Chebyshev polynomial `T_n` as integer coefficients, ascending.
pub fn chebyshev(n: usize) -> Vec<i64> {
    let mut prev = vec![1i64];
    let mut cur = vec![0i64, 1];
    if n == 0 {
        return prev;
    }
    for _ in 1..n {
        // T_{k+1} = 2x·T_k − T_{k−1}
        let mut next = vec![0i64; cur.len() + 1];
        for (i, &c) in cur.iter().enumerate() {
            next[i + 1] += 2 * c;
        }
        for (i, &c) in prev.iter().enumerate() {
            next[i] -= c;
        }
        prev = cur;
        cur = next;
    }
    cur
}

fn chebyshev_text(n: usize, var: char) -> String {
    let mut out = String::new();
    for (k, &c) in chebyshev(n).iter().enumerate().rev() {
        if c == 0 {
            continue;
        }
        let sign = if c < 0 { " - " } else { " + " };
        if out.is_empty() {
            if c < 0 {
                out.push('-');
            }
        } else {
            out.push_str(sign);
        }
        let a = c.unsigned_abs();
        match k {
            0 => out.push_str(&a.to_string()),
            _ => {
                if a != 1 {
                    out.push_str(&format!("{a}*"));
                }
                out.push(var);
                if k > 1 {
                    out.push_str(&format!("^{k}"));
                }
            }
        }
    }
    out
}

fn check_count(name: &str, params: &[f64], want: usize, what: &str) -> Result<(), String> {
    if params.len() != want {
        return Err(format!(
            "the preset '{name}' takes {want} number{} ({what}), not {}",
            if want == 1 { "" } else { "s" },
            params.len()
        ));
    }
    if let Some(v) = params.iter().find(|v| !v.is_finite()) {
        return Err(format!(
            "the parameters of '{name}' must be finite, not {v}"
        ));
    }
    Ok(())
}

/// The preset `name` with its parameters, or what is wrong with them.
pub fn preset(name: &str, params: &[f64]) -> Result<Preset, String> {
    let p = |equation: String, bound: f64| Ok(Preset { equation, bound });
    match name {
        "heart" => {
            check_count(name, params, 0, "none")?;
            p(HEART_EQUATION.into(), 2.0)
        }
        "taubin_heart" => {
            check_count(name, params, 0, "none")?;
            p(
                "(x^2 + 9/4*y^2 + z^2 - 1)^3 - x^2*z^3 - 9/80*y^2*z^3".into(),
                2.0,
            )
        }
        "torus" => {
            check_count(name, params, 2, "the radii R and r")?;
            let (big, small) = (params[0], params[1]);
            if !(big > 0.0 && small > 0.0) {
                return Err(format!(
                    "the torus radii R and r must both be greater than 0, not {big} and {small}"
                ));
            }
            let (bs, ss) = (num(big), num(small));
            p(
                format!("(x^2 + y^2 + z^2 + {bs}^2 - {ss}^2)^2 - 4*{bs}^2*(x^2 + y^2)"),
                1.05 * (big + small),
            )
        }
        "kummer" => {
            check_count(name, params, 1, "the parameter mu")?;
            let mu = params[0];
            if ((mu * mu) - 3.0).abs() < 1e-9 {
                return Err(format!(
                    "kummer's mu must not be ±√3 (then λ = (3μ² − 1)/(3 − μ²) is infinite), not {mu}"
                ));
            }
            let m = num(mu);
            p(
                format!(
                    "(x^2 + y^2 + z^2 - {m}^2)^2 - (3*{m}^2 - 1)/(3 - {m}^2)*((1 - z)^2 - 2*x^2)*((1 + z)^2 - 2*y^2)"
                ),
                2f64.max(2.0 * mu.abs()),
            )
        }
        "barth_sextic" => {
            check_count(name, params, 0, "none")?;
            let phi = (1.0 + 5f64.sqrt()) / 2.0;
            let p2 = num(phi * phi);
            let k = num(1.0 + 2.0 * phi);
            p(
                format!(
                    "4*({p2}*x^2 - y^2)*({p2}*y^2 - z^2)*({p2}*z^2 - x^2) - {k}*(x^2 + y^2 + z^2 - 1)^2"
                ),
                2.0,
            )
        }
        "clebsch" => {
            check_count(name, params, 0, "none")?;
            // Σ x_i³ = 0 with Σ x_i = 0 (i = 0…4), in the chart x₄ = 4 with
            // x_i = v_i·(x, y, z) − 1 for the tetrahedron v = (1,1,1), (1,−1,−1), (−1,1,−1),
            // (−1,−1,1): Σ_{i<4} x_i = −4 = −x₄, and the chart shows the tetrahedral symmetry.
            p(
                "(x + y + z - 1)^3 + (x - y - z - 1)^3 + (-x + y - z - 1)^3 + (-x - y + z - 1)^3 + 64"
                    .into(),
                5.0,
            )
        }
        "chmutov" => {
            check_count(name, params, 1, "the degree n")?;
            let n = params[0];
            if !(n.fract() == 0.0 && (1.0..=16.0).contains(&n)) {
                return Err(format!(
                    "chmutov's degree n must be a whole number from 1 to 16, not {n}"
                ));
            }
            let n = n as usize;
            // Where T_n(x) = 2: beyond it no other two terms (each ≥ −1) can cancel T_n(x).
            let a = (2f64.acosh() / n as f64).cosh();
            p(
                format!(
                    "{} + {} + {}",
                    chebyshev_text(n, 'x'),
                    chebyshev_text(n, 'y'),
                    chebyshev_text(n, 'z')
                ),
                (3f64.sqrt() * a * 1.01 * 1000.0).ceil() / 1000.0,
            )
        }
        _ => {
            let names: Vec<_> = super::PRESETS.iter().map(|(n, _)| *n).collect();
            Err(format!(
                "unknown preset '{name}': expected a quoted equation or one of {}",
                names.join(", ")
            ))
        }
    }
}

fn parse_num(text: &str) -> Option<f64> {
    text.trim_start_matches('(')
        .trim_end_matches(')')
        .parse()
        .ok()
}

/// The preset whose equation text is exactly `equation` (as [`preset`] writes it), if any:
/// lets an equation obtained from `preset_equation` keep its preset's default bound.
pub fn recognise(equation: &str) -> Option<Preset> {
    let eq = equation.trim();
    let same = |name: &str, params: &[f64]| preset(name, params).ok().filter(|p| p.equation == eq);
    for name in ["heart", "taubin_heart", "barth_sextic", "clebsch"] {
        if let Some(p) = same(name, &[]) {
            return Some(p);
        }
    }
    if let Some(p) = (1..=16).find_map(|n| same("chmutov", &[n as f64])) {
        return Some(p);
    }
    if let Some(rest) = eq.strip_prefix("(x^2 + y^2 + z^2 - ") {
        let mu = parse_num(rest.split_once("^2)^2").map(|(m, _)| m)?)?;
        return same("kummer", &[mu]);
    }
    if let Some(rest) = eq.strip_prefix("(x^2 + y^2 + z^2 + ") {
        let (big, rest) = rest.split_once("^2 - ")?;
        let small = rest.split_once("^2)^2").map(|(m, _)| m)?;
        return same("torus", &[parse_num(big)?, parse_num(small)?]);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chebyshev_polynomials() {
        assert_eq!(chebyshev(0), vec![1]);
        assert_eq!(chebyshev(2), vec![-1, 0, 2]);
        assert_eq!(chebyshev(4), vec![1, 0, -8, 0, 8]);
        assert_eq!(chebyshev_text(3, 'x'), "4*x^3 - 3*x");
        // T_16(cos θ) = cos 16θ.
        let c = chebyshev(16);
        let th: f64 = 0.3;
        let v: f64 = c
            .iter()
            .rev()
            .fold(0.0, |acc, &k| acc * th.cos() + k as f64);
        assert!((v - (16.0 * th).cos()).abs() < 1e-9);
    }

    #[test]
    fn every_preset_text_is_recognised() {
        for (name, params) in [
            ("heart", vec![]),
            ("taubin_heart", vec![]),
            ("barth_sextic", vec![]),
            ("clebsch", vec![]),
            ("chmutov", vec![3.0]),
            ("chmutov", vec![16.0]),
            ("kummer", vec![1.3f64.sqrt()]),
            ("kummer", vec![-0.5]),
            ("torus", vec![1.0, 0.3]),
            ("torus", vec![2.5e-3, 1e-3]),
        ] {
            let p = preset(name, &params).unwrap();
            assert_eq!(recognise(&p.equation), Some(p), "{name} {params:?}");
        }
        assert_eq!(recognise("x^2 + y^2 = 1"), None);
        assert_eq!(recognise("(x^2 + y^2 + z^2 - 1^2)^2"), None);
    }
}
