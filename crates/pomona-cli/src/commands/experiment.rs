//! `pomona experiment`: train, detect and evaluate in one command, for any pipeline, in three
//! protocols:
//!
//! * **random splits** (`--data DIR --splits K`, seed 000's protocol): several random
//!   image-level train/test splits of one labelled dataset; mean ± sd over the splits;
//! * **cross-domain** (`--train DIR... --test DIR...`): train on some datasets, evaluate on
//!   others — a test dataset that is also a training dataset is refused;
//! * **leave-one-out** (`--data DIR --leave-one-out`): each labelled frame is tested once by a
//!   model trained on all the others (small real sets such as the three `ak-apples` frames).
//!
//! Every model is trained with a calibrated confidence (`--calibration-folds`, 0 for none), and
//! precision/recall are reported at its operating confidence (or at `--threshold` on the score
//! for uncalibrated models). When no frame is tested twice (cross-domain, leave-one-out) the
//! report also pools all test frames into one evaluation.
//!
//! Split `k` shuffles the frame indices with ChaCha8 keyed by `--seed` on stream `k`, takes the
//! first `round(fraction · n)` as training frames and the rest as test frames (both sorted), so
//! a split depends only on (seed, k, n, fraction). Training of split `k` uses seed `seed + k`.
//! `--set` overrides stage parameters of each split's trained model before detection (a
//! detection-time ablation such as pruning on/off).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use pomona_core::{Detection, PinholeCamera};
use pomona_eval::{evaluate, EvalConfig, EvalReport, FrameInput, MeanSd, SplitSummary};
use pomona_pipeline::{
    train_calibrated, CalibrationParams, DatasetFrames, FrameSource, ModelFile, Pipeline,
    StageTimings, TrainOptions,
};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::commands::train::open_frames;
use crate::detection_run::{detect_frames, thread_pool, RunTotals};
use crate::matching_args::MatchingArgs;
use crate::params;
use crate::progress::{counter, progress_bar};
use pomona::{Detector, ModelSource, ParamOverride};

/// Arguments of `pomona experiment`.
#[derive(Debug, Clone, clap::Args)]
pub struct ExperimentArgs {
    /// Pipeline (detection method), e.g. `symmetry`.
    #[arg(long, value_name = "NAME")]
    pub pipeline: String,
    /// Labelled dataset folder (frames with truth are used), split randomly or leave-one-out.
    #[arg(long, value_name = "DIR", required_unless_present = "train",
          conflicts_with_all = ["train", "test"])]
    pub data: Option<PathBuf>,
    /// Training dataset(s) of a cross-domain experiment (repeat); needs `--test`.
    #[arg(long, value_name = "DIR", requires = "test")]
    pub train: Vec<PathBuf>,
    /// Test dataset(s) of a cross-domain experiment (repeat); none may be a training dataset.
    #[arg(long, value_name = "DIR", requires = "train")]
    pub test: Vec<PathBuf>,
    /// Test each labelled frame of `--data` once with a model trained on all the others.
    #[arg(long, requires = "data", conflicts_with = "splits")]
    pub leave_one_out: bool,
    /// Number of random train/test splits.
    #[arg(long, value_name = "K", default_value_t = 4,
          value_parser = clap::value_parser!(u64).range(1..=1000))]
    pub splits: u64,
    /// Fraction of frames used for training in each split (the rest are tested).
    #[arg(long, value_name = "F", default_value_t = 0.5, value_parser = parse_open_fraction)]
    pub train_fraction: f64,
    /// Seed of the splits and of training.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// How detections are matched to truth.
    #[command(flatten)]
    pub matching: MatchingArgs,
    /// Score threshold of the reported precision/recall for models without calibration (default
    /// 0, an SVM's decision boundary); calibrated models report at their operating confidence.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub threshold: f64,
    /// Folds of the confidence calibration of every trained model (0: no calibration).
    #[arg(long, value_name = "K", default_value_t = 3,
          value_parser = clap::value_parser!(u64).range(0..=100))]
    pub calibration_folds: u64,
    /// Fit every trained model's confidence to the held-out detections' geometric cues beside
    /// their score (as `pomona train --cues`).
    #[arg(long)]
    pub cues: bool,
    /// Evaluate only truth objects of this kind (repeat for several), e.g. `apple`.
    #[arg(long, value_name = "KIND")]
    pub kind: Vec<String>,
    /// Cross-validation folds of the classifier's grid search.
    #[arg(long, value_name = "K", default_value_t = 5,
          value_parser = clap::value_parser!(u64).range(2..=100))]
    pub folds: u64,
    /// Search LIBSVM's full (C, γ) grid (slow).
    #[arg(long)]
    pub full_grid: bool,
    /// Write the JSON report (per-split reports and the summary) here.
    #[arg(long, value_name = "REPORT")]
    pub json: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Override a stage parameter of every trained model before detection, KEY=VALUE; repeat.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<ParamOverride>,
    /// Override a training parameter of the pipeline before every split's training,
    /// KEY=VALUE; repeat (for ablations that change features, e.g. the reference frame).
    #[arg(long = "train-set", value_name = "KEY=VALUE")]
    pub train_set: Vec<ParamOverride>,
}

fn parse_open_fraction(s: &str) -> Result<f64, String> {
    let f: f64 = s.parse().map_err(|e| format!("not a number: {e}"))?;
    if f > 0.0 && f < 1.0 {
        Ok(f)
    } else {
        Err(format!("must be strictly between 0 and 1, got {f}"))
    }
}

/// Training and test frame indices (each sorted) of split `split` of `n` frames.
///
/// # Errors
/// Fewer than two frames, or a fraction that leaves either side empty.
pub fn split_indices(
    n: usize,
    train_fraction: f64,
    seed: u64,
    split: u64,
) -> Result<(Vec<usize>, Vec<usize>)> {
    if n < 2 {
        bail!("a train/test split needs at least 2 labelled frames, the dataset has {n}");
    }
    let n_train = (train_fraction * n as f64).round() as usize;
    if n_train == 0 || n_train >= n {
        bail!(
            "--train-fraction {train_fraction} of {n} frames leaves {} training and {} test frames; \
             both need at least one",
            n_train.min(n),
            n - n_train.min(n)
        );
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(split);
    let mut order: Vec<usize> = (0..n).collect();
    order.shuffle(&mut rng);
    let mut train = order[..n_train].to_vec();
    let mut test = order[n_train..].to_vec();
    train.sort_unstable();
    test.sort_unstable();
    Ok((train, test))
}

/// Which protocol an experiment ran.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Protocol {
    /// Random image-level splits of one dataset.
    RandomSplits,
    /// Train on some datasets, test on others.
    CrossDomain,
    /// Each frame tested once by a model trained on all the others.
    LeaveOneOut,
}

/// One split of an experiment.
#[derive(Debug, Clone, Serialize)]
pub struct SplitRecord {
    /// Split number, from 0.
    pub split: u64,
    /// Training frames (`<stem>`, or `<dataset>/<stem>` with several datasets).
    pub train_frames: Vec<String>,
    /// Test frames.
    pub test_frames: Vec<String>,
    /// Training wall time per training frame, milliseconds (calibration included).
    pub train_ms_per_frame: f64,
    /// The trained model's operating confidence (`None` without calibration).
    pub operating_confidence: Option<f64>,
    /// Detection time per test frame, milliseconds (single-frame cost).
    pub detect_ms_per_frame: Option<f64>,
    /// Mean milliseconds per run of each detection stage.
    pub stage_ms: Vec<(String, f64)>,
    /// Evaluation of the test frames.
    pub report: EvalReport,
}

/// The experiment's JSON report.
#[derive(Debug, Clone, Serialize)]
pub struct ExperimentReport {
    /// Pipeline name.
    pub pipeline: String,
    /// Protocol run.
    pub protocol: Protocol,
    /// Training dataset folders (the one `--data` folder for splits and leave-one-out).
    pub train_data: Vec<PathBuf>,
    /// Test dataset folders (the same folder for splits and leave-one-out).
    pub test_data: Vec<PathBuf>,
    /// Labelled frames in the training datasets.
    pub frames: usize,
    /// Seed of splits and training.
    pub seed: u64,
    /// Fraction of frames trained on (random splits only).
    pub train_fraction: Option<f64>,
    /// Evaluation parameters (the threshold applies to uncalibrated models).
    pub eval: EvalConfig,
    /// Truth kinds evaluated (empty: all).
    pub kinds: Vec<String>,
    /// `--set` overrides applied before detection.
    pub set: serde_json::Value,
    /// `--train-set` overrides applied to the pipeline before every split's training.
    pub train_set: serde_json::Value,
    /// Mean ± sd over splits of AP, precision, recall, centre error, and the mean PR curve.
    pub summary: SplitSummary,
    /// Every test frame of every split in one evaluation, when no frame was tested twice
    /// (cross-domain, leave-one-out); each frame at its own model's operating point.
    pub pooled: Option<EvalReport>,
    /// Mean ± sd of training time per training frame, milliseconds.
    pub train_ms_per_frame: Option<MeanSd>,
    /// Mean ± sd of detection time per test frame, milliseconds.
    pub detect_ms_per_frame: Option<MeanSd>,
    /// Every split.
    pub per_split: Vec<SplitRecord>,
}

/// Runs `pomona experiment` with the registered pipelines.
///
/// # Errors
/// See [`run_with`].
pub fn run(args: &ExperimentArgs) -> Result<()> {
    run_with(&pomona::pipelines(), args).map(|_| ())
}

fn fmt_mean_sd(m: Option<MeanSd>, scale: f64, digits: usize, unit: &str) -> String {
    m.map_or_else(
        || "n/a".to_owned(),
        |m| {
            format!(
                "{:.digits$} ± {:.digits$}{unit} (n = {})",
                m.mean * scale,
                m.sd * scale,
                m.n
            )
        },
    )
}

fn dirs(d: &[PathBuf]) -> String {
    d.iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The summary as a Markdown table: a heading saying what was run, then one row per figure.
pub fn summary_markdown(r: &ExperimentReport) -> String {
    let mut out = summary_heading(r);
    for (k, v, p) in summary_rows(r) {
        out.push_str(&format!("| {k} | {v} | {p} |\n"));
    }
    out
}

/// The figures of the summary table: (name, mean ± sd over splits, pooled).
fn summary_rows(r: &ExperimentReport) -> [(&'static str, String, String); 8] {
    let s = &r.summary;
    let fmt = |v: Option<f64>, scale: f64, digits: usize, unit: &str| {
        v.map_or_else(
            || "n/a".to_owned(),
            |v| format!("{:.digits$}{unit}", v * scale),
        )
    };
    let pooled = |f: &dyn Fn(&EvalReport) -> String| r.pooled.as_ref().map_or("".into(), f);
    [
        (
            "AP (VOC 11-point)",
            fmt_mean_sd(s.ap_voc11, 1.0, 3, ""),
            pooled(&|p| fmt(p.ap_voc11, 1.0, 3, "")),
        ),
        (
            "AP (all points)",
            fmt_mean_sd(s.ap, 1.0, 3, ""),
            pooled(&|p| fmt(p.ap, 1.0, 3, "")),
        ),
        (
            "precision",
            fmt_mean_sd(s.precision, 1.0, 3, ""),
            pooled(&|p| fmt(p.precision, 1.0, 3, "")),
        ),
        (
            "recall",
            fmt_mean_sd(s.recall, 1.0, 3, ""),
            pooled(&|p| fmt(p.recall, 1.0, 3, "")),
        ),
        // Each evaluation measures its centre error one way: metres in 3D, truth radii in 2D.
        match r.eval.radius_fraction_2d {
            None => (
                "centre error (median)",
                fmt_mean_sd(s.center_error_median_m, 1e3, 1, " mm"),
                pooled(&|p| fmt(p.center_error_m.median, 1e3, 1, " mm")),
            ),
            Some(_) => (
                "centre error (median, truth radii)",
                fmt_mean_sd(s.center_error_median_radii, 1.0, 3, " r"),
                pooled(&|p| fmt(p.center_error_radii.and_then(|e| e.median), 1.0, 3, " r")),
            ),
        },
        (
            "diameter error (mean abs)",
            "".into(),
            pooled(&|p| fmt(p.diameter_error_m.mean_abs, 1e3, 1, " mm")),
        ),
        (
            "train time / frame",
            fmt_mean_sd(r.train_ms_per_frame, 1.0, 1, " ms"),
            String::new(),
        ),
        (
            "detect time / frame",
            fmt_mean_sd(r.detect_ms_per_frame, 1.0, 1, " ms"),
            String::new(),
        ),
    ]
}

/// The heading and table header of the summary: protocol, data, matching, operating point.
fn summary_heading(r: &ExperimentReport) -> String {
    let s = &r.summary;
    let what = match r.protocol {
        Protocol::RandomSplits => format!(
            "{} ({} labelled frames), {} random splits, train fraction {}",
            dirs(&r.train_data),
            r.frames,
            s.splits,
            r.train_fraction.unwrap_or(0.5)
        ),
        Protocol::CrossDomain => format!(
            "trained on {} ({} labelled frames), tested on {}",
            dirs(&r.train_data),
            r.frames,
            dirs(&r.test_data)
        ),
        Protocol::LeaveOneOut => format!(
            "{} ({} labelled frames), leave-one-out",
            dirs(&r.train_data),
            r.frames
        ),
    };
    let operating = if r.per_split.iter().all(|p| p.operating_confidence.is_some()) {
        "each model's operating confidence".to_owned()
    } else {
        format!("score ≥ {}", r.eval.threshold)
    };
    let kinds = if r.kinds.is_empty() {
        String::new()
    } else {
        format!(", kind {}", r.kinds.join("/"))
    };
    let matching = match r.eval.radius_fraction_2d {
        Some(f) => format!("matched in the image within {f} truth radii"),
        None => format!("tolerance {:.0} mm", r.eval.tolerance_m * 1e3),
    };
    let matching = match r.eval.depth_range_m {
        Some((near, far)) => format!("{matching}, fruit {near}–{far} m deep"),
        None => matching,
    };
    format!(
        "## Experiment: `{}` {what}, seed {}, {matching}, operating point: {operating}{kinds}\n\n\
         | metric | mean ± sd over splits | pooled test frames |\n|---|---|---|\n",
        r.pipeline, r.seed,
    )
}

/// Refuses a cross-domain experiment whose test folders include a training folder (compared
/// after resolving links and `..`).
///
/// # Errors
/// A folder that cannot be resolved, or one that is both a training and a test set.
pub fn check_disjoint(train: &[PathBuf], test: &[PathBuf]) -> Result<()> {
    let resolve = |p: &PathBuf| {
        std::fs::canonicalize(p).with_context(|| format!("cannot open dataset {}", p.display()))
    };
    let train_resolved: Vec<PathBuf> = train.iter().map(resolve).collect::<Result<_>>()?;
    for t in test {
        let r = resolve(t)?;
        if let Some(i) = train_resolved.iter().position(|x| *x == r) {
            bail!(
                "{} is both a training set (--train {}) and a test set: a cross-domain \
                 experiment must test on data it did not train on",
                t.display(),
                train[i].display()
            );
        }
    }
    Ok(())
}

/// The (training, test) frame indices of every split of the protocol, with the training and
/// test sources they index.
struct Plan {
    protocol: Protocol,
    train: DatasetFrames,
    test: DatasetFrames,
    splits: Vec<(Vec<usize>, Vec<usize>)>,
    train_data: Vec<PathBuf>,
    test_data: Vec<PathBuf>,
}

fn plan(pipeline: &dyn Pipeline, args: &ExperimentArgs) -> Result<Plan> {
    if let Some(data) = &args.data {
        let frames = open_frames(pipeline, std::slice::from_ref(data))?;
        let n = frames.len();
        let (protocol, splits) = if args.leave_one_out {
            if n < 2 {
                bail!(
                    "leave-one-out needs at least 2 labelled frames, {} has {n}",
                    data.display()
                );
            }
            let splits = (0..n)
                .map(|k| ((0..n).filter(|&i| i != k).collect(), vec![k]))
                .collect();
            (Protocol::LeaveOneOut, splits)
        } else {
            let splits = (0..args.splits)
                .map(|k| split_indices(n, args.train_fraction, args.seed, k))
                .collect::<Result<_>>()?;
            (Protocol::RandomSplits, splits)
        };
        return Ok(Plan {
            protocol,
            test: frames.clone(),
            train: frames,
            splits,
            train_data: vec![data.clone()],
            test_data: vec![data.clone()],
        });
    }
    if args.train.is_empty() || args.test.is_empty() {
        bail!("give either --data DIR, or --train DIR... and --test DIR...");
    }
    check_disjoint(&args.train, &args.test)?;
    let train = open_frames(pipeline, &args.train)?;
    let test = open_frames(pipeline, &args.test)?;
    let splits = vec![((0..train.len()).collect(), (0..test.len()).collect())];
    Ok(Plan {
        protocol: Protocol::CrossDomain,
        train,
        test,
        splits,
        train_data: args.train.clone(),
        test_data: args.test.clone(),
    })
}

/// Name of frame `i` of `frames`: its stem, prefixed with its dataset folder when `several`.
fn frame_name(frames: &DatasetFrames, i: usize, several: bool) -> String {
    match frames.frame_ref(i) {
        Some((ds, stem)) if several => format!("{}/{stem}", ds.root().display()),
        Some((_, stem)) => stem.to_owned(),
        None => format!("#{i}"),
    }
}

/// What every split of an experiment shares.
struct Splits<'a> {
    pipeline: &'a dyn Pipeline,
    args: &'a ExperimentArgs,
    plan: &'a Plan,
    calibration: CalibrationParams,
    config: EvalConfig,
    camera: PinholeCamera,
}

impl Splits<'_> {
    /// Split `k`: trains a calibrated model on `train_idx`, detects on `test_idx` and scores at
    /// the model's operating confidence; returns the split's record, its scored frames (for the
    /// pooled report) and its detection stage times.
    fn split(
        &self,
        k: usize,
        train_idx: &[usize],
        test_idx: &[usize],
    ) -> Result<(SplitRecord, Vec<FrameInput>, StageTimings)> {
        let started = Instant::now();
        let model = self.train(k, &self.plan.train.subset(train_idx))?;
        let train_s = started.elapsed().as_secs_f64();
        let operating_confidence = model.calibration.map(|c| c.operating_confidence);
        let detector = Detector::builder_for(self.pipeline)
            .model(
                model,
                ModelSource::InMemory(format!("the model of split {}", k + 1)),
            )
            .overrides(self.args.set.iter().cloned())
            .build()?;
        let (inputs, totals) = self.detect(k, &detector, test_idx)?;
        let split_config = EvalConfig {
            min_confidence: operating_confidence,
            ..self.config
        };
        let report = evaluate(&inputs, &self.camera, &split_config)?;
        let fmt = |v: Option<f64>| v.map_or_else(|| "n/a".into(), |v| format!("{v:.3}"));
        eprintln!(
            "split {}/{}: trained on {} frames in {:.1} s{}, tested on {}: AP {} (VOC11 {}), P {}, R {}",
            k + 1,
            self.plan.splits.len(),
            train_idx.len(),
            train_s,
            operating_confidence.map_or(String::new(), |c| format!(" (operating confidence {c:.3})")),
            test_idx.len(),
            fmt(report.ap),
            fmt(report.ap_voc11),
            fmt(report.precision),
            fmt(report.recall)
        );
        let names = |frames: &DatasetFrames, several: bool, idx: &[usize]| -> Vec<String> {
            idx.iter()
                .map(|&i| frame_name(frames, i, several))
                .collect()
        };
        let record = SplitRecord {
            split: k as u64,
            train_frames: names(&self.plan.train, self.plan.train_data.len() > 1, train_idx),
            test_frames: names(&self.plan.test, self.plan.test_data.len() > 1, test_idx),
            train_ms_per_frame: 1e3 * train_s / train_idx.len().max(1) as f64,
            operating_confidence,
            detect_ms_per_frame: totals.ms_per_frame(),
            stage_ms: totals
                .timings
                .entries()
                .iter()
                .map(|&(s, d, runs)| (s.to_owned(), 1e3 * d.as_secs_f64() / f64::from(runs.max(1))))
                .collect(),
            report,
        };
        Ok((record, inputs, totals.timings))
    }

    /// Trains split `k`'s calibrated model on `train_set`.
    fn train(&self, k: usize, train_set: &DatasetFrames) -> Result<ModelFile> {
        let options = TrainOptions {
            seed: self.args.seed.wrapping_add(k as u64),
            folds: self.args.folds as usize,
            full_grid: self.args.full_grid,
        };
        let bar = progress_bar(train_set.len(), &format!("split {}: train", k + 1));
        let progress = counter(&bar);
        let pipeline = self.pipeline;
        let trained = train_calibrated(pipeline, train_set, &options, &self.calibration, &progress)
            .with_context(|| format!("training `{}` on split {}", pipeline.name(), k + 1))?;
        if let (Some(why), true) = (&trained.not_calibrated, self.calibration.folds > 0) {
            eprintln!("split {}: no confidence calibration: {why}", k + 1);
        }
        bar.finish_and_clear();
        Ok(trained.model)
    }

    /// Runs split `k`'s detector on the test frames `test_idx`: the scored frames (truth kept
    /// to `--kind`) and the detection totals.
    fn detect(
        &self,
        k: usize,
        detector: &Detector,
        test_idx: &[usize],
    ) -> Result<(Vec<FrameInput>, RunTotals)> {
        let test_set = self.plan.test.subset(test_idx);
        let bar = progress_bar(test_set.len(), &format!("split {}: detect", k + 1));
        let (results, totals) = detect_frames(
            detector,
            test_set.len(),
            |i| {
                let f = test_set.load(i)?;
                Ok((f.name, f.frame, f.truth))
            },
            |_, _| Ok(()),
            &|| bar.inc(1),
        )
        .all_or_first_error()?;
        bar.finish_and_clear();
        let several_test = self.plan.test_data.len() > 1;
        let kinds = &self.args.kind;
        let inputs = results
            .into_iter()
            .zip(test_idx)
            .map(|((r, mut truth), &i)| {
                truth.keep_kinds(kinds);
                FrameInput {
                    frame: frame_name(&self.plan.test, i, several_test),
                    truth,
                    detections: r.detections,
                }
            })
            .collect();
        Ok((inputs, totals))
    }
}

/// Runs `pomona experiment` choosing the pipeline from `pipelines` (tests pass their own).
///
/// # Errors
/// Unknown pipeline, unreadable data, too few labelled frames, a test set that is also a
/// training set, training or detection failures, bad `--set` keys, an unwritable report.
pub fn run_with(
    pipelines: &[Box<dyn Pipeline>],
    args: &ExperimentArgs,
) -> Result<ExperimentReport> {
    let found = pomona::find_pipeline(pipelines, &args.pipeline)?;
    let configured = params::configured(found, &args.train_set)?;
    let pipeline = configured.as_deref().unwrap_or(found);
    let plan = plan(pipeline, args)?;
    let (camera, test_has_depth) = match plan.test.frame_ref(0) {
        Some((ds, _)) => (*ds.camera(), ds.has_depth()),
        None => bail!("{}: no labelled frames", dirs(&plan.test_data)),
    };
    let config = args.matching.config(
        EvalConfig {
            threshold: args.threshold,
            ..EvalConfig::default()
        },
        test_has_depth,
    );
    config.validate()?;
    let calibration = CalibrationParams {
        folds: args.calibration_folds as usize,
        cues: args.cues,
        tolerance_m: config.tolerance_m,
        min_visibility: config.min_visibility,
        radius_fraction_2d: config.radius_fraction_2d,
        ..CalibrationParams::default()
    };
    let pool = thread_pool(args.threads.map(|n| n as usize))?;
    let run = Splits {
        pipeline,
        args,
        plan: &plan,
        calibration,
        config,
        camera,
    };
    let mut per_split = Vec::new();
    let mut pooled_inputs = Vec::new();
    let mut all_timings = StageTimings::default();
    for (k, (train_idx, test_idx)) in plan.splits.iter().enumerate() {
        let (record, inputs, timings) = pool.install(|| run.split(k, train_idx, test_idx))?;
        all_timings.merge(&timings);
        if plan.protocol != Protocol::RandomSplits {
            let op = record.operating_confidence;
            pooled_inputs.extend(inputs.into_iter().map(|f| (f, op)));
        }
        per_split.push(record);
    }

    let pooled = pooled_report(pooled_inputs, &camera, &config)?;
    let reports: Vec<EvalReport> = per_split.iter().map(|s| s.report.clone()).collect();
    let report = ExperimentReport {
        pipeline: pipeline.name().to_owned(),
        protocol: plan.protocol,
        train_data: plan.train_data,
        test_data: plan.test_data,
        frames: plan.train.len(),
        seed: args.seed,
        train_fraction: (plan.protocol == Protocol::RandomSplits).then_some(args.train_fraction),
        eval: config,
        kinds: args.kind.clone(),
        set: pomona::overrides_to_json(&args.set),
        train_set: pomona::overrides_to_json(&args.train_set),
        summary: SplitSummary::new(&reports),
        pooled,
        train_ms_per_frame: MeanSd::of(per_split.iter().map(|s| Some(s.train_ms_per_frame))),
        detect_ms_per_frame: MeanSd::of(per_split.iter().map(|s| s.detect_ms_per_frame)),
        per_split,
    };
    if let Some(path) = &args.json {
        pomona_io::write_json(path, &report)?;
    }
    print!("{}", summary_markdown(&report));
    if !all_timings.entries().is_empty() {
        println!("\nDetection stages over all test frames of all splits:\n\n```text");
        print!("{}", all_timings.table());
        println!("```");
    }
    Ok(report)
}

/// One evaluation of every split's test frames (`None` for random splits, which test frames
/// more than once). With calibrated models, detections are ranked by confidence (comparable
/// across the split models) and the operating point keeps, in each frame, the detections at or
/// above its own model's operating confidence; otherwise raw scores and `config.threshold`.
fn pooled_report(
    inputs: Vec<(FrameInput, Option<f64>)>,
    camera: &PinholeCamera,
    config: &EvalConfig,
) -> Result<Option<EvalReport>> {
    if inputs.is_empty() {
        return Ok(None);
    }
    if inputs.iter().any(|(_, op)| op.is_none()) {
        let frames: Vec<FrameInput> = inputs.into_iter().map(|(f, _)| f).collect();
        return Ok(Some(evaluate(&frames, camera, config)?));
    }
    let rescored = |shift: bool| -> Vec<FrameInput> {
        inputs
            .iter()
            .map(|(f, op)| FrameInput {
                detections: f
                    .detections
                    .iter()
                    .map(|d| Detection {
                        score: d.confidence.unwrap_or(0.0)
                            - if shift { op.unwrap_or(0.0) } else { 0.0 },
                        ..d.clone()
                    })
                    .collect(),
                ..f.clone()
            })
            .collect()
    };
    let at_zero = EvalConfig {
        threshold: 0.0,
        min_confidence: None,
        ..*config
    };
    let ranked = evaluate(&rescored(false), camera, &at_zero)?;
    let operating = evaluate(&rescored(true), camera, &at_zero)?;
    Ok(Some(EvalReport {
        ap: ranked.ap,
        ap_voc11: ranked.ap_voc11,
        pr_curve: ranked.pr_curve,
        ..operating
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_are_deterministic_disjoint_and_seed_dependent() {
        let a = split_indices(20, 0.5, 7, 0).unwrap();
        assert_eq!(a, split_indices(20, 0.5, 7, 0).unwrap());
        assert_eq!((a.0.len(), a.1.len()), (10, 10));
        let mut all: Vec<usize> = a.0.iter().chain(&a.1).copied().collect();
        all.sort_unstable();
        assert_eq!(all, (0..20).collect::<Vec<_>>());
        assert!(a.0.windows(2).all(|w| w[0] < w[1]));
        assert_ne!(a, split_indices(20, 0.5, 8, 0).unwrap(), "other seed");
        assert_ne!(a, split_indices(20, 0.5, 7, 1).unwrap(), "other split");
        let b = split_indices(7, 0.3, 1, 0).unwrap();
        assert_eq!((b.0.len(), b.1.len()), (2, 5));
    }

    #[test]
    fn degenerate_splits_are_refused() {
        assert!(split_indices(1, 0.5, 0, 0).is_err());
        assert!(split_indices(3, 0.1, 0, 0).is_err());
        assert!(split_indices(3, 0.9, 0, 0).is_err());
        assert!(parse_open_fraction("1").is_err());
        assert!(parse_open_fraction("0").is_err());
        assert!(parse_open_fraction("x").is_err());
        assert_eq!(parse_open_fraction("0.25"), Ok(0.25));
    }
}
