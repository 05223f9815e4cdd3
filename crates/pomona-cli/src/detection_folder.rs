//! The output folder of `pomona detect`: one `<frame>.json` per frame, `failures.json` for the
//! frames that failed, and whatever an earlier run (perhaps killed half-way) left there.
//!
//! Detection files record the pipeline, the model's identity and the confidence threshold that
//! made them. A run refuses a folder holding detection files made differently (another pipeline,
//! model, `--set` or `--min-confidence`), so two runs never mix silently; with `--resume` it skips
//! the frames whose file this same run would write. Files are written atomically, so a killed run
//! leaves whole files and at most some temporary `.pomona-*.partial` files, which are removed here.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use pomona_core::FrameDetections;
use pomona_eval::failures_file;
use serde::Serialize;

/// What makes a detection file this run's: the fields every file of the run shares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunIdentity<'a> {
    /// Pipeline name.
    pub pipeline: &'a str,
    /// The model's identity ([`pomona::ModelInfo::id`]).
    pub model_id: &'a str,
    /// The confidence threshold the files are written at.
    pub min_confidence: Option<f64>,
}

impl RunIdentity<'_> {
    /// Why `file` was not made by this run, or `None` when it was.
    fn difference(&self, file: &FrameDetections) -> Option<String> {
        if file.pipeline != self.pipeline {
            return Some(format!(
                "pipeline `{}` (this run: `{}`)",
                file.pipeline, self.pipeline
            ));
        }
        match file.model_id.as_deref() {
            None => return Some("a model of a Pomona version that recorded no model id".into()),
            Some(id) if id != self.model_id => {
                return Some(format!(
                    "model {id} (this run: {}; another model file or --set)",
                    self.model_id
                ))
            }
            Some(_) => {}
        }
        (file.min_confidence != self.min_confidence).then(|| {
            let show = |c: Option<f64>| c.map_or("none".to_owned(), |c| c.to_string());
            format!(
                "minimum confidence {} (this run: {})",
                show(file.min_confidence),
                show(self.min_confidence)
            )
        })
    }
}

/// Prepares `out` for a run over `frames`: creates it, removes temporary files a killed run
/// left, and checks existing detection files. Returns the frames whose file this run would write
/// unchanged (to skip with `--resume`).
///
/// # Errors
/// An unwritable folder, a `<frame>.json` that is not a detection file, or one made by another
/// pipeline, model or threshold (naming the file and the difference).
pub fn prepare(
    out: &Path,
    frames: &[String],
    identity: &RunIdentity<'_>,
) -> Result<BTreeSet<String>> {
    std::fs::create_dir_all(out)
        .with_context(|| format!("cannot create output folder {}", out.display()))?;
    remove_partial_files(out)?;
    let mut same = BTreeSet::new();
    for frame in frames {
        let path = out.join(format!("{frame}.json"));
        let text = match std::fs::read_to_string(&path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
            Err(e) => return Err(e).with_context(|| format!("cannot read {}", path.display())),
        };
        let file: FrameDetections = serde_json::from_str(&text).with_context(|| {
            format!(
                "{} is not a detection file; refusing to overwrite it (move it or choose \
                 another --out)",
                path.display()
            )
        })?;
        if let Some(why) = identity.difference(&file) {
            bail!(
                "{} holds detections made with {why}; refusing to mix two runs in one folder \
                 (choose another --out or remove the old files)",
                path.display()
            );
        }
        same.insert(frame.clone());
    }
    Ok(same)
}

/// Removes `.pomona-*.partial` files (temporaries of atomic writes cut short by a kill).
fn remove_partial_files(dir: &Path) -> Result<()> {
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("cannot list {}", dir.display()))?;
    for entry in entries {
        let path = entry
            .with_context(|| format!("cannot list {}", dir.display()))?
            .path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if name.starts_with(".pomona-") && name.ends_with(".partial") && path.is_file() {
            std::fs::remove_file(&path)
                .with_context(|| format!("cannot remove stale {}", path.display()))?;
        }
    }
    Ok(())
}

/// One frame that failed, as listed in `failures.json`.
#[derive(Debug, Clone, PartialEq, Serialize)]
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
struct FailuresFile<'a> {
    pipeline: &'a str,
    frames_tried: usize,
    failures: &'a [FailedFrame],
}

/// Writes `out/failures.json` (or shard `(I, N)`'s `failures.shard-I-of-N.json`, see
/// [`pomona_eval::failures_file`]) listing `failures` (atomically), or removes an old one when
/// there are none. Returns its path when written.
///
/// # Errors
/// An unwritable or unremovable file.
pub fn write_failures(
    out: &Path,
    shard: Option<(usize, usize)>,
    pipeline: &str,
    frames_tried: usize,
    failures: &[FailedFrame],
) -> Result<Option<PathBuf>> {
    let path = out.join(failures_file(shard));
    if failures.is_empty() {
        if path.is_file() {
            std::fs::remove_file(&path)
                .with_context(|| format!("cannot remove old {}", path.display()))?;
        }
        return Ok(None);
    }
    let file = FailuresFile {
        pipeline,
        frames_tried,
        failures,
    };
    pomona_io::write_json(&path, &file)?;
    Ok(Some(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(pipeline: &str, model_id: Option<&str>, min: Option<f64>) -> FrameDetections {
        FrameDetections {
            frame: "a".into(),
            pipeline: pipeline.into(),
            detections: Vec::new(),
            operating_confidence: None,
            min_confidence: min,
            model_id: model_id.map(str::to_owned),
            stamp_ns: None,
            frame_id: None,
        }
    }

    #[test]
    fn a_file_is_this_runs_only_with_the_same_pipeline_model_and_threshold() {
        let run = RunIdentity {
            pipeline: "shape-fit",
            model_id: "00ff",
            min_confidence: Some(0.3),
        };
        assert_eq!(
            run.difference(&file("shape-fit", Some("00ff"), Some(0.3))),
            None
        );
        for (other, word) in [
            (file("symmetry", Some("00ff"), Some(0.3)), "pipeline"),
            (file("shape-fit", Some("0aff"), Some(0.3)), "model 0aff"),
            (file("shape-fit", None, Some(0.3)), "no model id"),
            (
                file("shape-fit", Some("00ff"), None),
                "minimum confidence none",
            ),
        ] {
            let why = run.difference(&other).unwrap_or_default();
            assert!(why.contains(word), "{why}");
        }
    }

    #[test]
    fn prepare_skips_own_files_refuses_foreign_ones_and_clears_partials() {
        let dir = tempfile::tempdir().unwrap();
        let run = RunIdentity {
            pipeline: "p",
            model_id: "1",
            min_confidence: None,
        };
        let frames = vec!["a".to_owned(), "b".to_owned()];
        let write = |name: &str, f: &FrameDetections| {
            std::fs::write(dir.path().join(name), serde_json::to_string(f).unwrap()).unwrap();
        };
        write("a.json", &file("p", Some("1"), None));
        std::fs::write(dir.path().join(".pomona-x1.partial"), "{").unwrap();
        let same = prepare(dir.path(), &frames, &run).unwrap();
        assert_eq!(same.into_iter().collect::<Vec<_>>(), vec!["a".to_owned()]);
        assert!(!dir.path().join(".pomona-x1.partial").exists());

        write("b.json", &file("p", Some("2"), None));
        let err = format!("{:#}", prepare(dir.path(), &frames, &run).unwrap_err());
        assert!(err.contains("b.json") && err.contains("model 2"), "{err}");
        std::fs::write(dir.path().join("b.json"), "not json").unwrap();
        let err = format!("{:#}", prepare(dir.path(), &frames, &run).unwrap_err());
        assert!(err.contains("not a detection file"), "{err}");
    }

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
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("f1") && text.contains("bad png"), "{text}");
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
}
