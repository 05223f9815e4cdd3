//! Time one detection call: the `Detector::detect` of one frame already in memory, repeated, as
//! the reference the Python binding's `Detector.detect` is measured against (docs/results.md).
//!
//! ```text
//! RAYON_NUM_THREADS=1 cargo run --release -p pomona --example time_detect -- DATASET [PIPELINE] [REPEATS]
//! ```
//! Prints the median and every time in milliseconds, for the first frame of DATASET.

use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let Some(data) = args.next() else {
        return Err("usage: time_detect DATASET [PIPELINE] [REPEATS]".into());
    };
    let pipeline = args.next().unwrap_or_else(|| "shape-fit".to_owned());
    let repeats: usize = args.next().map_or(Ok(20), |r| r.parse())?;

    let dataset = pomona::Dataset::open(&data)?;
    let Some(stem) = dataset.frames().first() else {
        return Err(format!("{data} has no frames").into());
    };
    let frame = dataset.load_frame(stem)?;
    let detector = pomona::Detector::builtin(&pipeline)?;
    detector.detect(&frame)?; // warm-up
    let mut ms: Vec<f64> = (0..repeats)
        .map(|_| {
            let started = Instant::now();
            detector
                .detect(&frame)
                .map(|_| 1e3 * started.elapsed().as_secs_f64())
        })
        .collect::<Result<_, _>>()?;
    let shown: Vec<String> = ms.iter().map(|t| format!("{t:.2}")).collect();
    ms.sort_by(f64::total_cmp);
    let median = ms.get(ms.len() / 2).copied().unwrap_or(f64::NAN);
    println!(
        "rust {pipeline} {stem}: median {median:.2} ms over {repeats} ({})",
        shown.join(" ")
    );
    Ok(())
}
