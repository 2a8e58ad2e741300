//! The farm recipes of examples/farm/ (docs/farm.md): GNU parallel over frames and tiles gives
//! the files of one sequential run; the Kubernetes manifest is a valid Indexed Job; the Slurm
//! scripts are valid shell with the array index and the dependent join step.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::anim_cli::{ok, SCENE};

fn recipe(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/farm")
        .join(name)
}

/// Runs a recipe script with the test's kardia binary, in `dir`, two jobs at a time.
fn run_recipe(dir: &Path, name: &str, args: &[&str]) {
    run_recipe_with(dir, name, args, "-j 2");
}

/// Runs a recipe script of examples/farm/ with the test's kardia binary, in `dir`, with
/// `parallel_opts` (GNU parallel's options, as `PARALLEL_OPTS`); fails the test with the
/// recipe's output when it fails.
pub(crate) fn run_recipe_with(dir: &Path, name: &str, args: &[&str], parallel_opts: &str) {
    let out = Command::new("bash")
        .arg(recipe(name))
        .args(args)
        .env("KARDIA", env!("CARGO_BIN_EXE_kardia"))
        .env("PARALLEL_OPTS", parallel_opts)
        .current_dir(dir)
        .output()
        .expect("bash runs");
    assert!(
        out.status.success(),
        "{name} {args:?} with {parallel_opts} failed (GNU parallel must be installed: \
         apt-get install parallel):\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn gnu_parallel_over_frames_gives_the_files_of_a_sequential_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.scene"), SCENE).unwrap();
    run_recipe(
        d,
        "parallel-frames.sh",
        &["a.scene", "farm", "--spp", "2", "--threads", "1"],
    );
    ok(
        d,
        &[
            "render",
            "a.scene",
            "--spp",
            "2",
            "--frames",
            "0..3",
            "--quiet",
            "-o",
            "seq_####.png",
        ],
    );
    let made = crate::cli_render::listing(&d.join("farm"));
    assert_eq!(
        made,
        [
            "frame_0000.png",
            "frame_0001.png",
            "frame_0002.png",
            "frame_0003.png"
        ]
    );
    for f in 0..4 {
        let farm = std::fs::read(d.join(format!("farm/frame_{f:04}.png"))).unwrap();
        let seq = std::fs::read(d.join(format!("seq_{f:04}.png"))).unwrap();
        assert_eq!(farm, seq, "frame {f}");
    }
}

#[test]
fn gnu_parallel_over_tiles_joins_into_the_single_render() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.scene"), SCENE).unwrap();
    run_recipe(
        d,
        "parallel-tiles.sh",
        &["a.scene", "4", "joined.png", "--spp", "2"],
    );
    ok(
        d,
        &[
            "render",
            "a.scene",
            "--spp",
            "2",
            "--quiet",
            "-o",
            "single.png",
        ],
    );
    assert_eq!(
        std::fs::read(d.join("joined.png")).unwrap(),
        std::fs::read(d.join("single.png")).unwrap()
    );
}

#[test]
fn the_kubernetes_manifest_is_an_indexed_job_over_frames() {
    use yaml_rust2::YamlLoader;
    let text = std::fs::read_to_string(recipe("k8s-indexed-job.yaml")).unwrap();
    let docs = YamlLoader::load_from_str(&text).expect("valid YAML");
    let job = docs
        .iter()
        .find(|d| d["kind"].as_str() == Some("Job"))
        .expect("a Job");
    let claim = docs
        .iter()
        .find(|d| d["kind"].as_str() == Some("PersistentVolumeClaim"))
        .expect("the shared volume's claim");
    let modes = claim["spec"]["accessModes"].as_vec().unwrap();
    assert!(modes.iter().any(|m| m.as_str() == Some("ReadWriteMany")));
    assert_eq!(job["apiVersion"].as_str(), Some("batch/v1"));
    assert_eq!(job["kind"].as_str(), Some("Job"));
    let spec = &job["spec"];
    assert_eq!(spec["completionMode"].as_str(), Some("Indexed"));
    // completions = the scene's FRAMES.
    let scene = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/heartbeat.scene"),
    )
    .unwrap();
    assert!(scene.contains(&format!(
        "FRAMES {} ",
        spec["completions"].as_i64().unwrap()
    )));
    assert!(spec["parallelism"].as_i64().unwrap() >= 1);
    let pod = &spec["template"]["spec"];
    assert_eq!(pod["restartPolicy"].as_str(), Some("Never"));
    let container = &pod["containers"][0];
    let command: Vec<&str> = container["args"]
        .as_vec()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap())
        .collect();
    let line = command.join(" ");
    assert!(line.contains("kardia render"), "{line}");
    assert!(line.contains("--frame \"$JOB_COMPLETION_INDEX\""), "{line}");
    assert!(line.contains("mkdir -p \"$OUT\""), "a fresh volume: {line}");
    assert!(line.contains("-o \"$OUT/frame_####.png\""), "{line}");
    let env = container["env"].as_vec().unwrap();
    let out = env
        .iter()
        .find(|e| e["name"].as_str() == Some("OUT"))
        .and_then(|e| e["value"].as_str())
        .unwrap();
    let mount = container["volumeMounts"][0]["mountPath"].as_str().unwrap();
    assert!(out.starts_with(mount), "the output is on the shared volume");
    assert_eq!(
        pod["volumes"][0]["persistentVolumeClaim"]["claimName"].as_str(),
        claim["metadata"]["name"].as_str()
    );
    assert!(
        text.contains("Kubernetes 1.29 or newer"),
        "the minimum version is stated"
    );
}

#[test]
fn the_slurm_scripts_are_valid_and_chain_the_join_after_the_array() {
    for name in [
        "slurm-frames.sbatch",
        "slurm-tiles.sbatch",
        "slurm-assemble.sbatch",
        "slurm-submit.sh",
        "parallel-frames.sh",
        "parallel-tiles.sh",
    ] {
        let out = Command::new("bash")
            .arg("-n")
            .arg(recipe(name))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let frames = std::fs::read_to_string(recipe("slurm-frames.sbatch")).unwrap();
    assert!(frames.contains("--frame \"$SLURM_ARRAY_TASK_ID\""));
    let tiles = std::fs::read_to_string(recipe("slurm-tiles.sbatch")).unwrap();
    assert!(tiles.contains("--tile \"$SLURM_ARRAY_TASK_ID/$TILES\""));
    let submit = std::fs::read_to_string(recipe("slurm-submit.sh")).unwrap();
    assert!(submit.contains("--dependency=afterany:\"$tiles_job\""));
    assert!(submit.contains("--print-frame-count") && !submit.contains("sed "));
    for name in ["parallel-frames.sh", "parallel-tiles.sh"] {
        let text = std::fs::read_to_string(recipe(name)).unwrap();
        assert!(text.contains("--halt soon,fail=1") && !text.contains("--halt now"));
    }
}

#[test]
fn exr_files_are_the_same_bytes_whatever_the_threads() {
    // 320×256 holds 20 blocks of 64×64: enough for the blocks to finish in any order.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.scene"), SCENE).unwrap();
    for (half, name) in [(false, "float"), (true, "half")] {
        let render = |threads: &str, out: &str| {
            let mut a = vec![
                "render",
                "a.scene",
                "--width",
                "320",
                "--spp",
                "1",
                "--quiet",
                "--threads",
                threads,
                "-o",
                out,
            ];
            if half {
                a.push("--half");
            }
            ok(d, &a);
            std::fs::read(d.join(out)).unwrap()
        };
        let first = render("2", &format!("{name}_a.exr"));
        for (threads, out) in [("2", "b"), ("1", "c"), ("2", "d"), ("2", "e")] {
            let again = render(threads, &format!("{name}_{out}.exr"));
            assert!(
                first == again,
                "{name} EXR on {threads} thread(s) differs from the first render's bytes"
            );
        }
    }
}

/// A scene of many hearts (the object hierarchy's four-ray walks) for the code-path test.
const HEART_GRID: &str = "\
SIZE 96 96
CAMERA (12, 0, 0) (0, 0, 0) (0, 0, 1) 30
LIGHT (9, -4, 6) (0.9, 0.88, 0.85) 0.6 SAMPLES 2
MATERIAL ruby (0.8, 0.1, 0.1) SPECULAR 0.4 40
REPEAT i FROM 0 TO 7
  REPEAT j FROM 0 TO 7
    HEART (0, (j - 3.5) * 0.8, (i - 3.5) * 0.8) (0.3, 0, 0) (0, 0.3, 0) (0, 0, 0.3) ruby
  END
END
";

#[test]
fn the_baseline_and_avx2_code_paths_write_the_same_bytes() {
    // Every routine with an AVX2 or FMA copy promises its baseline copy's bits: a farm of
    // mixed processors makes one picture. KARDIA_CPU=baseline forces the baseline copies.
    let kardia = env!("CARGO_BIN_EXE_kardia");
    let version = |baseline: bool| {
        let mut c = Command::new(kardia);
        c.arg("--version");
        if baseline {
            c.env("KARDIA_CPU", "baseline");
        } else {
            c.env_remove("KARDIA_CPU");
        }
        String::from_utf8(c.output().unwrap().stdout).unwrap()
    };
    assert!(
        version(true).contains("code path: baseline"),
        "{}",
        version(true)
    );
    let detected = version(false);
    if detected.contains("code path: baseline") {
        eprintln!(
            "WARNING: this processor has neither AVX2 nor FMA: both runs take the baseline, \
             so this test compares the baseline with itself ({detected})"
        );
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("grid.scene"), HEART_GRID).unwrap();
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let cases = [
        (scenes.join("menagerie.scene"), "160"),
        (scenes.join("glass_heart.scene"), "120"),
        (scenes.join("implicit/barth_sextic.scene"), "120"),
        (scenes.join("implicit/chmutov.scene"), "120"),
        (scenes.join("implicit/sphere16.scene"), "100"),
        (d.join("grid.scene"), "96"),
    ];
    for (scene, width) in &cases {
        for format in ["png", "exr"] {
            let render = |baseline: bool| {
                let out = d.join(format!("out_{baseline}.{format}"));
                let mut c = Command::new(kardia);
                c.arg("render")
                    .arg(scene)
                    .args([
                        "--width",
                        width,
                        "--spp",
                        "2",
                        "--threads",
                        "2",
                        "--quiet",
                        "-o",
                    ])
                    .arg(&out)
                    .current_dir(d);
                if baseline {
                    c.env("KARDIA_CPU", "baseline");
                } else {
                    c.env_remove("KARDIA_CPU");
                }
                let run = c.output().unwrap();
                assert!(
                    run.status.success(),
                    "{}: {}",
                    scene.display(),
                    String::from_utf8_lossy(&run.stderr)
                );
                std::fs::read(out).unwrap()
            };
            assert!(
                render(false) == render(true),
                "{} as {format}: the baseline code path wrote other bytes than the detected one",
                scene.display()
            );
        }
    }
}

#[test]
fn without_a_terminal_progress_is_a_plain_line_and_quiet_silences_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.scene"), SCENE).unwrap();
    let base = [
        "render",
        "a.scene",
        "--frames",
        "0..1",
        "--spp",
        "1",
        "--progress-every",
        "0",
        "-o",
        "f_#.png",
    ];
    // stderr is a pipe here, as in a farm job's log.
    let out = super::anim_cli::kardia(d, &base);
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = err.lines().filter(|l| l.contains("eta")).collect();
    assert!(
        lines
            .iter()
            .any(|l| l.starts_with("kardia: frame 0 (1 of 2): ")),
        "{err}"
    );
    let last = lines.last().expect("progress lines");
    assert!(
        last.starts_with("kardia: frame 1 (2 of 2): 100%, ") && last.contains(" elapsed, eta "),
        "{err}"
    );
    assert!(
        !err.contains('\r') && !err.contains('\u{1b}'),
        "no bar: {err:?}"
    );
    // A still says "rendering".
    let still = super::anim_cli::kardia(
        d,
        &[
            "render",
            "a.scene",
            "--spp",
            "1",
            "--progress-every",
            "0",
            "-o",
            "s.png",
        ],
    );
    let err = String::from_utf8_lossy(&still.stderr);
    assert!(err.contains("kardia: rendering: 100%, "), "{err}");
    let mut quiet = base.to_vec();
    quiet.push("--quiet");
    let out = super::anim_cli::kardia(d, &quiet);
    assert!(out.status.success() && out.stderr.is_empty(), "{out:?}");
}

/// Starts a long render in `dir`, sends `signal` once it has begun, and returns its exit code
/// and the files left in `dir`.
#[cfg(unix)]
fn render_and_signal(dir: &Path, signal: &str, output: &[&str]) -> (Option<i32>, Vec<String>) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_kardia"))
        .args([
            "render", "a.scene", "--width", "2000", "--spp", "64", "--quiet",
        ])
        .args(output)
        .current_dir(dir)
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(700));
    let sent = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let status = child.wait().unwrap();
    (status.code(), crate::cli_render::listing(dir))
}

#[cfg(unix)]
#[test]
fn sigterm_exits_143_and_removes_the_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.scene"), SCENE).unwrap();
    for output in [
        &["-o", "still.png"][..],
        &["-o", "still.exr"],
        &["--frame", "1", "-o", "f_####.png"],
        &["--tile", "1/2", "-o", "part.png"],
    ] {
        let (code, left) = render_and_signal(d, "-TERM", output);
        assert_eq!(code, Some(143), "{output:?}");
        assert_eq!(left, ["a.scene"], "{output:?}");
    }
    let (code, left) = render_and_signal(d, "-HUP", &["-o", "still.png"]);
    assert_eq!((code, left.len()), (Some(129), 1));
}

#[test]
fn resume_keeps_only_files_of_this_render_key() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.scene"), SCENE).unwrap();
    let run = |extra: &[&str]| {
        let mut a = vec!["render", "a.scene", "--threads", "1", "--resume"];
        a.extend_from_slice(extra);
        let out = super::anim_cli::kardia(d, &a);
        assert!(out.status.success(), "{out:?}");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let read = |name: &str| std::fs::read(d.join(name)).unwrap();
    let err = run(&["--spp", "1", "--frames", "0..1", "-o", "f_#.png"]);
    assert!(!err.contains("skipped"), "{err}");
    let frame1 = read("f_1.png");
    // Frame 0's picture put in frame 1's place: a complete PNG, but not frame 1.
    std::fs::copy(d.join("f_0.png"), d.join("f_1.png")).unwrap();
    let err = run(&["--spp", "1", "--frames", "0..1", "-o", "f_#.png"]);
    assert!(err.contains("(1 already complete, skipped)"), "{err}");
    assert_eq!(read("f_1.png"), frame1, "frame 1 rendered anew");
    // Other settings: nothing is kept.
    let err = run(&["--spp", "2", "--frames", "0..1", "-o", "f_#.png"]);
    assert!(
        err.contains("kardia: 2 frames") && !err.contains("skipped"),
        "{err}"
    );
    let err = run(&["--spp", "2", "--frames", "0..1", "-o", "f_#.png"]);
    assert!(err.contains("(2 already complete, skipped)"), "{err}");
    // A file kardia did not write (no key) is rendered anew, EXR too.
    ok(
        d,
        &[
            "render", "a.scene", "--spp", "2", "--frame", "1", "--quiet", "-o", "e_#.exr",
        ],
    );
    let exr = read("e_1.exr");
    let mut image = kardia::film::Image::new(40, 32);
    image.pixels[0] = kardia::film::Vec3::new(1.0, 0.0, 0.0);
    kardia::film::write_image(&image, &d.join("e_1.exr")).unwrap();
    let err = run(&["--spp", "2", "--frame", "1", "-o", "e_#.exr"]);
    assert!(!err.contains("skipped"), "{err}");
    assert_eq!(read("e_1.exr"), exr);
    // Tiles resume too, by their part metadata.
    let err = run(&["--spp", "1", "--tile", "0/2", "-o", "p0.png"]);
    assert!(!err.contains("skipped"), "{err}");
    let err = run(&["--spp", "1", "--tile", "0/2", "-o", "p0.png"]);
    assert!(err.contains("(1 already complete, skipped)"), "{err}");
    let err = run(&["--spp", "1", "--tile", "1/2", "-o", "p0.png"]);
    assert!(!err.contains("skipped"), "band 1 is not band 0: {err}");
}

#[test]
fn animated_files_resume_only_with_their_own_render_key() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.scene"), SCENE).unwrap();
    for name in ["a.gif", "a.apng"] {
        let run = |extra: &[&str]| {
            let mut a = vec![
                "render",
                "a.scene",
                "--threads",
                "1",
                "--resume",
                "-o",
                name,
            ];
            a.extend_from_slice(extra);
            let out = super::anim_cli::kardia(d, &a);
            assert!(out.status.success(), "{out:?}");
            String::from_utf8_lossy(&out.stderr).into_owned()
        };
        let read = || std::fs::read(d.join(name)).unwrap();
        let err = run(&["--spp", "1"]);
        assert!(!err.contains("skipped"), "{name}: {err}");
        let spp1 = read();
        let err = run(&["--spp", "1"]);
        assert!(
            err.contains("(4 already complete, skipped)"),
            "{name}: {err}"
        );
        // Other settings, other frames, another rate: rendered anew each time.
        for extra in [
            &["--spp", "2"][..],
            &["--spp", "1", "--frames", "0..2"][..],
            &["--spp", "1", "--seed", "3"][..],
            &["--spp", "1", "--width", "20"][..],
        ] {
            let err = run(extra);
            assert!(!err.contains("skipped"), "{name} {extra:?}: {err}");
        }
        let err = run(&["--spp", "1"]);
        assert!(!err.contains("skipped"), "{name}: {err}");
        assert_eq!(
            read(),
            spp1,
            "{name}: the same settings give the same bytes"
        );
        // Another scene text: not this animation.
        std::fs::write(d.join("a.scene"), format!("{SCENE}# another scene\n")).unwrap();
        let err = run(&["--spp", "1"]);
        assert!(!err.contains("skipped"), "{name}: {err}");
        std::fs::write(d.join("a.scene"), SCENE).unwrap();
    }
}

#[test]
fn the_slurm_join_names_the_missing_bands_and_how_to_rerun_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.scene"), SCENE).unwrap();
    for i in [0, 2] {
        ok(
            d,
            &[
                "render",
                "a.scene",
                "--spp",
                "1",
                "--quiet",
                "--tile",
                &format!("{i}/4"),
                "-o",
                &format!("part_{i}.png"),
            ],
        );
    }
    let recipes = recipe("");
    let out = Command::new("bash")
        .arg(recipe("slurm-assemble.sbatch"))
        .env("KARDIA", env!("CARGO_BIN_EXE_kardia"))
        .env("KARDIA_ARGS", "--spp 1")
        .env("SCENE", d.join("a.scene"))
        .env("OUT", d)
        .env("TILES", "4")
        .env("IMAGE", "joined.png")
        .env("RECIPES", &recipes)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(err.contains("bands 1,3 of 4 are missing"), "{err}");
    assert!(!d.join("joined.png").exists());
    let lines: Vec<&str> = err.lines().collect();
    let at = lines
        .iter()
        .position(|l| *l == "Re-run them and this join with:")
        .expect("the recovery is printed");
    let recovery = lines[at + 1].trim();
    assert!(
        recovery.contains("--array=1,3") && recovery.contains("--dependency=afterany:"),
        "{recovery}"
    );
    // The printed line, run as it is in a fresh shell (nothing exported) with a stand-in for
    // sbatch that runs each script at once (each array task in turn), renders the missing
    // bands as the first ones were and joins them.
    let bin = d.join("bin");
    std::fs::create_dir(&bin).unwrap();
    std::fs::write(
        bin.join("sbatch"),
        "#!/usr/bin/env bash\n\
         chdir=. array=\n\
         for a in \"$@\"; do case $a in --chdir=*) chdir=${a#--chdir=};; \
         --array=*) array=${a#--array=};; esac; script=$a; done\n\
         cd \"$chdir\" || exit 1\n\
         if [ -n \"$array\" ]; then for i in ${array//,/ }; do \
         SLURM_ARRAY_TASK_ID=$i bash \"$script\" >&2 || exit 1; done; \
         else bash \"$script\" >&2 || exit 1; fi\n\
         echo 42\n",
    )
    .unwrap();
    let path = format!("{}:/usr/bin:/bin", bin.display());
    let rerun = Command::new("bash")
        .args([
            "-c",
            &format!("chmod +x {}/sbatch && {recovery}", bin.display()),
        ])
        .env_clear()
        .env("PATH", path)
        .current_dir(d)
        .output()
        .unwrap();
    assert!(
        rerun.status.success(),
        "{recovery}\n{}",
        String::from_utf8_lossy(&rerun.stderr)
    );
    ok(
        d,
        &[
            "render",
            "a.scene",
            "--spp",
            "1",
            "--quiet",
            "-o",
            "single.png",
        ],
    );
    assert_eq!(
        std::fs::read(d.join("joined.png")).unwrap(),
        std::fs::read(d.join("single.png")).unwrap()
    );
}

#[test]
fn kardia_prints_the_frame_count_turntable_included() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("a.scene"), SCENE).unwrap();
    std::fs::write(d.join("still.scene"), SCENE.replace("FRAMES 4 FPS 8\n", "")).unwrap();
    for (args, count) in [
        (&["a.scene"][..], "4"),
        (&["a.scene", "--turntable", "36"], "36"),
        (&["still.scene"], "1"),
    ] {
        let mut a = vec!["render"];
        a.extend_from_slice(args);
        a.push("--print-frame-count");
        let out = super::anim_cli::kardia(d, &a);
        assert!(out.status.success(), "{out:?}");
        assert_eq!(
            String::from_utf8_lossy(&out.stdout).trim(),
            count,
            "{args:?}"
        );
    }
    assert_eq!(crate::cli_render::listing(d), ["a.scene", "still.scene"]);
}

/// When a frame fails, the frame rendering beside it finishes and is written whole, no new
/// frame starts, and the recipe exits non-zero (GNU parallel's `--halt soon,fail=1`; with
/// `--halt now` frame 2 would be killed half-way and missing).
#[test]
fn gnu_parallel_lets_running_frames_finish_when_one_fails() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Frame 3 of 4 divides by zero (a scene error at that frame); the others render.
    let scene = SCENE.replace(
        "LET s = 0.8 + 0.2*clock",
        "LET s = 0.8 + 0.2*clock\nLET fails_at_3 = 1/(frame - 3)",
    );
    std::fs::write(d.join("a.scene"), scene).unwrap();
    let out = Command::new("bash")
        .arg(recipe("parallel-frames.sh"))
        .args([
            "a.scene",
            "farm",
            "--width",
            "240",
            "--spp",
            "16",
            "--threads",
            "1",
        ])
        .env("KARDIA", env!("CARGO_BIN_EXE_kardia"))
        .env("PARALLEL_OPTS", "-j 2")
        .current_dir(d)
        .output()
        .expect("bash runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "a failed frame fails the recipe: {err}"
    );
    assert!(
        err.contains("the value of fails_at_3 cannot be computed"),
        "{err}"
    );
    // Frames 2 and 3 ran together (two at a time); 3 failed at once and 2 still finished.
    let made = crate::cli_render::listing(&d.join("farm"));
    assert_eq!(
        made,
        ["frame_0000.png", "frame_0001.png", "frame_0002.png"],
        "{err}"
    );
    ok(
        d,
        &[
            "render",
            "a.scene",
            "--width",
            "240",
            "--spp",
            "16",
            "--frame",
            "2",
            "--quiet",
            "-o",
            "alone_####.png",
        ],
    );
    assert!(
        std::fs::read(d.join("farm/frame_0002.png")).unwrap()
            == std::fs::read(d.join("alone_0002.png")).unwrap(),
        "frame 2 was written whole"
    );
}
