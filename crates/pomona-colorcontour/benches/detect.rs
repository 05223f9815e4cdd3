//! Color-contour end to end with the embedded default model on frames held in memory (fixed
//! seeds), in a one-thread rayon pool; one iteration detects every frame of a set, so divide by
//! three for a frame:
//!
//! * `wide d435`: three `wide` 640×480 D435 frames of mixed fruit (seed 611, never used for
//!   training), the resolution seed 004's speed target is stated for;
//! * `orchard kinect-v2`: three `orchard` frames of citrus trees in daylight (seed 612), the
//!   domain the model is tested on but never trained on;
//! * `real ecopom apple`: the first colour-only frame of `../shared/data/ecopom-apples-2d`
//!   (D435i colour, 1280×720, 2D detection); skipped with a message when the data folder is
//!   absent (and a failure with `POMONA_REQUIRE_DATA=1`). Twice: with the built-in model, whose
//!   colour class (oranges) marks little of an apple orchard, and with a model trained by the
//!   pipeline on the other seven real frames (seed 0, as `pomona train` would), the case a user
//!   with their own orchard meets — its mask holds every apple, so contours, edge fit and Hough
//!   circles have several times the work.
//!
//! * `... ray circles on` / `ray circles alone`: the orchard frames with the opt-in ray circles
//!   (`params.ray_circles`), end to end and the stage alone on their cleaned fruit masks;
//!   `hough circles alone`: the Hough circles (on in the built-in model) on the same masks;
//!   `depth cut alone`: the mask cut at depth steps (on in the built-in model) on the cleaned
//!   masks and depth of both synthetic sets; `depth spheres alone`: the circles of spheres
//!   fitted to the depth (on in the built-in model) on those masks once cut, and both sets end
//!   to end with them off.
//! * `colour table compiled`: the built-in network compiled into its lookup table (with the
//!   intensity input: eight planes, in the rayon pool of one thread), and the same network
//!   without its intensity weights (the paper's single plane) — the cost of loading a model.
//!
//! `cargo bench -p pomona-colorcontour --bench detect`

#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion};
use pomona_colorcontour::stages::MaskCleaningStage;
use pomona_colorcontour::{
    cut_at_depth_steps, depth_sphere_circles, hough_circles, ray_circles, ColorContourDetector,
    ColorContourPipeline, ColorContourStageParams, HSigmaLut,
};
use pomona_core::RgbdFrame;
use pomona_io::Dataset;
use pomona_learn::ModelFile;
use pomona_pipeline::SyntheticFrames;
use pomona_pipeline::{
    DatasetFrames, Detector, FrameSource, Pipeline, Stage, StageTimings, TrainOptions,
};
use pomona_synth::{
    CameraPreset, Domain, FruitChoice, FruitKind, LightPreset, NoiseModel, SceneSpec,
};

fn load(frames: &dyn FrameSource) -> Vec<RgbdFrame> {
    (0..frames.len())
        .map(|i| frames.load(i).unwrap_or_else(|e| panic!("{e}")).frame)
        .collect()
}

/// The first ecopom-apples-2d frame and a model trained on the other frames, when the data is
/// there.
fn real_apple_frame(pipeline: &ColorContourPipeline) -> Option<(RgbdFrame, ModelFile)> {
    let root = pomona_test_support::shared_data(
        "ecopom-apples-2d",
        "pomona-colorcontour/benches/detect.rs",
    )?;
    let all = DatasetFrames::new(vec![Dataset::open(&root).unwrap_or_else(|e| panic!("{e}"))]);
    let others: Vec<usize> = (1..all.len()).collect();
    let model = pipeline
        .train(&all.subset(&others), &TrainOptions::default(), &|_, _| {})
        .unwrap_or_else(|e| panic!("{e}"));
    Some((all.load(0).unwrap_or_else(|e| panic!("{e}")).frame, model))
}

fn detect(c: &mut Criterion) {
    let pipeline = ColorContourPipeline::default();
    let json = pipeline
        .default_model()
        .unwrap_or_else(|| panic!("no embedded model"));
    let model = ModelFile::from_json(json, std::path::Path::new("default.json"), "color-contour")
        .unwrap_or_else(|e| panic!("{e}"));
    let detector = pipeline.load(&model).unwrap_or_else(|e| panic!("{e}"));
    let orchard = SyntheticFrames {
        spec: SceneSpec {
            fruit: FruitChoice::Only(FruitKind::Orange),
            camera: CameraPreset::KinectV2.camera(),
            noise: NoiseModel::for_camera(CameraPreset::KinectV2),
            domain: Domain::Orchard,
            light: LightPreset::Day,
            ..SceneSpec::default()
        },
        seed: 612,
        first: 0,
        count: 3,
    };
    let mut sets = vec![
        (
            "color-contour detect 3 wide d435 frames",
            load(&SyntheticFrames::mixed_fruit(
                Domain::Wide,
                CameraPreset::D435,
                0.2,
                611,
                3,
            )),
        ),
        (
            "color-contour detect 3 orchard kinect-v2 frames",
            load(&orchard),
        ),
    ];
    let real = real_apple_frame(&pipeline);
    if let Some((frame, _)) = &real {
        sets.push((
            "color-contour detect real ecopom apple frame",
            vec![frame.clone()],
        ));
    }
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap_or_else(|e| panic!("{e}"));
    // The opt-in ray circles: the orchard frames end to end with them on, and the stage alone
    // on those frames' fruit masks.
    let mut with_rays = model.clone();
    with_rays.stage_params["params"]["ray_circles"] = serde_json::json!({});
    let rays_detector = pipeline.load(&with_rays).unwrap_or_else(|e| panic!("{e}"));
    let orchard_frames = &sets[1].1;
    c.bench_function(
        "color-contour detect 3 orchard kinect-v2 frames, ray circles on",
        |b| {
            b.iter(|| {
                one.install(|| {
                    for frame in orchard_frames {
                        let found = rays_detector.detect(frame, &mut StageTimings::default());
                        criterion::black_box(found.unwrap_or_else(|e| panic!("{e}")));
                    }
                })
            })
        },
    );
    let stage_params: ColorContourStageParams =
        serde_json::from_value(with_rays.stage_params).unwrap_or_else(|e| panic!("{e}"));
    let rays = stage_params.params.ray_circles.unwrap_or_default();
    let by_color = ColorContourDetector::new(&stage_params).unwrap_or_else(|e| panic!("{e}"));
    // The stages alone read a frame's cleaned mask (closing, Gaussian, threshold), as in the
    // pipeline.
    let cleaned_mask = |f: &RgbdFrame| -> (Vec<bool>, usize) {
        let (mask, _) = by_color
            .fitted_circles(f, &mut StageTimings::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let width = f.camera().width as usize;
        let cleaning = MaskCleaningStage {
            closing_px: stage_params.params.mask_closing_px,
            width,
        };
        (cleaning.run(&mask).unwrap_or_else(|e| panic!("{e}")), width)
    };
    let masks: Vec<(Vec<bool>, usize)> = orchard_frames.iter().map(cleaned_mask).collect();
    c.bench_function("ray circles alone on 3 orchard kinect-v2 masks", |b| {
        b.iter(|| {
            for (mask, width) in &masks {
                criterion::black_box(ray_circles(mask, *width, &rays));
            }
        })
    });
    // The Hough circles (on in the built-in model) alone on the same masks, up to the size
    // test's largest circle as in the pipeline.
    let hough = stage_params.params.hough_circles.unwrap_or_default();
    let (_, max_radius_px) = stage_params
        .params
        .radius_px_range(orchard_frames[0].camera().mean_focal_px());
    c.bench_function("hough circles alone on 3 orchard kinect-v2 masks", |b| {
        b.iter(|| {
            for (mask, width) in &masks {
                criterion::black_box(hough_circles(mask, *width, max_radius_px, &hough));
            }
        })
    });
    // The depth cut (on in the built-in model) alone on the cleaned masks of both synthetic
    // sets and their frames' depth, as in the pipeline.
    let depth_cut = stage_params.params.depth_cut.unwrap_or_default();
    for (name, frames) in [
        ("depth cut alone on 3 wide d435 masks", &sets[0].1),
        ("depth cut alone on 3 orchard kinect-v2 masks", &sets[1].1),
    ] {
        let cut_inputs: Vec<(Vec<bool>, &[f32], usize)> = frames
            .iter()
            .map(|f| {
                let (cleaned, width) = cleaned_mask(f);
                (cleaned, f.depth().as_slice(), width)
            })
            .collect();
        c.bench_function(name, |b| {
            b.iter(|| {
                for (mask, depth_m, width) in &cut_inputs {
                    criterion::black_box(cut_at_depth_steps(mask, depth_m, *width, &depth_cut));
                }
            })
        });
    }
    // The circles of spheres fitted to the depth (on in the built-in model) alone on the same
    // cleaned (and cut) masks, and both synthetic sets end to end without them.
    let spheres = stage_params.params.depth_spheres.unwrap_or_default();
    let radius_range_m = stage_params.params.accepted_radius_range_m();
    for (name, frames) in [
        ("depth spheres alone on 3 wide d435 masks", &sets[0].1),
        (
            "depth spheres alone on 3 orchard kinect-v2 masks",
            &sets[1].1,
        ),
    ] {
        let inputs: Vec<(Vec<bool>, &RgbdFrame)> = frames
            .iter()
            .map(|f| {
                let (cleaned, width) = cleaned_mask(f);
                (
                    cut_at_depth_steps(&cleaned, f.depth().as_slice(), width, &depth_cut),
                    f,
                )
            })
            .collect();
        c.bench_function(name, |b| {
            b.iter(|| {
                for (mask, f) in &inputs {
                    criterion::black_box(depth_sphere_circles(
                        mask,
                        f.depth().as_slice(),
                        f.camera(),
                        radius_range_m,
                        &spheres,
                    ));
                }
            })
        });
    }
    let mut without_spheres = model.clone();
    without_spheres.stage_params["params"]["depth_spheres"] = serde_json::Value::Null;
    let plain = pipeline
        .load(&without_spheres)
        .unwrap_or_else(|e| panic!("{e}"));
    for (name, frames) in [
        (
            "color-contour detect 3 wide d435 frames, depth spheres off",
            &sets[0].1,
        ),
        (
            "color-contour detect 3 orchard kinect-v2 frames, depth spheres off",
            &sets[1].1,
        ),
    ] {
        c.bench_function(name, |b| {
            b.iter(|| {
                one.install(|| {
                    for frame in frames {
                        let found = plain.detect(frame, &mut StageTimings::default());
                        criterion::black_box(found.unwrap_or_else(|e| panic!("{e}")));
                    }
                })
            })
        });
    }
    let network = stage_params.mlp.clone();
    let plane_only = pomona_colorcontour::Mlp {
        intensity_weights: Vec::new(),
        ..network.clone()
    };
    for (name, net) in [
        (
            "colour table compiled, built-in network with intensity",
            &network,
        ),
        ("colour table compiled, the paper's plane only", &plane_only),
    ] {
        c.bench_function(name, |b| {
            b.iter(|| one.install(|| criterion::black_box(HSigmaLut::compile(net))))
        });
    }
    for (name, frames) in &sets {
        c.bench_function(name, |b| {
            b.iter(|| {
                one.install(|| {
                    for frame in frames {
                        let found = detector.detect(frame, &mut StageTimings::default());
                        criterion::black_box(found.unwrap_or_else(|e| panic!("{e}")));
                    }
                })
            })
        });
    }
    if let Some((frame, model)) = &real {
        let trained: Box<dyn Detector> = pipeline.load(model).unwrap_or_else(|e| panic!("{e}"));
        c.bench_function(
            "color-contour detect real ecopom apple frame, model trained on the other seven",
            |b| {
                b.iter(|| {
                    one.install(|| {
                        let found = trained.detect(frame, &mut StageTimings::default());
                        criterion::black_box(found.unwrap_or_else(|e| panic!("{e}")))
                    })
                })
            },
        );
    }
}

criterion_group!(benches, detect);
criterion_main!(benches);
