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

use clap::Parser;
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

/// The benchmark's options (see the module docs); a parameter left out keeps the detector's
/// default.
#[derive(Parser, Debug)]
struct Args {
    #[arg(long, default_value = "sr4000")]
    camera: CameraPreset,
    #[arg(long, default_value = "tof")]
    noise: NoiseModel,
    #[arg(long, default_value = "pepper")]
    fruit: FruitChoice,
    #[arg(long, default_value_t = 0.5)]
    green: f64,
    #[arg(long, default_value_t = 40)]
    train: u64,
    #[arg(long, default_value_t = 20)]
    test: u64,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[arg(long, default_value_t = 1)]
    splits: u64,
    #[arg(long, default_value_t = 1)]
    threads: usize,
    #[arg(long, default_value_t = 10)]
    quality: u64,
    #[arg(long, default_value_t = 5)]
    folds: usize,
    #[arg(long, default_value_t = 40)]
    negatives: usize,
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "symmetry+pruning,fixed+pruning"
    )]
    variants: Vec<String>,
    #[arg(long, default_value_t = 0.0)]
    cascade_min: f64,
    /// Distance, angle, θ and φ bins of the cascade's histogram.
    #[arg(long, value_delimiter = ',', num_args = 4)]
    cascade_bins: Option<Vec<usize>>,
    /// Highlight parameter overrides as a JSON object, e.g. `{"t_h": 0}`.
    #[arg(long, default_value = "{}")]
    highlight: String,
    #[arg(long)]
    stride: Option<f64>,
    #[arg(long)]
    min_behind: Option<f64>,
    #[arg(long)]
    lattice: Option<usize>,
    #[arg(long)]
    coherence: Option<f64>,
    #[arg(long)]
    nms: Option<f64>,
    #[arg(long)]
    bandwidth: Option<f64>,
    #[arg(long)]
    score_points: Option<usize>,
    #[arg(long)]
    refinements: Option<usize>,
    #[arg(long)]
    weight: Option<f64>,
    #[arg(long)]
    azimuth: Option<usize>,
    #[arg(long)]
    elevation: Option<usize>,
    #[arg(long)]
    coarse_points: Option<usize>,
    #[arg(long)]
    coarse_keep: Option<usize>,
    #[arg(long)]
    max_distance: Option<f64>,
}

/// `value`, when given, replaces `field`.
fn set<T: Copy>(field: &mut T, value: Option<T>) {
    if let Some(v) = value {
        *field = v;
    }
}

impl Args {
    /// The symmetry detector's defaults with this run's overrides (variants change frame,
    /// merging, pruning and cascade on top).
    fn base_params(&self) -> StageParams {
        let mut p = StageParams::symmetry();
        set(&mut p.boxes.stride_m, self.stride);
        set(&mut p.boxes.min_behind_m, self.min_behind);
        set(&mut p.boxes.pixel_lattice, self.lattice);
        set(&mut p.boxes.max_normal_coherence, self.coherence);
        set(&mut p.merging.nms_radius_m, self.nms);
        set(&mut p.merging.bandwidth_m, self.bandwidth);
        let sym = &mut p.symmetry;
        set(&mut sym.score_points, self.score_points);
        set(&mut sym.refinements, self.refinements);
        set(&mut sym.angle_weight_m, self.weight);
        set(&mut sym.azimuth_steps, self.azimuth);
        set(&mut sym.elevation_steps, self.elevation);
        set(&mut sym.coarse_points, self.coarse_points);
        set(&mut sym.coarse_keep, self.coarse_keep);
        set(&mut sym.max_distance_m, self.max_distance);
        if let Some(b) = &self.cascade_bins {
            let h = &mut p.cascade.histogram;
            (h.distance_bins, h.angle_bins, h.first_bins, h.second_bins) = (b[0], b[1], b[2], b[3]);
        }
        p.cascade.min_score = self.cascade_min;
        p.training.negatives_per_frame = self.negatives;
        let mut hl = serde_json::to_value(&p.highlight).unwrap();
        let overrides: serde_json::Value = serde_json::from_str(&self.highlight).unwrap();
        for (k, v) in overrides
            .as_object()
            .expect("--highlight must be a JSON object")
        {
            hl[k] = v.clone();
        }
        p.highlight = serde_json::from_value(hl).unwrap();
        p
    }

    /// `base` turned into `variant`: `symmetry`, `fixed` or `viewer`, with `+pruning` and
    /// `+cascade`.
    fn variant_params(base: &StageParams, variant: &str) -> StageParams {
        let mut p = match variant.split('+').next().unwrap_or_default() {
            "symmetry" => base.clone(),
            "fixed" => StageParams {
                frame: FrameKind::Fixed,
                ..base.clone()
            },
            "viewer" => {
                let viewer = StageParams::viewer_pose();
                let mut cascade = viewer.cascade.clone();
                cascade.min_score = base.cascade.min_score;
                cascade.histogram = base.cascade.histogram;
                StageParams {
                    frame: viewer.frame,
                    merge: viewer.merge,
                    refinement: viewer.refinement,
                    cascade,
                    ..base.clone()
                }
            }
            other => panic!("unknown variant `{other}` (symmetry, fixed or viewer)"),
        };
        p.highlight.enabled = variant.contains("+pruning");
        p.cascade.enabled = variant.contains("+cascade");
        p
    }
}

/// One variant's figures on one split: AP (VOC 11-point, all-point) and ms per frame.
type Figures = [f64; 3];

fn main() {
    let args = Args::parse();
    let spec = SceneSpec {
        camera: args.camera.camera(),
        noise: args.noise,
        green_fraction: args.green,
        fruit: args.fruit,
        ..SceneSpec::default()
    };
    println!(
        "benchmark: camera {} noise {} green {} train {} test {} seed {} splits {} detection \
         threads {}",
        args.camera.name(),
        args.noise.name(),
        args.green,
        args.train,
        args.test,
        args.seed,
        args.splits,
        args.threads
    );
    let base = args.base_params();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads)
        .build()
        .unwrap();
    let mut summary: Vec<Vec<Figures>> = vec![Vec::new(); args.variants.len()];
    for seed in args.seed..args.seed + args.splits {
        println!("\n#### split with dataset seed {seed}");
        let t0 = Instant::now();
        let train = frames(&spec, seed, 0..args.train);
        let test = frames(&spec, seed, args.train..args.train + args.test);
        println!("rendered in {:.1} s", t0.elapsed().as_secs_f64());
        highlight_recall(&test, &base.highlight);
        if args.quality > 0 && seed == args.seed {
            plane_quality(args.camera, seed, args.quality, base.symmetry);
        }
        for (vi, v) in args.variants.iter().enumerate() {
            let params = Args::variant_params(&base, v);
            let run = Run {
                spec: &spec,
                seed,
                folds: args.folds,
                threads: args.threads,
            };
            summary[vi].push(pool.install(|| run.variant(v, params, &train, &test)));
        }
    }
    println!(
        "\n#### mean ± sd over {} split(s): AP@50mm VOC11 | all-point AP | ms/frame",
        args.splits
    );
    for (v, runs) in args.variants.iter().zip(&summary) {
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

/// What every variant of one split shares.
struct Run<'a> {
    spec: &'a SceneSpec,
    seed: u64,
    folds: usize,
    threads: usize,
}

impl Run<'_> {
    /// Trains variant `v` on `train`, detects on `test` (in the caller's thread pool), prints
    /// its figures and stage table and returns its [`Figures`].
    fn variant(
        &self,
        v: &str,
        params: StageParams,
        train: &dyn FrameSource,
        test: &[LabelledFrame],
    ) -> Figures {
        let pipeline: Box<dyn Pipeline> = if params.merge == MergeKind::MeanShift {
            Box::new(ViewerPosePipeline::with_params(params))
        } else {
            Box::new(SymmetryPipeline::with_params(params))
        };
        let options = TrainOptions {
            seed: self.seed,
            folds: self.folds,
            full_grid: false,
        };
        let t = Instant::now();
        let model = pipeline.train(train, &options, &|_, _| {}).unwrap();
        let train_s = t.elapsed().as_secs_f64();
        let detector = BoxDetector::from_model(pipeline.name(), &model).unwrap();
        let mut timings = StageTimings::default();
        let mut inputs = Vec::new();
        let (mut boxes, mut searched, mut kept) = (0usize, 0usize, 0.0);
        let t = Instant::now();
        for f in test {
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
        let per_frame = |x: f64| x / test.len().max(1) as f64;
        let ms = per_frame(1e3 * t.elapsed().as_secs_f64());
        let report = evaluate(&inputs, &self.spec.camera, &EvalConfig::default()).unwrap();
        let nan = |x: Option<f64>| x.unwrap_or(f64::NAN);
        println!(
            "\n== {v}: AP@50mm voc11 {:.3} all-point {:.3} | precision {:.3} recall {:.3} at score \
             0 | {ms:.1} ms/frame ({} thread(s)) | {:.0} boxes/frame ({:.0} searched) | mask keeps \
             {:.0}% | train {train_s:.1} s, {} SVs",
            nan(report.ap_voc11),
            nan(report.ap),
            nan(report.precision),
            nan(report.recall),
            self.threads,
            per_frame(boxes as f64),
            per_frame(searched as f64),
            per_frame(100.0 * kept),
            model.svm.n_support(),
        );
        print!("{}", timings.table());
        [nan(report.ap_voc11), nan(report.ap), ms]
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
    let params = StageParams {
        symmetry: sym,
        ..StageParams::symmetry()
    };
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
