//! `pomona extract`: a recording (ROS 2 MCAP, ROS 1 bag or RealSense bag) written out as a dataset folder (camera.json,
//! `color/`, `depth/`; no truth), so every dataset command works on a recording.
//!
//! Frames are the recording's synchronised colour/depth pairs (see `pomona-recording`), named
//! by the colour header stamp in nanoseconds, 19 digits. The depth unit keeps the recording's
//! depth: 1 mm for `16UC1`, the finest unit from 0.1 mm up whose 16-bit range reaches the
//! farthest depth for `32FC1` (`pomona_recording::dataset_depth_unit_m`). Frames are decoded and
//! written in parallel; the camera must be the same in every frame (one `camera.json`).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use pomona_io::DatasetWriter;
use pomona_recording::{dataset_depth_unit_m, frame_stem};
use rayon::prelude::*;

use crate::progress::progress_bar;
use crate::robot_recording::RecordingArgs;

/// Arguments of `pomona extract`.
#[derive(Debug, Clone, clap::Args)]
pub struct ExtractArgs {
    /// The recording: ROS 2 MCAP (`ros2 bag record`), ROS 1 bag (`rosbag record`) or RealSense
    /// Viewer `.bag`, told apart by the file's first bytes.
    #[arg(value_name = "FILE")]
    pub file: PathBuf,
    /// Dataset folder to write (created if missing).
    #[arg(long, value_name = "DATASET")]
    pub out: PathBuf,
    /// Topics and synchronisation.
    #[command(flatten)]
    pub recording: RecordingArgs,
}

/// What an extraction did.
#[derive(Debug, Clone, PartialEq)]
pub struct ExtractSummary {
    /// Frames written.
    pub frames: usize,
    /// Colour images skipped for want of depth within the tolerance.
    pub unmatched: usize,
    /// The dataset's depth unit, metres.
    pub depth_unit_m: f64,
}

/// Runs `pomona extract`.
///
/// # Errors
/// An unreadable recording (naming the file), a frame that cannot be decoded (naming topic and
/// stamp), a camera that changes between frames, or an unwritable dataset.
pub fn run(args: &ExtractArgs) -> Result<()> {
    let started = Instant::now();
    let summary = extract(args)?;
    let wall = started.elapsed().as_secs_f64();
    println!(
        "extracted {} frame(s) from {} into {} in {wall:.2} s ({:.1} frames/s); depth unit {} m{}",
        summary.frames,
        args.file.display(),
        args.out.display(),
        summary.frames as f64 / wall.max(1e-9),
        summary.depth_unit_m,
        if summary.unmatched > 0 {
            format!(
                "; {} colour image(s) without depth skipped",
                summary.unmatched
            )
        } else {
            String::new()
        }
    );
    Ok(())
}

/// Writes the dataset and says what it wrote.
///
/// # Errors
/// As [`run`].
pub fn extract(args: &ExtractArgs) -> Result<ExtractSummary> {
    let recording = args.recording.open(&args.file)?;
    let count = recording.frame_count();
    if count == 0 {
        bail!(
            "{} has no synchronised frames ({} colour, {} depth images; none within {} ms)",
            args.file.display(),
            recording.message_counts().0,
            recording.message_counts().1,
            args.recording.sync_tolerance_ms
        );
    }
    let depth_unit_m = dataset_depth_unit_m(&recording)?;
    let first = recording.load_frame(0)?;
    let camera = *first.frame.camera();
    let writer = DatasetWriter::create(&args.out, &camera, depth_unit_m)
        .with_context(|| format!("cannot create dataset {}", args.out.display()))?;
    let bar = progress_bar(count, "extracting");
    (0..count).into_par_iter().try_for_each(|i| -> Result<()> {
        let synced = recording.load_frame(i)?;
        if synced.frame.camera() != &camera {
            bail!(
                "{}: the camera info of frame {} differs from that of the first frame {} \
                 ({:?} vs {:?}); a dataset has one camera",
                args.file.display(),
                synced.stamp_ns,
                first.stamp_ns,
                synced.frame.camera(),
                camera
            );
        }
        let stem = frame_stem(synced.stamp_ns);
        if let Some(color) = synced.frame.color() {
            writer.write_color(&stem, color)?;
        }
        writer.write_depth(&stem, synced.frame.depth())?;
        bar.inc(1);
        Ok(())
    })?;
    bar.finish_and_clear();
    Ok(ExtractSummary {
        frames: count,
        unmatched: recording.unmatched_color_ns().len(),
        depth_unit_m,
    })
}
