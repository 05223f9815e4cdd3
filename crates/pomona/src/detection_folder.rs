//! The output folder of a detection run (`pomona detect`, the Python package's Dask runner): one
//! `<frame>.json` per frame, a failures list (`failures_list.rs`), and whatever an earlier run
//! (perhaps killed half-way) left there.
//!
//! Detection files record the pipeline, the model's identity and the confidence threshold that
//! made them ([`RunIdentity`]). A run refuses a folder holding detection files made differently
//! (another pipeline, model, parameter override or threshold), so two runs never mix silently,
//! and refuses to overwrite a `<frame>.json` that is not a detection file. A resumed run skips
//! the frames whose file it would write unchanged. Files are written atomically, so a killed run
//! leaves whole files and at most some temporary `.pomona-*.partial` files, which are removed
//! here. Both front ends call this one code, so they accept and refuse the same folders.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use pomona_core::FrameDetections;

use crate::{Detector, Error, KeepRule};

/// What makes a detection file this run's: the fields every file of the run shares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunIdentity<'a> {
    /// Pipeline name.
    pub pipeline: &'a str,
    /// The model's identity ([`crate::ModelInfo::id`]).
    pub model_id: &'a str,
    /// The threshold the files are written at.
    pub keep: KeepRule,
}

impl Detector {
    /// The identity of the detection files this detector writes ([`Detector::frame_record`]) on
    /// frames with or without colour (`has_color`) kept by `keep` (from
    /// [`Detector::keep_rule_for`]).
    ///
    /// ```
    /// # fn main() -> Result<(), pomona::Error> {
    /// let detector = pomona::Detector::builtin("shape-fit")?;
    /// let run = detector.run_identity(true, pomona::KeepRule::Confidence(0.5));
    /// assert_eq!((run.pipeline, run.model_id), ("shape-fit", detector.model().id.as_str()));
    /// # Ok(())
    /// # }
    /// ```
    pub fn run_identity(&self, has_color: bool, keep: KeepRule) -> RunIdentity<'_> {
        RunIdentity {
            pipeline: self.pipeline(),
            model_id: &self.model_for_color(has_color).id,
            keep,
        }
    }
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
        let same = file.min_confidence == self.keep.min_confidence()
            && file.min_score == self.keep.min_score();
        (!same).then(|| {
            let show = |c: Option<f64>, s: Option<f64>| match (c, s) {
                (Some(c), _) => format!("minimum confidence {c}"),
                (None, Some(s)) => format!("minimum score {s}"),
                (None, None) => "no threshold".to_owned(),
            };
            format!(
                "{} (this run: {})",
                show(file.min_confidence, file.min_score),
                show(self.keep.min_confidence(), self.keep.min_score())
            )
        })
    }
}

/// Prepares `out` for a run over `frames`: creates it, removes temporary files a killed run
/// left, and checks the existing detection files of those frames. Returns the frames whose file
/// this run would write unchanged (to skip when resuming; rewritten otherwise).
///
/// # Errors
/// [`Error::OutputIo`] for a folder that cannot be created or listed, a file that cannot be read
/// or a stale temporary that cannot be removed; [`Error::NotDetectionFile`] for a
/// `<frame>.json` that is not a detection file; [`Error::ForeignDetections`] for one made by
/// another pipeline, model or threshold. Each names the file.
pub fn prepare_detection_folder(
    out: &Path,
    frames: &[String],
    identity: &RunIdentity<'_>,
) -> Result<BTreeSet<String>, Error> {
    std::fs::create_dir_all(out).map_err(|source| Error::OutputIo {
        action: "create output folder",
        path: out.to_owned(),
        source,
    })?;
    remove_partial_files(out)?;
    let mut same = BTreeSet::new();
    for frame in frames {
        let path = out.join(format!("{frame}.json"));
        let text = match std::fs::read_to_string(&path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
            Err(source) => {
                return Err(Error::OutputIo {
                    action: "read",
                    path,
                    source,
                })
            }
        };
        let file: FrameDetections = match serde_json::from_str(&text) {
            Ok(file) => file,
            Err(source) => return Err(Error::NotDetectionFile { path, source }),
        };
        if let Some(difference) = identity.difference(&file) {
            return Err(Error::ForeignDetections { path, difference });
        }
        same.insert(frame.clone());
    }
    Ok(same)
}

/// Removes `.pomona-*.partial` files (temporaries of atomic writes cut short by a kill).
fn remove_partial_files(dir: &Path) -> Result<(), Error> {
    let listing = |source| Error::OutputIo {
        action: "list",
        path: dir.to_owned(),
        source,
    };
    for entry in std::fs::read_dir(dir).map_err(listing)? {
        let path: PathBuf = entry.map_err(listing)?.path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if name.starts_with(".pomona-") && name.ends_with(".partial") && path.is_file() {
            std::fs::remove_file(&path).map_err(|source| Error::OutputIo {
                action: "remove stale",
                path: path.clone(),
                source,
            })?;
        }
    }
    Ok(())
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
            min_score: None,
            model_id: model_id.map(str::to_owned),
            stamp_ns: None,
            frame_id: None,
        }
    }

    const RUN: RunIdentity<'static> = RunIdentity {
        pipeline: "p",
        model_id: "1",
        keep: KeepRule::Confidence(0.5),
    };

    fn write(dir: &Path, name: &str, f: &FrameDetections) {
        std::fs::write(dir.join(name), serde_json::to_string(f).unwrap()).unwrap();
    }

    fn frames(names: &[&str]) -> Vec<String> {
        names.iter().map(|&n| n.to_owned()).collect()
    }

    #[test]
    fn a_file_is_this_runs_only_with_the_same_pipeline_model_and_threshold() {
        let run = RunIdentity {
            pipeline: "shape-fit",
            model_id: "00ff",
            keep: KeepRule::Confidence(0.3),
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
                "no threshold (this run: minimum confidence 0.3)",
            ),
            (
                FrameDetections {
                    min_score: Some(0.0),
                    ..file("shape-fit", Some("00ff"), None)
                },
                "minimum score 0 (this run: minimum confidence 0.3)",
            ),
        ] {
            let why = run.difference(&other).unwrap_or_default();
            assert!(why.contains(word), "{why}");
        }
    }

    #[test]
    fn the_frames_this_run_wrote_are_returned_and_others_are_not() {
        let dir = tempfile::tempdir().unwrap();
        write(dir.path(), "a.json", &file("p", Some("1"), Some(0.5)));
        write(dir.path(), "c.json", &file("p", Some("1"), Some(0.5)));
        // A file of a frame outside this run is not read (shards share a folder).
        std::fs::write(dir.path().join("z.json"), "not json").unwrap();
        let same = prepare_detection_folder(dir.path(), &frames(&["a", "b", "c"]), &RUN).unwrap();
        assert_eq!(same.into_iter().collect::<Vec<_>>(), frames(&["a", "c"]));
        // A missing folder is created, and holds nothing to skip.
        let fresh = dir.path().join("new").join("out");
        assert!(prepare_detection_folder(&fresh, &frames(&["a"]), &RUN)
            .unwrap()
            .is_empty());
        assert!(fresh.is_dir());
    }

    #[test]
    fn foreign_pipeline_model_or_threshold_is_refused_naming_the_file() {
        for (other, word) in [
            (
                file("q", Some("1"), Some(0.5)),
                "pipeline `q` (this run: `p`)",
            ),
            (file("p", Some("2"), Some(0.5)), "model 2 (this run: 1"),
            (file("p", Some("1"), Some(0.25)), "minimum confidence 0.25"),
            (file("p", Some("1"), None), "no threshold"),
        ] {
            let dir = tempfile::tempdir().unwrap();
            write(dir.path(), "a.json", &file("p", Some("1"), Some(0.5)));
            write(dir.path(), "b.json", &other);
            let err = prepare_detection_folder(dir.path(), &frames(&["a", "b"]), &RUN).unwrap_err();
            assert!(
                matches!(&err, Error::ForeignDetections { path, .. } if path.ends_with("b.json")),
                "{err:?}"
            );
            let message = err.to_string();
            assert!(
                message.contains("b.json") && message.contains(word),
                "{message}"
            );
            assert!(message.contains("refusing to mix"), "{message}");
        }
    }

    #[test]
    fn a_frame_file_that_is_not_a_detection_file_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a.json"), r#"{"notes": "mine"}"#).unwrap();
        let err = prepare_detection_folder(dir.path(), &frames(&["a"]), &RUN).unwrap_err();
        assert!(
            matches!(&err, Error::NotDetectionFile { path, .. } if path.ends_with("a.json")),
            "{err:?}"
        );
        assert!(err.to_string().contains("not a detection file"), "{err}");
        assert_eq!(
            std::fs::read_to_string(dir.path().join("a.json")).unwrap(),
            r#"{"notes": "mine"}"#,
            "the file is left as it was"
        );
    }

    #[test]
    fn partial_files_of_a_killed_run_are_removed_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        for name in [".pomona-x1.partial", ".pomona-Ab9.partial"] {
            std::fs::write(dir.path().join(name), "{").unwrap();
        }
        for keep in ["notes.partial", ".pomona-keep.txt", "failures.json"] {
            std::fs::write(dir.path().join(keep), "kept").unwrap();
        }
        std::fs::create_dir(dir.path().join(".pomona-dir.partial")).unwrap();
        prepare_detection_folder(dir.path(), &[], &RUN).unwrap();
        let mut left: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(
            left,
            [
                ".pomona-dir.partial",
                ".pomona-keep.txt",
                "failures.json",
                "notes.partial"
            ]
        );
    }

    #[test]
    fn an_output_path_that_is_a_file_is_an_error_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        std::fs::write(&out, "a file").unwrap();
        let err = prepare_detection_folder(&out, &frames(&["a"]), &RUN).unwrap_err();
        assert!(matches!(err, Error::OutputIo { .. }), "{err:?}");
        assert!(
            err.to_string().contains(&out.display().to_string()),
            "{err}"
        );
    }

    #[test]
    fn the_identity_is_the_one_frame_records_carry() {
        let detector = Detector::builtin("shape-fit").unwrap();
        for keep in [
            KeepRule::Confidence(0.5),
            KeepRule::Score(0.0),
            KeepRule::All,
        ] {
            let record = detector.frame_record("f", false, &[], keep);
            let run = detector.run_identity(false, keep);
            assert_eq!(run.difference(&record), None, "{keep:?}");
        }
        let record = detector.frame_record("f", false, &[], KeepRule::Confidence(0.5));
        for other in [KeepRule::Score(0.0), KeepRule::All] {
            assert!(detector
                .run_identity(false, other)
                .difference(&record)
                .is_some());
        }
    }
}
