//! Writes a dataset folder as a ROS 1 bag on the RealSense ROS 1 driver's default topics, as if
//! the camera had published its frames at 30 Hz: for benchmarks of `pomona extract` and
//! `pomona detect --recording` on bags and for trying them without a robot.
//!
//! ```text
//! cargo run --release -p pomona-recording --example dataset_to_bag -- DATASET OUT.bag [--bz2 | --lz4] [--bgr] [--float-depth]
//! ```
//! Frame `i` is stamped `1.7e18 + i × 33 366 700` ns in `camera_color_optical_frame`; colour is
//! `rgb8` (`--bgr`: `bgr8`), depth `16UC1` millimetres (`--float-depth`: `32FC1` metres); chunks
//! are stored uncompressed unless `--bz2` or `--lz4`.

#[path = "common/record_dataset.rs"]
mod record_dataset;

use std::process::ExitCode;

use pomona_recording::{BagCompression, BagWriter, FrameEncodings, RecordingTopics};
use record_dataset::{main_with, positional, record_dataset, FRAME_ID};

fn run(args: &[String]) -> Result<usize, Box<dyn std::error::Error>> {
    let Some((data, out)) = positional(args) else {
        return Err(
            "usage: dataset_to_bag DATASET OUT.bag [--bz2 | --lz4] [--bgr] [--float-depth]".into(),
        );
    };
    let flag = |name: &str| args.iter().any(|a| a == name);
    let compression = match (flag("--bz2"), flag("--lz4")) {
        (true, true) => return Err("--bz2 and --lz4 exclude each other".into()),
        (true, false) => BagCompression::Bz2,
        (false, true) => BagCompression::Lz4,
        (false, false) => BagCompression::None,
    };
    let encodings = FrameEncodings {
        bgr: flag("--bgr"),
        float_depth: flag("--float-depth"),
    };
    let topics = RecordingTopics::ros1();
    let mut writer = BagWriter::create(out, compression)?;
    let n = record_dataset(data, |stamp_ns, frame| {
        writer.write_frame(&topics, stamp_ns, FRAME_ID, frame, encodings)
    })?;
    writer.finish()?;
    Ok(n)
}

fn main() -> ExitCode {
    main_with(run)
}
