//! Atomic output: a file that appears complete under its name, or not at all.

use super::encode::{ImageFormat, OutputError};
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// The bytes an [`AtomicFile`] gathers before each write to the operating system. A PNG
/// encoder hands over 4 KiB chunks: with the standard 8 KiB buffer each became a `write` call
/// of its own (85 for the benchmark heart at 1200², each a system call on the encoder's
/// thread); 64 KiB make them six, and leave at most 64 KiB to write once the encoder is done.
const WRITE_BUFFER: usize = 64 << 10;

/// A file being written atomically: the bytes go to a temporary file of its own in the
/// target's directory (`.NAME.kardia@HOST.PID-N.tmp`, never an existing file); [`AtomicFile::commit`]
/// flushes it to disk and renames it over the target. Dropped without a commit (an error, a
/// cancelled render, a panic), it removes its temporary file and leaves the target as it was.
/// Any number of them may be open at once, from any threads, for distinct targets. A
/// buffered `Write + Seek`: hand `&mut file` to any encoder.
#[derive(Debug)]
pub struct AtomicFile {
    target: PathBuf,
    temp: PathBuf,
    /// `None` only once committed.
    out: Option<BufWriter<File>>,
}

impl AtomicFile {
    /// Starts writing `target`: creates the temporary file beside it. Fails when the directory
    /// does not exist or cannot be written, or when `target` is a directory.
    /// The first time a process writes into a directory, it removes the temporaries there that
    /// kardia runs on this host left behind when killed ([`remove_stale_temporaries`]).
    pub fn create(target: &Path) -> Result<Self, OutputError> {
        check_directory(target)?;
        sweep_once(parent_dir(target));
        let (temp, file) = create_temp_beside(target).map_err(|e| write_error(target, e))?;
        Ok(Self {
            target: target.to_path_buf(),
            temp,
            out: Some(BufWriter::with_capacity(WRITE_BUFFER, file)),
        })
    }

    /// The file this will become.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// The temporary file being written (removed on drop, renamed on commit).
    pub fn temp_path(&self) -> &Path {
        &self.temp
    }

    /// Finishes the write: flushes and syncs the temporary file, renames it over the target
    /// and syncs the directory where the platform allows. On failure the temporary file is
    /// removed and the target is as it was.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let out = self.out.take().expect("an uncommitted file has its writer");
        let synced = out
            .into_inner()
            .map_err(|e| e.into_error())
            .and_then(|file| file.sync_all());
        if let Err(e) = synced {
            let _ = std::fs::remove_file(&self.temp);
            return Err(write_error(&self.target, e));
        }
        if let Err(e) = std::fs::rename(&self.temp, &self.target) {
            let _ = std::fs::remove_file(&self.temp);
            return Err(write_error(&self.target, e));
        }
        // Make the rename itself durable where the platform allows opening a directory.
        if let Ok(dir) = File::open(parent_dir(&self.target)) {
            let _ = dir.sync_all();
        }
        Ok(())
    }

    fn writer(&mut self) -> &mut BufWriter<File> {
        self.out
            .as_mut()
            .expect("an uncommitted file has its writer")
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.writer().write(buf)
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.writer().write_all(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.writer().flush()
    }
}

impl Seek for AtomicFile {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.writer().seek(pos)
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if let Some(out) = self.out.take() {
            drop(out);
            let _ = std::fs::remove_file(&self.temp);
        }
    }
}

fn write_error(path: &Path, e: std::io::Error) -> OutputError {
    OutputError::Write {
        path: path.display().to_string(),
        reason: e.to_string(),
    }
}

/// The directory a file path will be written into (`.` for a bare file name).
fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// An error unless `path`'s directory exists and `path` is not itself a directory.
fn check_directory(path: &Path) -> Result<(), OutputError> {
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(OutputError::NoDirectory(dir.display().to_string()));
    }
    if path.is_dir() {
        return Err(OutputError::IsDirectory(path.display().to_string()));
    }
    Ok(())
}

/// Checks, before any rendering, that `path` can be written: known extension (`.png` or
/// `.exr`), an existing directory to write into in which a file can be created (tried with a
/// temporary file, removed at once), and not itself a directory. Returns the format the
/// extension selects.
pub fn check_output_path(path: &Path) -> Result<ImageFormat, OutputError> {
    let format = ImageFormat::from_path(path)?;
    // Prove the directory is writable with the same kind of temporary file the write uses.
    drop(AtomicFile::create(path)?);
    Ok(format)
}

/// What sits between the target's name and the host in kardia's temporary file names.
const TEMP_MARK: &str = ".kardia@";

/// This machine's host name (as in temporary file names: letters, digits, `-`, `_` and `.`
/// only), or `unknown` where it cannot be read.
fn host_name() -> &'static str {
    static HOST: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    HOST.get_or_init(|| {
        let name = std::fs::read_to_string("/proc/sys/kernel/hostname")
            .or_else(|_| std::fs::read_to_string("/etc/hostname"))
            .unwrap_or_default();
        let name: String = name
            .trim()
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                    c
                } else {
                    '_'
                }
            })
            .collect();
        if name.is_empty() {
            "unknown".into()
        } else {
            name
        }
    })
}

/// The host and process id in a kardia temporary file name (`.NAME.kardia@HOST.PID-N.tmp`),
/// or `None` for any other name.
fn temp_owner(file_name: &str) -> Option<(&str, u32)> {
    let inner = file_name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let (rest, pid_n) = inner.rsplit_once('.')?;
    let (name, host) = rest.rsplit_once(TEMP_MARK)?;
    let (pid, n) = pid_n.split_once('-')?;
    if name.is_empty() || host.is_empty() || n.parse::<u64>().is_err() {
        return None;
    }
    Some((host, pid.parse().ok()?))
}

/// True only when process `pid` of this machine is known to have ended (Linux: no
/// `/proc/PID`). Elsewhere, or when `/proc` is not there, never true.
fn process_has_ended(pid: u32) -> bool {
    cfg!(target_os = "linux")
        && Path::new("/proc/self").exists()
        && !Path::new("/proc").join(pid.to_string()).exists()
}

/// Removes from `dir` the temporary files that kardia runs on this host left behind when they
/// were killed (a name `.NAME.kardia@HOST.PID-N.tmp` with this host and a process that has
/// ended); never any other file, nor those of other hosts sharing the directory, nor those of
/// processes still running. Returns the files removed.
pub fn remove_stale_temporaries(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut removed = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some((host, pid)) = name.to_str().and_then(temp_owner) else {
            continue;
        };
        let is_file = entry.file_type().is_ok_and(|t| t.is_file());
        if is_file
            && host == host_name()
            && pid != std::process::id()
            && process_has_ended(pid)
            && std::fs::remove_file(entry.path()).is_ok()
        {
            removed.push(entry.path());
        }
    }
    removed
}

/// [`remove_stale_temporaries`] in `dir`, once per directory per process.
fn sweep_once(dir: &Path) {
    use std::sync::Mutex;
    static SWEPT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
    let key = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
    let Ok(mut swept) = SWEPT.lock() else {
        return;
    };
    if swept.contains(&key) {
        return;
    }
    swept.push(key);
    drop(swept);
    remove_stale_temporaries(dir);
}

/// Creates a fresh temporary file in the target's directory, named after the target
/// (`.NAME.kardia@HOST.PID-N.tmp`), never overwriting anything.
fn create_temp_beside(path: &Path) -> std::io::Result<(PathBuf, File)> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let dir = parent_dir(path);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "image".into());
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(
            ".{name}{TEMP_MARK}{}.{}-{n}.tmp",
            host_name(),
            std::process::id()
        ));
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => return Ok((tmp, f)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn listing(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    #[test]
    fn check_rejects_missing_directory_and_directories() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("nope").join("a.png");
        assert!(matches!(
            check_output_path(&missing),
            Err(OutputError::NoDirectory(_))
        ));
        let sub = dir.path().join("d.png");
        std::fs::create_dir(&sub).unwrap();
        assert!(matches!(
            check_output_path(&sub),
            Err(OutputError::IsDirectory(_))
        ));
        assert!(check_output_path(&dir.path().join("ok.exr")).is_ok());
        assert!(check_output_path(Path::new("bare.png")).is_ok());
        assert_eq!(listing(dir.path()), ["d.png"]);
    }

    #[test]
    fn committed_file_appears_whole_and_dropped_file_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("a.bin");
        std::fs::write(&target, b"old").unwrap();
        let mut file = AtomicFile::create(&target).unwrap();
        file.write_all(b"new bytes").unwrap();
        assert!(file.temp_path().exists());
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        drop(file);
        assert_eq!(listing(dir.path()), ["a.bin"]);
        assert_eq!(std::fs::read(&target).unwrap(), b"old");

        let mut file = AtomicFile::create(&target).unwrap();
        file.write_all(b"new bytes").unwrap();
        file.seek(SeekFrom::Start(0)).unwrap();
        file.write_all(b"N").unwrap();
        file.commit().unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"New bytes");
        assert_eq!(listing(dir.path()), ["a.bin"]);
    }

    #[test]
    fn failed_commit_removes_the_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("t.bin");
        let mut file = AtomicFile::create(&target).unwrap();
        file.write_all(b"x").unwrap();
        // The target becomes a non-empty directory: the rename must fail.
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("inside"), b"").unwrap();
        assert!(file.commit().is_err());
        assert_eq!(listing(dir.path()), ["t.bin"]);
    }

    #[test]
    fn temporaries_are_named_for_their_host_and_process() {
        let dir = tempfile::tempdir().unwrap();
        let file = AtomicFile::create(&dir.path().join("a.b.png")).unwrap();
        let name = file.temp_path().file_name().unwrap().to_str().unwrap();
        assert_eq!(temp_owner(name), Some((host_name(), std::process::id())));
        assert_eq!(temp_owner(".a.png.1234-0.tmp"), None);
        assert_eq!(temp_owner(".x.tmp"), None);
        assert_eq!(
            temp_owner(".f.png.kardia@node-1.lab.77-3.tmp"),
            Some(("node-1.lab", 77))
        );
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn only_kardias_own_stale_temporaries_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        // No process has this id (above Linux's largest pid_max, 2^22).
        let ended = 4_194_305 + 17;
        let host = host_name();
        let stale = format!(".f_0001.png{TEMP_MARK}{host}.{ended}-0.tmp");
        let keep = [
            format!(".f_0002.png{TEMP_MARK}other-host.{ended}-0.tmp"), // another node's
            format!(".f_0003.png{TEMP_MARK}{host}.{}-0.tmp", std::process::id()), // alive
            format!(".f_0004.png.{ended}-0.tmp"),                      // not kardia's marker
            "notes.tmp".to_string(),
            "f_0000.png".to_string(),
        ];
        for name in keep.iter().chain([&stale]) {
            std::fs::write(d.join(name), b"x").unwrap();
        }
        let removed = remove_stale_temporaries(d);
        assert_eq!(removed, [d.join(&stale)]);
        let mut expected = keep.to_vec();
        expected.sort();
        assert_eq!(listing(d), expected);
        // The first write into a directory sweeps it.
        std::fs::write(d.join(&stale), b"x").unwrap();
        AtomicFile::create(&d.join("new.png"))
            .unwrap()
            .commit()
            .unwrap();
        assert!(!d.join(&stale).exists());
    }

    #[test]
    fn many_concurrent_writes_to_distinct_targets() {
        let dir = tempfile::tempdir().unwrap();
        std::thread::scope(|s| {
            for i in 0..8 {
                let path = dir.path().join(format!("f{i}.txt"));
                s.spawn(move || {
                    let mut file = AtomicFile::create(&path).unwrap();
                    for _ in 0..1000 {
                        write!(file, "{i}").unwrap();
                    }
                    if i % 2 == 0 {
                        file.commit().unwrap();
                    }
                });
            }
        });
        assert_eq!(
            listing(dir.path()),
            ["f0.txt", "f2.txt", "f4.txt", "f6.txt"]
        );
        for i in [0, 2, 4, 6] {
            let text = std::fs::read_to_string(dir.path().join(format!("f{i}.txt"))).unwrap();
            assert_eq!(text, i.to_string().repeat(1000));
        }
    }
}
