//! What `dataset_to_mcap` and `dataset_to_bag` share: every frame of a dataset handed to a
//! recording writer with a 30 Hz stamp, and the exit status.

use std::process::ExitCode;

use pomona_core::RgbdFrame;
use pomona_io::Dataset;
use pomona_recording::RecordingError;

/// The stamp of frame 0 (2023-11-14T22:13:20Z), ns.
pub const FIRST_STAMP_NS: u64 = 1_700_000_000_000_000_000;
/// 29.97 Hz, ns.
pub const FRAME_INTERVAL_NS: u64 = 33_366_700;
/// The frame id every message carries.
pub const FRAME_ID: &str = "camera_color_optical_frame";

/// Loads every frame of the dataset at `data` and hands it to `write` with its stamp; returns
/// the number of frames.
pub fn record_dataset(
    data: &str,
    mut write: impl FnMut(u64, &RgbdFrame) -> Result<(), RecordingError>,
) -> Result<usize, Box<dyn std::error::Error>> {
    let dataset = Dataset::open(data)?;
    for (i, stem) in dataset.frames().iter().enumerate() {
        let frame = dataset.load_frame(stem)?;
        write(FIRST_STAMP_NS + i as u64 * FRAME_INTERVAL_NS, &frame)?;
    }
    Ok(dataset.frames().len())
}

/// The two positional arguments (dataset, output) among `args`.
pub fn positional(args: &[String]) -> Option<(&str, &str)> {
    let p: Vec<&String> = args.iter().filter(|a| !a.starts_with("--")).collect();
    match p.as_slice() {
        [data, out] => Some((data.as_str(), out.as_str())),
        _ => None,
    }
}

/// Runs `run` on the command line and reports its outcome.
pub fn main_with(
    run: impl FnOnce(&[String]) -> Result<usize, Box<dyn std::error::Error>>,
) -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(n) => {
            let out = positional(&args).map_or("", |(_, out)| out);
            println!("wrote {n} frame(s) to {out}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
