//! Writing an output file so that it is either wholly replaced or untouched: a temporary
//! file in the same directory, flushed and synced, given the original's permissions, then
//! renamed over the target.

use std::fs;
use std::io::{self, BufWriter, Write};
use std::path::Path;

use anyhow::Context;

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
    let tmp = tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(".delta-gcode.tmp")
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
