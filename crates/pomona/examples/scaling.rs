//! How detection time grows with the number of points and with the number of fruit, per
//! built-in pipeline (issue 17: "state the growth, expected linear; say where it is not").
//!
//! ```text
//! RAYON_NUM_THREADS=1 cargo run --release -p pomona --example scaling [-- ROUNDS]
//! ```
//!
//! * **Points:** the same three `wide` scenes of mixed fruit (seed 640) rendered by a Kinect v2
//!   scaled to 0.5, 0.71, 1, 1.41 and 2 times its 512×424 pixels (a quarter to four times the
//!   points; the scene in metres is the same, since a scaled camera sees the same rays).
//! * **Fruit:** `wide` Kinect v2 scenes with exactly 2, 4, 8, 16 and 32 fruit (seed 641, three
//!   frames each); the detections before any threshold are printed as the number of
//!   candidates that survive to the end.
//!
//! Each configuration: one warm-up pass, then ROUNDS (default 5) passes over its frames; the
//! figure is the median over passes of the time per frame. The growth exponent is the slope of
//! a least-squares line through `ln time` against `ln size` (1 is linear); for fruit, the
//! marginal milliseconds per added fruit is the slope of the straight-line fit as well. Run with
//! `RAYON_NUM_THREADS=1` for one thread.

use std::time::Instant;

use pomona::{Detector, RgbdFrame};
use pomona_synth::{render, CameraPreset, Domain, FruitChoice, NoiseModel, SceneSpec};

const PIPELINES: [&str; 4] = ["shape-fit", "symmetry", "viewer-pose", "color-contour"];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let rounds: usize = std::env::args().nth(1).map_or(Ok(5), |r| r.parse())?;
    let base = SceneSpec {
        fruit: FruitChoice::Mixed,
        camera: CameraPreset::KinectV2.camera(),
        noise: NoiseModel::for_camera(CameraPreset::KinectV2),
        green_fraction: 0.2,
        domain: Domain::Wide,
        ..SceneSpec::default()
    };
    let mut by_points = Vec::new();
    for scale in [
        0.5,
        std::f64::consts::FRAC_1_SQRT_2,
        1.0,
        std::f64::consts::SQRT_2,
        2.0,
    ] {
        let spec = SceneSpec {
            camera: base.camera.scaled(scale),
            ..base.clone()
        };
        let frames = frames(&spec, 640)?;
        by_points.push((spec.camera.pixel_count() as f64, frames));
    }
    let mut by_fruit = Vec::new();
    for n in [2u32, 4, 8, 16, 32] {
        let spec = SceneSpec {
            fruit_count: (n, n),
            ..base.clone()
        };
        by_fruit.push((f64::from(n), frames(&spec, 641)?));
    }

    println!("| pipeline | sweep | size | ms/frame (median of {rounds}) | detections/frame |");
    println!("|---|---|---:|---:|---:|");
    let mut summary = Vec::new();
    for name in PIPELINES {
        let detector = Detector::builtin(name)?;
        let mut fits = Vec::new();
        for (sweep, sets) in [("pixels", &by_points), ("fruit", &by_fruit)] {
            let mut points = Vec::new();
            for (size, frames) in sets.iter() {
                let (ms, detections) = time_per_frame(&detector, frames, rounds)?;
                println!("| {name} | {sweep} | {size:.0} | {ms:.2} | {detections:.1} |");
                points.push((*size, ms));
            }
            let log: Vec<(f64, f64)> = points.iter().map(|(x, y)| (x.ln(), y.ln())).collect();
            fits.push((sweep, least_squares(&log).0, least_squares(&points)));
        }
        summary.push((name, fits));
    }
    println!();
    println!("| pipeline | sweep | growth exponent | straight line: ms at 0 + ms per unit |");
    println!("|---|---|---:|---|");
    for (name, fits) in summary {
        for (sweep, exponent, (slope, intercept)) in fits {
            let unit = if sweep == "pixels" {
                "per 100k px"
            } else {
                "per fruit"
            };
            let per = if sweep == "pixels" {
                slope * 1e5
            } else {
                slope
            };
            println!("| {name} | {sweep} | {exponent:.2} | {intercept:.1} + {per:.2} {unit} |");
        }
    }
    Ok(())
}

/// Three rendered frames of `spec`.
fn frames(spec: &SceneSpec, seed: u64) -> Result<Vec<RgbdFrame>, Box<dyn std::error::Error>> {
    (0..3)
        .map(|i| {
            let scene = spec.sample_frame(seed, i)?;
            Ok(render(&scene, &spec.camera)?.frame)
        })
        .collect()
}

/// Median over `rounds` passes of the time per frame (ms), and the detections per frame.
fn time_per_frame(
    detector: &Detector,
    frames: &[RgbdFrame],
    rounds: usize,
) -> Result<(f64, f64), Box<dyn std::error::Error>> {
    let mut detections = 0;
    for frame in frames {
        detections += detector.detect(frame)?.len(); // warm-up
    }
    let mut per_frame = Vec::with_capacity(rounds);
    for _ in 0..rounds.max(1) {
        let started = Instant::now();
        for frame in frames {
            detector.detect(frame)?;
        }
        per_frame.push(1e3 * started.elapsed().as_secs_f64() / frames.len() as f64);
    }
    per_frame.sort_by(f64::total_cmp);
    Ok((
        per_frame[per_frame.len() / 2],
        detections as f64 / frames.len() as f64,
    ))
}

/// Slope and intercept of the least-squares line through `(x, y)`.
fn least_squares(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len() as f64;
    let (mx, my) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), (x, y)| {
        (a + (x - mx) * (y - my), b + (x - mx) * (x - mx))
    });
    let slope = sxy / sxx;
    (slope, my - slope * mx)
}
