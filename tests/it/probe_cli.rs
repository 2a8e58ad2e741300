//! `kardia probe` end to end: the binary, a scene file, rays on stdin, JSON Lines out.

use std::io::Write;
use std::process::{Command, Stdio};

const SCENE: &str = "# probe test scene
SIZE 40 30
CAMERA (6, 0, 0) (0, 0, 0) (0, 0, 1) 30
BACKGROUND (0, 0, 0)
AMBIENT (0.1, 0.1, 0.1)
LIGHT (7, -4, 6) (1, 1, 1)
HEART (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.8, 0.1, 0.1)
SPHERE (0, 5, 0) 1 (0.5, 0.5, 0.5)
";

fn scene_file() -> tempfile::NamedTempFile {
    let mut f = tempfile::Builder::new()
        .suffix(".scene")
        .tempfile()
        .unwrap();
    f.write_all(SCENE.as_bytes()).unwrap();
    f
}

/// Runs `kardia probe` with `args` and `stdin`; returns (exit code, stdout, stderr).
fn probe(args: &[&str], stdin: &str) -> (i32, String, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_kardia"))
        .arg("probe")
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The probe may exit before reading its input (a bad scene, --pixel): a broken pipe here
    // is expected then.
    let _ = child.stdin.take().unwrap().write_all(stdin.as_bytes());
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

/// The number after `"key":` in a JSON line (test helper, not a JSON parser).
fn number(line: &str, key: &str) -> f64 {
    let at = line
        .find(&format!("\"{key}\":"))
        .unwrap_or_else(|| panic!("{key} in {line}"));
    let rest = &line[at + key.len() + 3..];
    let end = rest.find([',', '}']).unwrap();
    rest[..end].parse().unwrap()
}

/// The three numbers of `"key":[x,y,z]`.
fn triple(line: &str, key: &str) -> [f64; 3] {
    let at = line.find(&format!("\"{key}\":[")).unwrap();
    let rest = &line[at + key.len() + 4..];
    let inner = &rest[..rest.find(']').unwrap()];
    let v: Vec<f64> = inner.split(',').map(|s| s.parse().unwrap()).collect();
    [v[0], v[1], v[2]]
}

#[test]
fn probe_answers_each_stdin_line() {
    let scene = scene_file();
    let path = scene.path().to_str().unwrap();
    let input = "0 -5 0 0 2 0\n6 0 0.1 -1 0 0\n9 9 9 1 0 0\n1 2 three 4 5 6\n\n0 8 0 0 -1 0\n";
    let (code, out, err) = probe(&[path], input);
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 6, "{out}");
    // The heart's equator at Y = −1, in units of d = (0, 2, 0): t = 2 exactly.
    assert_eq!(
        lines[0],
        r#"{"hit":true,"t":2.0,"point":[0.0,-1.0,0.0],"normal":[0.0,-0.8944271909999159,-0.4472135954999579],"object":"HEART","line":7}"#
    );
    assert!(lines[1].starts_with(r#"{"hit":true,"#) && lines[1].contains(r#""line":7}"#));
    let p = triple(lines[1], "point");
    let t = number(lines[1], "t");
    assert_eq!(p, [6.0 - t, 0.0, 0.1]);
    let n = triple(lines[1], "normal");
    assert!((n[0] * n[0] + n[1] * n[1] + n[2] * n[2] - 1.0).abs() < 1e-15 && n[0] > 0.9);
    assert_eq!(lines[2], r#"{"hit":false}"#);
    assert!(
        lines[3].starts_with(r#"{"error":"line 4: 'three' is not a number"#),
        "{}",
        lines[3]
    );
    assert!(
        lines[4].starts_with(r#"{"error":"line 5: "#),
        "{}",
        lines[4]
    );
    // Every primitive answers: the sphere at (0, 5, 0), radius 1, from Y = 8 along −Y.
    assert_eq!(
        lines[5],
        r#"{"hit":true,"t":2.0,"point":[0.0,6.0,0.0],"normal":[0.0,1.0,0.0],"object":"SPHERE","line":8}"#
    );
}

#[test]
fn probe_pixel_is_the_camera_ray_through_the_pixel_centre() {
    let scene = scene_file();
    let path = scene.path().to_str().unwrap();
    // The camera at (6, 0, 0) looks at the origin; image 40×30: the centre of pixel (19, 14)
    // is half a pixel off the optical axis in each direction, so it hits the heart's front.
    let (code, out, err) = probe(&[path, "--pixel", "19,14"], "");
    assert_eq!(code, 0, "{err}");
    assert!(
        out.starts_with(r#"{"hit":true,"#) && out.contains(r#""object":"HEART","line":7}"#),
        "{out}"
    );
    assert_eq!(out.lines().count(), 1);
    // A corner pixel sees the background.
    let (code, out, _) = probe(&[path, "--pixel", "0,0"], "");
    assert_eq!((code, out.trim()), (0, r#"{"hit":false}"#));
    // Outside the image: an error, exit code 2.
    let (code, out, err) = probe(&[path, "--pixel", "40,0"], "");
    assert_eq!(code, 2);
    assert!(out.is_empty() && err.contains("outside"), "{err}");
}

#[test]
fn probe_solver_option_takes_every_listed_name() {
    let scene = scene_file();
    let path = scene.path().to_str().unwrap();
    for (_, name) in kardia::roots::Solver::ALL {
        let (code, out, err) = probe(&[path, "--solver", name], "0 -5 0 0 2 0\n");
        assert_eq!(code, 0, "{err}");
        assert!(out.starts_with(r#"{"hit":true,"t":2.0,"#), "{name}: {out}");
    }
    let (code, _, err) = probe(&[path, "--solver", "nope"], "");
    assert_eq!(code, 2);
    assert!(err.contains("sturm"), "{err}");
}

#[test]
fn probe_reports_a_bad_scene() {
    let mut f = tempfile::Builder::new()
        .suffix(".scene")
        .tempfile()
        .unwrap();
    // A singular basis (u ∥ v) on line 7.
    let bad = SCENE.replace(
        "(1, 0, 0) (0, 1, 0) (0, 0, 1)",
        "(1, 0, 0) (2, 0, 0) (0, 0, 1)",
    );
    f.write_all(bad.as_bytes()).unwrap();
    let (code, out, err) = probe(&[f.path().to_str().unwrap()], "0 -5 0 0 2 0\n");
    assert_eq!(code, 1);
    assert!(out.is_empty());
    assert!(err.contains(":7:"), "the error names line 7: {err}");
}
