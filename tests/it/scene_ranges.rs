//! Every numeric parameter swept over its documented range (`kardia::scene::limits`, the
//! table in docs/scene-format.md): at each end and one step inside, the scene loads and a
//! tiny render has finite pixels; one step beyond, it is refused with a file:line:column
//! error at the number that states the range.

use crate::fuzz_support::renders_finite;
use kardia::scene::limits::{self, Limits};
use kardia::scene::{parse, LoadOptions, SceneError};

const HEAD: &str = "CAMERA (6, 1, 0.5) (0, 0, 0) (0, 0, 1) 40\nLIGHT (5, -3, 4) (0.9, 0.9, 0.9)\n";

/// Scene lines with `@` where the swept number goes, and the range that applies.
fn cases() -> Vec<(&'static str, Limits)> {
    vec![
        ("SIZE @ 9", limits::IMAGE_SIDE),
        ("SIZE 12 @", limits::IMAGE_SIDE),
        ("CAMERA2 (@, 1, 0.5) (0, 0, 0) (0, 0, 1) 40", limits::COORDINATE),
        ("CAMERA2 (6, 1, 0.5) (0, @, 0) (0, 0, 1) 40", limits::COORDINATE),
        ("CAMERA2 (6, 1, 0.5) (0, 0, 0) (0, 0, @) 40", limits::DIRECTION_LENGTH),
        ("CAMERA2 (6, 1, 0.5) (0, 0, 0) (0, 0, 1) @", limits::FIELD_OF_VIEW),
        ("BACKGROUND (@, 0.1, 0.1)", limits::COLOUR),
        ("AMBIENT (0.1, @, 0.1)", limits::COLOUR),
        ("LIGHT (@, 2, 3) (1, 1, 1)", limits::COORDINATE),
        ("LIGHT (4, 2, 3) (1, 1, @)", limits::INTENSITY),
        ("LIGHT (4, 2, 3) (1, 1, 1) @", limits::LIGHT_RADIUS),
        ("LIGHT (4, 2, 3) (1, 1, 1) 0.5 SAMPLES @", limits::LIGHT_SAMPLES),
        ("SPHERE (0, @, 0) 1 (0.5, 0.5, 0.5)", limits::COORDINATE),
        ("SPHERE (0, 0, 0) @ (0.5, 0.5, 0.5)", limits::LENGTH),
        ("SPHERE (0, 0, 0) 1 (@, 0.5, 0.5)", limits::COLOUR),
        ("SPHERE (0, 0, 0) 1 (0.5, 0.5, 0.5) SPECULAR @ 10", limits::SPECULAR_WEIGHT),
        ("SPHERE (0, 0, 0) 1 (0.5, 0.5, 0.5) SPECULAR 0.5 @", limits::SPECULAR_EXPONENT),
        ("SPHERE (0, 0, 0) 1 (0.5, 0.5, 0.5) REFLECT @", limits::WEIGHT),
        ("SPHERE (0, 0, 0) 1 (0.5, 0.5, 0.5) TRANSMIT @ IOR 1.5", limits::WEIGHT),
        ("SPHERE (0, 0, 0) 1 (0.5, 0.5, 0.5) TRANSMIT 1 IOR @", limits::IOR),
        (
            "SPHERE (0, 0, 0) 1 (0.5, 0.5, 0.5) TRANSMIT 1 ATTENUATION (@, 1, 0)",
            limits::ATTENUATION,
        ),
        ("SPHERE (0, 0, 0) 1 (0.5, 0.5, 0.5) INSIDE (0, @, 0)", limits::COLOUR),
        (
            "PLANE (0, 0, -1) (0, 0, 1) (0.9, 0.9, 0.9) CHECKER (@, 0.1, 0.1) 0.5",
            limits::COLOUR,
        ),
        (
            "PLANE (0, 0, -1) (0, 0, 1) (0.9, 0.9, 0.9) CHECKER (0.1, 0.1, 0.1) @",
            limits::LENGTH,
        ),
        ("PLANE (0, 0, -1) (0, @, 0) (0.9, 0.9, 0.9)", limits::DIRECTION_LENGTH),
        ("PLANE (0, 0, -1) (0, 0, @) (0.9, 0.9, 0.9)", limits::COORDINATE),
        (
            "BOX (@, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.5, 0.5, 0.5)",
            limits::COORDINATE,
        ),
        (
            "BOX (0, 0, 0) (1, 0, 0) (0, @, 0) (0, 0, 1) (0.5, 0.5, 0.5)",
            limits::DIRECTION_LENGTH,
        ),
        (
            "ELLIPSOID (0, 0, 0) (@, 0, 0) (0, 1, 0) (0, 0, 1) (0.5, 0.5, 0.5)",
            limits::DIRECTION_LENGTH,
        ),
        (
            "HEART (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, @) (0.5, 0.5, 0.5)",
            limits::DIRECTION_LENGTH,
        ),
        (
            "HEART (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, @) (0.5, 0.5, 0.5)",
            limits::COORDINATE,
        ),
        (
            "POLYGON 3 (0, 0, 0) (0, 1, 0) (0, 0, @) (0.5, 0.5, 0.5)",
            limits::COORDINATE,
        ),
        (
            "IMPLICIT \"x^2 + y^2 + z^2 - 1\" (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.5, 0.5, 0.5) BOUND @",
            limits::LENGTH,
        ),
        (
            "IMPLICIT torus @ 0.3 (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.5, 0.5, 0.5)",
            limits::LENGTH,
        ),
        (
            "IMPLICIT torus 1 @ (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.5, 0.5, 0.5)",
            limits::LENGTH,
        ),
        (
            "IMPLICIT kummer @ (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.5, 0.5, 0.5)",
            limits::KUMMER_MU,
        ),
        (
            "IMPLICIT chmutov @ (0, 0, 0) (0.6, 0, 0) (0, 0.6, 0) (0, 0, 0.6) (0.5, 0.5, 0.5)",
            limits::CHMUTOV_DEGREE,
        ),
    ]
}

/// The values swept for a range: `(value, inside)`.
fn sweep(l: &Limits) -> Vec<(f64, bool)> {
    let mut out = Vec::new();
    for (end, open, outward) in [(l.min, l.min_open, -1.0), (l.max, l.max_open, 1.0)] {
        if !end.is_finite() {
            continue;
        }
        let (step_in, step_out) = if l.whole {
            (end - outward, end + outward)
        } else if outward < 0.0 {
            (end.next_up(), end.next_down())
        } else {
            (end.next_down(), end.next_up())
        };
        out.push((end, !open));
        out.push((step_in, true));
        out.push((step_out, false));
        if l.whole {
            out.push((end - 0.5 * outward, false));
        }
    }
    out
}

/// The scene text for a line with `@` replaced by `x` (and `CAMERA2` standing for the camera).
fn scene_text(line: &str, x: f64) -> String {
    let line = line.replace('@', &format!("{x:?}"));
    match line.strip_prefix("CAMERA2") {
        Some(rest) => format!(
            "CAMERA{rest}\nLIGHT (5, -3, 4) (0.9, 0.9, 0.9)\nSPHERE (0, 0, 0) 1 (0.5, 0.5, 0.5)\n"
        ),
        None => format!("{HEAD}{line}\n"),
    }
}

fn render_is_finite(text: &str) -> bool {
    let scene = parse(text, "sweep.scene", &LoadOptions::default()).unwrap();
    renders_finite(&scene, 1)
}

#[test]
fn every_range_end_loads_and_renders_and_beyond_is_refused() {
    let mut checked = 0;
    for (line, l) in cases() {
        for (x, inside) in sweep(&l) {
            let text = scene_text(line, x);
            let written = format!("{x:?}");
            let line_no = if line.starts_with("CAMERA2") { 1 } else { 3 };
            match parse(&text, "sweep.scene", &LoadOptions::default()) {
                Ok(_) => {
                    assert!(inside, "{written} is outside {l} but was accepted:\n{text}");
                    assert!(render_is_finite(&text), "non-finite pixels:\n{text}");
                }
                Err(e) => {
                    assert!(
                        !inside,
                        "{written} is inside {l} but was refused: {e}\n{text}"
                    );
                    let (err_line, _) = e.location().unwrap();
                    assert_eq!(err_line, line_no, "{e}");
                    let message = e.message();
                    let (requirement, _) = l.violation(x);
                    assert!(
                        message.contains(&l.to_string()) || message.contains(&requirement),
                        "`{message}` does not state the range {l}\n{text}"
                    );
                    if let SceneError::Invalid(b) = &e {
                        let at = &text[b.span.offset()..b.span.offset() + b.span.len()];
                        assert!(
                            at.contains(&written),
                            "the error points at `{at}`, not at {written}"
                        );
                    }
                }
            }
            checked += 1;
        }
    }
    assert!(checked > 150, "{checked}");
}

/// A polygon's vertex count at its ends: 3 and 100 000 vertices load and render.
#[test]
fn polygon_vertex_counts() {
    let polygon = |n: u32| {
        let mut line = format!("POLYGON {n}");
        for k in 0..n {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            line.push_str(&format!(" (0, {:?}, {:?})", a.cos(), a.sin()));
        }
        format!("{HEAD}{line} (0.5, 0.5, 0.5)\n")
    };
    for n in [3, 100_000] {
        assert!(render_is_finite(&polygon(n)), "{n} vertices");
    }
    let e = parse(&polygon(100_001), "p", &LoadOptions::default()).unwrap_err();
    assert!(e.message().contains("from 3 to 100000"), "{e}");
    let e = parse(
        &format!("{HEAD}POLYGON 2 (0,0,0) (0,1,0) (1,1,1)\n"),
        "p",
        &LoadOptions::default(),
    )
    .unwrap_err();
    assert!(e.message().contains("at least 3 vertices"), "{e}");
}

/// Extreme values that were accepted before the ranges: refused now, with the range.
#[test]
fn values_that_overflowed_the_radiance_are_refused() {
    for (line, message) in [
        (
            "LIGHT (0, 0, 5) (1e308, 1, 1)",
            "the red component of the light's colour must be at most 1e6, not 1e308 (the valid range is 0 to 1e6)",
        ),
        (
            "SPHERE (0, 0, 0) 1 (2e6, 1, 1) SPECULAR 1e308 2",
            "the red component of the diffuse colour must be at most 1e6, not 2000000",
        ),
        (
            "PLANE (0, 0, -1) (0, 0, 1) (0.85, 0.85, 0.85) CHECKER (0.25, 0.25, 0.3) 11e-308",
            "the checker's cell size must be at least 1e-6, not 1.1e-307 (the valid range is 1e-6 to 1e6)",
        ),
        (
            "SPHERE (0, 0, 0) 1 (1, 1, 1) TRANSMIT 1 IOR 5e-324",
            "the index of refraction must be at least 0.01, not 5e-324",
        ),
        (
            "SPHERE (1e300, 0, 0) 1 (1, 1, 1)",
            "the x component of the sphere's centre must be at most 1e6, not 1e300",
        ),
    ] {
        let e = parse(&format!("{HEAD}{line}\n"), "t.scene", &LoadOptions::default()).unwrap_err();
        assert!(e.message().contains(message), "`{}` lacks `{message}`", e.message());
        assert!(e.to_string().starts_with("t.scene:3:"), "{e}");
    }
}
