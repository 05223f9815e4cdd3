//! Trains the model embedded in the binary as color-contour's default: synthetic oranges,
//! fixed seeds — 40 `wide` frames (randomised leaves, backgrounds, light, distances 0.3–1.6 m,
//! ripe, green, blushed and yellow fruit; 24 Kinect v2, 16 D435) and 30 `orchard` frames (citrus
//! trees, touching clusters, orange to yellow-green fruit; 6 Kinect v2 frames under each of the
//! five light presets) — with a confidence
//! calibration and operating threshold fitted on 3 held-out folds
//! (`pomona_pipeline::train_calibrated`). Then prints the colour classifier's pixel precision,
//! recall and F1 on held-out orange frames: 16 `wide` D435 frames, 8 `narrow` Kinect v2 frames
//! per lighting preset and 6 `orchard` frames per preset. Rerun after changing the pipeline:
//!
//! ```sh
//! cargo run --release -p pomona-colorcontour --example train_color_contour_default -- crates/pomona-colorcontour/models
//! ```
//!
//! With `--no-orchard` after the folder, the 40 `wide` frames alone (the built-in recipe until 3
//! December; docs/results.md, "Training on orchard light", explains the change). With
//! `--ray-circles`, the model runs and is calibrated with the ray circles on (the "after" model of
//! docs/results.md, "Ray circles from inscribed discs"); with `--no-hough-circles`, without the
//! Hough circles that the pipeline's defaults now run. The shipped file is this example's output
//! byte for byte (since the colour network's intensity input, docs/results.md, "Colour with
//! intensity"); training is deterministic.

use pomona_colorcontour::{
    pixel_counts, ColorContourPipeline, ColorContourStageParams, HSigmaLut, RayCircleParams,
};
use pomona_pipeline::{
    train_calibrated, CalibrationParams, ChainedFrames, FrameSource, SyntheticFrames, TrainOptions,
};
use pomona_synth::{
    CameraPreset, Domain, FruitChoice, FruitKind, LightPreset, NoiseModel, SceneSpec,
};

/// `wide` training frames per camera; seeds 1400–1401 and 1420–1424 (orchard, unless `--no-orchard`)
/// are reserved for this model, 1410–1413 and 1430–1434 for the held-out pixel scores.
const CAMERAS: [(CameraPreset, usize, u64); 2] = [
    (CameraPreset::KinectV2, 24, 1400),
    (CameraPreset::D435, 16, 1401),
];
/// The light presets of the `orchard` frames, each with its training and held-out seed.
const ORCHARD_LIGHTS: [(LightPreset, u64, u64); 5] = [
    (LightPreset::Day, 1420, 1430),
    (LightPreset::Dim, 1421, 1431),
    (LightPreset::Harsh, 1422, 1432),
    (LightPreset::LowSun, 1423, 1433),
    (LightPreset::Backlight, 1424, 1434),
];
/// `orchard` frames per light preset, for the held-out pixel scores and (unless `--no-orchard`)
/// training.
const ORCHARD_FRAMES: usize = 6;
const TRAIN_SEED: u64 = 1;

fn oranges(
    domain: Domain,
    camera: CameraPreset,
    light: LightPreset,
    seed: u64,
    count: usize,
) -> SyntheticFrames {
    SyntheticFrames {
        spec: SceneSpec {
            fruit: FruitChoice::Only(FruitKind::Orange),
            camera: camera.camera(),
            noise: match domain {
                Domain::Narrow => NoiseModel::Tof,
                Domain::Wide | Domain::Orchard => NoiseModel::for_camera(camera),
            },
            light,
            domain,
            backgrounds: domain.default_backgrounds(),
            ..SceneSpec::default()
        },
        seed,
        first: 0,
        count,
    }
}

/// `orchard` frames of oranges under `light` (Kinect v2), the domain's own backgrounds.
fn orchard(light: LightPreset, seed: u64) -> SyntheticFrames {
    oranges(
        Domain::Orchard,
        CameraPreset::KinectV2,
        light,
        seed,
        ORCHARD_FRAMES,
    )
}

/// The held-out sets of the pixel scores: `wide` D435, `narrow` Kinect v2 per light preset,
/// `orchard` per light preset.
fn held_out_sets() -> Vec<(&'static str, SyntheticFrames)> {
    let narrow = |light, seed| oranges(Domain::Narrow, CameraPreset::KinectV2, light, seed, 8);
    let mut sets = vec![
        (
            "wide d435",
            oranges(Domain::Wide, CameraPreset::D435, LightPreset::Day, 1410, 16),
        ),
        ("narrow day", narrow(LightPreset::Day, 1411)),
        ("narrow dim", narrow(LightPreset::Dim, 1412)),
        ("narrow harsh", narrow(LightPreset::Harsh, 1413)),
    ];
    for &(light, _, seed) in &ORCHARD_LIGHTS {
        sets.push(("orchard", orchard(light, seed)));
    }
    sets
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = std::path::PathBuf::from(
        args.next()
            .unwrap_or_else(|| "crates/pomona-colorcontour/models".into()),
    );
    let (mut with_orchard, mut ray_circles, mut hough_circles) = (true, false, true);
    for arg in args {
        match arg.as_str() {
            "--no-orchard" => with_orchard = false,
            "--ray-circles" => ray_circles = true,
            "--no-hough-circles" => hough_circles = false,
            other => {
                return Err(format!(
                    "unexpected argument `{other}`; usage: train_color_contour_default [DIR] \
                     [--no-orchard] [--ray-circles] [--no-hough-circles]"
                )
                .into())
            }
        }
    }
    let rendered = ChainedFrames(
        CAMERAS
            .iter()
            .map(|&(camera, count, seed)| {
                oranges(Domain::Wide, camera, LightPreset::Day, seed, count)
            })
            .chain(
                ORCHARD_LIGHTS
                    .iter()
                    .filter(|_| with_orchard)
                    .map(|&(light, seed, _)| orchard(light, seed)),
            )
            .collect(),
    );
    let frames = rendered.load_all()?;
    let mut pipeline = ColorContourPipeline::default();
    if ray_circles {
        pipeline.params.ray_circles = Some(RayCircleParams::default());
    }
    if !hough_circles {
        pipeline.params.hough_circles = None;
    }
    let options = TrainOptions {
        seed: TRAIN_SEED,
        ..TrainOptions::default()
    };
    let progress = |done: usize, total: usize| eprint!("\rframes {done}/{total}");
    let start = std::time::Instant::now();
    let trained = train_calibrated(
        &pipeline,
        &frames,
        &options,
        &CalibrationParams::default(),
        &progress,
    )?;
    eprintln!();
    let model = trained.model;
    let out = dir.join("default.json");
    model.save(&out)?;
    let calibration = match &model.calibration {
        Some(c) => c.to_string(),
        None => format!(
            "no calibration: {}",
            trained.not_calibrated.unwrap_or_default()
        ),
    };
    println!(
        "wrote {}: {calibration}, {:.1} s",
        out.display(),
        start.elapsed().as_secs_f64()
    );

    let stage: ColorContourStageParams = serde_json::from_value(model.stage_params.clone())?;
    let lut = HSigmaLut::compile(&stage.mlp);
    let threshold = pomona_colorcontour::quantise_probability(stage.params.color_threshold);
    let held_out = held_out_sets();
    for (name, set) in &held_out {
        let counts = pixel_counts(set as &dyn FrameSource, &lut, threshold)?;
        let (p, r, f1) = counts.precision_recall_f1();
        let light = set.spec.light;
        println!(
            "pixel colour, held-out {name} ({light:?}): precision {p:.3} recall {r:.3} F1 {f1:.3}"
        );
    }
    Ok(())
}
