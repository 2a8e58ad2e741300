//! The implicit-surface algebra: expansion, per-ray composition, gradients, errors, presets.

use kardia::geometry::{DVec3, Frame, Ray};
use kardia::shapes::implicit::coef::Coef;
use kardia::shapes::implicit::equation;
use kardia::shapes::implicit::poly::{derive_bound, Compiled};
use kardia::shapes::implicit::{self, preset, preset_equation, Implicit, PRESETS};
use rand::{Rng, SeedableRng};

fn rng() -> rand_pcg::Pcg64 {
    rand_pcg::Pcg64::seed_from_u64(0x6b61_7264_6961)
}

fn all_presets() -> Vec<(String, String, f64)> {
    let mut v = Vec::new();
    for &(name, _) in PRESETS {
        let params: Vec<Vec<f64>> = match name {
            "torus" => vec![vec![1.0, 0.3]],
            "kummer" => vec![vec![1.3f64.sqrt()], vec![0.5]],
            "chmutov" => vec![vec![2.0], vec![3.0], vec![16.0]],
            _ => vec![vec![]],
        };
        for p in params {
            let pr = preset(name, &p).unwrap();
            v.push((format!("{name} {p:?}"), pr.equation, pr.bound));
        }
    }
    v
}

fn sample_equations() -> Vec<String> {
    let mut v: Vec<String> = vec![
        "x^2 + y^2 + z^2 = 1".into(),
        "(x^2+y^2+z^2)^8 - 1".into(),
        "2x y - 3.25*z^3 + (x - 0.1)(y + 0.7) = 0.5".into(),
        "(x + y + z + 1)^16".into(),
        "-(x - y/3)^5 + 1e-2*z^4 - 7".into(),
        "x^2^3 + 2^3*y".into(),
        "(x^2 + 9/4*y^2 + z^2 - 1)^3 = x^2*z^3 + 9/80*y^2*z^3".into(),
    ];
    v.extend(all_presets().into_iter().map(|(_, e, _)| e));
    v
}

/// Σ|term| at p: the scale of rounding errors in any evaluation of the polynomial.
fn magnitude(c: &Compiled, p: [f64; 3]) -> f64 {
    c.terms
        .iter()
        .map(|t| {
            (t.c * p[0].powi(t.e[0] as i32) * p[1].powi(t.e[1] as i32) * p[2].powi(t.e[2] as i32))
                .abs()
        })
        .sum()
}

#[test]
fn expansion_equals_direct_evaluation() {
    let mut r = rng();
    for eq in sample_equations() {
        let expr = equation::parse(&eq).unwrap();
        let poly = implicit::expand(&eq).unwrap();
        let c = Compiled::new(&poly);
        for _ in 0..200 {
            let p = [
                r.random_range(-1.5..1.5),
                r.random_range(-1.5..1.5),
                r.random_range(-1.5..1.5),
            ];
            let direct = expr.eval(p);
            let expanded = c.eval(p);
            let scale = magnitude(&c, p).max(direct.abs()).max(1e-300);
            assert!(
                (direct - expanded).abs() <= 1e-12 * scale,
                "{eq} at {p:?}: direct {direct}, expanded {expanded}"
            );
        }
    }
}

#[test]
fn coefficients_are_exact() {
    let p = implicit::expand("(0.1*x + 0.2)^2 - 0.3*x/3").unwrap();
    assert_eq!(p.terms[&[2, 0, 0]], Coef::Exact(1, 100));
    assert_eq!(p.terms[&[1, 0, 0]], Coef::Exact(-3, 50));
    assert_eq!(p.terms[&[0, 0, 0]], Coef::Exact(1, 25));
    // The multinomial coefficients of (x²+y²+z²)⁸: e.g. x⁴y⁶z⁶ has 8!/(2!3!3!) = 560.
    let s = implicit::expand("(x^2+y^2+z^2)^8 = 1").unwrap();
    assert_eq!(s.terms[&[4, 6, 6]], Coef::int(560));
    assert_eq!(s.terms[&[0, 0, 0]], Coef::int(-1));
    assert_eq!(s.terms.len(), 46);
    // Cancellation is exact: nothing is left of a difference of equal expansions.
    let z = implicit::expand("(x+0.3)^5 - (x+0.3)^4*(x+0.3) + y").unwrap();
    assert_eq!(z.terms.len(), 1);
}

#[test]
fn ray_polynomial_equals_f_along_the_ray() {
    let mut r = rng();
    for eq in sample_equations() {
        let shape = Implicit::new(&eq, Frame::identity(), Some(2.0)).unwrap();
        let c = Compiled::new(&implicit::expand(&eq).unwrap());
        let mut checked = 0;
        while checked < 40 {
            let o = DVec3::new(
                r.random_range(-4.0..4.0),
                r.random_range(-4.0..4.0),
                r.random_range(-4.0..4.0),
            );
            let d = DVec3::new(
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
            ) * r.random_range(0.01..100.0);
            let ray = Ray::new(o, d);
            let Some(rp) = shape.ray_polynomial(&ray) else {
                continue;
            };
            checked += 1;
            for _ in 0..10 {
                let s: f64 = r.random_range(-1.0..1.0);
                let t = rp.t_mid + s * rp.t_half;
                let p = ray.at(t).to_array();
                let direct = c.eval(p);
                let composed = rp.coeffs.iter().rev().fold(0.0, |acc, k| acc * s + k);
                let scale = magnitude(&c, p).max(rp.coeffs.iter().map(|k| k.abs()).sum::<f64>());
                assert!(
                    (direct - composed).abs() <= 1e-11 * scale,
                    "{eq}: ray {ray:?} s={s}: direct {direct}, composed {composed}"
                );
            }
        }
    }
}

#[test]
fn gradient_matches_finite_differences() {
    let mut r = rng();
    for eq in sample_equations() {
        let shape = Implicit::new(&eq, Frame::identity(), Some(2.0)).unwrap();
        for _ in 0..50 {
            let p = DVec3::new(
                r.random_range(-1.2..1.2),
                r.random_range(-1.2..1.2),
                r.random_range(-1.2..1.2),
            );
            let g = shape.gradient(p);
            let h = 1e-5;
            let fd = DVec3::new(
                shape.value(p + DVec3::X * h) - shape.value(p - DVec3::X * h),
                shape.value(p + DVec3::Y * h) - shape.value(p - DVec3::Y * h),
                shape.value(p + DVec3::Z * h) - shape.value(p - DVec3::Z * h),
            ) / (2.0 * h);
            let c = Compiled::new(&implicit::expand(&eq).unwrap());
            let scale = g.abs().max_element() + magnitude(&c, p.to_array());
            assert!(
                (g - fd).abs().max_element() <= 1e-6 * scale,
                "{eq} at {p}: gradient {g}, finite differences {fd}"
            );
        }
    }
}

#[test]
fn heart_preset_gradient_and_value_agree_with_the_generic_expansion() {
    let heart = Implicit::from_preset("heart", &[], Frame::identity(), None).unwrap();
    assert!(heart.is_heart());
    // Typed otherwise, the heart is still recognised; the generic path is asked for.
    let typed = "(2x^2 + y^2 + z^2 - 1)^3 = (0.1x^2 + y^2) z^3";
    assert!(Implicit::new(typed, Frame::identity(), None)
        .unwrap()
        .is_heart());
    let generic = Implicit::new_generic(typed, Frame::identity(), 2.0).unwrap();
    assert!(!generic.is_heart());
    let mut r = rng();
    for _ in 0..100 {
        let p = DVec3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        );
        assert!((heart.value(p) - generic.value(p)).abs() < 1e-12);
        assert!((heart.gradient(p) - generic.gradient(p)).length() < 1e-11);
    }
}

/// (equation, expected caret offset, expected caret length, expected words in the message)
const BAD: &[(&str, usize, usize, &str)] = &[
    ("", 0, 1, "empty"),
    ("   ", 0, 3, "empty"),
    ("x^2.5 + y", 2, 3, "whole number"),
    ("x^(-2) + y", 2, 4, "negative"),
    ("x^-2", 2, 2, "negative"),
    ("x^y", 2, 1, "whole number"),
    ("1/(x+1) + y", 2, 5, "only allowed by a constant"),
    ("x/0 + y", 2, 1, "division by zero"),
    ("x + w", 4, 1, "unknown variable 'w'"),
    ("sin(x) + y", 4, 1, "sin(…) of x, y or z"),
    ("sine(2) + y", 0, 4, "unknown function 'sine'"),
    ("sqrt(2) + y;;x", 11, 1, "nothing may follow"),
    ("(x + y", 0, 1, "never closed"),
    ("x + y)", 5, 1, "unmatched ')'"),
    ("((x+y)^2", 0, 1, "never closed"),
    ("x^17 + y", 0, 4, "degree 17"),
    ("(x^2 + y^2 + z^2)^9", 0, 19, "degree 18"),
    ("x^9 * y^8", 0, 9, "degree 17"),
    ("x + ", 4, 1, "ends too early"),
    ("x = ", 4, 1, "after '='"),
    ("x = y = z", 6, 1, "only one '='"),
    ("x² + y", 1, 2, "x^2"),
    ("x + y - x - y", 0, 13, "identically zero"),
    ("3 = 4", 0, 5, "does not involve"),
    ("x . y", 2, 1, "part of a number"),
    ("x + ()", 4, 2, "empty parentheses"),
    ("x + 10^400", 0, 10, "too large"),
    ("x + 1e400", 4, 5, "out of range"),
    ("(x + y", 0, 1, "never closed"),
    ("x + y +* z", 7, 1, "not '*'"),
];

#[test]
fn bad_equations_point_at_the_problem() {
    for &(eq, offset, len, words) in BAD {
        let e = Implicit::new(eq, Frame::identity(), Some(1.0)).unwrap_err();
        assert!(
            e.message.contains(words),
            "{eq:?}: message {:?} lacks {words:?}",
            e.message
        );
        assert_eq!((e.offset, e.len), (offset, len), "{eq:?}: {}", e.message);
    }
}

#[test]
fn bounds_are_derived_or_asked_for() {
    let sphere = Implicit::new("x^2 + y^2 + z^2 = 1", Frame::identity(), None).unwrap();
    assert!(
        sphere.bound() > 1.0 && sphere.bound() < 1.6,
        "{}",
        sphere.bound()
    );
    let s16 = Implicit::new("(x^2+y^2+z^2)^8 - 1", Frame::identity(), None).unwrap();
    assert!(s16.bound() > 1.0 && s16.bound() < 1.1, "{}", s16.bound());
    for unbounded in [
        "x^2 + y^2 = 1",
        "z = 0",
        "x^3 + y^3 + z^3 = 1",
        "x^2 - y^2 + z^2 = 1",
    ] {
        let e = Implicit::new(unbounded, Frame::identity(), None).unwrap_err();
        assert!(e.message.contains("BOUND"), "{unbounded}: {}", e.message);
    }
    // Every derived bound really holds the surface: f keeps one sign outside it.
    let mut r = rng();
    for eq in [
        "x^2 + y^2 + z^2 = 1",
        "(x^2+y^2+z^2)^8 - 1",
        "x^4 + y^4 + z^4 - 3x y z = 5",
    ] {
        let c = Compiled::new(&implicit::expand(eq).unwrap());
        let b = derive_bound(&c).unwrap();
        for _ in 0..2000 {
            let u = DVec3::new(
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
            )
            .normalize();
            let p = u * b * r.random_range(1.0..3.0);
            assert!(c.eval(p.to_array()) > 0.0, "{eq}: f ≤ 0 at {p}, bound {b}");
        }
    }
    assert!(Implicit::new("x^2 + y^2 = 1", Frame::identity(), Some(0.0)).is_err());
    // A preset's text keeps its default bound, even for unbounded presets.
    for (name, params) in [
        ("kummer", vec![1.2]),
        ("clebsch", vec![]),
        ("chmutov", vec![5.0]),
    ] {
        let p = preset(name, &params).unwrap();
        let s = Implicit::new(&p.equation, Frame::identity(), None).unwrap();
        assert_eq!(s.bound(), p.bound, "{name}");
        let s = Implicit::from_preset(name, &params, Frame::identity(), Some(0.5)).unwrap();
        assert_eq!(s.bound(), 0.5, "{name}");
    }
}

#[test]
fn presets_parse_and_reject_bad_parameters() {
    for (name, eq, bound) in all_presets() {
        assert!(bound > 0.0, "{name}");
        let p = implicit::expand(&eq).unwrap_or_else(|e| panic!("{name}: {eq}: {}", e.message));
        assert!(p.degree() >= 1 && p.degree() <= 16, "{name}");
    }
    assert_eq!(
        implicit::expand(&preset_equation("chmutov", &[16.0]).unwrap())
            .unwrap()
            .degree(),
        16
    );
    for (name, params) in [
        ("torus", vec![1.0]),
        ("torus", vec![1.0, -0.3]),
        ("kummer", vec![3f64.sqrt()]),
        ("chmutov", vec![17.0]),
        ("chmutov", vec![2.5]),
        ("chmutov", vec![0.0]),
        ("heart", vec![1.0]),
        ("dodecahedron", vec![]),
        ("torus", vec![f64::NAN, 1.0]),
    ] {
        assert!(preset(name, &params).is_err(), "{name} {params:?}");
    }
    // Torus: (R + r, 0, 0) and (R, 0, r) lie on it; the centre does not.
    let t =
        Compiled::new(&implicit::expand(&preset_equation("torus", &[1.0, 0.3]).unwrap()).unwrap());
    assert!(t.eval([1.3, 0.0, 0.0]).abs() < 1e-12);
    assert!(t.eval([1.0, 0.0, 0.3]).abs() < 1e-12);
    assert!(t.eval([0.0, 0.0, 0.0]) > 0.0);
    // Clebsch: the line z = −1, x + y = −2 (x₀ + x₄ = 0, x₁ + x₂ = 0, x₃ = 0) lies on it, and
    // so do its Eckardt points −v_i, where three lines meet.
    let c = Compiled::new(&implicit::expand(&preset_equation("clebsch", &[]).unwrap()).unwrap());
    for x in [-2.0, 0.3, 1.7] {
        assert!(c.eval([x, -2.0 - x, -1.0]).abs() < 1e-12);
    }
    for v in [
        [-1.0, -1.0, -1.0],
        [-1.0, 1.0, 1.0],
        [1.0, -1.0, 1.0],
        [1.0, 1.0, -1.0],
    ] {
        assert!(c.eval(v).abs() < 1e-12);
    }
    // It is the diagonal cubic: the same as x₀³ + … + x₄³ written with x₄ = −Σ_{i<4} x_i.
    let d = Compiled::new(
        &implicit::expand(
            "(x+y+z-1)^3 + (x-y-z-1)^3 + (-x+y-z-1)^3 + (-x-y+z-1)^3 \
             - ((x+y+z-1) + (x-y-z-1) + (-x+y-z-1) + (-x-y+z-1))^3",
        )
        .unwrap(),
    );
    assert_eq!(c, d);
}

#[test]
fn bounded_presets_fit_inside_their_default_bound() {
    let mut r = rng();
    for (name, params) in [
        ("heart", vec![]),
        ("taubin_heart", vec![]),
        ("torus", vec![1.0, 0.3]),
        ("torus", vec![0.5, 0.7]),
        ("chmutov", vec![2.0]),
        ("chmutov", vec![6.0]),
        ("chmutov", vec![16.0]),
    ] {
        let p = preset(name, &params).unwrap();
        let c = Compiled::new(&implicit::expand(&p.equation).unwrap());
        for _ in 0..3000 {
            let u = DVec3::new(
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
            )
            .normalize();
            let q = u * p.bound * r.random_range(1.0..2.0);
            assert!(
                c.eval(q.to_array()) > 0.0,
                "{name} {params:?}: f ≤ 0 at {q}"
            );
        }
    }
    // The heart's containing radius really contains it.
    let h = implicit::presets::HEART_RADIUS;
    let c = Compiled::new(&implicit::expand(implicit::HEART_EQUATION).unwrap());
    for _ in 0..3000 {
        let u = DVec3::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        )
        .normalize();
        assert!(c.eval((u * h * r.random_range(1.0..2.0)).to_array()) > 0.0);
    }
}

#[test]
fn kummer_and_barth_have_their_nodes() {
    // Kummer μ² = 1.3: a node at (±√(μ² − 1), 0, −1), where r·s = (1 + z)² − 2y² vanishes
    // to second order and the sphere term x² + z² − μ² = 0.
    let k = Implicit::new(
        &preset_equation("kummer", &[1.3f64.sqrt()]).unwrap(),
        Frame::identity(),
        Some(3.0),
    )
    .unwrap();
    let p = DVec3::new(0.3f64.sqrt(), 0.0, -1.0);
    assert!(k.value(p).abs() < 1e-12, "{}", k.value(p));
    assert!(k.gradient(p).length() < 1e-10, "{}", k.gradient(p));
    // Barth: nodes at radius 1 and √3, e.g. (1, 0, 0) and (1, 1, 1).
    let b = Implicit::new(
        &preset_equation("barth_sextic", &[]).unwrap(),
        Frame::identity(),
        Some(2.0),
    )
    .unwrap();
    for q in [DVec3::ONE, DVec3::X, DVec3::new(-1.0, 1.0, -1.0)] {
        assert!(b.value(q).abs() < 1e-12, "{}", b.value(q));
        assert!(b.gradient(q).length() < 1e-10, "{}", b.gradient(q));
    }
}

#[test]
fn long_and_deep_equations_are_safe() {
    // A long flat sum is fine (no deep recursion).
    let long = format!("x{}", " + x - y".repeat(50_000));
    let p = implicit::expand(&long).unwrap();
    assert_eq!(p.terms[&[1, 0, 0]], Coef::int(50_001));
    let long_product = format!("x{}", " * 1.5 / 1.5".repeat(20_000));
    assert_eq!(
        implicit::expand(&long_product).unwrap().terms[&[1, 0, 0]],
        Coef::ONE
    );
    // Deep nesting is refused with a clear message instead of overflowing the stack.
    let ok = format!("{}x{} + y", "(".repeat(150), ")".repeat(150));
    assert!(implicit::expand(&ok).is_ok());
    for deep in [
        format!("{}x{}", "(".repeat(5000), ")".repeat(5000)),
        format!("{}x", "-".repeat(5000)),
        format!("x{}", "^1".repeat(5000)),
    ] {
        let e = implicit::expand(&deep).unwrap_err();
        assert!(e.message.contains("nested too deeply"), "{}", e.message);
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(400))]

    /// Any text: no panic, and an error's caret lies within the text (or just past its end,
    /// for "ends too early"), on character boundaries.
    #[test]
    fn arbitrary_text_never_panics(eq in "[xyzw0-9 .()+*/^=eE²-]{0,40}") {
        match Implicit::new(&eq, Frame::identity(), Some(2.0)) {
            Ok(_) => {}
            Err(e) => {
                proptest::prop_assert!(e.offset <= eq.len(), "{eq:?}: {e:?}");
                proptest::prop_assert!(
                    e.offset == eq.len() || e.offset + e.len <= eq.len(),
                    "{eq:?}: {e:?}"
                );
                proptest::prop_assert!(eq.is_char_boundary(e.offset + e.len.min(eq.len() - e.offset)));
                proptest::prop_assert!(eq.is_char_boundary(e.offset.min(eq.len())));
                proptest::prop_assert!(!e.message.is_empty());
            }
        }
    }
}
