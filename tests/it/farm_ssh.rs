//! The GNU parallel recipes over ssh (`--sshloginfile`, docs/farm.md) against a real sshd on
//! 127.0.0.1: a throwaway host key and user key in a temporary folder, sshd on a free port, the
//! recipes run with absolute paths (frames) and with `--workdir .` and relative paths (tiles);
//! the files equal those of one machine byte for byte. Needs Debian's openssh-server and GNU
//! parallel (installed by .ci/run); without them the test fails under CI and skips loudly
//! elsewhere.

use std::net::{Ipv4Addr, TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use super::anim_cli::{ok, SCENE};
use super::farm::run_recipe_with as run_recipe;

const SSHD: &str = "/usr/sbin/sshd";

/// An sshd on 127.0.0.1 that accepts one throwaway key, stopped when dropped.
struct Sshd {
    child: Child,
    port: u16,
    key: PathBuf,
}

impl Drop for Sshd {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn keygen(path: &Path) {
    let made = Command::new("ssh-keygen")
        .args(["-q", "-t", "ed25519", "-N", "", "-f"])
        .arg(path)
        .status()
        .expect("ssh-keygen runs");
    assert!(made.success());
}

/// Starts sshd for the current user with keys made in `dir`.
fn start_sshd(dir: &Path) -> Sshd {
    keygen(&dir.join("host_key"));
    keygen(&dir.join("user_key"));
    std::fs::copy(dir.join("user_key.pub"), dir.join("authorized_keys")).unwrap();
    // A free port: bound on port 0, read, released.
    let port = TcpListener::bind((Ipv4Addr::LOCALHOST, 0))
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let config = format!(
        "ListenAddress 127.0.0.1\nPort {port}\nHostKey {host}\nAuthorizedKeysFile {keys}\n\
         PidFile {pid}\nStrictModes no\nUsePAM no\nPasswordAuthentication no\n\
         KbdInteractiveAuthentication no\nPermitRootLogin prohibit-password\n",
        host = dir.join("host_key").display(),
        keys = dir.join("authorized_keys").display(),
        pid = dir.join("sshd.pid").display(),
    );
    std::fs::write(dir.join("sshd_config"), config).unwrap();
    // sshd's privilege separation needs its empty folder.
    let _ = std::fs::create_dir_all("/run/sshd");
    let child = Command::new(SSHD)
        .args(["-D", "-e", "-f"])
        .arg(dir.join("sshd_config"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("sshd starts");
    let started = Instant::now();
    while TcpStream::connect((Ipv4Addr::LOCALHOST, port)).is_err() {
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "sshd did not listen on 127.0.0.1:{port}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    Sshd {
        child,
        port,
        key: dir.join("user_key"),
    }
}

#[test]
fn gnu_parallel_over_ssh_to_127_0_0_1_gives_the_files_of_one_machine() {
    let missing: Vec<&str> = [(SSHD, "openssh-server"), ("/usr/bin/parallel", "parallel")]
        .into_iter()
        .filter(|(path, _)| !Path::new(path).exists())
        .map(|(_, package)| package)
        .collect();
    if !missing.is_empty() {
        let message = format!("apt-get install {} (.ci/run does it)", missing.join(" "));
        assert!(std::env::var_os("CI").is_none(), "{message}");
        eprintln!("\n!!!!! SKIPPED the ssh farm test: {message} !!!!!\n");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sshd = start_sshd(d);
    let user = String::from_utf8(Command::new("id").arg("-un").output().unwrap().stdout)
        .unwrap()
        .trim()
        .to_string();
    // Two job slots on the one "node"; the ssh command names the key and trusts the
    // throwaway host key without a known_hosts file.
    let login = format!(
        "2/ssh -p {} -i {} -o BatchMode=yes -o StrictHostKeyChecking=no \
         -o UserKnownHostsFile=/dev/null -o LogLevel=ERROR {user}@127.0.0.1",
        sshd.port,
        sshd.key.display()
    );
    std::fs::write(d.join("nodes.txt"), format!("{login}\n")).unwrap();
    let nodes = format!("--sshloginfile {}", d.join("nodes.txt").display());
    std::fs::write(d.join("a.scene"), SCENE).unwrap();

    // Frames: the scene and the output as absolute paths (remote jobs start in $HOME).
    let scene = d.join("a.scene").display().to_string();
    let farm = d.join("farm").display().to_string();
    run_recipe(
        d,
        "parallel-frames.sh",
        &[&scene, &farm, "--spp", "2"],
        &nodes,
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
    for f in 0..4 {
        let remote = std::fs::read(d.join(format!("farm/frame_{f:04}.png"))).unwrap();
        let local = std::fs::read(d.join(format!("seq_{f:04}.png"))).unwrap();
        assert!(remote == local, "frame {f} over ssh differs");
    }

    // Tiles: relative paths with --workdir . (the jobs start in the same folder there).
    let workdir = format!("{nodes} --workdir .");
    run_recipe(
        d,
        "parallel-tiles.sh",
        &["a.scene", "3", "joined.png", "--spp", "2"],
        &workdir,
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
    assert!(
        std::fs::read(d.join("joined.png")).unwrap()
            == std::fs::read(d.join("single.png")).unwrap(),
        "tiles over ssh do not join into the single render"
    );
    assert!(
        !d.join("joined.png.parts").exists(),
        "the parts folder is removed"
    );
}
