//! Every kind of bad scene text gets one clear error: the right message at the right
//! line:column, with a caret display.

use kardia::scene::{parse, parse_file, LoadOptions, SceneError};

const CAM: &str = "CAMERA (0,0,0) (1,0,0) (0,0,1) 40\n";

/// Parses `text`, expects an error on line `line` at the first occurrence of `at` in that
/// line (or just after the line's last character when `at` is empty) whose message contains
/// `message`; returns the error. A `>` in `at` marks the expected column within the match
/// (`"IOR >0"` means the `0` after `IOR`).
fn check_text(text: &str, line: usize, at: &str, message: &str) -> SceneError {
    let e = match parse(text, "t.scene", &LoadOptions::default()) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e,
    };
    let src_line = text.split('\n').nth(line - 1).unwrap();
    let column = if at.is_empty() {
        src_line.trim_end().chars().count() + 1
    } else {
        let marker = at.find('>').unwrap_or(0);
        let pattern = at.replacen('>', "", 1);
        let i = src_line
            .find(&pattern)
            .unwrap_or_else(|| panic!("`{pattern}` not in `{src_line}`"));
        src_line[..i + marker].chars().count() + 1
    };
    assert!(
        e.message().contains(message),
        "message `{}` lacks `{message}` for:\n{text}",
        e.message()
    );
    assert_eq!(
        e.location(),
        Some((line, column)),
        "wrong place for `{}` in:\n{text}",
        e.message()
    );
    assert_eq!(
        e.to_string(),
        format!("t.scene:{line}:{column}: {}", e.message())
    );
    e
}

/// As [`check_text`] for a one-line statement after a valid camera (so on line 2).
fn check(statement: &str, at: &str, message: &str) -> SceneError {
    check_text(&format!("{CAM}{statement}\n"), 2, at, message)
}

fn help(e: &SceneError) -> String {
    match e {
        SceneError::Invalid(b) => b.help.clone().unwrap_or_default(),
        SceneError::Unreadable { .. } => String::new(),
    }
}

#[test]
fn unknown_keyword() {
    let e = check(
        "SPHER (0,0,0) 1 (1,1,1)",
        "SPHER",
        "unknown keyword `SPHER`",
    );
    assert!(help(&e).contains("did you mean SPHERE?"), "{}", help(&e));
    let e = check("TEAPOT 3", "TEAPOT", "unknown keyword `TEAPOT`");
    assert!(help(&e).contains("keywords: SIZE, CAMERA"), "{}", help(&e));
    check(
        "SPECULAR 0.5 10",
        "SPECULAR",
        "SPECULAR is a surface property, not a statement",
    );
    check(
        "42 (0,0,0)",
        "42",
        "expected a keyword at the start of the statement, found the number `42`",
    );
    check(
        "(0,0,0) 1",
        "(",
        "expected a keyword at the start of the statement, found `(`",
    );
}

#[test]
fn missing_numbers() {
    check(
        "SPHERE (0,0,0)",
        "",
        "expected the sphere's radius (a number), found end of line",
    );
    check(
        "SPHERE (0,0) 1 (1,1,1)",
        ")",
        "the sphere's centre has only 2 numbers: a vector needs 3",
    );
    check(
        "SIZE 800",
        "",
        "expected the image height (a number), found end of line",
    );
    check(
        "LIGHT (0,0,5)",
        "",
        "expected the light's colour, a vector (r, g, b), found end of line",
    );
    check(
        "SPHERE (0,0,0) 1",
        "",
        "expected a diffuse colour (r, g, b) or a material name, found end of line",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,1) SPECULAR 0.5",
        "",
        "expected the specular exponent (a number), found end of line",
    );
    check(
        "SPHERE (0,0,0 (1,1,1)",
        "(1,1,1)",
        "expected `)` to close the sphere's centre, found `(`",
    );
    check(
        "SPHERE (0,0,0 1 (1,1,1)",
        "1",
        "too many numbers in the sphere's centre",
    );
    check_text(
        "CAMERA (0,0,0) (1,0,0) (0,0,1)\n",
        1,
        "",
        "expected the field of view in degrees (a number), found end of line",
    );
}

#[test]
fn extra_numbers() {
    check(
        "SIZE 800 600 700",
        "700",
        "expected end of line, found the number `700`",
    );
    check(
        "SPHERE (0,0,0 7) 1 (1,1,1)",
        "7",
        "too many numbers in the sphere's centre: a vector has exactly 3",
    );
    check(
        "SPHERE (0,0,0) 1 2 (1,1,1)",
        "2",
        "expected a diffuse colour (r, g, b) or a material name, found the number `2`",
    );
    check(
        "LIGHT (0,0,5) (1,1,1) 0.5 3",
        "3",
        "expected end of line, found the number `3`",
    );
    check(
        "LIGHT (0,0,5) (1,1,1) 0.5 SAMPLES 4 9",
        "9",
        "expected end of line, found the number `9`",
    );
    check(
        "BACKGROUND (0,0,0) 1",
        "1",
        "expected end of line, found the number `1`",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,1) 5",
        "5",
        "expected a surface property or end of line, found the number `5`",
    );
}

#[test]
fn not_a_number() {
    check(
        "SPHERE (0,zero,0) 1 (1,1,1)",
        "zero",
        "expected the y component of the sphere's centre (a number), found `zero`",
    );
    check(
        "SIZE 800 tall",
        "tall",
        "expected the image height (a number), found `tall`",
    );
    check(
        "SPHERE (0,0,0) one (1,1,1)",
        "one",
        "expected the sphere's radius (a number), found `one`",
    );
    check(
        "SIZE 800, 600",
        ",",
        "expected the image height (a number), found `,`",
    );
    check(
        "SPHERE (0,,0,0) 1 (1,1,1)",
        ",0,0",
        "expected the y component of the sphere's centre (a number), found `,`",
    );
}

#[test]
fn nan_and_infinity() {
    check(
        "SPHERE (0,0,0) nan (1,1,1)",
        "nan",
        "the sphere's radius must be a finite number, but `nan` is not a number (NaN)",
    );
    check(
        "LIGHT (inf,0,0) (1,1,1)",
        "inf",
        "the x component of the light's position must be a finite number, but `inf` is infinite",
    );
    check(
        "SPHERE (0,0,0) 1e999 (1,1,1)",
        "1e999",
        "`1e999` is too large: it overflows a 64-bit float to infinity",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,-Infinity)",
        "-Infinity",
        "is infinite",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,1) IOR NaN",
        "NaN",
        "the index of refraction must be a finite number",
    );
}

#[test]
fn zero_length_directions() {
    check(
        "PLANE (1,2,3) (0,0,0) (1,1,1)",
        "(0,0,0)",
        "the plane's normal is the zero vector, but it must give a direction",
    );
    check(
        "HEART (0,0,0) (1,0,0) (0,1,0) (0, 0, 0) (1,0,0)",
        "(0, 0, 0)",
        "the basis vector w is the zero vector",
    );
    check(
        "ELLIPSOID (1,1,1) (0,0,0) (0,1,0) (0,0,1) (1,0,0)",
        "(0,0,0)",
        "the basis vector u is the zero vector",
    );
    check(
        "BOX (1,1,1) (1,0,0) (0,0,0) (0,0,1) (1,0,0)",
        "(0,0,0)",
        "the basis vector edge2 is the zero vector",
    );
    check_text(
        "CAMERA (1,1,1) (0,0,0) (0,0,0) 40\n",
        1,
        "(0,0,0) 40",
        "the up vector is the zero vector",
    );
}

#[test]
fn singular_bases() {
    check(
        "BOX (0,0,0) (1,0,0) (0,1,0) (1,1,0) (1,1,1)",
        "(1,0,0)",
        "edge1, edge2 and edge3 are linearly dependent",
    );
    check(
        "HEART (0,0,0) (1,0,0) (0,1,0) (2,0,0) (1,0,0)",
        "(1,0,0)",
        "u, v and w are linearly dependent",
    );
    check(
        "IMPLICIT \"x^2+y^2+z^2-1\" (0,0,0) (1,0,0) (1,0,0) (0,0,1) (1,0,0)",
        "(1,0,0)",
        "u, v and w are linearly dependent",
    );
}

#[test]
fn bad_radii() {
    check(
        "SPHERE (0,0,0) -1 (1,1,1)",
        "-1",
        "the sphere's radius must be greater than 0, not -1",
    );
    check(
        "SPHERE (1,1,1) 0 (1,1,1)",
        "0",
        "the sphere's radius must be greater than 0, not 0",
    );
    check(
        "LIGHT (0,0,5) (1,1,1) -0.5",
        "-0.5",
        "the light's radius must be at least 0, not -0.5",
    );
    check(
        "LIGHT (1,1,5) (1,1,1) 1.5 SAMPLES 0",
        "0",
        "the light's shadow samples must be a whole number from 1 to 1024, not 0",
    );
    check(
        "LIGHT (0,0,5) (1,1,1) 0.5 SAMPLES 2.5",
        "2.5",
        "the light's shadow samples must be a whole number from 1 to 1024, not 2.5",
    );
    check(
        "IMPLICIT \"x^2+y^2+z^2-1\" (0,0,0) (1,0,0) (0,1,0) (0,0,1) (1,0,0) BOUND 0",
        "BOUND >0",
        "the bounding radius must be greater than 0",
    );
}

#[test]
fn degenerate_cameras() {
    let e = check_text(
        "CAMERA (0,0,0) (1,0,0) (2,0,0) 40\n",
        1,
        "(2,0,0)",
        "degenerate camera: the up vector is zero or parallel to the view direction",
    );
    assert!(help(&e).contains("usage: CAMERA (eye) (look_at) (up) fov"));
    check_text(
        "CAMERA (0,0,0) (0,0,3) (0,0,1) 40\n",
        1,
        "(0,0,1)",
        "parallel to the view direction",
    );
    check_text(
        "CAMERA (0,0,0) (1,0,0) (0,0,1) 0.0\n",
        1,
        "0.0",
        "the field of view must be greater than 0 and less than 180 degrees, not 0",
    );
    check_text(
        "CAMERA (0,0,0) (1,0,0) (0,0,1) 180\n",
        1,
        "180",
        "less than 180 degrees, not 180",
    );
    check_text("CAMERA (0,0,0) (1,0,0) (0,0,1) -5\n", 1, "-5", "not -5");
    check_text(
        "CAMERA (1,1,1) (1,1,1) (0,0,1) 40\n",
        1,
        "(1,1,1)",
        "look_at must differ from eye",
    );
}

#[test]
fn missing_or_repeated_camera_and_size() {
    check_text(
        "SIZE 800 600\n# nothing else\n",
        1,
        "",
        "the scene has no CAMERA",
    );
    check_text("", 1, "", "the scene has no CAMERA");
    let e = check_text(
        &format!("{CAM}SIZE 8 8\nSIZE 9 9\n"),
        3,
        "SIZE",
        "SIZE is given twice (first on line 2)",
    );
    assert!(help(&e).contains("at most one SIZE"));
    check_text(
        &format!("{CAM}{CAM}"),
        2,
        "CAMERA",
        "CAMERA is given twice (first on line 1)",
    );
    check_text(
        &format!("{CAM}BACKGROUND (0,0,0)\nBACKGROUND (1,1,1)\n"),
        3,
        "BACKGROUND",
        "BACKGROUND is given twice (first on line 2)",
    );
    check_text(
        &format!("{CAM}AMBIENT (0,0,0)\nAMBIENT (1,1,1)\n"),
        3,
        "AMBIENT",
        "AMBIENT is given twice (first on line 2)",
    );
}

#[test]
fn unknown_materials() {
    let e = check(
        "SPHERE (0,0,0) 1 glass",
        "glass",
        "unknown material `glass`",
    );
    assert!(help(&e).contains("no MATERIAL is defined before this line"));
    let e = check_text(
        &format!("{CAM}SPHERE (0,0,0) 1 glass\nMATERIAL glass (1,1,1) TRANSMIT 0.9\n"),
        2,
        "glass",
        "unknown material `glass`",
    );
    assert!(
        help(&e).contains("defined on line 3, after this use"),
        "{}",
        help(&e)
    );
    let e = check_text(
        &format!("{CAM}MATERIAL Glass (1,1,1)\nSPHERE (0,0,0) 1 glass\n"),
        3,
        "glass",
        "unknown material `glass`",
    );
    assert!(help(&e).contains("did you mean `Glass`? (material names are case-sensitive)"));
    let e = check_text(
        &format!("{CAM}MATERIAL gold (1,0.8,0)\nMATERIAL silver (0.9,0.9,0.9)\nSPHERE (0,0,0) 1 sliver\n"),
        4,
        "sliver",
        "unknown material `sliver`",
    );
    assert!(help(&e).contains("did you mean `silver`?"));
    check_text(
        &format!("{CAM}MATERIAL m (1,1,1)\nMATERIAL m (0,0,0)\n"),
        3,
        "m (0",
        "material `m` is already defined on line 2",
    );
    check(
        "MATERIAL reflect (1,1,1)",
        "reflect",
        "`reflect` is a surface-property keyword",
    );
    check(
        "MATERIAL 3d (1,1,1)",
        "3d",
        "`3d` is not a valid material name",
    );
    check(
        "MATERIAL",
        "",
        "expected the material's name, found end of line",
    );
    check(
        "SPHERE (0,0,0) 1 SPECULAR 1 10",
        "SPECULAR",
        "expected a diffuse colour (r, g, b) or a material name before SPECULAR",
    );
}

#[test]
fn polygons() {
    check(
        "POLYGON 2 (0,0,0) (1,0,0) (1,1,1)",
        "2",
        "a polygon needs a whole number of at least 3 vertices, not 2",
    );
    check(
        "POLYGON 3.5 (0,0,0) (1,0,0) (0,1,0) (1,1,1)",
        "3.5",
        "at least 3 vertices, not 3.5",
    );
    check(
        "POLYGON (0,0,0) (1,0,0) (0,1,0) (1,1,1)",
        "(",
        "expected the number of vertices (a number), found `(`",
    );
    // A pentagon with its fourth vertex lifted out of the plane z = 0.
    check(
        "POLYGON 5 (0,0,0) (2,0,0) (2,1,0) (1,2,0.5) (0,1,0) (1,1,1)",
        "(1,2,0.5)",
        "invalid polygon: the polygon's vertices are not in one plane: vertex 4",
    );
    // A skew quadrilateral.
    check(
        "POLYGON 4 (0,0,0) (1,0,0) (1,1,0) (0,1,0.5) (1,1,1)",
        "(0,1,0.5)",
        "not in one plane: vertex 4 is 0.5 units off the plane of the others",
    );
    check(
        "POLYGON 3 (0,0,0) (1,1,1) (2,2,2) (1,1,1)",
        "(0,0,0)",
        "invalid polygon: the polygon has no area: all its vertices lie on one line",
    );
    check(
        "POLYGON 3 (1,1,1) (1,1,1) (1,1,1) (1,1,1)",
        "(1,1,1)",
        "are the same point",
    );
    check(
        "POLYGON 4 (0,0,0) (1,0,0) (0,1,0) red",
        "red",
        "expected vertex 4 of 4, a vector (x, y, z), found `red`",
    );
    check(
        "POLYGON 4 (0,0,0) (1,0,0) (0,1,0) (1,1,1)",
        "",
        "are there fewer vertices than the polygon's vertex count n",
    );
    let e = check(
        "POLYGON 3 (0,0,0) (1,0,0) (0,1,0) (1,1,0) (1,1,1)",
        "(1,1,1)",
        "is there one vertex more than the polygon's vertex count n?",
    );
    assert!(help(&e).contains("usage: POLYGON n"));
}

#[test]
fn image_sizes() {
    check(
        "SIZE 0 600",
        "0",
        "the image width must be a whole number from 1 to 32768, not 0",
    );
    check(
        "SIZE 800 40000",
        "40000",
        "the image height must be a whole number from 1 to 32768, not 40000",
    );
    check("SIZE 800.5 600", "800.5", "whole number");
    check("SIZE -8 600", "-8", "not -8");
    check("SIZE 32769 1", "32769", "not 32769");
}

#[test]
fn material_values() {
    check(
        "SPHERE (0,0,0) 1 (1,1,1) SPECULAR -1 10",
        "-1",
        "the specular weight ks must be at least 0, not -1",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,1) SPECULAR 0.4 0.5",
        "0.5",
        "the specular exponent must be at least 1, not 0.5",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,1) REFLECT 1.5",
        "1.5",
        "the reflection weight kr must be between 0 and 1, not 1.5",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,1) TRANSMIT -0.1",
        "-0.1",
        "the transmission weight kt must be between 0 and 1",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,1) IOR 0",
        "IOR >0",
        "the index of refraction must be greater than 0, not 0",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,1) ATTENUATION (0,-1,0)",
        "-1",
        "the green component of the attenuation must not be negative",
    );
    check(
        "SPHERE (0,0,0) 1 (1,-0.2,0)",
        "-0.2",
        "the green component of the diffuse colour must not be negative",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,1) CHECKER (0,0,0) 0",
        "(0,0,0) >0",
        "the checker's cell size must be greater than 0",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,1) INSIDE (-1,0,0)",
        "-1",
        "the red component of the inside colour must not be negative",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,1) REFLECT 0.1 REFLECT 0.2",
        "REFLECT 0.2",
        "REFLECT is given twice for this surface",
    );
    let e = check(
        "SPHERE (0,0,0) 1 (1,1,1) SPECULR 0.5 10",
        "SPECULR",
        "expected a surface property or end of line, found `SPECULR`",
    );
    assert!(help(&e).contains("did you mean SPECULAR?"));
    check(
        "BACKGROUND (-1,0,0)",
        "-1",
        "the red component of the background colour must not be negative",
    );
    check(
        "AMBIENT (0,0,-0.1)",
        "-0.1",
        "the blue component of the ambient light must not be negative",
    );
    check(
        "LIGHT (0,0,5) (1,-1,1)",
        "-1",
        "the green component of the light's colour must not be negative",
    );
    check(
        "SPHERE (0,0,0) 1 (1,1,1) BOUND 3",
        "BOUND",
        "BOUND applies only to IMPLICIT surfaces",
    );
}

#[test]
fn implicit_surfaces() {
    let basis = "(0,0,0) (1,0,0) (0,1,0) (0,0,1) (1,0,0)";
    let e = check(
        &format!("IMPLICIT tours 1 0.3 {basis}"),
        "tours",
        "unknown implicit-surface preset `tours`",
    );
    assert!(help(&e).contains("did you mean `torus`?"));
    check(
        &format!("IMPLICIT kummer 1 2 {basis}"),
        "2",
        "too many parameters: the preset kummer takes 1, not 2",
    );
    check(
        &format!("IMPLICIT torus 1 {basis}"),
        "(",
        "expected parameter 2 of torus, found `(`: the preset torus takes 2",
    );
    check(
        &format!("IMPLICIT torus 1 big {basis}"),
        "big",
        "expected parameter 2 of torus (a number), found `big`",
    );
    check(
        &format!("IMPLICIT \"x^2 {basis}"),
        "\"",
        "unterminated string",
    );
    check(
        &format!("IMPLICIT {basis}"),
        "(",
        "expected an equation in quotes or a preset name, found `(`",
    );
    check(
        &format!("IMPLICIT \"x^2+y^2+z^2-1\" {basis} BOUND 1 2"),
        "1 >2",
        "expected end of line, found the number `2`",
    );
    check(
        &format!("IMPLICIT \"x^2+y^2+z^2-1\" {basis} BOUND"),
        "",
        "expected the bounding radius (a number), found end of line",
    );
    check(
        "IMPLICIT \"x^2+y^2+z^2-1\" (0,0,0) (1,0,0) (0,1,0) (0,0,1) BOUND 2 (1,0,0)",
        "BOUND",
        "expected a diffuse colour (r, g, b) or a material name before BOUND",
    );
}

#[test]
fn comments_and_strings_do_not_confuse_positions() {
    // The error is on line 4, after a comment line, a blank line and multi-byte characters.
    check_text(
        &format!("# héart scene — comment\n\n{CAM}SPHERE (0,0,0) 1 (1,1,1) # ok\nSPHERE (0,0,0) x (1,1,1) # ß\n"),
        5,
        "x",
        "expected the sphere's radius (a number), found `x`",
    );
    // Column counts characters, not bytes.
    check_text(
        &format!("{CAM}MATERIAL é (1,1,1)\nSPHERE (0,0,0) 1 é REFLECT 2\n"),
        3,
        "2",
        "the reflection weight kr must be between 0 and 1, not 2",
    );
    // CRLF line endings.
    check_text(
        "CAMERA (0,0,0) (1,0,0) (0,0,1) 40\r\nSPHERE (0,0,0) -1 (1,1,1)\r\n",
        2,
        "-1",
        "greater than 0",
    );
}

#[test]
fn unreadable_file() {
    let e = parse_file(
        std::path::Path::new("/nonexistent-dir/missing.scene"),
        &LoadOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e, SceneError::Unreadable { .. }));
    assert!(
        e.to_string()
            .starts_with("cannot read scene file /nonexistent-dir/missing.scene: "),
        "{e}"
    );
    assert_eq!(e.location(), None);
    let dir = tempfile::tempdir().unwrap();
    let e = parse_file(dir.path(), &LoadOptions::default()).unwrap_err();
    assert!(e.to_string().starts_with("cannot read scene file"), "{e}");
    // Not UTF-8.
    let latin1 = dir.path().join("latin1.scene");
    std::fs::write(&latin1, b"# c\xe6ur\nCAMERA (6,0,0) (0,0,0) (0,0,1) 40\n").unwrap();
    let e = parse_file(&latin1, &LoadOptions::default()).unwrap_err();
    assert!(matches!(e, SceneError::Unreadable { .. }), "{e}");
    assert!(e.to_string().contains("UTF-8"), "{e}");
}

#[test]
fn report_shows_the_line_and_a_caret() {
    let e = check("SPHERE (0,0,0) -1 (1,1,1)", "-1", "greater than 0");
    let shown = format!("{:?}", miette::Report::new(e));
    assert!(
        shown.contains("t.scene:2:16: the sphere's radius must be greater than 0, not -1"),
        "{shown}"
    );
    assert!(shown.contains("SPHERE (0,0,0) -1 (1,1,1)"), "{shown}");
    assert!(shown.contains("must be > 0"), "{shown}");
    assert!(
        shown.contains("usage: SPHERE (centre) radius <surface>"),
        "{shown}"
    );
}

#[test]
fn equation_errors_point_inside_the_quotes() {
    let text =
        format!("{CAM}IMPLICIT \"x^2 + * y^2 = 1\" (0,0,0) (1,0,0) (0,1,0) (0,0,1) (1,0,0)\n");
    let e = check_text(&text, 2, "*", "invalid equation: ");
    let shown = format!("{:?}", miette::Report::new(e));
    assert!(shown.contains("here"), "{shown}");
}
