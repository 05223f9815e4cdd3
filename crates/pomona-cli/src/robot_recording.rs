//! What `extract` and `detect --recording` share: the flags choosing a recording's (ROS 2 MCAP,
//! ROS 1 bag or RealSense bag) topics and sync tolerance, opening it, and telling the user which colour images found no
//! depth (they are skipped, never silently).

use std::path::Path;

use anyhow::{bail, Context, Result};
use pomona_recording::{Recording, RecordingFormat, RecordingOptions, TopicRequest};

/// Topic and synchronisation flags of the commands that read recordings.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct RecordingArgs {
    /// Colour topic (`sensor_msgs/Image`, rgb8 or bgr8) [default: MCAP
    /// /camera/camera/color/image_raw, ROS 1 bag /camera/color/image_raw].
    #[arg(long, value_name = "TOPIC")]
    pub color_topic: Option<String>,
    /// Depth topic registered to colour (`sensor_msgs/Image`, 16UC1 mm or 32FC1 m) [default:
    /// MCAP /camera/camera/aligned_depth_to_color/image_raw, ROS 1 bag
    /// /camera/aligned_depth_to_color/image_raw].
    #[arg(long, value_name = "TOPIC")]
    pub depth_topic: Option<String>,
    /// Colour camera-info topic (`sensor_msgs/CameraInfo`) [default: MCAP
    /// /camera/camera/color/camera_info, ROS 1 bag /camera/color/camera_info]. A ROS 1 bag
    /// without the defaults and no topic flag is read as a RealSense SDK bag when it has
    /// /device_0/... streams.
    #[arg(long, value_name = "TOPIC")]
    pub info_topic: Option<String>,
    /// Largest difference between a colour and a depth header stamp of one frame, ms.
    #[arg(long, value_name = "MS", default_value_t = 20.0)]
    pub sync_tolerance_ms: f64,
}

impl Default for RecordingArgs {
    fn default() -> Self {
        Self {
            color_topic: None,
            depth_topic: None,
            info_topic: None,
            sync_tolerance_ms: 20.0,
        }
    }
}

impl RecordingArgs {
    /// The reader options these flags ask for.
    ///
    /// # Errors
    /// A negative or non-finite tolerance.
    pub fn options(&self) -> Result<RecordingOptions> {
        let ms = self.sync_tolerance_ms;
        if !(ms.is_finite() && ms >= 0.0) {
            bail!("--sync-tolerance-ms must be a finite number ≥ 0 (got {ms})");
        }
        Ok(RecordingOptions {
            topics: TopicRequest {
                color: self.color_topic.clone(),
                depth: self.depth_topic.clone(),
                camera_info: self.info_topic.clone(),
            },
            sync_tolerance_ns: (ms * 1e6).round() as u64,
        })
    }

    /// Opens `path` and reports on standard error the colour images that have no depth within
    /// the tolerance (and duplicate stamps), which are not frames.
    ///
    /// # Errors
    /// Bad flags, or a recording that cannot be read (naming the file; a missing topic lists
    /// the recording's topics).
    pub fn open(&self, path: &Path) -> Result<Recording> {
        let recording = Recording::open_with(path, &self.options()?)
            .with_context(|| format!("cannot read recording {}", path.display()))?;
        if recording.format() == RecordingFormat::RealSenseBag {
            let topics = recording.selected_topics();
            eprintln!(
                "note: {} is a RealSense SDK bag: colour {}, depth {} registered to colour",
                path.display(),
                topics.color,
                topics.depth
            );
        }
        let unmatched = recording.unmatched_color_ns();
        if let (Some(first), Some(last)) = (unmatched.first(), unmatched.last()) {
            eprintln!(
                "warning: {} of {} colour image(s) in {} have no depth image within {} ms and \
                 are skipped (stamps {first} … {last} ns); widen --sync-tolerance-ms to keep them",
                unmatched.len(),
                recording.message_counts().0,
                path.display(),
                self.sync_tolerance_ms
            );
        }
        if recording.duplicate_color() > 0 {
            eprintln!(
                "warning: {} colour image(s) in {} repeat an earlier stamp and are skipped",
                recording.duplicate_color(),
                path.display()
            );
        }
        Ok(recording)
    }
}
