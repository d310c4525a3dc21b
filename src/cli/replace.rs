//! Writing an output file so that it is either wholly replaced or untouched: a temporary
//! file in the same directory, flushed and synced, given the original's permissions (a new
//! file: 0666 less the umask, as any program creates one), then renamed over the target.

use std::fs;
use std::io::{self, BufWriter, Write};
use std::path::Path;

use anyhow::Context;

/// The ending of our temporary files: `.NAME.XXXXXX.delta-gcode.tmp` beside NAME.
const TMP_SUFFIX: &str = ".delta-gcode.tmp";

/// A temporary file of ours this old was left by a run that was killed (a signal, a power
/// cut): no run takes this long to write its output.
const STALE_AFTER: std::time::Duration = std::time::Duration::from_secs(600);

/// Writes `target` through a temporary file beside it; `write` fills the file. On any
/// error the temporary file is removed and `target` is left as it was.
pub fn replace_file(
    target: &Path,
    write: impl FnOnce(&mut (dyn Write + Send)) -> io::Result<()>,
) -> anyhow::Result<()> {
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let prefix = format!(".{name}.");
    remove_stale(dir, &prefix);
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(TMP_SUFFIX);
    // A new file gets the mode any program gives it (0666 less the umask), not the 0600 of
    // a temporary file; a replaced one keeps its own (below).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(fs::Permissions::from_mode(0o666));
    }
    let tmp = builder
        .tempfile_in(dir)
        .with_context(|| format!("cannot create a temporary file in {}", dir.display()))?;
    let mut out = BufWriter::with_capacity(1 << 16, tmp);
    write(&mut out)
        .and_then(|()| out.flush())
        .with_context(|| format!("cannot write the new {}", target.display()))?;
    let tmp = out.into_inner().map_err(|e| e.into_error())?;
    tmp.as_file()
        .sync_all()
        .with_context(|| format!("cannot sync the new {}", target.display()))?;
    if let Ok(meta) = fs::metadata(target) {
        fs::set_permissions(tmp.path(), meta.permissions())
            .with_context(|| format!("cannot copy the permissions of {}", target.display()))?;
    }
    tmp.persist(target)
        .map_err(|e| e.error)
        .with_context(|| format!("cannot replace {}", target.display()))?;
    Ok(())
}

/// Removes temporary files that an interrupted run left for the same target. Best effort:
/// a file that cannot be read or removed is left alone.
fn remove_stale(dir: &Path, prefix: &str) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if !(name.starts_with(prefix) && name.ends_with(TMP_SUFFIX)) {
            continue;
        }
        let age = entry
            .metadata()
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok());
        if age.is_some_and(|a| a > STALE_AFTER) {
            let _ = fs::remove_file(entry.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_whole_or_not_at_all() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("a.gcode");
        fs::write(&f, b"G1 X1\n").unwrap();
        replace_file(&f, |w| w.write_all(b"G1 X2\n")).unwrap();
        assert_eq!(fs::read(&f).unwrap(), b"G1 X2\n");
        let err = replace_file(&f, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("disk full"))
        });
        assert!(err.is_err());
        assert_eq!(fs::read(&f).unwrap(), b"G1 X2\n");
        // No temporary file is left behind.
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn removes_stale_temporary_files_of_the_same_target_only() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("a.gcode");
        let old = dir.path().join(".a.gcode.XyZ123.delta-gcode.tmp");
        let fresh = dir.path().join(".a.gcode.AbC456.delta-gcode.tmp");
        let other = dir.path().join(".b.gcode.XyZ123.delta-gcode.tmp");
        for p in [&old, &fresh, &other] {
            fs::write(p, b"partial").unwrap();
        }
        let long_ago = std::time::SystemTime::now() - 2 * STALE_AFTER;
        for p in [&old, &other] {
            fs::File::options()
                .write(true)
                .open(p)
                .unwrap()
                .set_modified(long_ago)
                .unwrap();
        }
        replace_file(&f, |w| w.write_all(b"x")).unwrap();
        assert!(!old.exists());
        assert!(fresh.exists() && other.exists());
    }

    #[cfg(unix)]
    #[test]
    fn keeps_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("a.gcode");
        fs::write(&f, b"x").unwrap();
        fs::set_permissions(&f, fs::Permissions::from_mode(0o640)).unwrap();
        replace_file(&f, |w| w.write_all(b"y")).unwrap();
        assert_eq!(
            fs::metadata(&f).unwrap().permissions().mode() & 0o777,
            0o640
        );
    }
}
