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

/// Runs `kardia probe` on the test scene with raw bytes on stdin; returns (exit code,
/// stdout lines).
fn probe_bytes(stdin: &[u8]) -> (i32, Vec<String>) {
    probe_scene_bytes(SCENE, stdin)
}

/// Runs `kardia probe` on the scene `text` with raw bytes on stdin; returns (exit code,
/// stdout lines).
fn probe_scene_bytes(text: &str, stdin: &[u8]) -> (i32, Vec<String>) {
    let mut scene = tempfile::Builder::new()
        .suffix(".scene")
        .tempfile()
        .unwrap();
    scene.write_all(text.as_bytes()).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_kardia"))
        .arg("probe")
        .arg(scene.path())
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = child.stdin.take().unwrap();
    let bytes = stdin.to_vec();
    let writer = std::thread::spawn(move || input.write_all(&bytes));
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap().unwrap();
    let text = String::from_utf8(out.stdout).unwrap();
    (
        out.status.code().unwrap_or(-1),
        text.lines().map(str::to_string).collect(),
    )
}

#[test]
fn probe_answers_huge_binary_and_extreme_lines_with_errors() {
    let mut input = Vec::new();
    input.extend_from_slice(&vec![b'7'; 1 << 20]); // A 1 MiB line.
    input.push(b'\n');
    input.extend_from_slice(b"6 0 0.1 -1 0 \xff\xfe\n"); // Not UTF-8.
    input.extend_from_slice(b"1e308 0 0 -1 0 0\n");
    input.extend_from_slice(b"6 0 0 -5e-324 0 0\n");
    input.extend_from_slice(b"6 0 0 -1 0 0 7 8 9 10\n");
    input.extend_from_slice(b"nan 0 0 -1 0 0\n");
    input.extend_from_slice(&vec![b' '; 10_000]);
    input.extend_from_slice(b"\n\0\0\0\n"); // Spaces (too long), then NULs (one field).
    input.extend_from_slice(b"6 0 0.1 -1 0 0"); // Last line without a newline.
    let (code, lines) = probe_bytes(&input);
    assert_eq!(code, 0);
    assert_eq!(lines.len(), 9, "{lines:#?}");
    let expect = [
        "line 1: longer than 4096 bytes",
        "line 2: not valid UTF-8",
        "line 3: '1e308' is outside the valid range of a coordinate, -1e6 to 1e6",
        "line 4: the direction (dx, dy, dz) is too short",
        "line 5: expected 6 numbers",
        "line 6: 'nan' is not a finite number",
        "line 7: longer than 4096 bytes",
        "line 8: expected 6 numbers 'ox oy oz dx dy dz', found 1 field",
    ];
    for (line, want) in lines.iter().zip(expect) {
        assert!(
            line.starts_with(&format!("{{\"error\":\"{want}")),
            "{line} should start with {want}"
        );
    }
    assert!(lines[8].starts_with(r#"{"hit":true,"#), "{}", lines[8]);
}

/// Lines for the probe fuzzer: rays built from extreme and ordinary numbers, garbage,
/// non-UTF-8 bytes, huge lines and odd separators.
fn fuzz_line(rng: &mut impl rand::Rng) -> Vec<u8> {
    use crate::fuzz_support::EXTREMES;
    let number = |rng: &mut dyn rand::RngCore| -> String {
        match rng.next_u32() % 4 {
            0 => EXTREMES[rng.next_u32() as usize % EXTREMES.len()].to_string(),
            1 => format!(
                "{:?}",
                (rng.next_u32() as f64 / u32::MAX as f64 - 0.5) * 20.0
            ),
            2 => [
                "1e6",
                "-1e6",
                "1000000.0000000001",
                "1e-6",
                "9.999999999999999e-7",
            ][rng.next_u32() as usize % 5]
                .to_string(),
            _ => format!("{}", rng.next_u32() % 10),
        }
    };
    match rng.random_range(0..10) {
        0 => (0..rng.random_range(0..200))
            .map(|_| rng.random())
            .collect(),
        1 => vec![b'1'; rng.random_range(4000..5000)],
        2 => {
            let sep = [" ", "\t", ",", " , ", "\r", "\u{a0}"][rng.random_range(0..6)];
            let n = rng.random_range(0..9);
            (0..n)
                .map(|_| number(rng))
                .collect::<Vec<_>>()
                .join(sep)
                .into_bytes()
        }
        _ => {
            // A ray from outside the objects towards them, with one number replaced.
            let mut v: Vec<String> = [6.0, 0.0, 0.1, -1.0, 0.0, 0.0]
                .iter()
                .map(|x: &f64| format!("{:?}", x + (rng.random::<f64>() - 0.5) * 0.5))
                .collect();
            let at = rng.random_range(0..6);
            v[at] = number(rng);
            v.join(" ").into_bytes()
        }
    }
}

/// 20 000 fuzzed lines against three scenes (one with every keyword): every line gets one
/// well-formed answer (a hit with finite numbers, a miss, or an error), and the probe exits
/// normally.
#[test]
fn probe_answers_every_fuzzed_line() {
    use rand::SeedableRng;
    let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(10);
    let scenes = [
        crate::fuzz_support::EVERY_KEYWORD,
        SCENE,
        include_str!("../../scenes/menagerie.scene"),
    ];
    for text in scenes {
        let mut input = Vec::new();
        let count = 20_000 / scenes.len();
        for _ in 0..count {
            let line = fuzz_line(&mut rng);
            let line: Vec<u8> = line.into_iter().filter(|&b| b != b'\n').collect();
            input.extend_from_slice(&line);
            input.push(b'\n');
        }
        let (code, lines) = probe_scene_bytes(text, &input);
        assert_eq!(code, 0);
        assert_eq!(lines.len(), count);
        for line in &lines {
            let ok = line == r#"{"hit":false}"#
                || (line.starts_with(r#"{"error":""#) && line.ends_with("\"}"))
                || (line.starts_with(r#"{"hit":true,"t":"#)
                    && line.ends_with('}')
                    && number(line, "t") > 0.0
                    && triple(line, "point").iter().all(|x| x.is_finite())
                    && triple(line, "normal").iter().all(|x| x.is_finite()));
            assert!(ok, "{line}");
            if line.starts_with(r#"{"hit""#) {
                assert!(!line.contains("NaN") && !line.contains("inf"), "{line}");
            }
        }
    }
}
