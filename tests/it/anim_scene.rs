//! Expressions, `LET`, `FRAMES` and the animation time in scene files: values against hand
//! computation, and errors with their caret and (when the value depends on the time) frame.

use kardia::scene::{parse, parse_animated, Animation, FrameTime, LoadOptions, Scene, SceneError};

const CAM: &str = "CAMERA (6, 0, 0) (0, 0, 0) (0, 0, 1) 40\n";

fn at_frame(text: &str, frame: u32, count: u32) -> Result<Scene, SceneError> {
    animated_at(text, frame, count).map(|(s, _)| s)
}

fn animated_at(text: &str, frame: u32, count: u32) -> Result<(Scene, Animation), SceneError> {
    let options = LoadOptions {
        time: Some(FrameTime { frame, count }),
        ..LoadOptions::default()
    };
    parse_animated(text, "t.scene", &options)
}

fn still(text: &str) -> Scene {
    still_animated(text).0
}

fn still_animated(text: &str) -> (Scene, Animation) {
    parse_animated(text, "t.scene", &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn expressions_and_let_give_hand_computed_values() {
    let text = format!(
        "{CAM}LET r = 0.5 + 0.25*clock\nLET side = 2*r\n\
         SPHERE (sin(pi/2), -1, 2^3) side (1, 0.5*(1 + 1), 0) SPECULAR 0.5 max(10, 4*frame)\n\
         LIGHT (1 -2 3) (1, 1, 1)\n"
    );
    let (s, animation) = animated_at(&text, 3, 5).unwrap();
    let b = s.objects[0].bounds;
    // clock = 3/4, r = 0.6875, radius = 1.375, centre (1, -1, 8).
    let r = 2.0 * (0.5 + 0.25 * 0.75);
    assert!((b.min.x - (1.0 - r)).abs() < 1e-6, "{b:?}");
    assert!((b.max.z - (8.0 + r)).abs() < 1e-6, "{b:?}");
    assert_eq!(s.objects[0].material.diffuse.y, 1.0);
    assert_eq!(s.objects[0].material.shininess, 12.0);
    // `(1 -2 3)`: a sign after a space still starts the next component.
    assert_eq!(s.lights[0].position.to_array(), [1.0, -2.0, 3.0]);
    assert!(animation.uses_time);
    assert_eq!(animation.frames, None);
}

#[test]
fn frames_statement_and_a_scene_without_time() {
    let (_, a) = still_animated(&format!(
        "{CAM}FRAMES 36 FPS 12\nSPHERE (0,0,0) 1 (1,1,1)\n"
    ));
    assert_eq!(a.frames, Some(36));
    assert_eq!(a.fps, 12.0);
    assert!(!a.uses_time);
    let (_, a) = still_animated(&format!("{CAM}frames 10\n"));
    assert_eq!((a.frames, a.fps), (Some(10), 24.0));
    let (_, a) = still_animated(&format!("{CAM}LET a = 2 * pi\nSPHERE (0,0,0) a (1,1,1)\n"));
    assert!(!a.uses_time, "pi is not the time");
    let (_, a) = still_animated(&format!("{CAM}SPHERE (0,0,0) 1 (1,1,1)\n"));
    assert_eq!(a, Animation::default());
}

#[test]
fn let_names_morph_presets_and_equations() {
    // kummer mu at frame 2 of 3 (clock = 1): mu = 1.4, the same surface as `kummer 1.4`.
    let basis = "(0,0,0) (1,0,0) (0,1,0) (0,0,1) (1,1,1)";
    let morph = format!("{CAM}LET mu = 0.8 + 0.6*clock\nIMPLICIT kummer mu {basis}\n");
    let fixed = format!("{CAM}IMPLICIT kummer 1.4 {basis}\n");
    let a = at_frame(&morph, 2, 3).unwrap();
    let b = still(&fixed);
    assert_eq!(
        format!("{:?}", a.objects[0].shape),
        format!("{:?}", b.objects[0].shape)
    );
    // A name inside a quoted equation reads as its decimal value.
    let named = format!("{CAM}LET r = 0.5 * 3\nIMPLICIT \"x^2 + y^2 + z^2 - r^2\" {basis}\n");
    let plain = format!("{CAM}IMPLICIT \"x^2 + y^2 + z^2 - 1.5^2\" {basis}\n");
    assert_eq!(
        format!("{:?}", still(&named).objects[0].shape),
        format!("{:?}", still(&plain).objects[0].shape)
    );
    let neg = format!("{CAM}LET a = -1\nIMPLICIT \"x^2 + y^2 + z^2 + a\" {basis}\n");
    let plain = format!("{CAM}IMPLICIT \"x^2 + y^2 + z^2 - 1\" {basis}\n");
    assert_eq!(
        format!("{:?}", still(&neg).objects[0].shape),
        format!("{:?}", still(&plain).objects[0].shape)
    );
    assert!(at_frame(&named, 0, 1).unwrap().objects.len() == 1);
}

/// The error of `text` at `frame` of `count`: its message and 1-based (line, column).
fn error_at(text: &str, frame: u32, count: u32) -> (String, (usize, usize)) {
    let e = at_frame(text, frame, count).expect_err("expected an error");
    let shown = format!(
        "{:?}",
        miette::Report::new(at_frame(text, frame, count).unwrap_err())
    );
    assert!(
        shown.contains('^') || shown.contains('─'),
        "no caret:\n{shown}"
    );
    (e.message(), e.location().unwrap())
}

#[test]
fn errors_that_appear_at_one_frame_name_it() {
    // Division by zero only at clock = 0.5 (frame 2 of 5).
    let text = format!("{CAM}SPHERE (0,0,0) 1/(clock - 0.5)^2 (1,1,1)\n");
    assert!(at_frame(&text, 1, 5).is_ok());
    let (m, at) = error_at(&text, 2, 5);
    assert!(m.contains("division by zero"), "{m}");
    assert!(m.ends_with("(at frame 2 of 0..=4, clock = 0.5)"), "{m}");
    assert_eq!(at, (2, 18)); // the caret under `(clock - 0.5)`
                             // A zero-length basis vector at the last frame.
    let text = format!("{CAM}LET s = 1 - clock\nHEART (0,0,0) (s,0,0) (0,1,0) (0,0,1) (1,0,0)\n");
    assert!(at_frame(&text, 8, 10).is_ok());
    let (m, at) = error_at(&text, 9, 10);
    assert!(m.contains("the basis vector u is the zero vector"), "{m}");
    assert!(m.contains("at frame 9 of 0..=9, clock = 1"), "{m}");
    assert_eq!(at, (3, 15));
    // sqrt of a negative number, in a LET.
    let text = format!("{CAM}LET a = sqrt(0.5 - clock)\n");
    let (m, at) = error_at(&text, 3, 4);
    assert!(m.contains("sqrt of a negative number (-0.5)"), "{m}");
    assert!(m.contains("at frame 3 of 0..=3"), "{m}");
    assert_eq!(at, (2, 14));
    // An equation whose degree passes 16 at frame 17.
    let text = format!(
        "{CAM}LET n = frame\nIMPLICIT \"x^n + y^2 + z^2 - 1\" (0,0,0) (1,0,0) (0,1,0) (0,0,1) (1,1,1) BOUND 2\n"
    );
    assert!(at_frame(&text, 16, 20).is_ok());
    let (m, _) = error_at(&text, 17, 20);
    assert!(m.contains("16"), "{m}");
    assert!(m.contains("at frame 17 of 0..=19"), "{m}");
    // Errors that do not depend on the time name no frame.
    let (m, _) = error_at(&format!("{CAM}SPHERE (0,0,0) 1/0 (1,1,1)\n"), 3, 4);
    assert!(
        m.contains("division by zero") && !m.contains("frame"),
        "{m}"
    );
}

#[test]
fn expression_and_let_errors_point_at_the_problem() {
    let cases: &[(&str, &str, (usize, usize))] = &[
        (
            "SPHERE (0,0,0) 1 + mu (1,1,1)",
            "unknown name `mu`",
            (2, 20),
        ),
        (
            "SPHERE (0,0,0) sin 1 (1,1,1)",
            "`sin` is a function",
            (2, 16),
        ),
        (
            "SPHERE (0,0,0) (1 + 2 (1,1,1)",
            "expected an operator or `)`",
            (2, 23),
        ),
        (
            "SPHERE (0,0,0) 2*3x (1,1,1)",
            "is an operator missing?",
            (2, 19),
        ),
        ("LET clock = 2", "`clock` is a built-in name", (2, 5)),
        ("LET a 2", "expected `=` after the name", (2, 7)),
        (
            "LET a = ",
            "expected the value of a (an expression)",
            (2, 8),
        ),
        (
            "LET a = 1\nLET a = 2",
            "`a` is already defined on line 2",
            (3, 5),
        ),
        (
            "FRAMES 0",
            "the number of frames must be a whole number",
            (2, 8),
        ),
        ("FRAMES 10 FPS 0", "the frame rate", (2, 15)),
        ("FRAMES 10\nFRAMES 12", "FRAMES is given twice", (3, 1)),
        ("FRAMES 2*frames", "FRAMES must not depend on clock", (2, 1)),
        ("LET a = 1 +", "ends too early", (2, 12)),
    ];
    for (statement, message, at) in cases {
        let text = format!("{CAM}{statement}\n");
        let e = parse(&text, "t.scene", &LoadOptions::default()).expect_err(statement);
        assert!(
            e.message().contains(message),
            "`{statement}`: `{}` lacks `{message}`",
            e.message()
        );
        assert_eq!(e.location(), Some(*at), "`{statement}`: {}", e.message());
    }
    // A typo of a defined name gets a suggestion.
    let text = format!("{CAM}LET radius = 1\nSPHERE (0,0,0) 2*radus (1,1,1)\n");
    let SceneError::Invalid(e) = parse(&text, "t.scene", &LoadOptions::default()).unwrap_err()
    else {
        panic!("expected an invalid scene");
    };
    assert_eq!(e.help.as_deref(), Some("did you mean `radius`?"));
}
