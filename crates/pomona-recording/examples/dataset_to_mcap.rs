//! Writes a dataset folder as a ROS 2 MCAP recording on the RealSense driver's default topics,
//! as if the camera had published its frames at 30 Hz: for benchmarks of `pomona extract` and
//! `pomona detect --recording` and for trying them without a robot.
//!
//! ```text
//! cargo run --release -p pomona-recording --example dataset_to_mcap -- DATASET OUT.mcap [--bgr] [--float-depth]
//! ```
//! Frame `i` is stamped `1.7e18 + i × 33 366 700` ns in `camera_color_optical_frame`; colour is
//! `rgb8` (`--bgr`: `bgr8`), depth `16UC1` millimetres (`--float-depth`: `32FC1` metres).

use std::process::ExitCode;

use pomona_io::Dataset;
use pomona_recording::{FrameEncodings, RecordingTopics, RecordingWriter};

const FIRST_STAMP_NS: u64 = 1_700_000_000_000_000_000;
const FRAME_INTERVAL_NS: u64 = 33_366_700;

fn run(args: &[String]) -> Result<usize, Box<dyn std::error::Error>> {
    let positional: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    let [data, out] = positional.as_slice() else {
        return Err("usage: dataset_to_mcap DATASET OUT.mcap [--bgr] [--float-depth]".into());
    };
    let encodings = FrameEncodings {
        bgr: args.iter().any(|a| a == "--bgr"),
        float_depth: args.iter().any(|a| a == "--float-depth"),
    };
    let dataset = Dataset::open(data.as_str())?;
    let topics = RecordingTopics::default();
    let mut writer = RecordingWriter::create(out.as_str())?;
    for (i, stem) in dataset.frames().iter().enumerate() {
        let frame = dataset.load_frame(stem)?;
        let stamp_ns = FIRST_STAMP_NS + i as u64 * FRAME_INTERVAL_NS;
        writer.write_frame(
            &topics,
            stamp_ns,
            "camera_color_optical_frame",
            &frame,
            encodings,
        )?;
    }
    writer.finish()?;
    Ok(dataset.frames().len())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(n) => {
            println!(
                "wrote {n} frame(s) to {}",
                args.get(1).map_or("", String::as_str)
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
