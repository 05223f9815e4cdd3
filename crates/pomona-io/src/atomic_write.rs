//! Writing a file so that readers never see half of it: write a temporary file beside the
//! destination, flush it, then rename it over the destination (atomic on one filesystem).
//!
//! Every writer in this crate goes through here, so a failure (disk full, a bad value found
//! half-way, an encoder error) leaves whatever was at the destination untouched.

use std::io::{BufWriter, Write};
use std::path::Path;

/// Writes `path` through `fill`, atomically. The closure gets a buffered writer; its error type
/// must be constructible from the I/O error of creating, flushing or renaming the temp file.
pub(crate) fn write_atomically<E>(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<&mut std::fs::File>) -> Result<(), E>,
    io_error: impl Fn(&Path, std::io::Error) -> E,
) -> Result<(), E> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new()
        .prefix(".pomona-")
        .suffix(".partial")
        .tempfile_in(dir)
        .map_err(|e| io_error(path, temp_file_error(dir, &e)))?;
    {
        let mut w = BufWriter::new(tmp.as_file_mut());
        fill(&mut w)?;
        w.flush().map_err(|e| io_error(path, e))?;
    }
    // Temporary files are created owner-only; what we write is ordinary output (rw-r--r--).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        tmp.as_file()
            .set_permissions(std::fs::Permissions::from_mode(0o644))
            .map_err(|e| io_error(path, e))?;
    }
    tmp.persist(path).map_err(|e| io_error(path, e.error))?;
    Ok(())
}

/// Why no temporary file could be made in `dir`, said of the destination (the temporary file's
/// own name would only confuse): a missing folder, or the system's reason.
fn temp_file_error(dir: &Path, e: &std::io::Error) -> std::io::Error {
    let reason = if dir.is_dir() {
        format!("cannot create a file in {}: {}", dir.display(), e.kind())
    } else {
        format!("its folder {} does not exist", dir.display())
    };
    std::io::Error::new(e.kind(), reason)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_folder_is_named_with_the_destination() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("missing").join("x.json");
        let err = write_atomically(
            &path,
            |w| w.write_all(b"{}").map_err(|e| e.to_string()),
            |p, e| format!("{}: {e}", p.display()),
        )
        .unwrap_err();
        assert!(
            err.contains("x.json") && err.contains("does not exist"),
            "{err}"
        );
        assert!(!err.contains(".partial"), "{err}");
    }

    #[test]
    fn failure_keeps_previous_contents() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.txt");
        std::fs::write(&path, "old").unwrap();
        let r: Result<(), std::io::Error> = write_atomically(
            &path,
            |w| {
                w.write_all(b"half")?;
                Err(std::io::Error::other("encoder failed"))
            },
            |_, e| e,
        );
        assert!(r.is_err());
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "temp file cleaned up"
        );
        write_atomically(&path, |w| w.write_all(b"new"), |_, e| e).unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
    }
}
