//! Measures the `symmetry` / `viewer-pose` detectors on a synthetic pepper benchmark rendered in
//! memory: AP@50 mm per variant (pruning × frame), mean ms per frame per stage, and the symmetry
//! plane quality on noise-free peppers.
//!
//! ```sh
//! cargo run --release -p pomona-symmetry --example benchmark -- \
//!     --camera sr4000 --noise tof --green 0.5 --train 40 --test 20 --seed 1 \
//!     --variants symmetry+pruning,symmetry,fixed+pruning,fixed,viewer+pruning --threads 1
//! ```
//!
//! Options:
//! * data: `--camera kinect-v2|sr4000|d435`, `--noise none|low|tof`, `--fruit pepper|mixed`
//!   (mixed: one kind per frame), `--green F`, `--train N`,
//!   `--test N`, `--seed S`, `--splits K` (K independent train/test datasets with seeds S, S+1,
//!   …; mean ± sd at the end);
//! * runs: `--threads T` (detection timing; training always uses every core), `--variants a,b`
//!   from `symmetry`, `fixed`, `viewer`, each optionally suffixed `+pruning` and (symmetry only)
//!   `+cascade` (the fixed-frame pre-filter, threshold `--cascade-min S`, default 0, bins `--cascade-bins D,A,F,S` (distance, angle, θ, φ bins); without
//!   the suffix the cascade is off, the paper's detector), `--quality N`
//!   (noise-free frames for the plane-quality figure, 0 to skip), `--folds K`;
//! * parameters: `--negatives N` (per frame), `--nms M`, `--bandwidth M`, `--stride M`,
//!   `--min-behind M`, `--coherence C`, `--lattice G`, `--score-points N`, `--refinements N`,
//!   `--weight W` (m/rad), `--coarse-points N`, `--coarse-keep N`, `--azimuth N`,
//!   `--elevation N`, `--max-distance M`, and highlight overrides as JSON, e.g.
//!   `--highlight '{"t_h": 0}'`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::time::Instant;

use pomona_core::nalgebra::Point3;
use pomona_eval::{evaluate, EvalConfig, FrameInput};
use pomona_pipeline::{
    FrameSource, LabelledFrame, Pipeline, StageTimings, SyntheticFrames, TrainOptions,
};
use pomona_symmetry::{
    BoxDetector, FrameKind, MergeKind, PruningState, SlidingBox, StageParams, SymmetryPipeline,
    SymmetryPlaneSearch, ViewerPosePipeline,
};
use pomona_synth::{CameraPreset, FruitChoice, NoiseModel, SceneSpec};

/// Frames `range` of the synthetic dataset `(spec, seed)`, rendered once.
fn frames(spec: &SceneSpec, seed: u64, range: std::ops::Range<u64>) -> Vec<LabelledFrame> {
    SyntheticFrames {
        spec: spec.clone(),
        seed,
        first: range.start,
        count: (range.end - range.start) as usize,
    }
    .load_all()
    .unwrap()
}

fn arg<'a>(args: &'a [String], name: &str, default: &'a str) -> &'a str {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map_or(default, String::as_str)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let camera = match arg(&args, "--camera", "sr4000") {
        "kinect-v2" => CameraPreset::KinectV2,
        "d435" => CameraPreset::D435,
        _ => CameraPreset::Sr4000,
    };
    let noise = match arg(&args, "--noise", "tof") {
        "none" => NoiseModel::None,
        "low" => NoiseModel::Low,
        _ => NoiseModel::Tof,
    };
    let green: f64 = arg(&args, "--green", "0.5").parse().unwrap();
    let n_train: u64 = arg(&args, "--train", "40").parse().unwrap();
    let n_test: u64 = arg(&args, "--test", "20").parse().unwrap();
    let base_seed: u64 = arg(&args, "--seed", "1").parse().unwrap();
    let splits: u64 = arg(&args, "--splits", "1").parse().unwrap();
    let threads: usize = arg(&args, "--threads", "1").parse().unwrap();
    let quality: u64 = arg(&args, "--quality", "10").parse().unwrap();
    let folds: usize = arg(&args, "--folds", "5").parse().unwrap();
    let mut boxes = StageParams::symmetry().boxes;
    boxes.stride_m = arg(&args, "--stride", &boxes.stride_m.to_string())
        .parse()
        .unwrap();
    boxes.min_behind_m = arg(&args, "--min-behind", &boxes.min_behind_m.to_string())
        .parse()
        .unwrap();
    boxes.pixel_lattice = arg(&args, "--lattice", &boxes.pixel_lattice.to_string())
        .parse()
        .unwrap();
    boxes.max_normal_coherence = arg(
        &args,
        "--coherence",
        &boxes.max_normal_coherence.to_string(),
    )
    .parse()
    .unwrap();
    let mut merging = StageParams::symmetry().merging;
    merging.nms_radius_m = arg(&args, "--nms", &merging.nms_radius_m.to_string())
        .parse()
        .unwrap();
    merging.bandwidth_m = arg(&args, "--bandwidth", &merging.bandwidth_m.to_string())
        .parse()
        .unwrap();
    let cascade_min: f64 = arg(&args, "--cascade-min", "0").parse().unwrap();
    let mut cascade_bins = StageParams::symmetry().cascade.histogram;
    if let Some(b) = args.iter().position(|a| a == "--cascade-bins") {
        let v: Vec<usize> = args[b + 1].split(',').map(|x| x.parse().unwrap()).collect();
        cascade_bins.distance_bins = v[0];
        cascade_bins.angle_bins = v[1];
        cascade_bins.first_bins = v[2];
        cascade_bins.second_bins = v[3];
    }
    let negatives: usize = arg(&args, "--negatives", "40").parse().unwrap();
    let variants: Vec<String> = arg(&args, "--variants", "symmetry+pruning,fixed+pruning")
        .split(',')
        .filter(|v| !v.is_empty())
        .map(str::to_owned)
        .collect();
    let mut sym = StageParams::symmetry().symmetry;
    sym.score_points = arg(&args, "--score-points", &sym.score_points.to_string())
        .parse()
        .unwrap();
    sym.refinements = arg(&args, "--refinements", &sym.refinements.to_string())
        .parse()
        .unwrap();
    sym.angle_weight_m = arg(&args, "--weight", &sym.angle_weight_m.to_string())
        .parse()
        .unwrap();
    sym.azimuth_steps = arg(&args, "--azimuth", &sym.azimuth_steps.to_string())
        .parse()
        .unwrap();
    sym.elevation_steps = arg(&args, "--elevation", &sym.elevation_steps.to_string())
        .parse()
        .unwrap();
    sym.coarse_points = arg(&args, "--coarse-points", &sym.coarse_points.to_string())
        .parse()
        .unwrap();
    sym.coarse_keep = arg(&args, "--coarse-keep", &sym.coarse_keep.to_string())
        .parse()
        .unwrap();
    sym.max_distance_m = arg(&args, "--max-distance", &sym.max_distance_m.to_string())
        .parse()
        .unwrap();

    let fruit = match arg(&args, "--fruit", "pepper") {
        "mixed" => FruitChoice::Mixed,
        _ => SceneSpec::default().fruit,
    };
    let spec = SceneSpec {
        camera: camera.camera(),
        noise,
        green_fraction: green,
        fruit,
        ..SceneSpec::default()
    };
    println!(
        "benchmark: camera {} noise {} green {green} train {n_train} test {n_test} seed {base_seed} \
         splits {splits} detection threads {threads}",
        camera.name(),
        noise.name()
    );
    let mut summary: Vec<(String, Vec<[f64; 3]>)> =
        variants.iter().map(|v| (v.clone(), Vec::new())).collect();
    for seed in base_seed..base_seed + splits {
        println!("\n#### split with dataset seed {seed}");
        let t0 = Instant::now();
        let train = frames(&spec, seed, 0..n_train);
        let test = frames(&spec, seed, n_train..n_train + n_test);
        println!("rendered in {:.1} s", t0.elapsed().as_secs_f64());

        let mut hl = serde_json::to_value(StageParams::symmetry().highlight).unwrap();
        let overrides: serde_json::Value =
            serde_json::from_str(arg(&args, "--highlight", "{}")).unwrap();
        for (k, v) in overrides.as_object().unwrap() {
            hl[k] = v.clone();
        }
        let hl: pomona_symmetry::HighlightParams = serde_json::from_value(hl).unwrap();
        highlight_recall(&test, &hl);
        if quality > 0 && seed == base_seed {
            plane_quality(camera, seed, quality, sym);
        }

        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        for (vi, v) in variants.iter().enumerate() {
            let pruning = v.contains("+pruning");
            let cascade = v.contains("+cascade");
            let mut params = match v.split('+').next().unwrap_or_default() {
                "viewer" => StageParams::viewer_pose(),
                "fixed" => {
                    let mut p = StageParams::symmetry();
                    p.frame = FrameKind::Fixed;
                    p
                }
                _ => StageParams::symmetry(),
            };
            params.highlight.enabled = pruning;
            params.cascade.enabled = cascade;
            params.cascade.min_score = cascade_min;
            params.cascade.histogram = cascade_bins;
            params.symmetry = sym;
            params.boxes = boxes;
            params.merging = merging;
            params.training.negatives_per_frame = negatives;
            params.highlight = pomona_symmetry::HighlightParams {
                enabled: pruning,
                ..hl.clone()
            };
            let pipeline: Box<dyn Pipeline> = if params.merge == MergeKind::MeanShift {
                Box::new(ViewerPosePipeline::with_params(params.clone()))
            } else {
                Box::new(SymmetryPipeline::with_params(params.clone()))
            };
            let options = TrainOptions {
                seed,
                folds,
                full_grid: false,
            };
            let t = Instant::now();
            let model = pipeline.train(&train, &options, &|_, _| {}).unwrap();
            let train_s = t.elapsed().as_secs_f64();
            let detector = BoxDetector::from_model(pipeline.name(), &model).unwrap();
            let mut timings = StageTimings::default();
            let mut inputs = Vec::new();
            let (mut boxes, mut searched, mut kept) = (0usize, 0usize, 0.0);
            let t = Instant::now();
            pool.install(|| {
                for f in &test {
                    let r = detector.detect_frame(&f.frame, &mut timings).unwrap();
                    boxes += r.boxes;
                    searched += r.searched;
                    if let PruningState::Applied { kept_fraction, .. } = r.pruning {
                        kept += kept_fraction;
                    }
                    inputs.push(FrameInput {
                        frame: f.name.clone(),
                        truth: f.truth.clone(),
                        detections: r.detections,
                    });
                }
            });
            let ms = 1e3 * t.elapsed().as_secs_f64() / test.len().max(1) as f64;
            let report = evaluate(&inputs, &spec.camera, &EvalConfig::default()).unwrap();
            println!(
            "\n== {v}: AP@50mm voc11 {:.3} all-point {:.3} | precision {:.3} recall {:.3} at score 0 \
             | {ms:.1} ms/frame ({threads} thread(s)) | {:.0} boxes/frame ({:.0} searched) | mask keeps {:.0}% | \
             train {train_s:.1} s, {} SVs",
            report.ap_voc11.unwrap_or(f64::NAN),
            report.ap.unwrap_or(f64::NAN),
            report.precision.unwrap_or(f64::NAN),
            report.recall.unwrap_or(f64::NAN),
            boxes as f64 / test.len().max(1) as f64,
            searched as f64 / test.len().max(1) as f64,
            100.0 * kept / test.len().max(1) as f64,
            model.svm.n_support(),
        );
            print!("{}", timings.table());
            summary[vi].1.push([
                report.ap_voc11.unwrap_or(f64::NAN),
                report.ap.unwrap_or(f64::NAN),
                ms,
            ]);
        }
    }
    println!("\n#### mean ± sd over {splits} split(s): AP@50mm VOC11 | all-point AP | ms/frame");
    for (v, runs) in &summary {
        let stat = |k: usize| {
            let n = runs.len().max(1) as f64;
            let m = runs.iter().map(|r| r[k]).sum::<f64>() / n;
            let sd =
                (runs.iter().map(|r| (r[k] - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
            (m, sd)
        };
        let ((a, sa), (b, sb), (t, st)) = (stat(0), stat(1), stat(2));
        println!("{v:<18} {a:.3} ± {sa:.3} | {b:.3} ± {sb:.3} | {t:.1} ± {st:.1}");
    }
}

/// Median |90° − angle(plane normal, truth axis)| for boxes centred on noise-free peppers.
fn plane_quality(
    camera: CameraPreset,
    seed: u64,
    n: u64,
    sym: pomona_symmetry::SymmetryPlaneParams,
) {
    let spec = SceneSpec {
        camera: camera.camera(),
        noise: NoiseModel::None,
        ..SceneSpec::default()
    };
    let mut params = StageParams::symmetry();
    params.symmetry = sym;
    let stages = pomona_symmetry::Stages::new(&params).unwrap();
    let search = SymmetryPlaneSearch::new(params.symmetry);
    let sb = SlidingBox::new(params.boxes);
    let mut offs = Vec::new();
    let mut offs_visible = Vec::new();
    for f in frames(&spec, seed + 1000, 0..n) {
        let cloud = stages.normal_stage().cloud(&f.frame).unwrap();
        for fruit in &f.truth.fruits {
            let (Some(c), Some(axis)) = (fruit.center_m, fruit.axis) else {
                continue;
            };
            let Some(patch) = sb.patch(&cloud, c) else {
                continue;
            };
            let Some(plane) = search.best(&patch, &Point3::origin()) else {
                continue;
            };
            let off = 90.0
                - plane
                    .normal
                    .dot(&axis)
                    .abs()
                    .clamp(0.0, 1.0)
                    .acos()
                    .to_degrees();
            offs.push(off);
            if fruit.visibility.unwrap_or(1.0) >= 0.5 {
                offs_visible.push(off);
            }
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
    };
    let within = offs_visible.iter().filter(|&&o| o <= 10.0).count();
    let mut hist = [0usize; 6];
    for &o in &offs_visible {
        hist[((o / 15.0) as usize).min(5)] += 1;
    }
    println!("plane error histogram (15° bins, visibility >= 0.5): {hist:?}");
    println!(
        "symmetry plane quality (noise-free, {} camera, {n} frames): median |90° − angle| = \
         {:.1}° over {} fruit with visibility ≥ 0.5 ({} within 10°), {:.1}° over all {} fruit",
        camera.name(),
        median(&mut offs_visible),
        offs_visible.len(),
        within,
        median(&mut offs),
        offs.len()
    );
}

/// How well the highlight mask covers the fruit: markers on fruit pixels and the fraction of
/// fruit (visibility ≥ 0.5) whose centre projects into the mask.
fn highlight_recall(frames: &[LabelledFrame], hl: &pomona_symmetry::HighlightParams) {
    let det = pomona_symmetry::HighlightDetector::new(hl.clone());
    let (mut markers, mut on_fruit, mut covered, mut fruit, mut kept) = (0, 0, 0, 0, 0.0);
    for f in frames {
        let Some(color) = f.frame.color() else {
            continue;
        };
        let h = det.detect(color, f.frame.camera());
        kept += h.mask.kept_fraction();
        for &(u, v) in &h.markers {
            markers += 1;
            let id = f
                .mask
                .as_ref()
                .and_then(|m| m.get(u.round() as u32, v.round() as u32));
            if id.is_some_and(|i| i > 0) {
                on_fruit += 1;
            }
        }
        for t in &f.truth.fruits {
            let (Some(c), true) = (t.center_m, t.visibility.unwrap_or(1.0) >= 0.5) else {
                continue;
            };
            fruit += 1;
            let px = f
                .frame
                .camera()
                .project(&c)
                .and_then(|p| f.frame.camera().pixel_of(&p));
            if px.is_some_and(|(u, v)| h.mask.get(u as usize, v as usize)) {
                covered += 1;
            }
        }
    }
    println!(
        "highlights: {markers} markers ({on_fruit} on fruit) in {} frames; mask keeps {:.0}% of \
         pixels and covers {covered} of {fruit} fruit centres (visibility >= 0.5)",
        frames.len(),
        100.0 * kept / frames.len().max(1) as f64
    );
}
