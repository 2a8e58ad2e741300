//! `kardia render --frames/--frame/--resume/--turntable/--tile`, animated outputs and
//! `kardia assemble`, end to end through the binary.

use std::path::Path;
use std::process::{Command, Output};

/// A small animated scene: a heart that moves and grows over 4 frames, with a soft light (so
/// the seed matters).
pub const SCENE: &str = "\
SIZE 40 32
FRAMES 4 FPS 8
LET s = 0.8 + 0.2*clock
CAMERA (6, 1.2, 0.9) (0, 0, 0.05) (0, 0, 1) 32
LIGHT (7, -4, 6) (0.9, 0.88, 0.85) 0.6 SAMPLES 2
HEART (0, 0.3*sin(2*pi*clock), 0) (s, 0, 0) (0, s, 0) (0, 0, s) (0.75, 0.04, 0.08) SPECULAR 0.6 80
PLANE (0, 0, -1.05) (0, 0, 1) (0.5, 0.5, 0.55)
";

/// Runs the kardia binary in `dir`.
pub fn kardia(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kardia"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the kardia binary runs")
}

/// Runs kardia and expects success.
pub fn ok(dir: &Path, args: &[&str]) {
    let out = kardia(dir, args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Runs kardia and expects failure (code 1); returns stderr with its words joined by single
/// spaces (miette wraps long messages and marks the continued lines with `│`).
fn refused(dir: &Path, args: &[&str]) -> String {
    let out = kardia(dir, args);
    assert_eq!(out.status.code(), Some(1), "{args:?} should fail");
    String::from_utf8_lossy(&out.stderr)
        .split_whitespace()
        .filter(|w| *w != "│")
        .collect::<Vec<_>>()
        .join(" ")
}

fn read(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

fn setup() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.scene"), SCENE).unwrap();
    dir
}

const COMMON: [&str; 4] = ["--spp", "2", "--quiet", "--threads"];

fn args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec!["render", "a.scene"];
    v.extend(COMMON);
    v.push("2");
    v.extend(extra);
    v
}

#[test]
fn one_frame_equals_that_frame_of_the_sequence() {
    let dir = setup();
    let d = dir.path();
    ok(d, &args(&["--frames", "0..3", "-o", "seq_####.png"]));
    let names: Vec<String> = (0..4).map(|f| format!("seq_{f:04}.png")).collect();
    for (f, name) in names.iter().enumerate() {
        let f = f.to_string();
        ok(d, &args(&["--frame", &f, "-o", "one.png"]));
        assert_eq!(read(d, "one.png"), read(d, name), "frame {f}");
    }
    // Frames differ from each other (the scene moves; the seeds differ too).
    assert_ne!(read(d, &names[0]), read(d, &names[1]));
    // Out of order, in two halves, gives the same files.
    ok(d, &args(&["--frames", "2..3", "-o", "half_####.png"]));
    ok(d, &args(&["--frames", "0..1", "-o", "half_####.png"]));
    for (f, name) in names.iter().enumerate() {
        assert_eq!(
            read(d, &format!("half_{f:04}.png")),
            read(d, name),
            "frame {f}"
        );
    }
    // Frame 0 of a scene is its still with the same seed: the same pixels. The files differ in
    // their render key only (a still is frame 0 of 1, not of 4), so `--resume` tells them apart.
    ok(d, &args(&["-o", "still.png"]));
    let pixels = |name: &str| image::open(d.join(name)).unwrap().to_rgb8().into_raw();
    assert_eq!(pixels("still.png"), pixels(&names[0]));
    let key = |name: &str| kardia::film::read_tag(&d.join(name), kardia::tiles::KEY_TAG);
    assert!(key("still.png").is_some() && key("still.png") != key(&names[0]));
}

#[test]
fn resume_skips_complete_frames_and_redoes_broken_ones() {
    let dir = setup();
    let d = dir.path();
    ok(d, &args(&["--frames", "0..3", "-o", "f_##.png"]));
    let good = read(d, "f_02.png");
    std::fs::write(d.join("f_02.png"), &good[..good.len() / 2]).unwrap(); // a truncated file
    std::fs::remove_file(d.join("f_03.png")).unwrap();
    let before = std::fs::metadata(d.join("f_00.png"))
        .unwrap()
        .modified()
        .unwrap();
    let out = kardia(
        d,
        &[
            "render", "a.scene", "--spp", "2", "--frames", "0..3", "--resume", "-o", "f_##.png",
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("2 frames of 40×32") && err.contains("2 already complete"),
        "{err}"
    );
    assert_eq!(read(d, "f_02.png"), good);
    assert!(d.join("f_03.png").is_file());
    let after = std::fs::metadata(d.join("f_00.png"))
        .unwrap()
        .modified()
        .unwrap();
    assert_eq!(before, after, "a complete frame was rewritten");
}

#[test]
fn turntable_orbits_without_editing_the_scene() {
    let dir = setup();
    let d = dir.path();
    ok(
        d,
        &args(&["--turntable", "8", "--frames", "0..7", "-o", "t_#.png"]),
    );
    ok(
        d,
        &args(&["--turntable", "8", "--frame", "5", "-o", "t5.png"]),
    );
    assert_eq!(read(d, "t5.png"), read(d, "t_5.png"));
    assert_ne!(read(d, "t_0.png"), read(d, "t_4.png"));
    let err = refused(
        d,
        &args(&["--turntable", "8", "--frame", "8", "-o", "x.png"]),
    );
    assert!(
        err.contains("frame 8 does not exist: --turntable 8 makes 8 frames"),
        "{err}"
    );
}

/// (frames, width, height) of a GIF.
fn gif_frames(path: &Path) -> (usize, u32, u32) {
    use image::AnimationDecoder;
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let frames: Vec<image::Frame> = image::codecs::gif::GifDecoder::new(file)
        .unwrap()
        .into_frames()
        .collect::<Result<_, _>>()
        .unwrap();
    let (w, h) = frames[0].buffer().dimensions();
    (frames.len(), w, h)
}

#[test]
fn animated_outputs_hold_every_frame() {
    let dir = setup();
    let d = dir.path();
    ok(d, &args(&["-o", "a.gif"]));
    assert_eq!(gif_frames(&d.join("a.gif")), (4, 40, 32));
    ok(
        d,
        &args(&["--frames", "1..2", "--width", "20", "-o", "b.gif"]),
    );
    assert_eq!(gif_frames(&d.join("b.gif")), (2, 20, 16));
    ok(d, &args(&["-o", "a.apng"]));
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(d.join("a.apng")).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let control = reader.info().animation_control.unwrap();
    assert_eq!((control.num_frames, control.num_plays), (4, 0));
    // Each APNG frame holds exactly the pixels of that frame's PNG.
    ok(d, &args(&["--frames", "0..3", "-o", "p_#.png"]));
    let mut buffer = vec![0; reader.output_buffer_size().unwrap()];
    for f in 0..4 {
        reader.next_frame(&mut buffer).unwrap();
        let still = image::open(d.join(format!("p_{f}.png"))).unwrap().to_rgb8();
        assert_eq!(&buffer[..], still.as_raw().as_slice(), "frame {f}");
    }
    // Only the animation is left: no temporary files.
    let hidden: Vec<String> = crate::cli_render::listing(d)
        .into_iter()
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(hidden.is_empty(), "{hidden:?}");
}

#[test]
fn sequences_need_a_frame_pattern_or_an_animated_output() {
    let dir = setup();
    let d = dir.path();
    let err = refused(d, &args(&["--frames", "0..3", "-o", "x.png"]));
    assert!(
        err.contains("4 frames need `####` in the output name"),
        "{err}"
    );
    let err = refused(d, &args(&["--frame", "4", "-o", "x.png"]));
    assert!(err.contains("the scene's FRAMES 4 makes 4 frames"), "{err}");
    let err = refused(d, &args(&["--tile", "0/2", "-o", "x.gif"]));
    assert!(
        err.contains("--tile and --region need a .png or .exr output"),
        "{err}"
    );
    // A value that goes bad only at the last frame names it.
    std::fs::write(
        d.join("bad.scene"),
        "CAMERA (6,0,0) (0,0,0) (0,0,1) 40\nFRAMES 3\nSPHERE (0,0,0) 1/(1 - clock) (1,1,1)\n",
    )
    .unwrap();
    let err = refused(
        d,
        &["render", "bad.scene", "--frames", "0..2", "-o", "b_#.png"],
    );
    assert!(err.contains("bad.scene:3:18"), "{err}");
    assert!(err.contains("division by zero"), "{err}");
    assert!(err.contains("at frame 2 of 0..=2, clock = 1"), "{err}");
    assert!(d.join("b_0.png").is_file() && !d.join("b_2.png").exists());
}

#[test]
fn tiles_assemble_into_the_single_render_byte_for_byte() {
    let dir = setup();
    let d = dir.path();
    for ext in ["png", "exr"] {
        let whole = format!("whole.{ext}");
        ok(d, &args(&["--frame", "2", "-o", &whole]));
        let mut parts = Vec::new();
        for i in 0..3 {
            let part = format!("band{i}.{ext}");
            let tile = format!("{i}/3");
            ok(d, &args(&["--frame", "2", "--tile", &tile, "-o", &part]));
            parts.push(part);
        }
        let joined = format!("joined.{ext}");
        let mut a = vec!["assemble", &parts[2], &parts[0], &parts[1], "-o", &joined];
        a.push("--quiet");
        ok(d, &a);
        assert_eq!(read(d, &joined), read(d, &whole), "{ext}");
    }
    // Regions of any shape join too.
    ok(d, &args(&["--region", "0,0,25,32", "-o", "left.png"]));
    ok(d, &args(&["--region", "25,0,15,20", "-o", "top_right.png"]));
    ok(
        d,
        &args(&["--region", "25,20,15,12", "-o", "bottom_right.png"]),
    );
    ok(d, &args(&["-o", "still.png"]));
    ok(
        d,
        &[
            "assemble",
            "left.png",
            "top_right.png",
            "bottom_right.png",
            "-o",
            "j.png",
        ],
    );
    assert_eq!(read(d, "j.png"), read(d, "still.png"));
}

#[test]
fn assemble_refuses_parts_that_do_not_fit() {
    let dir = setup();
    let d = dir.path();
    for i in 0..2 {
        let tile = format!("{i}/2");
        ok(d, &args(&["--tile", &tile, "-o", &format!("p{i}.png")]));
    }
    ok(
        d,
        &args(&["--tile", "1/2", "--seed", "9", "-o", "seed9.png"]),
    );
    ok(
        d,
        &args(&["--tile", "1/2", "--frame", "1", "-o", "frame1.png"]),
    );
    ok(
        d,
        &args(&["--tile", "1/2", "--width", "80", "-o", "wide.png"]),
    );
    ok(d, &args(&["--region", "0,10,40,10", "-o", "middle.png"]));
    ok(d, &args(&["-o", "plain.png"]));
    let mut other = SCENE.replace("0.75, 0.04", "0.05, 0.74");
    other.push('\n');
    std::fs::write(d.join("b.scene"), other).unwrap();
    ok(
        d,
        &[
            "render",
            "b.scene",
            "--spp",
            "2",
            "--tile",
            "1/2",
            "-o",
            "other.png",
        ],
    );
    ok(d, &args(&["--tile", "1/2", "-o", "p1.exr"]));

    let cases: &[(&[&str], &str)] = &[
        (
            &["p0.png"],
            "nothing holds the pixels in x 0..=39, y 16..=31 (640 pixels)",
        ),
        (
            &["p0.png", "p1.png", "middle.png"],
            "overlap (both hold pixel (0, 10))",
        ),
        (&["p0.png", "seed9.png"], "their seeds differ (0 against 9)"),
        (
            &["p0.png", "frame1.png"],
            "their frames differ (0 against 1)",
        ),
        (
            &["p0.png", "wide.png"],
            "their image sizes differ (40×32 against 80×64)",
        ),
        (
            &["p0.png", "other.png"],
            "their scenes or settings (render keys) differ",
        ),
        (&["p0.png", "plain.png"], "plain.png is not a kardia part"),
        (&["p0.png", "p1.exr"], "of different formats"),
        (
            &["p0.png", "missing.png"],
            "cannot read the part missing.png",
        ),
    ];
    for (parts, message) in cases {
        let mut a = vec!["assemble"];
        a.extend_from_slice(parts);
        a.extend(["-o", "out.png"]);
        let err = refused(d, &a);
        assert!(err.contains(message), "{parts:?}: {err}");
        assert!(!d.join("out.png").exists(), "{parts:?} wrote an output");
    }
}
