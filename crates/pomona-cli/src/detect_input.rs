//! Where `pomona detect` reads its frames: a dataset folder (`--data`) or a recording
//! (`--recording`: ROS 2 MCAP, ROS 1 bag or RealSense bag), behind one interface so the run (parallel detection, resume,
//! shards, failures) is the same for both.
//!
//! A recording's frames are its synchronised colour/depth pairs, named by the colour stamp
//! (19-digit nanoseconds); their detection files also record `stamp_ns` and `frame_id`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use pomona::{Pipeline, RgbdFrame};
use pomona_core::FrameDetections;
use pomona_io::Dataset;
use pomona_recording::Recording;

use crate::detection_run::check_inputs;
use crate::robot_recording::RecordingArgs;

/// The median depth, metres, a crop scene's first frame may have without a warning that the
/// depth unit looks wrong: nearer than a camera on a harvesting arm or farther than any
/// depth camera's useful range is a unit off by a factor of ten or more.
pub const PLAUSIBLE_MEDIAN_DEPTH_M: (f64, f64) = (0.1, 15.0);

/// The frames a detection run reads.
#[derive(Debug)]
pub enum DetectInput {
    /// A dataset folder.
    Dataset(Dataset),
    /// A recording, with its frame stems (sorted, as the stamps are).
    Recording {
        /// The opened recording.
        recording: Box<Recording>,
        /// [`pomona_recording::frame_stem`] of each synchronised frame, in frame order.
        stems: Vec<String>,
    },
}

impl DetectInput {
    /// Opens the dataset `data` or the recording `recording` (exactly one is given).
    ///
    /// # Errors
    /// Neither or both given; an unreadable dataset or recording (naming it).
    pub fn open(
        data: Option<&Path>,
        recording: Option<&Path>,
        topics: &RecordingArgs,
    ) -> Result<Self> {
        match (data, recording) {
            (Some(data), None) => {
                if *topics != RecordingArgs::default() {
                    bail!(
                        "--color-topic, --depth-topic, --info-topic and --sync-tolerance-ms \
                         apply to --recording FILE, not to the dataset folder {}",
                        data.display()
                    );
                }
                Ok(Self::Dataset(Dataset::open(data).with_context(|| {
                    format!("cannot open dataset {}", data.display())
                })?))
            }
            (None, Some(file)) => {
                let recording = topics.open(file)?;
                let stems = recording.frame_stems();
                Ok(Self::Recording {
                    recording: Box::new(recording),
                    stems,
                })
            }
            _ => bail!("give either --data DIR or --recording FILE"),
        }
    }

    /// The dataset folder or recording file, for messages.
    pub fn path(&self) -> PathBuf {
        match self {
            Self::Dataset(d) => d.root().to_owned(),
            Self::Recording { recording, .. } => recording.path().to_owned(),
        }
    }

    /// The dataset, when the input is one (overlays and rerun recordings need its files).
    pub fn dataset(&self) -> Option<&Dataset> {
        match self {
            Self::Dataset(d) => Some(d),
            Self::Recording { .. } => None,
        }
    }

    /// Frame stems, sorted.
    pub fn frames(&self) -> &[String] {
        match self {
            Self::Dataset(d) => d.frames(),
            Self::Recording { stems, .. } => stems,
        }
    }

    /// Whether frames have colour (a recording's always do).
    pub fn has_color(&self) -> bool {
        self.dataset().is_none_or(Dataset::has_color)
    }

    /// Checks that the input has the images `pipeline` needs (a recording has both).
    ///
    /// # Errors
    /// As [`check_inputs`].
    pub fn check(&self, pipeline: &dyn Pipeline) -> Result<()> {
        match self.dataset() {
            Some(d) => check_inputs(pipeline, d),
            None => Ok(()),
        }
    }

    /// A warning when the first frame's depth is implausible for a crop scene — its median
    /// reading nearer than [`PLAUSIBLE_MEDIAN_DEPTH_M`]`.0` or farther than `.1` — as a wrong
    /// `depth_unit_m` in `camera.json` gives (millimetres read as tenths of a millimetre put the
    /// fruit ten times nearer): every detector would then quietly find nothing. `None` for a
    /// recording (its unit comes from the sensor), a dataset without depth or frames, or
    /// plausible depth.
    pub fn depth_unit_warning(&self) -> Option<String> {
        let Self::Dataset(d) = self else { return None };
        if !d.has_depth() {
            return None;
        }
        let first = d.frames().first()?;
        // The depth image alone: decoding the colour image would only cost time.
        let depth = d.load_depth(first).ok()?;
        let mut readings: Vec<f32> = depth
            .as_slice()
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        if readings.is_empty() {
            return None;
        }
        let middle = readings.len() / 2;
        let median = f64::from(*readings.select_nth_unstable_by(middle, f32::total_cmp).1);
        let (near, far) = PLAUSIBLE_MEDIAN_DEPTH_M;
        (!(near..=far).contains(&median)).then(|| {
            format!(
                "the median depth of frame {first} of {} is {median:.3} m with camera.json's \
                 depth_unit_m {}: check the unit (metres per depth-PNG step, 0.001 for \
                 millimetres)",
                d.root().display(),
                d.depth_unit_m()
            )
        })
    }

    fn index_of(&self, stems: &[String], stem: &str) -> Result<usize> {
        stems
            .binary_search_by(|s| s.as_str().cmp(stem))
            .ok()
            .with_context(|| format!("{} has no frame {stem}", self.path().display()))
    }

    /// Loads frame `stem`.
    ///
    /// # Errors
    /// An unreadable or undecodable frame, naming the file (and, in a recording, the topic and
    /// stamp).
    pub fn load_frame(&self, stem: &str) -> Result<RgbdFrame> {
        match self {
            Self::Dataset(d) => Ok(d.load_frame(stem)?),
            Self::Recording { recording, stems } => {
                Ok(recording.load_frame(self.index_of(stems, stem)?)?.frame)
            }
        }
    }

    /// Adds what the input knows of frame `stem` to its detection record: a recording's colour
    /// stamp and frame id (a dataset adds nothing, so its files stay as they were).
    ///
    /// # Errors
    /// A stem the recording does not have.
    pub fn annotate(&self, stem: &str, record: &mut FrameDetections) -> Result<()> {
        if let Self::Recording { recording, stems } = self {
            let index = self.index_of(stems, stem)?;
            if let Some((stamp_ns, frame_id)) = recording.frame_header(index) {
                record.stamp_ns = Some(stamp_ns);
                record.frame_id = Some(frame_id.to_owned());
            }
        }
        Ok(())
    }
}
