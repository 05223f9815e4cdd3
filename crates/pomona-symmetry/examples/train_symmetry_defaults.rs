//! Trains the models embedded in the binary as the defaults of `symmetry`
//! (`models/symmetry.json`) and `viewer-pose` (`models/viewer-pose.json`): synthetic frames of
//! every fruit kind (one kind per frame), 64 for `symmetry` and the first 32 of them for
//! `viewer-pose`. The 64 are 48 of the `wide` domain (randomised leaves, backgrounds, light,
//! distances 0.3–1.6 m) from three cameras with their own depth noise (32 Kinect v2, 8 D435,
//! 8 SR4000) and 16 of the `narrow` crop row (Kinect v2, `tof`; trained on
//! wide frames alone, the models lost AP on narrow scenes and gained none on wide ones, see
//! docs/results.md), green fraction 0.5, dataset seeds 1000–1003 (reserved for
//! default models; tests and benchmarks use other seeds), training seed 1. Both pipelines use
//! their default parameters except highlight pruning, which is off (see [`without_pruning`];
//! `symmetry`'s boxes also reach 2 m, see [`reaching_two_metres`]),
//! and each model carries a confidence calibration and operating threshold fitted on 3
//! held-out folds (`pomona_pipeline::train_calibrated`).
//!
//! Mixed fruit rather than peppers only: the detectors are shape-only, with one 12 cm box that
//! holds every kind the scene generator makes, and the demo renders mixed fruit; the crate
//! README gives the mixed-fruit and pepper-only figures behind this choice.
//!
//! Both files are this recipe's output as it stands: `symmetry.json` rewritten on 6 December for
//! the cascade's weighted score (`CascadeParams::score_weight`), `viewer-pose.json` the same day
//! for its new fixed-frame cascade (docs/results.md, "Two classifiers, one score"). The normal
//! window's scaling on cameras finer than 615 px (`normals.scale_above_focal_px`, session 58)
//! touches none of the training cameras, so it was added to both files by hand; rerunning the
//! recipe afterwards gave both files byte for byte (`cmp`). Both were rewritten by the recipe
//! on 7 December (session 64) when the refinement began fitting only the side the camera sees
//! (`refinement.facing_camera`): the SVMs came out byte-identical, the radius and confidence
//! calibrations refitted.
//!
//! Model size: each support vector is 168 numbers, and each model holds two SVMs (the main one
//! and its cascade's fixed-frame one, see `CascadeParams`): the files are 5.6 and 2.7 MB
//! (`ModelFile::save` writes compact JSON). Rerun after changing the pipeline (about
//! 8 minutes on 2 cores):
//!
//! ```sh
//! cargo run --release -p pomona-symmetry --example train_symmetry_defaults -- crates/pomona-symmetry/models
//! ```

use pomona_learn::ModelFile;
use pomona_pipeline::{
    train_calibrated, CalibrationParams, ChainedFrames, FrameSource, Pipeline, SyntheticFrames,
    TrainOptions,
};
use pomona_symmetry::{StageParams, SymmetryPipeline, ViewerPosePipeline};
use pomona_synth::{CameraPreset, Domain};

/// The domains and cameras of the training frames, with the dataset seeds reserved for the
/// default models.
const CAMERAS: [(Domain, CameraPreset, u64); 4] = [
    (Domain::Narrow, CameraPreset::KinectV2, 1003),
    (Domain::Wide, CameraPreset::KinectV2, 1000),
    (Domain::Wide, CameraPreset::D435, 1001),
    (Domain::Wide, CameraPreset::Sr4000, 1002),
];

/// Frames per entry of [`CAMERAS`] for `symmetry` (64) and for `viewer-pose` (32, the first
/// frames of the same seeds): each count scored best on the held-out wide sets of two seed
/// batches (docs/results.md, "Highlight pruning off").
const SYMMETRY_FRAMES: [usize; 4] = [16, 32, 8, 8];
const VIEWER_POSE_FRAMES: [usize; 4] = [12, 12, 4, 4];

/// Seed of the training (sampling of negatives and jitters, cross-validation folds).
const TRAIN_SEED: u64 = 1;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::path::PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "crates/pomona-symmetry/models".into()),
    );
    let options = TrainOptions {
        seed: TRAIN_SEED,
        ..TrainOptions::default()
    };
    let progress = |done: usize, total: usize| eprint!("\rframes {done}/{total}");
    let pipelines: [(&str, [usize; 4], Box<dyn Pipeline>); 2] = [
        (
            "symmetry.json",
            SYMMETRY_FRAMES,
            Box::new(SymmetryPipeline::with_params(reaching_two_metres(
                without_pruning(StageParams::symmetry()),
            ))),
        ),
        (
            "viewer-pose.json",
            VIEWER_POSE_FRAMES,
            Box::new(ViewerPosePipeline::with_params(without_pruning(
                StageParams::viewer_pose(),
            ))),
        ),
    ];
    for (name, counts, pipeline) in pipelines {
        let start = std::time::Instant::now();
        // Rendered once per pipeline, trained on by every calibration fold.
        let frames = ChainedFrames(
            CAMERAS
                .iter()
                .zip(counts)
                .map(|(&(domain, camera, seed), count)| {
                    SyntheticFrames::mixed_fruit(domain, camera, 0.5, seed, count)
                })
                .collect(),
        )
        .load_all()?;
        let trained = train_calibrated(
            pipeline.as_ref(),
            &frames,
            &options,
            &CalibrationParams::default(),
            &progress,
        )?;
        eprintln!();
        let model = trained.model;
        let calibration = match &model.calibration {
            Some(c) => c.to_string(),
            None => format!(
                "no calibration: {}",
                trained.not_calibrated.unwrap_or_default()
            ),
        };
        let out = dir.join(name);
        model.save(&out)?;
        let bytes = std::fs::metadata(&out)?.len();
        // The file must load back as this pipeline's model.
        ModelFile::load(&out, pipeline.name())?;
        let cascade = model.stage_params["cascade"]["classifier"]["svm"]["coef"]
            .as_array()
            .map_or(0, Vec::len);
        println!(
            "wrote {} ({:.2} MB): {} support vectors (+ {cascade} in the cascade), {calibration}, \
             {:.1} s",
            out.display(),
            bytes as f64 / 1e6,
            model.svm.n_support(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// The built-in models detect without highlight pruning (seed 000's first stage). Pruning keeps
/// only boxes near a detected specular highlight; in the `wide` worlds (random exposure, gloss,
/// shade) many fruit show none, and on the held-out wide sets pruning removed up to half of the
/// fruit before any box was scored (docs/results.md, "Highlight pruning off").
/// `pomona train` keeps the paper's default (on).
fn without_pruning(mut params: StageParams) -> StageParams {
    params.highlight.enabled = false;
    params
}

/// `symmetry`'s boxes reach 2 m from the camera instead of 1.6 m: the real orchard frames in
/// `../shared/data/ak-apples` hold apples up to 1.9 m deep (2 m along the ray), which the
/// narrower range never scored. Trained this way, `symmetry` found 24 of their 84 tagged apples
/// at its operating confidence against 15; `viewer-pose` found fewer (22 against 32) and lost
/// held-out AP, so it keeps 1.6 m (docs/results.md, "Highlight pruning off").
fn reaching_two_metres(mut params: StageParams) -> StageParams {
    params.boxes.max_range_m = 2.0;
    params
}
