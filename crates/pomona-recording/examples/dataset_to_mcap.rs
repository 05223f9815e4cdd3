//! Writes a dataset folder as a ROS 2 MCAP recording on the RealSense driver's default topics,
//! as if the camera had published its frames at 30 Hz: for benchmarks of `pomona extract` and
//! `pomona detect --recording` and for trying them without a robot.
//!
//! ```text
//! cargo run --release -p pomona-recording --example dataset_to_mcap -- DATASET OUT.mcap [--bgr] [--float-depth]
//! ```
//! Frame `i` is stamped `1.7e18 + i × 33 366 700` ns in `camera_color_optical_frame`; colour is
//! `rgb8` (`--bgr`: `bgr8`), depth `16UC1` millimetres (`--float-depth`: `32FC1` metres).

#[path = "common/record_dataset.rs"]
mod record_dataset;

use std::process::ExitCode;

use pomona_recording::{FrameEncodings, RecordingTopics, RecordingWriter};
use record_dataset::{main_with, positional, record_dataset, FRAME_ID};

fn run(args: &[String]) -> Result<usize, Box<dyn std::error::Error>> {
    let Some((data, out)) = positional(args) else {
        return Err("usage: dataset_to_mcap DATASET OUT.mcap [--bgr] [--float-depth]".into());
    };
    let encodings = FrameEncodings {
        bgr: args.iter().any(|a| a == "--bgr"),
        float_depth: args.iter().any(|a| a == "--float-depth"),
    };
    let topics = RecordingTopics::default();
    let mut writer = RecordingWriter::create(out)?;
    let n = record_dataset(data, |stamp_ns, frame| {
        writer.write_frame(&topics, stamp_ns, FRAME_ID, frame, encodings)
    })?;
    writer.finish()?;
    Ok(n)
}

fn main() -> ExitCode {
    main_with(run)
}
