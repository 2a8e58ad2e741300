//! `kardia explore` in a real browser: starts the server on 127.0.0.1:0 and runs
//! tests/browser/explore.mjs (playwright-core driving Debian's chromium) against it.
//!
//! Needs `/usr/bin/chromium` (or `$CHROMIUM`), node and `npm ci`'s node_modules; `.ci/run`
//! installs all three. Without them the test says so loudly and passes, except under CI
//! (`CI` set), where it fails.

use kardia::explore::{Options, Server};
use std::path::{Path, PathBuf};
use std::process::Command;

fn missing_tools(root: &Path) -> Vec<String> {
    let chromium = std::env::var("CHROMIUM").unwrap_or_else(|_| "/usr/bin/chromium".into());
    let mut missing = vec![];
    if !Path::new(&chromium).exists() {
        missing.push(format!("chromium ({chromium})"));
    }
    if Command::new("node").arg("--version").output().is_err() {
        missing.push("node".into());
    }
    for package in ["playwright-core", "pngjs"] {
        if !root.join("node_modules").join(package).exists() {
            missing.push(format!("node_modules/{package} (run `npm ci`)"));
        }
    }
    missing
}

#[test]
fn explorer_works_in_chromium() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let missing = missing_tools(&root);
    if !missing.is_empty() {
        let message = format!("browser tests need {}", missing.join(", "));
        assert!(std::env::var_os("CI").is_none(), "{message}");
        eprintln!("\n!!!!! SKIPPED explorer_works_in_chromium: {message} !!!!!\n");
        return;
    }
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap();
    let (url, stop, served) = runtime.block_on(async {
        let server = Server::bind(Options::default()).await.unwrap();
        let url = server.url();
        let (stop, stopped) = tokio::sync::oneshot::channel::<()>();
        let served = tokio::spawn(server.serve(async move {
            let _ = stopped.await;
        }));
        (url, stop, served)
    });
    let output = Command::new("node")
        .arg(root.join("tests/browser/explore.mjs"))
        .arg(&url)
        .env("KARDIA_BIN", env!("CARGO_BIN_EXE_kardia"))
        .current_dir(&root)
        .output()
        .expect("node runs");
    let _ = stop.send(());
    runtime.block_on(served).unwrap().unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    eprintln!("{stdout}{}", String::from_utf8_lossy(&output.stderr));
    assert!(output.status.success(), "browser tests failed:\n{stdout}");
    assert!(stdout.contains(" passed, 0 failed"), "{stdout}");
}
