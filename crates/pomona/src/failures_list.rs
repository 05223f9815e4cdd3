//! The list of frames a detection run could not process: `failures.json` in its output folder
//! (`failures.shard-I-of-N.json` for shard `I` of `N`, [`pomona_eval::failures_file`], so shards
//! sharing a folder keep their own lists). A failed frame does not stop a run; this file says
//! which frames are missing and why. `pomona detect` and the Python package's Dask runner both
//! write it here, so the list has one format.

use std::path::{Path, PathBuf};

use pomona_eval::failures_file;
use serde::{Deserialize, Serialize};

use crate::Error;

/// One frame that failed, as listed in `failures.json` (read back from it, or from a front
/// end's rows, with serde).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailedFrame {
    /// Frame stem.
    pub frame: String,
    /// The file at fault, when the error names one.
    pub file: Option<PathBuf>,
    /// The error, with its causes, on one line.
    pub error: String,
}

/// Contents of `failures.json`.
#[derive(Debug, Serialize)]
struct FailuresList<'a> {
    pipeline: &'a str,
    frames_tried: usize,
    failures: &'a [FailedFrame],
}

/// Writes `out/failures.json` (or shard `(I, N)`'s `failures.shard-I-of-N.json`) listing
/// `failures` of a run of `pipeline` that tried `frames_tried` frames (atomically), or removes
/// an old one when there are none. Returns its path when written.
///
/// # Errors
/// [`Error::Dataset`] for a file that cannot be written, [`Error::OutputIo`] for an old one that
/// cannot be removed; both name the file.
pub fn write_failures(
    out: &Path,
    shard: Option<(usize, usize)>,
    pipeline: &str,
    frames_tried: usize,
    failures: &[FailedFrame],
) -> Result<Option<PathBuf>, Error> {
    let path = out.join(failures_file(shard));
    if failures.is_empty() {
        if path.is_file() {
            std::fs::remove_file(&path).map_err(|source| Error::OutputIo {
                action: "remove old",
                path: path.clone(),
                source,
            })?;
        }
        return Ok(None);
    }
    let list = FailuresList {
        pipeline,
        frames_tried,
        failures,
    };
    pomona_io::write_json(&path, &list)?;
    Ok(Some(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failures_file_is_written_and_removed() {
        let dir = tempfile::tempdir().unwrap();
        let failed = vec![FailedFrame {
            frame: "f1".into(),
            file: Some("/d/depth/f1.png".into()),
            error: "bad png".into(),
        }];
        let path = write_failures(dir.path(), None, "p", 3, &failed)
            .unwrap()
            .unwrap();
        assert!(path.ends_with("failures.json"));
        let written: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_eq!(
            written,
            serde_json::json!({
                "pipeline": "p",
                "frames_tried": 3,
                "failures": [{"frame": "f1", "file": "/d/depth/f1.png", "error": "bad png"}],
            })
        );
        let shard = write_failures(dir.path(), Some((1, 4)), "p", 3, &failed)
            .unwrap()
            .unwrap();
        assert!(shard.ends_with("failures.shard-1-of-4.json"));
        assert_eq!(write_failures(dir.path(), None, "p", 3, &[]).unwrap(), None);
        assert!(
            !path.exists() && shard.exists(),
            "a run removes only its own list"
        );
    }

    #[test]
    fn an_unwritable_folder_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("gone");
        let failed = [FailedFrame {
            frame: "f".into(),
            file: None,
            error: "e".into(),
        }];
        let err = write_failures(&missing, None, "p", 1, &failed).unwrap_err();
        assert!(err.to_string().contains("gone"), "{err}");
    }
}
