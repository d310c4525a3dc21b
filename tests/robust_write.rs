//! Writing the output: `annotate --in-place` and `-o` go through a temporary file in the
//! target's directory, renamed over the target only when complete. Whatever fails, the
//! original stays byte-identical.
//!
//! Tests run as root, so permission bits stop nothing: an unwritable place is a path whose
//! parent is a regular file, or a read-only tmpfs when `mount -t tmpfs` works here (it
//! needs CAP_SYS_ADMIN); a full disk is a 512 KiB tmpfs, or `ulimit -f` (tests/cli_check.rs).
//! Without mount the tmpfs variants print a note and pass.

mod common;

use common::*;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const KOSSEL: &str = "machines/kossel.yaml";
const CUBE: &str = "samples/calib-cube_cura413_kossel-mini.gcode";

fn annotate(args: &[&str]) -> Output {
    let mut all = vec!["annotate", "-m"];
    let machine = repo(KOSSEL);
    all.push(machine.to_str().unwrap());
    all.extend_from_slice(args);
    let o = run(&all);
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    o
}

/// Files in `dir` other than `keep`: temporary files left behind.
fn leftovers(dir: &Path, keep: &[&str]) -> Vec<String> {
    fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !keep.contains(&n.as_str()))
        .collect()
}

/// A tmpfs of `size` mounted on a new directory, unmounted on drop; `None` (with a note)
/// where mounting is not allowed.
struct Tmpfs {
    dir: tempfile::TempDir,
}

impl Tmpfs {
    fn mount(size: &str) -> Option<Tmpfs> {
        let dir = tempfile::tempdir().ok()?;
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(dir.path())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            eprintln!("note: `mount -t tmpfs` is not allowed here; tmpfs variant skipped");
            return None;
        }
        Some(Tmpfs { dir })
    }

    fn path(&self) -> &Path {
        self.dir.path()
    }

    fn remount_read_only(&self) -> bool {
        Command::new("mount")
            .args(["-o", "remount,ro"])
            .arg(self.path())
            .status()
            .is_ok_and(|s| s.success())
    }
}

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(self.dir.path()).status();
    }
}

#[test]
fn output_whose_parent_is_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.gcode");
    let original = fs::read(repo(CUBE)).unwrap();
    fs::write(&input, &original).unwrap();
    let blocker = dir.path().join("not-a-dir");
    fs::write(&blocker, b"x").unwrap();
    let out = blocker.join("out.gcode");
    let o = annotate(&[input.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("cannot create a temporary file in"), "{err}");
    assert!(err.contains("not-a-dir"), "{err}");
    assert_eq!(fs::read(&input).unwrap(), original);
    assert_eq!(fs::read(&blocker).unwrap(), b"x");
    assert_eq!(
        leftovers(dir.path(), &["in.gcode", "not-a-dir"]),
        Vec::<String>::new()
    );
    // The same for the trace and for --report.
    let t = run(&[
        "trace",
        input.to_str().unwrap(),
        "-m",
        repo(KOSSEL).to_str().unwrap(),
        "-o",
        blocker.join("t.csv").to_str().unwrap(),
    ]);
    assert_eq!(t.status.code(), Some(2), "{}", stderr(&t));
    let r = annotate(&[
        input.to_str().unwrap(),
        "--in-place",
        "--report",
        blocker.join("r.json").to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(2), "{}", stderr(&r));
}

#[test]
fn in_place_on_a_read_only_file_system() {
    let Some(fs_) = Tmpfs::mount("4m") else {
        return;
    };
    let f = fs_.path().join("part.gcode");
    let original = fs::read(repo(CUBE)).unwrap();
    fs::write(&f, &original).unwrap();
    if !fs_.remount_read_only() {
        eprintln!("note: cannot remount read-only; variant skipped");
        return;
    }
    let o = annotate(&["--in-place", f.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("cannot create a temporary file"),
        "{}",
        stderr(&o)
    );
    assert!(
        stderr(&o).contains("Read-only file system"),
        "{}",
        stderr(&o)
    );
    assert_eq!(fs::read(&f).unwrap(), original);
    assert_eq!(leftovers(fs_.path(), &["part.gcode"]), Vec::<String>::new());
}

#[test]
fn in_place_on_a_full_disk() {
    // 512 KiB holds the 307 KiB cube, not a second, annotated copy of it.
    let Some(fs_) = Tmpfs::mount("512k") else {
        return;
    };
    let f = fs_.path().join("part.gcode");
    let original = fs::read(repo(CUBE)).unwrap();
    fs::write(&f, &original).unwrap();
    let o = annotate(&["--in-place", f.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("cannot write the new"), "{err}");
    assert!(err.contains("No space left on device"), "{err}");
    assert_eq!(fs::read(&f).unwrap(), original);
    assert_eq!(leftovers(fs_.path(), &["part.gcode"]), Vec::<String>::new());
    // -o to the full disk leaves the input (elsewhere) and the disk as they were.
    let input = tempfile::tempdir().unwrap();
    let src = input.path().join("in.gcode");
    fs::write(&src, &original).unwrap();
    let out = fs_.path().join("out.gcode");
    let o = annotate(&[src.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(
        o.status.code() == Some(0) || o.status.code() == Some(2),
        "{}",
        stderr(&o)
    );
    if o.status.code() == Some(2) {
        assert!(!out.exists());
    }
    assert_eq!(fs::read(&src).unwrap(), original);
}

/// A large G-code file: the cube 20 times over (6 MB, 300 000 lines).
fn large_file(dir: &Path) -> (PathBuf, Vec<u8>) {
    let cube = fs::read(repo(CUBE)).unwrap();
    let data = cube.repeat(20);
    let f = dir.join("big.gcode");
    fs::write(&f, &data).unwrap();
    (f, data)
}

/// Starts `annotate --in-place` on `f`, waits until its temporary file exists (it is
/// writing), sends `signal`, and returns the exit status and whether the temporary file
/// was seen.
fn interrupt_while_writing(f: &Path, signal: &str) -> (std::process::ExitStatus, bool) {
    let mut child = bin()
        .args(["annotate", "--in-place", "-m"])
        .arg(repo(KOSSEL))
        .arg(f)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let dir = f.parent().unwrap();
    let start = Instant::now();
    let mut seen = false;
    while start.elapsed() < Duration::from_secs(60) {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if !leftovers(dir, &["big.gcode"]).is_empty() {
            seen = true;
            let _ = Command::new("kill")
                .args([signal, &child.id().to_string()])
                .status();
            break;
        }
        std::thread::sleep(Duration::from_micros(200));
    }
    (child.wait().unwrap(), seen)
}

#[test]
fn interrupted_while_writing() {
    for signal in ["-INT", "-TERM"] {
        let dir = tempfile::tempdir().unwrap();
        let (f, data) = large_file(dir.path());
        let (status, seen) = interrupt_while_writing(&f, signal);
        // Whatever the timing, the file is the original or its complete annotated form.
        let now = fs::read(&f).unwrap();
        if now != data {
            assert_eq!(strip_ours(&now), data, "{signal}: a partial file");
        }
        if seen && !status.success() {
            assert_eq!(now, data, "{signal}: killed, yet the file changed");
            let left = leftovers(dir.path(), &["big.gcode"]);
            // The signal ends the process before it can remove its temporary file: a
            // `.big.gcode.*.delta-gcode.tmp` stays beside the original until the next run on
            // the same file removes it as stale (src/cli/replace.rs).
            for name in &left {
                assert!(
                    name.starts_with(".big.gcode.") && name.ends_with(".delta-gcode.tmp"),
                    "{name}"
                );
            }
            eprintln!(
                "{signal}: killed while writing ({status}); original intact; left behind: {left:?}"
            );
        } else {
            eprintln!("{signal}: not caught while writing ({status}, tmp seen: {seen})");
        }
    }
}
