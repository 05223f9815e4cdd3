//! Follow one fruit through the frames of a dataset, using only the `pomona` library: what the
//! arm's program does while it closes in — detect once, choose the fruit, then track it every
//! frame (seed 004's approach tracker, a fraction of a millisecond a frame).
//!
//! ```text
//! cargo run --release -p pomona --example track_fruit -- DATASET
//! ```
//! Starts from the first frame's most confident `color-contour` detection and prints the
//! estimate of every frame (an approach sequence of `pomona synth --approach` is one dataset per
//! `seq-*` folder).

use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Some(data) = std::env::args().nth(1) else {
        return Err("usage: track_fruit DATASET".into());
    };
    let dataset = pomona::Dataset::open(&data)?;
    let Some(first) = dataset.frames().first() else {
        return Err(format!("{data} has no frames").into());
    };

    // Choose: the most confident detection of the first frame.
    let detector = pomona::Detector::builtin("color-contour")?;
    let found = detector.detect(&dataset.load_frame(first)?)?;
    let Some(chosen) = found
        .iter()
        .filter(|d| detector.keeps(d))
        .max_by(|a, b| a.score.total_cmp(&b.score))
        .and_then(|d| d.image_circle(dataset.camera()))
    else {
        return Err(format!("no fruit detected in frame {first} of {data}").into());
    };
    println!(
        "start: ({:.1}, {:.1}) px, radius {:.1} px",
        chosen.center_px.x, chosen.center_px.y, chosen.radius_px
    );

    // Follow it.
    let tracker = pomona::Tracker::builder().build()?;
    let mut track = tracker.start(chosen)?;
    for stem in dataset.frames() {
        let Some(color) = dataset.load_color(stem)? else {
            return Err(format!("frame {stem} of {data} has no colour image").into());
        };
        let started = Instant::now();
        let estimate = track.update(&color);
        println!(
            "{stem}: ({:.1}, {:.1}) px, radius {:.1} px, {:?}, {:.3} ms",
            estimate.center_px.x,
            estimate.center_px.y,
            estimate.radius_px,
            estimate.status,
            started.elapsed().as_secs_f64() * 1e3
        );
    }
    Ok(())
}
