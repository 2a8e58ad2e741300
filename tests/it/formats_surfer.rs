//! SURFER's `.jsurf` and surf's `.pic` files read by kardia (`kardia::formats`): every key of
//! each format changes the translated scene as docs/surfer.md says; files written for these
//! tests render the expected camera, colours and clip (checked on pixels); and
//! `kardia convert` writes a scene that renders the same image as the file itself.

use std::path::Path;
use std::process::{Command, Output};

use kardia::formats::{self, Format, Translation};
use kardia::scene::LoadOptions;

use crate::render_support::{pixels, render, RenderSettings};

/// A plane `z = a` (a = 0.5) facing the camera, clipped by SURFER's view ball: a red disc of
/// radius √(1 − 0.25) ≈ 0.866 of the half height on blue, seen orthographically.
const JSURF: &str = "\
#written for kardia's tests
surface_equation=z - a
surface_parameter_a=0.5
scale_factor=0.0
rotation_matrix=1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1
camera_type=ORTHOGRAPHIC_CAMERA
camera_height=2.0
camera_transform=1 0 0 0 0 1 0 0 0 0 1 -1 0 0 0 1
background_color=0.0 0.0 1.0
front_material_color=1.0 0.0 0.0
back_material_color=0.0 1.0 0.0
front_material_ambient_intensity=0.4
front_material_diffuse_intensity=0.8
front_material_specular_iIntensity=0.0
front_material_shininess=30.0
light_position_0=0.0 0.0 100.0
light_color_0=1.0 1.0 1.0
light_intensity_0=1.0
light_status_0=ON
";

/// A surf script of the same kind: the plane z = 0.5 (surface units) scaled by 10 on the
/// screen, clipped by the ball of radius 8 (0.8 in surface units): a red disc of radius
/// √(0.64 − 0.25) ≈ 0.6245 surface units, 6.245 of the window's 10 screen units, on blue.
const PIC: &str = "\
// written for kardia's tests
width = 64; height = 64;
double a = 0.5;
poly f1 = z - a;
surface = f1;
scale_x = 0.1; scale_y = 0.1; scale_z = 0.1;
radius = 8.0;
surface_red = 255; surface_green = 0; surface_blue = 0;
inside_red = 0; inside_green = 255; inside_blue = 0;
background_red = 0; background_green = 0; background_blue = 255;
ambient = 40; diffuse = 80; reflected = 0; smoothness = 50;
light1_x = 0; light1_y = 0; light1_z = 100; light1_vol = 100;
light1_red = 255; light1_green = 255; light1_blue = 255;
draw_surface;
";

fn translate(format: Format, text: &str) -> Translation {
    formats::translate(format, text, "test")
        .unwrap_or_else(|e| panic!("{:?}", miette::Report::new(e)))
}

/// The 8-bit pixels of the file rendered at 64×64 with one sample a pixel.
fn rendered(format: Format, text: &str) -> Vec<[u8; 3]> {
    let t = translate(format, text);
    let scene = formats::parse_translation(&t, text, "test", &LoadOptions::default())
        .unwrap_or_else(|e| panic!("{:?}\n{}", miette::Report::new(e), t.text));
    let mut scene = scene;
    scene.width = 64;
    scene.height = 64;
    let settings = RenderSettings {
        spp: 1,
        max_depth: 2,
        seed: 1,
        threads: 2,
    };
    pixels(&render(&scene, &settings))
}

fn at(p: &[[u8; 3]], x: usize, y: usize) -> [u8; 3] {
    p[y * 64 + x]
}

fn is_red(c: [u8; 3]) -> bool {
    c[0] > 100 && c[1] < 30 && c[2] < 30
}

fn is_green(c: [u8; 3]) -> bool {
    c[1] > 100 && c[0] < 30 && c[2] < 30
}

fn is_blue(c: [u8; 3]) -> bool {
    c == [0, 0, 255]
}

#[test]
fn a_jsurf_renders_its_orthographic_camera_colours_and_clip() {
    let p = rendered(Format::Jsurf, JSURF);
    // The disc reaches 0.866 · 32 ≈ 27.7 pixels from the centre, the same along every row
    // of the orthographic view.
    for (x, y) in [
        (32, 32),
        (32 + 25, 32),
        (32 - 25, 32),
        (32, 32 + 25),
        (32, 8),
    ] {
        assert!(is_red(at(&p, x, y)), "({x}, {y}): {:?}", at(&p, x, y));
    }
    for (x, y) in [(32 + 30, 32), (2, 2), (32, 32 - 30), (61, 61)] {
        assert!(is_blue(at(&p, x, y)), "({x}, {y}): {:?}", at(&p, x, y));
    }
    // The back colour where the plane faces away (its gradient points away from the camera).
    let flipped = JSURF.replace("surface_equation=z - a", "surface_equation=a - z");
    let p = rendered(Format::Jsurf, &flipped);
    assert!(is_green(at(&p, 32, 32)), "{:?}", at(&p, 32, 32));
    // A perspective camera 3.2 from the centre with a vertical field of 40°: the plane z = 0
    // (a = 0) clipped to the unit ball is a disc of radius 1 / (3.2 · tan 20°) ≈ 0.86 of the
    // half height, 27.5 pixels: the pixel 30 from the centre, inside the orthographic disc,
    // is background.
    let perspective = JSURF
        .replace(
            "camera_type=ORTHOGRAPHIC_CAMERA",
            "camera_type=PERSPECTIVE_CAMERA\ncamera_fov_y=40",
        )
        .replace("0 0 1 -1 0 0 0 1", "0 0 1 -3.2 0 0 0 1")
        .replace("surface_parameter_a=0.5", "surface_parameter_a=0");
    let p = rendered(Format::Jsurf, &perspective);
    assert!(is_red(at(&p, 32 + 25, 32)), "{:?}", at(&p, 32 + 25, 32));
    assert!(is_blue(at(&p, 32 + 30, 32)), "{:?}", at(&p, 32 + 30, 32));
    let orthographic = JSURF.replace("surface_parameter_a=0.5", "surface_parameter_a=0");
    let p = rendered(Format::Jsurf, &orthographic);
    assert!(is_red(at(&p, 32 + 30, 32)), "{:?}", at(&p, 32 + 30, 32));
}

#[test]
fn a_pic_renders_its_camera_colours_clip_and_rotation() {
    let p = rendered(Format::Pic, PIC);
    // 6.245 of 10 screen units is 20 pixels.
    for (x, y) in [(32, 32), (32 + 17, 32), (32, 32 - 17)] {
        assert!(is_red(at(&p, x, y)), "({x}, {y}): {:?}", at(&p, x, y));
    }
    for (x, y) in [(32 + 23, 32), (32, 32 + 23), (2, 2)] {
        assert!(is_blue(at(&p, x, y)), "({x}, {y}): {:?}", at(&p, x, y));
    }
    // Turned half a turn about x, the plane faces away: the inside colour.
    let turned = PIC.replace(
        "surface = f1;",
        "surface = f1;\nsurface = rotate(surface, pi, xAxis);",
    );
    let p = rendered(Format::Pic, &turned);
    assert!(is_green(at(&p, 32, 32)), "{:?}", at(&p, 32, 32));
    assert!(is_blue(at(&p, 32 + 23, 32)), "{:?}", at(&p, 32 + 23, 32));
}

/// Each jsurf key, a value for it, and a piece of the scene text that value gives.
const JSURF_KEYS: &[(&str, &str, &str)] = &[
    (
        "surface_equation",
        "x^2 + y^2 - z - b",
        "IMPLICIT \"x^2 + y^2 - z - b\"",
    ),
    ("surface_parameter_a", "0.25", "LET a = 0.25"),
    ("surface_parameter_b", "2", "LET b = 2"),
    ("surface_parameter_c", "3", "LET c = 3"),
    ("surface_parameter_d", "-4", "LET d = -4"),
    ("scale_factor", "1", "(0.1, 0, 0) (0, 0.1, 0) (0, 0, 0.1)"),
    (
        "rotation_matrix",
        "0 1 0 0 -1 0 0 0 0 0 1 0 0 0 0 1",
        "(0, 1, 0) (-1, 0, 0) (0, 0, 1)",
    ),
    (
        "camera_type",
        "PERSPECTIVE_CAMERA",
        "CAMERA (0, 0, 1) (0, 0, 0) (0, 1, 0) 60",
    ),
    (
        "camera_transform",
        "1 0 0 0 0 1 0 0 0 0 1 -5 0 0 0 1",
        "CAMERA (0, 0, 3)",
    ),
    (
        "camera_fov_y",
        "30",
        "CAMERA (0, 0, 3) (0, 0, 2) (0, 1, 0) ORTHOGRAPHIC 2",
    ),
    ("camera_height", "3", "ORTHOGRAPHIC 3"),
    ("background_color", "1 1 1", "BACKGROUND (1, 1, 1)"),
    ("front_material_color", "1 1 1 1", "(1, 1, 1) SPECULAR"),
    ("back_material_color", "0 0 0", "INSIDE (0, 0, 0)"),
    (
        "front_material_ambient_intensity",
        "0.1",
        "AMBIENT (0.1, 0.1, 0.1)",
    ),
    (
        "front_material_diffuse_intensity",
        "0.5",
        "LIGHT (-100, 100, 101) (0.5, 0.5, 0.5)",
    ),
    (
        "front_material_specular_iIntensity",
        "0.7",
        "SPECULAR 0.7 30",
    ),
    (
        "front_material_specular_intensity",
        "0.6",
        "SPECULAR 0.6 30",
    ),
    ("front_material_shininess", "12", "SPECULAR 0.5 12"),
    (
        "back_material_ambient_intensity",
        "0.4",
        "AMBIENT (0.4, 0.4, 0.4)",
    ),
    (
        "back_material_diffuse_intensity",
        "0.8",
        "AMBIENT (0.4, 0.4, 0.4)",
    ),
    (
        "back_material_specular_iIntensity",
        "0.5",
        "SPECULAR 0.5 30",
    ),
    ("back_material_specular_intensity", "0.5", "SPECULAR 0.5 30"),
    ("back_material_shininess", "30", "SPECULAR 0.5 30"),
    (
        "light_position_0",
        "1 2 3",
        "LIGHT (1, 2, 4) (0.8, 0.8, 0.8)",
    ),
    (
        "light_color_0",
        "1 1 0",
        "LIGHT (-100, 100, 101) (0.8, 0.8, 0)",
    ),
    (
        "light_intensity_0",
        "0.5",
        "LIGHT (-100, 100, 101) (0.4, 0.4, 0.4)",
    ),
    ("light_status_0", "OFF", "#no light"),
    (
        "light_status_7",
        "ON",
        "LIGHT (-100, 100, 101) (0.8, 0.8, 0.8)\nLIGHT (-100, 100, 101)",
    ),
];

/// The smallest .jsurf the key table starts from (each row adds or replaces one key).
const JSURF_BASE: &str = "surface_equation=x^2 + y^2 + z^2 - 1\n";

#[test]
fn every_jsurf_key_changes_the_scene_as_documented() {
    let base = translate(Format::Jsurf, JSURF_BASE).text;
    assert!(
        base.contains("CAMERA (0, 0, 3) (0, 0, 2) (0, 1, 0) ORTHOGRAPHIC 2"),
        "{base}"
    );
    assert!(
        base.contains("LIGHT (-100, 100, 101) (0.8, 0.8, 0.8)"),
        "{base}"
    );
    assert!(base.contains("BOUND 1"), "{base}");
    for &(key, value, want) in JSURF_KEYS {
        let file = format!("{JSURF_BASE}{key}={value}\n");
        let text = translate(Format::Jsurf, &file).text;
        match want.strip_prefix('#') {
            Some("no light") => assert!(!text.contains("LIGHT"), "{key}: {text}"),
            _ => assert!(text.contains(want), "{key}={value}: no {want:?} in\n{text}"),
        }
        let t = translate(Format::Jsurf, &file);
        assert!(t.warnings.is_empty(), "{key}: {:?}", t.warnings);
    }
    // The table names every key the reader knows.
    for key in formats::jsurf::KEYS {
        assert!(
            JSURF_KEYS.iter().any(|(k, _, _)| k == key),
            "{key} has no test"
        );
    }
}

/// Each .pic setting, a value for it, and a piece of the scene text that value gives.
const PIC_KEYS: &[(&str, &str, &str)] = &[
    ("width", "100", "SIZE 100 512"),
    ("height", "100", "SIZE 512 100"),
    ("radius", "3", "BOUND 3"),
    ("scale_x", "0.5", "(2, 0, 0) (0, -1, 0) (0, 0, 1)"),
    ("scale_y", "0.5", "(1, 0, 0) (0, -2, 0) (0, 0, 1)"),
    ("scale_z", "0.25", "(1, 0, 0) (0, -1, 0) (0, 0, 4)"),
    (
        "rot_x",
        "pi",
        "(1, 0, 0) (0, 1, -0.00000000000000012246467991473532)",
    ),
    ("rot_y", "pi", "(-1, 0, 0.00000000000000012246467991473532)"),
    ("rot_z", "pi", "(-1, 0.00000000000000012246467991473532, 0)"),
    ("ambient", "10", "AMBIENT (0.1, 0.1, 0.1)"),
    ("diffuse", "100", "LIGHT (-100, -100, 100) (0.5, 0.5, 0.5)"),
    ("reflected", "20", "SPECULAR 0.2 13"),
    ("smoothness", "40", "SPECULAR 0.6 40"),
    ("background_red", "255", "BACKGROUND (1, 0, 0)"),
    ("background_green", "255", "BACKGROUND (0, 1, 0)"),
    ("background_blue", "255", "BACKGROUND (0, 0, 1)"),
    ("surface_red", "0", "(0, 0.6038273388553378, 0) SPECULAR"),
    ("surface_green", "0", "(1, 0, 0) SPECULAR"),
    ("surface_blue", "255", "(1, 0.6038273388553378, 1) SPECULAR"),
    ("inside_red", "0", "INSIDE (0, 0.3672464682101826, 0)"),
    ("inside_green", "0", "INSIDE (0.6038273388553378, 0, 0)"),
    (
        "inside_blue",
        "255",
        "INSIDE (0.6038273388553378, 0.3672464682101826, 1)",
    ),
    ("light1_x", "5", "LIGHT (5, -100, 100)"),
    ("light1_y", "5", "LIGHT (-100, -5, 100)"),
    ("light1_z", "5", "LIGHT (-100, -100, 5)"),
    (
        "light1_vol",
        "100",
        "LIGHT (-100, -100, 100) (0.6, 0.6, 0.6)",
    ),
    ("light1_red", "0", "LIGHT (-100, -100, 100) (0, 0.3, 0.3)"),
    ("light1_green", "0", "LIGHT (-100, -100, 100) (0.3, 0, 0.3)"),
    ("light1_blue", "0", "LIGHT (-100, -100, 100) (0.3, 0.3, 0)"),
    (
        "light9_vol",
        "100",
        "LIGHT (-100, -100, 100) (0.6, 0.6, 0.6)",
    ),
];

const PIC_BASE: &str = "surface = x^2 + y^2 + z^2 - 1;\n";

#[test]
fn every_pic_setting_changes_the_scene_as_documented() {
    let base = translate(Format::Pic, PIC_BASE).text;
    for want in [
        "SIZE 512 512",
        "CAMERA (0, 0, 1000) (0, 0, 0) (0, 1, 0) ORTHOGRAPHIC 20",
        "BACKGROUND (0, 0, 0)",
        "AMBIENT (0.35, 0.35, 0.35)",
        "LIGHT (-100, -100, 100) (0.3, 0.3, 0.3)",
        "IMPLICIT \"x^2 + y^2 + z^2 - 1\" (0, 0, 0) (1, 0, 0) (0, -1, 0) (0, 0, 1)",
        "BOUND 10",
    ] {
        assert!(base.contains(want), "no {want:?} in\n{base}");
    }
    for &(key, value, want) in PIC_KEYS {
        let file = format!("{PIC_BASE}{key} = {value};\n");
        let t = translate(Format::Pic, &file);
        assert!(
            t.text.contains(want),
            "{key} = {value}: no {want:?} in\n{}",
            t.text
        );
        // Unequal scales warn that the clip ball follows the smallest.
        assert_eq!(
            t.warnings.is_empty(),
            !key.starts_with("scale_"),
            "{key}: {:?}",
            t.warnings
        );
    }
    // Statements: double names become LET names, poly names are written out, rotate turns.
    let t = translate(
        Format::Pic,
        "double a = 2*0.25; int n = 3;\npoly f = x^n - a;\npoly g = f*y;\nsurface = g + z;\n\
         surface = rotate(surface, pi/2, zAxis);\ndraw_surface;\n",
    );
    assert!(t.text.contains("LET a = 0.5\nLET n = 3\n"), "{}", t.text);
    assert!(
        t.text.contains("IMPLICIT \"((x^n - a)*y) + z\""),
        "{}",
        t.text
    );
    assert!(t.text.contains("(0.00000000000000006123233995736766, 1, 0) (1, -0.00000000000000006123233995736766, 0)"), "{}", t.text);
    assert!(t.warnings.is_empty(), "{:?}", t.warnings);
}

#[test]
fn ignored_and_unknown_keys_are_warnings_naming_them() {
    let t = translate(
        Format::Jsurf,
        &format!("{JSURF_BASE}zoom=2\nlight_status_9=ON\n"),
    );
    let messages: Vec<(usize, String)> = t
        .warnings
        .iter()
        .map(|w| (w.line, w.message.clone()))
        .collect();
    assert_eq!(
        messages,
        vec![
            (3, "unknown key 'light_status_9' ignored".to_string()),
            (2, "unknown key 'zoom' ignored".to_string()),
        ]
    );
    let t = translate(
        Format::Pic,
        "antialiasing = 6;\nsurface = x - 1;\nzoom = 3; save_color_image;\nsurface2 = y;\n",
    );
    let messages: Vec<(usize, String)> = t
        .warnings
        .iter()
        .map(|w| (w.line, w.message.clone()))
        .collect();
    assert_eq!(
        messages,
        vec![
            (1, "'antialiasing' ignored".to_string()),
            (3, "unknown setting 'zoom' ignored".to_string()),
            (3, "'save_color_image' ignored".to_string()),
            (
                4,
                "'surface2' ignored: kardia draws one surface".to_string()
            ),
        ]
    );
}

#[test]
fn malformed_files_are_errors_at_their_line() {
    let cases: &[(Format, &str, usize, &str)] = &[
        (
            Format::Jsurf,
            "# only a comment\n",
            1,
            "needs a surface_equation",
        ),
        (
            Format::Jsurf,
            "surface_equation=x\nscale_factor=big\n",
            2,
            "scale_factor must be a number",
        ),
        (
            Format::Jsurf,
            "surface_equation=x\n\ncamera_type=FISHEYE\n",
            3,
            "unknown camera_type 'FISHEYE'",
        ),
        (
            Format::Jsurf,
            "surface_equation=x\nlight_status_2=MAYBE\n",
            2,
            "must be ON or OFF",
        ),
        (
            Format::Jsurf,
            "surface_equation=x\nrotation_matrix=1 0 0\n",
            2,
            "must be 16 numbers, not 3",
        ),
        (Format::Pic, "radius = 9;\n", 1, "needs a surface"),
        (
            Format::Pic,
            "surface = x;\nradius = 9 +;\n",
            2,
            "ends too early",
        ),
        (
            Format::Pic,
            "surface = x;\nsurface = rotate(surface, 1, wAxis);\n",
            2,
            "unknown axis 'wAxis'",
        ),
        (
            Format::Pic,
            "surface = x;\nfloat q = 1;\n",
            2,
            "unknown type 'float'",
        ),
        (
            Format::Pic,
            "surface = x;\nradius = x;\n",
            2,
            "must be a number",
        ),
    ];
    for &(format, text, line, words) in cases {
        let e = formats::translate(format, text, "bad").unwrap_err();
        let (got, _) = e.location().expect("a located error");
        assert_eq!(got, line, "{text:?}: {e}");
        assert!(e.to_string().contains(words), "{text:?}: {e}");
        assert!(e.to_string().starts_with(&format!("bad:{line}:")), "{e}");
    }
    // An equation kardia cannot read is reported at the file's line, quoting the scene line.
    let text = "# a comment\nsurface_parameter_a=1\nsurface_equation=sin(x) + a\n";
    let t = translate(Format::Jsurf, text);
    let e = formats::parse_translation(&t, text, "bad.jsurf", &LoadOptions::default()).unwrap_err();
    let message = e.to_string();
    assert!(message.starts_with("bad.jsurf:3:"), "{message}");
    assert!(message.contains("sin(…) of x, y or z"), "{message}");
    assert!(message.contains("IMPLICIT \"sin(x) + a\""), "{message}");
}

fn kardia(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kardia"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the kardia binary runs")
}

#[test]
fn convert_writes_a_scene_that_renders_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in [("plane.jsurf", JSURF), ("plane.pic", PIC)] {
        std::fs::write(dir.path().join(name), text).unwrap();
        let scene = format!("{name}.scene");
        let o = kardia(dir.path(), &["convert", name, "-o", &scene, "--quiet"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let size = ["--width", "48", "--height", "48", "--spp", "2", "--quiet"];
        let direct = kardia(
            dir.path(),
            &[&["render", name, "-o", "direct.png"][..], &size[..]].concat(),
        );
        assert!(
            direct.status.success(),
            "{}",
            String::from_utf8_lossy(&direct.stderr)
        );
        let via = kardia(
            dir.path(),
            &[&["render", &scene, "-o", "via.png"][..], &size[..]].concat(),
        );
        assert!(
            via.status.success(),
            "{}",
            String::from_utf8_lossy(&via.stderr)
        );
        let a = std::fs::read(dir.path().join("direct.png")).unwrap();
        let b = std::fs::read(dir.path().join("via.png")).unwrap();
        assert!(a == b, "{name}: the converted scene renders another image");
        // Without -o the scene goes to standard output.
        let o = kardia(dir.path(), &["convert", name]);
        let printed = String::from_utf8_lossy(&o.stdout).into_owned();
        assert_eq!(
            printed,
            std::fs::read_to_string(dir.path().join(&scene)).unwrap()
        );
    }
    // Warnings name the file, the line and the key.
    std::fs::write(
        dir.path().join("odd.jsurf"),
        format!("{JSURF_BASE}zoom=2\n"),
    )
    .unwrap();
    let o = kardia(dir.path(), &["convert", "odd.jsurf", "-o", "odd.scene"]);
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("kardia: warning: odd.jsurf:2: unknown key 'zoom' ignored"),
        "{err}"
    );
}

/// `--frames`, `--turntable`, `--tile` and `--region` read a foreign file through its
/// translation, as a still does: each file equals the one its converted scene gives, byte for
/// byte (render keys included), and the tiles join into the still.
#[test]
fn frames_turntables_and_tiles_of_a_foreign_file_render_its_translation() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (name, text) in [("plane.jsurf", JSURF), ("plane.pic", PIC)] {
        std::fs::write(d.join(name), text).unwrap();
        let scene = format!("{name}.scene");
        let o = kardia(d, &["convert", name, "-o", &scene, "--quiet"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let small = ["--width", "32", "--height", "32", "--spp", "1", "--quiet"];
        let runs: [(&[&str], &[&str]); 4] = [
            (
                &["--turntable", "3", "--frames", "0..2"],
                &["f_0.png", "f_1.png", "f_2.png"],
            ),
            (&["--tile", "0/2"], &["t_0.png"]),
            (&["--tile", "1/2"], &["t_1.png"]),
            (&["--region", "3,4,10,9"], &["r.png"]),
        ];
        for (options, files) in runs {
            for (input, prefix) in [(name, "direct"), (scene.as_str(), "via")] {
                let output = if files.len() > 1 {
                    format!("{prefix}_f_#.png")
                } else {
                    format!("{prefix}_{}", files[0])
                };
                let args = [&["render", input, "-o", &output][..], options, &small[..]].concat();
                let o = kardia(d, &args);
                assert!(
                    o.status.success(),
                    "{args:?}: {}",
                    String::from_utf8_lossy(&o.stderr)
                );
            }
            for file in files {
                let direct = std::fs::read(d.join(format!("direct_{file}"))).unwrap();
                let via = std::fs::read(d.join(format!("via_{file}"))).unwrap();
                assert!(direct == via, "{name} {options:?}: {file} differs");
            }
        }
        let o = kardia(
            d,
            &[&["render", name, "-o", "still.png"][..], &small[..]].concat(),
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let o = kardia(
            d,
            &[
                "assemble",
                "direct_t_0.png",
                "direct_t_1.png",
                "-o",
                "joined.png",
            ],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(
            std::fs::read(d.join("joined.png")).unwrap()
                == std::fs::read(d.join("still.png")).unwrap(),
            "{name}: the tiles do not join into the still"
        );
    }
}
