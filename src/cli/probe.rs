//! `kardia probe`: intersect rays with a scene and print one JSON object per ray (JSON Lines).
//!
//! Input (stdin), one ray per line: six numbers `ox oy oz dx dy dz` (world space, separated by
//! spaces, tabs or commas; `d` need not be unit length). Output, one line per input line:
//! `{"hit":true,"t":…,"point":[x,y,z],"normal":[x,y,z],"object":"HEART","line":N}` (t in units
//! of the given d; point and unit outward normal in world space; line the scene-file line of the
//! object), or `{"hit":false}`, or `{"error":"…"}` for a line that is not a ray: not UTF-8,
//! not six numbers, a number outside the scene language's coordinate range (±1e6, see
//! [`crate::scene::limits`]), a zero or too short direction, or a line longer than
//! [`MAX_LINE`] bytes. Every input line gets exactly one answer, whatever it holds.

use crate::geometry::{DVec3, Ray};
use crate::roots::Solver;
use crate::scene::limits::{self, show};
use crate::scene::{self, LoadOptions, Scene};
use clap::Args;
use std::io::{self, BufRead, BufReader, Write};
use std::path::PathBuf;

/// Arguments of `kardia probe`.
#[derive(Debug, Args)]
pub struct ProbeArgs {
    /// Scene file.
    pub scene: PathBuf,
    /// Probe the camera's primary ray through the centre of pixel X,Y ((0,0) is the top-left
    /// pixel) instead of reading rays from stdin.
    #[arg(long, value_name = "X,Y", value_parser = parse_pixel)]
    pub pixel: Option<(u32, u32)>,
    /// Root-isolation strategy for polynomial surfaces (hearts, implicit surfaces).
    #[arg(long, value_name = "NAME", value_parser = parse_solver, help = solver_help())]
    pub solver: Option<Solver>,
}

/// The `--solver` help line, listing every name in [`Solver::ALL`].
fn solver_help() -> String {
    let names: Vec<&str> = Solver::ALL.iter().map(|(_, n)| *n).collect();
    format!(
        "Root-isolation strategy for polynomial surfaces: {} (default {})",
        names.join(", "),
        Solver::default().name()
    )
}

fn parse_solver(s: &str) -> Result<Solver, String> {
    s.parse()
}

/// Parses `X,Y` (two non-negative integers).
fn parse_pixel(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("expected X,Y (two whole numbers, e.g. 400,300), not '{s}'");
    let (x, y) = s.split_once(',').ok_or_else(bad)?;
    let x = x.trim().parse().map_err(|_| bad())?;
    let y = y.trim().parse().map_err(|_| bad())?;
    Ok((x, y))
}

/// Runs `kardia probe`; returns the exit code (0 success, 1 unreadable or invalid scene or an
/// output failure, 2 a pixel outside the image).
pub fn run(args: ProbeArgs) -> i32 {
    let options = LoadOptions {
        solver: args.solver.unwrap_or_default(),
        ..LoadOptions::default()
    };
    let scene = match scene::parse_file(&args.scene, &options) {
        Ok(scene) => scene,
        Err(e) => {
            eprintln!("{:?}", miette::Report::new(e));
            return 1;
        }
    };
    let stdout = io::stdout();
    let result = match args.pixel {
        Some((x, y)) => {
            if x >= scene.width || y >= scene.height {
                eprintln!(
                    "kardia probe: pixel {x},{y} is outside the {}×{} image (0,0 is the top-left pixel)",
                    scene.width, scene.height
                );
                return 2;
            }
            let ray = scene
                .camera
                .ray(x as f64 + 0.5, y as f64 + 0.5, scene.width, scene.height);
            let mut out = stdout.lock();
            writeln!(out, "{}", hit_json(&scene, &ray)).and_then(|_| out.flush())
        }
        None => probe_stream(&scene, BufReader::new(io::stdin().lock()), stdout.lock()),
    };
    match result {
        Ok(()) => 0,
        Err(e) if e.kind() == io::ErrorKind::BrokenPipe => 0,
        Err(e) => {
            eprintln!("kardia probe: {e}");
            1
        }
    }
}

/// Longest input line answered as a ray, in bytes without its line ending; a longer line
/// is answered with an error (and not kept in memory).
pub const MAX_LINE: usize = 4096;

/// Answers every line of `input` with one JSON line on `out`; output is flushed whenever the
/// input has no more data buffered, so an interactive caller gets each answer at once.
pub fn probe_stream<R: io::Read>(
    scene: &Scene,
    mut input: BufReader<R>,
    out: impl Write,
) -> io::Result<()> {
    let mut out = io::BufWriter::new(out);
    let mut raw = Vec::new();
    let mut number = 0usize;
    while let Some(too_long) = read_line_capped(&mut input, &mut raw, MAX_LINE)? {
        number += 1;
        let answer = if too_long {
            error_json(&format!(
                "line {number}: longer than {MAX_LINE} bytes, so not a ray"
            ))
        } else {
            match std::str::from_utf8(&raw) {
                Ok(text) => match parse_ray(text) {
                    Ok(ray) => hit_json(scene, &ray),
                    Err(why) => error_json(&format!("line {number}: {why}")),
                },
                Err(_) => error_json(&format!("line {number}: not valid UTF-8 text")),
            }
        };
        writeln!(out, "{answer}")?;
        if input.buffer().is_empty() {
            out.flush()?;
        }
    }
    out.flush()
}

/// Reads one line (up to and including `\n`, or to the end of the input) into `line`,
/// keeping at most `cap` bytes before the `\n`: `None` at the end of the input, else whether
/// the line was longer (then `line` is empty and the rest of it was skipped).
fn read_line_capped<R: BufRead>(
    input: &mut R,
    line: &mut Vec<u8>,
    cap: usize,
) -> io::Result<Option<bool>> {
    line.clear();
    let mut read_any = false;
    let mut too_long = false;
    loop {
        let available = match input.fill_buf() {
            Ok(b) => b,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if available.is_empty() {
            return Ok(read_any.then_some(too_long));
        }
        read_any = true;
        let newline = available.iter().position(|&b| b == b'\n');
        let chunk = &available[..newline.map_or(available.len(), |i| i + 1)];
        let content = chunk.len() - usize::from(newline.is_some());
        if !too_long && line.len() + content <= cap {
            line.extend_from_slice(chunk);
        } else {
            too_long = true;
            line.clear();
        }
        let used = chunk.len();
        input.consume(used);
        if newline.is_some() {
            return Ok(Some(too_long));
        }
    }
}

/// Parses `ox oy oz dx dy dz` (whitespace- or comma-separated finite numbers, non-zero
/// direction) into a world ray; the error says what is wrong with the line.
pub fn parse_ray(line: &str) -> Result<Ray, String> {
    let fields: Vec<&str> = line
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|f| !f.is_empty())
        .collect();
    if fields.len() != 6 {
        return Err(format!(
            "expected 6 numbers 'ox oy oz dx dy dz', found {} field{}",
            fields.len(),
            if fields.len() == 1 { "" } else { "s" }
        ));
    }
    let mut v = [0.0; 6];
    for (slot, field) in v.iter_mut().zip(&fields) {
        let shown = shorten(field);
        let x: f64 = field
            .parse()
            .map_err(|_| format!("'{shown}' is not a number"))?;
        if !x.is_finite() {
            return Err(format!("'{shown}' is not a finite number"));
        }
        if !limits::COORDINATE.contains(x) {
            return Err(format!(
                "'{shown}' is outside the valid range of a coordinate, {}",
                limits::COORDINATE
            ));
        }
        *slot = x;
    }
    let origin = DVec3::new(v[0], v[1], v[2]);
    let dir = DVec3::new(v[3], v[4], v[5]);
    if dir == DVec3::ZERO {
        return Err("the direction (dx, dy, dz) must not be zero".into());
    }
    if !limits::DIRECTION_LENGTH.contains(dir.length()) {
        return Err(format!(
            "the direction (dx, dy, dz) is too short: its length must be {}, not {}",
            limits::DIRECTION_LENGTH,
            show(dir.length())
        ));
    }
    Ok(Ray::new(origin, dir))
}

/// One ray's hit as its JSON line: the fields in this order, numbers in their shortest
/// round-trip form (serde_json).
#[derive(serde::Serialize)]
struct HitLine<'a> {
    hit: bool,
    t: f64,
    point: [f64; 3],
    normal: [f64; 3],
    object: &'a str,
    line: usize,
}

/// A missed ray's JSON line, `{"hit":false}`.
#[derive(serde::Serialize)]
struct MissLine {
    hit: bool,
}

/// An input line that is not a ray, `{"error":"…"}`.
#[derive(serde::Serialize)]
struct ErrorLine<'a> {
    error: &'a str,
}

/// `value` as one line of JSON (serde_json: strings escaped, numbers finite and read back
/// to the same bits).
fn to_json(value: &impl serde::Serialize) -> String {
    serde_json::to_string(value).unwrap_or_else(|e| format!(r#"{{"error":"{e}"}}"#))
}

/// The JSON answer for one ray: its first hit with `t > 0` in the scene (each shape keeps a
/// ray that starts on it from hitting its own origin), or `{"hit":false}`.
pub fn hit_json(scene: &Scene, ray: &Ray) -> String {
    let Some(hit) = scene.intersect(ray, 0.0, f64::INFINITY) else {
        return to_json(&MissLine { hit: false });
    };
    let object = &scene.objects[hit.object];
    let finite = hit.t.is_finite() && hit.point.is_finite() && hit.normal.is_finite();
    if !finite {
        return error_json("the intersection produced a non-finite number");
    }
    to_json(&HitLine {
        hit: true,
        t: hit.t,
        point: hit.point.to_array(),
        normal: hit.normal.to_array(),
        object: object.keyword,
        line: object.line,
    })
}

/// `{"error":"…"}` with the message escaped.
pub fn error_json(message: &str) -> String {
    to_json(&ErrorLine { error: message })
}

/// At most 30 characters of `field`, with `…` when cut.
fn shorten(field: &str) -> String {
    match field.char_indices().nth(30) {
        Some((i, _)) => format!("{}…", &field[..i]),
        None => field.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Camera;
    use crate::materials::Material;
    use crate::scene::Object;
    use crate::shapes::{Heart, Sphere};

    fn scene() -> Scene {
        Scene {
            width: 40,
            height: 30,
            camera: Camera::new(
                DVec3::new(6.0, 0.0, 0.1),
                DVec3::new(0.0, 0.0, 0.1),
                DVec3::Z,
                30.0,
            )
            .unwrap(),
            background: DVec3::ZERO,
            ambient: DVec3::ZERO,
            lights: Vec::new(),
            index: Default::default(),
            objects: vec![
                Object::new(
                    Box::new(Sphere::new(DVec3::new(0.0, 5.0, 0.0), 1.0).unwrap()),
                    Material::default(),
                    "SPHERE",
                    3,
                ),
                Object::new(
                    Box::new(Heart::new(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z).unwrap()),
                    Material::default(),
                    "HEART",
                    7,
                ),
            ],
        }
    }

    #[test]
    fn numbers_round_trip_and_stay_json() {
        let scene = scene();
        for x in [
            0.0,
            -0.0,
            1.0,
            -2.0,
            0.1,
            1e-7,
            1.5e300,
            123456789.0,
            f64::MIN_POSITIVE,
        ] {
            // A ray from (x, 9, 9) along +X misses everything: its origin's x is not
            // printed, so check the numbers through a hit line's fields directly.
            let line = to_json(&HitLine {
                hit: true,
                t: x,
                point: [x, -x, x],
                normal: [0.0, 0.0, 1.0],
                object: "HEART",
                line: 1,
            });
            let value: serde_json::Value = serde_json::from_str(&line).unwrap();
            assert_eq!(
                value["t"].as_f64().unwrap().to_bits(),
                x.to_bits(),
                "{line}"
            );
            assert_eq!(
                value["point"][1].as_f64().unwrap().to_bits(),
                (-x).to_bits()
            );
            assert!(!line.contains("inf") && !line.contains("NaN"));
        }
        let line = hit_json(&scene, &Ray::new(DVec3::new(0.0, -5.0, 0.0), DVec3::Y));
        assert!(
            line.starts_with(r#"{"hit":true,"t":4.0,"point":[0.0,-1.0,0.0],"normal":"#),
            "{line}"
        );
        assert_eq!(
            error_json("a\"b\\c\n\u{1}"),
            r#"{"error":"a\"b\\c\n\u0001"}"#
        );
    }

    #[test]
    fn parses_rays_and_explains_bad_lines() {
        let r = parse_ray("  1 2 3\t4,5 , 6 \r\n").unwrap();
        assert_eq!(
            r,
            Ray::new(DVec3::new(1.0, 2.0, 3.0), DVec3::new(4.0, 5.0, 6.0))
        );
        assert!(parse_ray("1 2 3 4 5")
            .unwrap_err()
            .contains("found 5 fields"));
        assert!(parse_ray("").unwrap_err().contains("found 0 fields"));
        assert!(parse_ray("1 2 3 4 5 x")
            .unwrap_err()
            .contains("'x' is not a number"));
        assert!(parse_ray("1 2 3 4 5 inf").unwrap_err().contains("finite"));
        assert!(parse_ray("1 2 3 0 0 0")
            .unwrap_err()
            .contains("must not be zero"));
    }

    #[test]
    fn stream_answers_every_line() {
        let input = b"6 0 0.1 -1 0 0\n0 0 0 0 0 0\n0 -5 0 0 2 0\n9 9 9 1 0 0\nbad\n6 0 0.1 -2 0 0";
        let mut out = Vec::new();
        probe_stream(&scene(), BufReader::new(&input[..]), &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 6, "{text}");
        assert!(lines[0].starts_with(r#"{"hit":true,"t":"#), "{}", lines[0]);
        assert!(
            lines[0].ends_with(r#","object":"HEART","line":7}"#),
            "{}",
            lines[0]
        );
        assert!(
            lines[1].starts_with(r#"{"error":"line 2: the direction"#),
            "{}",
            lines[1]
        );
        // From Y = −5 along +Y in the plane Z = 0: the heart's equator at Y = −1 (t = 2 in
        // units of d = 2), before the sphere behind it.
        assert!(
            lines[2].starts_with(r#"{"hit":true,"t":2.0,"point":[0.0,-1.0,0.0],"normal":"#),
            "{}",
            lines[2]
        );
        assert_eq!(lines[3], r#"{"hit":false}"#);
        assert!(lines[4].starts_with(r#"{"error":"line 5: expected 6 numbers"#));
        // t is in units of the given direction: twice as long a direction, half the t.
        let t = |l: &str| -> f64 {
            let rest = &l[l.find(r#""t":"#).unwrap() + 4..];
            rest[..rest.find(',').unwrap()].parse().unwrap()
        };
        // The front of the heart at Y = 0, Z = 0.1 is at X ≈ 0.70.
        assert!((t(lines[0]) - 5.3).abs() < 0.02, "{}", lines[0]);
        assert!((t(lines[0]) - 2.0 * t(lines[5])).abs() < 1e-12);
    }

    #[test]
    fn lines_are_capped_at_max_line_bytes() {
        let mut input = vec![b'1'; MAX_LINE];
        input.extend_from_slice(b"\r\n");
        input.extend_from_slice(&vec![b'2'; MAX_LINE + 1]);
        input.extend_from_slice(b"\nend");
        let mut reader = BufReader::with_capacity(64, &input[..]);
        let mut line = Vec::new();
        // The `\r` counts as content: MAX_LINE + 1 bytes before the `\n`.
        assert_eq!(
            read_line_capped(&mut reader, &mut line, MAX_LINE + 1).unwrap(),
            Some(false)
        );
        assert_eq!(line.len(), MAX_LINE + 2);
        assert_eq!(
            read_line_capped(&mut reader, &mut line, MAX_LINE).unwrap(),
            Some(true)
        );
        assert!(line.is_empty());
        assert_eq!(
            read_line_capped(&mut reader, &mut line, MAX_LINE).unwrap(),
            Some(false)
        );
        assert_eq!(line, b"end");
        assert_eq!(
            read_line_capped(&mut reader, &mut line, MAX_LINE).unwrap(),
            None
        );
    }

    #[test]
    fn rays_outside_the_coordinate_range_are_refused() {
        assert!(parse_ray("1e6 -1e6 0 1e-6 0 0").is_ok());
        let e = parse_ray("1000000.0000000001 0 0 1 0 0").unwrap_err();
        assert!(
            e.contains("outside the valid range of a coordinate, -1e6 to 1e6"),
            "{e}"
        );
        let e = parse_ray("0 0 0 1e-7 0 0").unwrap_err();
        assert!(e.contains("too short"), "{e}");
        let long = "9".repeat(500);
        let e = parse_ray(&format!("{long} 0 0 1 0 0")).unwrap_err();
        assert!(e.len() < 120, "{e}");
    }

    #[test]
    fn pixel_and_solver_arguments() {
        assert_eq!(parse_pixel("400,300"), Ok((400, 300)));
        assert_eq!(parse_pixel(" 0 , 0"), Ok((0, 0)));
        assert!(parse_pixel("1;2").is_err() && parse_pixel("-1,2").is_err());
        for (solver, name) in Solver::ALL {
            assert_eq!(parse_solver(name), Ok(*solver));
            assert!(solver_help().contains(name));
        }
        assert!(parse_solver("nope").is_err());
    }
}
