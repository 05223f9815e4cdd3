//! `pomona experiment`: seed 000's protocol for any pipeline — several random image-level
//! train/test splits of one labelled dataset; for each, train on one part, detect on the other
//! and evaluate; then mean ± sd over the splits.
//!
//! Split `k` shuffles the frame indices with ChaCha8 keyed by `--seed` on stream `k`, takes the
//! first `round(fraction · n)` as training frames and the rest as test frames (both sorted), so
//! a split depends only on (seed, k, n, fraction). Training of split `k` uses seed `seed + k`.
//! `--set` overrides stage parameters of each split's trained model before detection (a
//! detection-time ablation such as pruning on/off).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use pomona_eval::{evaluate, EvalConfig, EvalReport, FrameInput, MeanSd, SplitSummary};
use pomona_pipeline::{FrameSource, ModelFile, Pipeline, StageTimings, TrainOptions};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::commands::train::open_frames;
use crate::detection_run::{build_detector, detect_frames, thread_pool, ModelSource};
use crate::params::{self, parse_override, ParamOverride};
use crate::pipelines;
use crate::progress::progress_bar;

/// Arguments of `pomona experiment`.
#[derive(Debug, Clone, clap::Args)]
pub struct ExperimentArgs {
    /// Pipeline (detection method), e.g. `symmetry`.
    #[arg(long, value_name = "NAME")]
    pub pipeline: String,
    /// Labelled dataset folder (frames with truth are used).
    #[arg(long, value_name = "DIR")]
    pub data: PathBuf,
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
    /// Largest centre distance, millimetres, at which a detection matches a fruit.
    #[arg(long, default_value_t = 50.0)]
    pub tolerance_mm: f64,
    /// Truth fruit less visible than this (0–1) are ignored: neither found nor missed.
    #[arg(long, default_value_t = 0.5)]
    pub min_visibility: f64,
    /// Score threshold of the reported precision/recall (default 0, an SVM's decision boundary).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub threshold: f64,
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
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = parse_override)]
    pub set: Vec<ParamOverride>,
    /// Override a training parameter of the pipeline before every split's training,
    /// KEY=VALUE; repeat (for ablations that change features, e.g. the reference frame).
    #[arg(long = "train-set", value_name = "KEY=VALUE", value_parser = parse_override)]
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

/// One split of an experiment.
#[derive(Debug, Clone, Serialize)]
pub struct SplitRecord {
    /// Split number, from 0.
    pub split: u64,
    /// Training frames (`<dataset>/<stem>`).
    pub train_frames: Vec<String>,
    /// Test frames.
    pub test_frames: Vec<String>,
    /// Training wall time per training frame, milliseconds.
    pub train_ms_per_frame: f64,
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
    /// Dataset folder.
    pub data: PathBuf,
    /// Labelled frames in the dataset.
    pub frames: usize,
    /// Seed of splits and training.
    pub seed: u64,
    /// Fraction of frames trained on.
    pub train_fraction: f64,
    /// Evaluation parameters.
    pub eval: EvalConfig,
    /// `--set` overrides applied before detection.
    pub set: serde_json::Value,
    /// Mean ± sd over splits of AP, precision, recall, centre error, and the mean PR curve.
    pub summary: SplitSummary,
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
    run_with(&pipelines::all(), args).map(|_| ())
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

/// The summary as a Markdown table.
pub fn summary_markdown(r: &ExperimentReport) -> String {
    let s = &r.summary;
    let rows = [
        ("AP (VOC 11-point)", fmt_mean_sd(s.ap_voc11, 1.0, 3, "")),
        ("AP (all points)", fmt_mean_sd(s.ap, 1.0, 3, "")),
        ("precision", fmt_mean_sd(s.precision, 1.0, 3, "")),
        ("recall", fmt_mean_sd(s.recall, 1.0, 3, "")),
        (
            "centre error (median)",
            fmt_mean_sd(s.center_error_median_m, 1e3, 1, " mm"),
        ),
        (
            "train time / frame",
            fmt_mean_sd(r.train_ms_per_frame, 1.0, 1, " ms"),
        ),
        (
            "detect time / frame",
            fmt_mean_sd(r.detect_ms_per_frame, 1.0, 1, " ms"),
        ),
    ];
    let mut out = format!(
        "## Experiment: `{}` on {} ({} labelled frames), {} splits, train fraction {}, seed {}, \
         tolerance {:.0} mm, threshold {}\n\n| metric | mean ± sd |\n|---|---|\n",
        r.pipeline,
        r.data.display(),
        r.frames,
        s.splits,
        r.train_fraction,
        r.seed,
        r.eval.tolerance_m * 1e3,
        r.eval.threshold
    );
    for (k, v) in rows {
        out.push_str(&format!("| {k} | {v} |\n"));
    }
    out
}

/// Runs `pomona experiment` choosing the pipeline from `pipelines` (tests pass their own).
///
/// # Errors
/// Unknown pipeline, unreadable data, too few labelled frames, training or detection failures,
/// bad `--set` keys, an unwritable report.
pub fn run_with(
    pipelines: &[Box<dyn Pipeline>],
    args: &ExperimentArgs,
) -> Result<ExperimentReport> {
    let found = pipelines::find(pipelines, &args.pipeline)?;
    let configured = params::configured(found, &args.train_set)?;
    let pipeline = configured.as_deref().unwrap_or(found);
    let config = EvalConfig {
        tolerance_m: args.tolerance_mm / 1000.0,
        min_visibility: args.min_visibility,
        threshold: args.threshold,
    };
    config.validate()?;
    let frames = open_frames(pipeline, std::slice::from_ref(&args.data))?;
    let camera = match frames.frame_ref(0) {
        Some((ds, _)) => *ds.camera(),
        None => bail!("{}: no labelled frames", args.data.display()),
    };
    // Fail on a bad split fraction before training anything.
    split_indices(frames.len(), args.train_fraction, args.seed, 0)?;
    let pool = thread_pool(args.threads.map(|n| n as usize))?;
    let name_of = |i: usize| {
        frames
            .frame_ref(i)
            .map_or_else(|| format!("#{i}"), |(_, stem)| stem.to_owned())
    };

    let mut per_split = Vec::new();
    let mut all_timings = StageTimings::default();
    for k in 0..args.splits {
        let (train_idx, test_idx) = split_indices(frames.len(), args.train_fraction, args.seed, k)?;
        let train_set = frames.subset(&train_idx);
        let test_set = frames.subset(&test_idx);
        let options = TrainOptions {
            seed: args.seed.wrapping_add(k),
            folds: args.folds as usize,
            full_grid: args.full_grid,
        };
        let bar = progress_bar(train_set.len(), &format!("split {}: train", k + 1));
        let progress = |done: usize, total: usize| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        };
        let started = Instant::now();
        let model: ModelFile = pool
            .install(|| pipeline.train(&train_set, &options, &progress))
            .with_context(|| format!("training `{}` on split {}", pipeline.name(), k + 1))?;
        let train_s = started.elapsed().as_secs_f64();
        bar.finish_and_clear();
        let source = ModelSource::File(PathBuf::from(format!("<model of split {}>", k + 1)));
        let detector = build_detector(pipeline, model, &source, &args.set)?;

        let bar = progress_bar(test_set.len(), &format!("split {}: detect", k + 1));
        let (results, totals) = pool.install(|| {
            detect_frames(
                detector.as_ref(),
                test_set.len(),
                |i| {
                    let f = test_set.load(i)?;
                    Ok((f.name, f.frame, f.truth))
                },
                |_, _| Ok(()),
                &|| bar.inc(1),
            )
        })?;
        bar.finish_and_clear();
        all_timings.merge(&totals.timings);
        let mut inputs = Vec::with_capacity(results.len());
        for (i, (r, truth)) in results.into_iter().enumerate() {
            inputs.push(FrameInput {
                frame: name_of(test_idx[i]),
                truth,
                detections: r.detections,
            });
        }
        let report = evaluate(&inputs, &camera, &config)?;
        let fmt = |v: Option<f64>| v.map_or_else(|| "n/a".into(), |v| format!("{v:.3}"));
        eprintln!(
            "split {}/{}: trained on {} frames in {:.1} s, tested on {}: AP {} (VOC11 {}), P {}, R {}",
            k + 1,
            args.splits,
            train_idx.len(),
            train_s,
            test_idx.len(),
            fmt(report.ap),
            fmt(report.ap_voc11),
            fmt(report.precision),
            fmt(report.recall)
        );
        per_split.push(SplitRecord {
            split: k,
            train_frames: train_idx.iter().map(|&i| name_of(i)).collect(),
            test_frames: test_idx.iter().map(|&i| name_of(i)).collect(),
            train_ms_per_frame: 1e3 * train_s / train_idx.len().max(1) as f64,
            detect_ms_per_frame: totals.ms_per_frame(),
            stage_ms: totals
                .timings
                .entries()
                .iter()
                .map(|&(s, d, runs)| (s.to_owned(), 1e3 * d.as_secs_f64() / f64::from(runs.max(1))))
                .collect(),
            report,
        });
    }

    let reports: Vec<EvalReport> = per_split.iter().map(|s| s.report.clone()).collect();
    let report = ExperimentReport {
        pipeline: pipeline.name().to_owned(),
        data: args.data.clone(),
        frames: frames.len(),
        seed: args.seed,
        train_fraction: args.train_fraction,
        eval: config,
        set: params::to_json(&args.set),
        summary: SplitSummary::new(&reports),
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
