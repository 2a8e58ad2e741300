//! The Kubernetes recipe without a cluster (`bench/k8s-local.sh`, docs/farm.md): the manifest
//! validates offline for the versions it states, and its Job's own pod command and
//! environment, run in podman containers for every completion index on one fresh volume,
//! give byte for byte the frames of one `--frames` run. Needs the virtual environment
//! `.venv-k8s` with kubernetes-validate and podman (both installed by .ci/run); without the
//! first the test fails under CI and skips loudly elsewhere; where podman cannot start a
//! container it skips loudly (the bench script runs the same steps by hand).

use std::path::Path;
use std::process::Command;

use super::anim_cli::ok;

/// A small animated scene of `frames` frames (the manifest's completions).
fn scene(frames: i64) -> String {
    format!(
        "SIZE 24 20\nFRAMES {frames} FPS 8\nLET s = 0.8 + 0.2*clock\n\
         CAMERA (6, 1.2, 0.9) (0, 0, 0.05) (0, 0, 1) 32\n\
         LIGHT (7, -4, 6) (0.9, 0.88, 0.85) 0.6\n\
         HEART (0, 0.3*sin(2*pi*clock), 0) (s, 0, 0) (0, s, 0) (0, 0, s) (0.75, 0.04, 0.08)\n"
    )
}

/// The Job's completions, read from the manifest.
fn completions(repo: &Path) -> i64 {
    use yaml_rust2::YamlLoader;
    let text = std::fs::read_to_string(repo.join("examples/farm/k8s-indexed-job.yaml")).unwrap();
    let docs = YamlLoader::load_from_str(&text).expect("valid YAML");
    let job = docs
        .iter()
        .find(|d| d["kind"].as_str() == Some("Job"))
        .expect("a Job");
    job["spec"]["completions"].as_i64().expect("completions")
}

#[test]
fn the_kubernetes_job_validates_offline_and_its_pods_render_the_sequence() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let venv = repo.join(".venv-k8s");
    if !venv.join("bin/kubernetes-validate").exists() {
        let message = "kubernetes-validate is not installed in .venv-k8s \
                       (python3 -m venv .venv-k8s && .venv-k8s/bin/pip install kubernetes-validate==1.37.0; \
                       .ci/run does it)";
        assert!(std::env::var_os("CI").is_none(), "{message}");
        eprintln!("\n!!!!! SKIPPED the Kubernetes stand-in: {message} !!!!!\n");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let frames = completions(repo);
    std::fs::write(d.join("job.scene"), scene(frames)).unwrap();
    let out = Command::new("bash")
        .arg(repo.join("bench/k8s-local.sh"))
        .arg(d.join("job.scene"))
        .arg(d.join("work"))
        .env("KARDIA", env!("CARGO_BIN_EXE_kardia"))
        .env("K8S_VENV", &venv)
        .output()
        .expect("bash runs");
    let log = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        log.contains("valid for Kubernetes 1.") && log.contains("as expected"),
        "the offline validation did not run or failed:\n{log}"
    );
    if out.status.code() == Some(77) {
        eprintln!(
            "\n!!!!! SKIPPED the Kubernetes pods in containers (the offline validation passed): \
             this machine cannot start a container; run bench/k8s-local.sh where one can:\n{log} !!!!!\n"
        );
        return;
    }
    assert!(out.status.success(), "bench/k8s-local.sh failed:\n{log}");
    // The script compared the frames; compare them again here, every one.
    ok(
        d,
        &[
            "render",
            "job.scene",
            "--frames",
            &format!("0..{}", frames - 1),
            "--quiet",
            "-o",
            "seq_####.png",
        ],
    );
    let made = crate::cli_render::listing(&d.join("work/volume/out"));
    assert_eq!(made.len() as i64, frames, "{made:?}");
    for f in 0..frames {
        let pod = std::fs::read(d.join(format!("work/volume/out/frame_{f:04}.png"))).unwrap();
        let seq = std::fs::read(d.join(format!("seq_{f:04}.png"))).unwrap();
        assert!(
            pod == seq,
            "frame {f} from its pod differs from the sequential run"
        );
    }
}
