//! End-to-end tests of `kardia render`: the built binary on tiny images.

use std::path::Path;
use std::process::{Command, Output};

const SCENE: &str = "\
SIZE 40 30
CAMERA (0, -5, 1) (0, 0, 0) (0, 0, 1) 40
BACKGROUND (0.1, 0.1, 0.2)
AMBIENT (0.1, 0.1, 0.1)
LIGHT (3, -3, 5) (1, 1, 1) 0.5
SPHERE (0, 0, 0) 1 (0.8, 0.2, 0.2) SPECULAR 0.5 40
PLANE (0, 0, -1) (0, 0, 1) (0.5, 0.5, 0.5) REFLECT 0.2
";

/// A scene whose third line has an error (a sphere radius that is not a number).
const BAD_SCENE: &str = "\
SIZE 40 30
CAMERA (0, -5, 1) (0, 0, 0) (0, 0, 1) 40
SPHERE (0, 0, 0) oops (0.8, 0.2, 0.2)
";

fn kardia(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_kardia"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the kardia binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The names in a directory, sorted (the other test modules use it too).
pub(crate) fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

fn setup(scene: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("s.scene"), scene).unwrap();
    dir
}

#[test]
fn writes_png_quietly() {
    let dir = setup(SCENE);
    let o = kardia(
        dir.path(),
        &[
            "render", "s.scene", "-o", "out.png", "--spp", "2", "--quiet",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stderr(&o), "", "--quiet prints nothing");
    let img = image::open(dir.path().join("out.png")).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (40, 30));
    // The sphere is in the middle of the picture and reddish.
    let [r, g, b] = img.get_pixel(20, 15).0;
    assert!(r > g && r > b, "centre pixel {r} {g} {b}");
    assert_eq!(listing(dir.path()), ["out.png", "s.scene"]);
}

#[test]
fn writes_exr_float_and_half_with_size_overrides() {
    let dir = setup(SCENE);
    for (name, extra) in [("f.exr", None), ("h.exr", Some("--half"))] {
        let mut args = vec![
            "render",
            "s.scene",
            "-o",
            name,
            "--width",
            "24",
            "--height",
            "16",
            "--spp",
            "1",
            "--threads",
            "1",
            "--quiet",
        ];
        args.extend(extra);
        let o = kardia(dir.path(), &args);
        assert!(o.status.success(), "{}", stderr(&o));
        let read = exr::prelude::read_first_rgba_layer_from_file(
            dir.path().join(name),
            |res, _| (res.width(), res.height()),
            |_, _, _: (f32, f32, f32, f32)| {},
        )
        .unwrap();
        assert_eq!(read.layer_data.channel_data.pixels, (24, 16));
    }
    assert_eq!(listing(dir.path()), ["f.exr", "h.exr", "s.scene"]);
}

#[test]
fn prints_a_summary_line() {
    let dir = setup(SCENE);
    let o = kardia(
        dir.path(),
        &[
            "render",
            "s.scene",
            "-o",
            "a.png",
            "--spp",
            "4",
            "--threads",
            "2",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "{err}");
    let line = lines[0];
    assert!(
        line.starts_with("kardia: 40×30, 4 spp, 2 threads, ") && line.ends_with(" → a.png"),
        "{line}"
    );
    assert!(
        line.contains(" rays, ") && line.contains("rays/s"),
        "{line}"
    );
}

#[test]
fn same_seed_same_image_different_seed_different_image() {
    let dir = setup(SCENE);
    let run = |out: &str, seed: &str| {
        let o = kardia(
            dir.path(),
            &["render", "s.scene", "-o", out, "--seed", seed, "--quiet"],
        );
        assert!(o.status.success(), "{}", stderr(&o));
        std::fs::read(dir.path().join(out)).unwrap()
    };
    let a = run("a.png", "5");
    let b = run("b.png", "5");
    let c = run("c.png", "6");
    assert_eq!(a, b);
    assert_ne!(a, c);
}

#[test]
fn missing_output_directory_is_refused_before_rendering() {
    let dir = setup(SCENE);
    let o = kardia(dir.path(), &["render", "s.scene", "-o", "nowhere/out.png"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("nowhere") && err.contains("does not exist"),
        "{err}"
    );
    assert!(!err.contains("rays/s"), "nothing was rendered: {err}");
    assert_eq!(listing(dir.path()), ["s.scene"]);
}

#[test]
fn unknown_extension_is_refused() {
    let dir = setup(SCENE);
    let o = kardia(dir.path(), &["render", "s.scene", "-o", "out.jpg"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains(".png or .exr"), "{}", stderr(&o));
    assert_eq!(listing(dir.path()), ["s.scene"]);
}

#[test]
fn unreadable_scene_is_an_error() {
    let dir = setup(SCENE);
    let o = kardia(dir.path(), &["render", "missing.scene", "-o", "out.png"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.contains("missing.scene"), "{err}");
    assert_eq!(listing(dir.path()), ["s.scene"]);
}

#[test]
fn bad_scene_leaves_existing_output_untouched() {
    let dir = setup(BAD_SCENE);
    std::fs::write(dir.path().join("out.png"), b"previous image").unwrap();
    let o = kardia(dir.path(), &["render", "s.scene", "-o", "out.png"]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.contains("s.scene:3:"), "names file:line:column: {err}");
    assert!(err.contains("oops"), "shows the line: {err}");
    assert!(o.stdout.is_empty());
    assert_eq!(
        std::fs::read(dir.path().join("out.png")).unwrap(),
        b"previous image"
    );
    assert_eq!(listing(dir.path()), ["out.png", "s.scene"]);
}

#[test]
fn renders_the_built_in_heart_to_heart_png() {
    let dir = tempfile::tempdir().unwrap();
    let o = kardia(
        dir.path(),
        &[
            "render", "--width", "32", "--height", "32", "--spp", "1", "--quiet",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let img = image::open(dir.path().join("heart.png")).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (32, 32));
    // The heart is red and in the middle of the default view.
    let [r, g, b] = img.get_pixel(16, 14).0;
    assert!(r > 2 * g && r > 2 * b, "centre pixel {r} {g} {b}");
    assert_eq!(listing(dir.path()), ["heart.png"]);
}

#[test]
fn bad_arguments_exit_with_an_error() {
    let dir = setup(SCENE);
    for args in [
        &["render", "--spp", "0"][..],
        &["render", "--solver", "nonsense"],
        &["render", "--width", "0"],
    ] {
        let o = kardia(dir.path(), args);
        assert_ne!(o.status.code(), Some(0), "{args:?}");
        assert_eq!(listing(dir.path()), ["s.scene"]);
    }
}

#[cfg(unix)]
#[test]
fn interrupt_exits_130_and_writes_nothing() {
    let dir = setup(SCENE);
    let mut child = Command::new(env!("CARGO_BIN_EXE_kardia"))
        .args([
            "render", "s.scene", "-o", "out.png", "--width", "2000", "--height", "2000", "--spp",
            "64", "--quiet",
        ])
        .current_dir(dir.path())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(500));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{status:?}");
    assert_eq!(listing(dir.path()), ["s.scene"]);
}

/// SCENE without its floor: the sphere alone in front of the background.
fn sphere_alone() -> String {
    SCENE
        .lines()
        .filter(|l| !l.starts_with("PLANE"))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn alpha_png_is_rgba_with_transparent_background_and_partial_edges() {
    let dir = setup(&sphere_alone());
    let run = |args: &[&str]| {
        let o = kardia(dir.path(), args);
        assert!(o.status.success(), "{}", stderr(&o));
    };
    run(&[
        "render", "s.scene", "-o", "a.png", "--spp", "4", "--alpha", "--quiet",
    ]);
    run(&["render", "s.scene", "-o", "o.png", "--spp", "4", "--quiet"]);
    let alpha = image::open(dir.path().join("a.png")).unwrap();
    assert_eq!(alpha.color(), image::ColorType::Rgba8);
    let opaque = image::open(dir.path().join("o.png")).unwrap();
    assert_eq!(
        opaque.color(),
        image::ColorType::Rgb8,
        "no --alpha: RGB as before"
    );
    let (alpha, opaque) = (alpha.to_rgba8(), opaque.to_rgb8());
    for (x, y) in [(0, 0), (39, 0), (0, 29), (39, 29)] {
        assert_eq!(alpha.get_pixel(x, y).0, [0, 0, 0, 0], "corner ({x}, {y})");
    }
    let centre = alpha.get_pixel(20, 15).0;
    assert_eq!(centre[3], 255);
    assert_eq!(
        centre[..3],
        opaque.get_pixel(20, 15).0,
        "a covered pixel keeps its colour"
    );
    let partial = alpha.pixels().filter(|p| p[3] > 0 && p[3] < 255).count();
    assert!(
        partial > 10,
        "{partial} partly covered pixels on the silhouette"
    );

    run(&[
        "render", "s.scene", "-o", "a.exr", "--spp", "4", "--alpha", "--quiet",
    ]);
    let exr = exr::prelude::read_first_rgba_layer_from_file(
        dir.path().join("a.exr"),
        |res, _| vec![(0.0f32, 0.0f32, 0.0f32, 0.0f32); res.width() * res.height()],
        |v, pos, px: (f32, f32, f32, f32)| v[pos.y() * 40 + pos.x()] = px,
    )
    .unwrap();
    let px = &exr.layer_data.channel_data.pixels;
    assert_eq!(
        px[0],
        (0.0, 0.0, 0.0, 0.0),
        "premultiplied: a miss is all zero"
    );
    assert_eq!(px[15 * 40 + 20].3, 1.0);
}

#[test]
fn alpha_in_frames_and_apng_but_not_gif_or_parts() {
    let dir = setup(&sphere_alone());
    let o = kardia(
        dir.path(),
        &[
            "render",
            "s.scene",
            "--turntable",
            "2",
            "-o",
            "f_####.png",
            "--alpha",
            "--quiet",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    for frame in ["f_0000.png", "f_0001.png"] {
        let image = image::open(dir.path().join(frame)).unwrap();
        assert_eq!(image.color(), image::ColorType::Rgba8, "{frame}");
        assert_eq!(image.to_rgba8().get_pixel(0, 0).0[3], 0);
    }
    let o = kardia(
        dir.path(),
        &[
            "render",
            "s.scene",
            "--turntable",
            "2",
            "-o",
            "t.apng",
            "--alpha",
            "--quiet",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let reader = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(dir.path().join("t.apng")).unwrap(),
    ))
    .read_info()
    .unwrap();
    assert_eq!(reader.info().color_type, png::ColorType::Rgba);
    for (args, says) in [
        (
            &["-o", "t.gif", "--turntable", "2"][..],
            "GIF has only on/off transparency",
        ),
        (
            &["-o", "p.png", "--tile", "0/2"][..],
            "--alpha is not available for parts",
        ),
        (
            &["-o", "p.png", "--region", "0,0,8,8"][..],
            "--alpha is not available for parts",
        ),
    ] {
        let mut all = vec!["render", "s.scene", "--alpha", "--quiet"];
        all.extend_from_slice(args);
        let o = kardia(dir.path(), &all);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
    }
    assert!(!dir.path().join("t.gif").exists() && !dir.path().join("p.png").exists());
}

#[test]
fn a_solver_view_prints_its_legend_and_uses_its_colours() {
    let dir = setup("SIZE 48 36\nCAMERA (4, 0, 0.1) (0, 0, 0.1) (0, 0, 1) 40\nHEART (0, 0, 0) (1, 0, 0) (0, 1, 0) (0, 0, 1) (0.8, 0.1, 0.1)\n");
    let o = kardia(
        dir.path(),
        &[
            "render", "s.scene", "-o", "p.png", "--view", "path", "--spp", "1",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("path view: which method settled"), "{err}");
    assert!(err.contains("#4c9be8  Bernstein test"), "{err}");
    // The heart's middle: a ray the Bernstein test settles, in the legend's colour exactly.
    let img = image::open(dir.path().join("p.png")).unwrap().to_rgb8();
    assert_eq!(img.get_pixel(24, 18).0, [0x4c, 0x9b, 0xe8]);
    let quiet = kardia(
        dir.path(),
        &["render", "s.scene", "-o", "q.png", "--view", "roots", "-q"],
    );
    assert_eq!(stderr(&quiet), "");
}
