//! Labelled frames for training and experiments, loaded on demand.
//!
//! Training sets can be hundreds of frames; loading lazily keeps memory flat and lets
//! experiments split datasets by frame index without copying anything.

use pomona_core::{FrameTruth, InstanceMask, RgbdFrame};
use pomona_io::Dataset;

use crate::PipelineError;

/// A frame with its truth and, when the dataset has one, its instance mask.
#[derive(Debug, Clone)]
pub struct LabelledFrame {
    /// `"<dataset folder>/<frame stem>"`, for messages.
    pub name: String,
    /// The RGB-D frame.
    pub frame: RgbdFrame,
    /// Its ground truth.
    pub truth: FrameTruth,
    /// Instance ids, when available.
    pub mask: Option<InstanceMask>,
}

/// An indexable collection of labelled frames.
pub trait FrameSource: Sync {
    /// Number of frames.
    fn len(&self) -> usize;

    /// Whether there are no frames.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Loads frame `i` (0-based).
    ///
    /// # Errors
    /// Dataset errors naming the file.
    fn load(&self, i: usize) -> Result<LabelledFrame, PipelineError>;

    /// Frame `i`'s truth alone (training passes that read only the annotations). By default
    /// the whole frame is loaded; sources that can read the annotation by itself override it.
    ///
    /// # Errors
    /// As [`FrameSource::load`].
    fn truth(&self, i: usize) -> Result<FrameTruth, PipelineError> {
        Ok(self.load(i)?.truth)
    }

    /// Loads every frame, in order (for sets rendered or read once and reused).
    ///
    /// # Errors
    /// The first error of [`FrameSource::load`].
    fn load_all(&self) -> Result<Vec<LabelledFrame>, PipelineError> {
        (0..self.len()).map(|i| self.load(i)).collect()
    }
}

/// Frames already in memory, e.g. a synthetic set rendered once and trained on several times.
impl FrameSource for [LabelledFrame] {
    fn len(&self) -> usize {
        <[LabelledFrame]>::len(self)
    }

    fn load(&self, i: usize) -> Result<LabelledFrame, PipelineError> {
        held(self, i).cloned()
    }

    /// Clones the truth only, not the images.
    fn truth(&self, i: usize) -> Result<FrameTruth, PipelineError> {
        held(self, i).map(|lf| lf.truth.clone())
    }
}

/// Frame `i` of frames held in memory, or the error for an index past them.
fn held(frames: &[LabelledFrame], i: usize) -> Result<&LabelledFrame, PipelineError> {
    frames
        .get(i)
        .ok_or_else(|| PipelineError::InvalidParameter {
            name: "frame index".into(),
            reason: format!("{i} is past the {} frames held", frames.len()),
        })
}

impl FrameSource for Vec<LabelledFrame> {
    fn len(&self) -> usize {
        self.as_slice().len()
    }

    fn load(&self, i: usize) -> Result<LabelledFrame, PipelineError> {
        self.as_slice().load(i)
    }

    fn truth(&self, i: usize) -> Result<FrameTruth, PipelineError> {
        self.as_slice().truth(i)
    }
}

/// Several frame sources one after another (e.g. synthetic sets of different cameras or
/// domains trained on together): frame `i` is the `i`-th frame of the concatenation.
#[derive(Debug, Clone, Default)]
pub struct ChainedFrames<S>(pub Vec<S>);

impl<S: FrameSource> ChainedFrames<S> {
    /// The part holding frame `i` and the frame's index in it.
    fn locate(&self, i: usize) -> Result<(&S, usize), PipelineError> {
        let mut rest = i;
        for part in &self.0 {
            if rest < part.len() {
                return Ok((part, rest));
            }
            rest -= part.len();
        }
        Err(PipelineError::InvalidParameter {
            name: "frame index".into(),
            reason: format!("{i} is past the {} chained frames", self.len()),
        })
    }
}

impl<S: FrameSource> FrameSource for ChainedFrames<S> {
    fn len(&self) -> usize {
        self.0.iter().map(FrameSource::len).sum()
    }

    fn load(&self, i: usize) -> Result<LabelledFrame, PipelineError> {
        let (part, j) = self.locate(i)?;
        part.load(j)
    }

    fn truth(&self, i: usize) -> Result<FrameTruth, PipelineError> {
        let (part, j) = self.locate(i)?;
        part.truth(j)
    }
}

/// Frames drawn from one or more datasets; only frames that have truth are included.
#[derive(Debug, Clone, Default)]
pub struct DatasetFrames {
    frames: Vec<(usize, String)>,
    datasets: Vec<Dataset>,
}

impl DatasetFrames {
    /// Every frame with a truth file from every dataset, in dataset then frame order.
    pub fn new(datasets: Vec<Dataset>) -> Self {
        let frames = datasets
            .iter()
            .enumerate()
            .flat_map(|(d, ds)| {
                ds.frames()
                    .iter()
                    .filter(|f| ds.truth_path(f).is_file())
                    .map(move |f| (d, f.clone()))
            })
            .collect();
        Self { frames, datasets }
    }

    /// A subset by position (for train/test splits); out-of-range indices are skipped.
    pub fn subset(&self, indices: &[usize]) -> Self {
        Self {
            frames: indices
                .iter()
                .filter_map(|&i| self.frames.get(i).cloned())
                .collect(),
            datasets: self.datasets.clone(),
        }
    }

    /// Whether every dataset has depth images (`false` when any is colour-only).
    pub fn has_depth(&self) -> bool {
        self.datasets.iter().all(Dataset::has_depth)
    }

    /// `(dataset, frame stem)` of frame `i`.
    pub fn frame_ref(&self, i: usize) -> Option<(&Dataset, &str)> {
        let (d, f) = self.frames.get(i)?;
        Some((&self.datasets[*d], f.as_str()))
    }

    /// [`DatasetFrames::frame_ref`], or the error for an index past the frames.
    fn indexed(&self, i: usize) -> Result<(&Dataset, &str), PipelineError> {
        self.frame_ref(i)
            .ok_or_else(|| PipelineError::InvalidParameter {
                name: "frame index".into(),
                reason: format!("{i} is beyond the {} frames", self.frames.len()),
            })
    }
}

impl FrameSource for DatasetFrames {
    fn len(&self) -> usize {
        self.frames.len()
    }

    fn load(&self, i: usize) -> Result<LabelledFrame, PipelineError> {
        let (ds, stem) = self.indexed(i)?;
        let frame = ds.load_frame(stem)?;
        let truth = self.truth(i)?;
        let mask = ds.load_mask(stem)?;
        Ok(LabelledFrame {
            name: format!("{}/{stem}", ds.root().display()),
            frame,
            truth,
            mask,
        })
    }

    /// Reads only the truth file.
    fn truth(&self, i: usize) -> Result<FrameTruth, PipelineError> {
        let (ds, stem) = self.indexed(i)?;
        ds.load_truth(stem)?
            .ok_or_else(|| PipelineError::NotEnoughTrainingData {
                pipeline: "any",
                reason: format!("{} has no truth", ds.truth_path(stem).display()),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::{DepthImage, PinholeCamera};

    fn frame(name: &str) -> LabelledFrame {
        let camera = PinholeCamera::new(2, 2, 1.0, 1.0, 0.5, 0.5).unwrap();
        let depth = DepthImage::from_meters(2, 2, vec![1.0; 4]).unwrap();
        LabelledFrame {
            name: name.to_owned(),
            frame: RgbdFrame::new(camera, depth, None).unwrap(),
            truth: FrameTruth {
                complete: true,
                fruits: Vec::new(),
                extra: serde_json::Map::new(),
            },
            mask: None,
        }
    }

    #[test]
    fn chained_sources_index_through_every_part() {
        let part =
            |n: usize| -> Vec<LabelledFrame> { (0..n).map(|k| frame(&k.to_string())).collect() };
        let chained = ChainedFrames(vec![part(2), part(0), part(3)]);
        assert_eq!(chained.len(), 5);
        let names: Vec<String> = (0..5).map(|i| chained.load(i).unwrap().name).collect();
        assert_eq!(names, ["0", "1", "0", "1", "2"]);
        assert!(chained.load(5).is_err());
        // Truth alone goes through the same parts.
        for i in 0..5 {
            assert_eq!(chained.truth(i).unwrap(), chained.load(i).unwrap().truth);
        }
        assert!(chained.truth(5).is_err());
    }

    /// A dataset's truth is read without its images: a frame whose depth image is unreadable
    /// still gives its truth, and its `load` names the broken file.
    #[test]
    fn dataset_truth_is_read_alone() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        for sub in ["depth", "truth"] {
            std::fs::create_dir_all(root.join(sub)).unwrap();
        }
        std::fs::write(
            root.join("camera.json"),
            r#"{"width": 2, "height": 2, "fx": 1.0, "fy": 1.0, "cx": 0.5, "cy": 0.5, "depth_unit_m": 0.001}"#,
        )
        .unwrap();
        std::fs::write(root.join("depth/000000.png"), b"not a png").unwrap();
        std::fs::write(
            root.join("truth/000000.json"),
            r#"{"complete": true, "fruits": [{"id": "a", "kind": "apple", "center_m": [0, 0, 1]}]}"#,
        )
        .unwrap();
        let frames = DatasetFrames::new(vec![Dataset::open(root).unwrap()]);
        assert_eq!(frames.len(), 1);
        let truth = frames.truth(0).unwrap();
        assert_eq!(truth.fruits.len(), 1);
        let err = frames.load(0).unwrap_err().to_string();
        assert!(err.contains("000000.png"), "{err}");
        assert!(frames.truth(1).is_err());
    }
}
