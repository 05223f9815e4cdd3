//! `pomona detect`: run a trained detector (any registered pipeline) over every frame of a
//! dataset (or of a recording, `--recording`: ROS 2 MCAP, ROS 1 bag or RealSense bag) and write one detection file per frame
//! (`<out>/<frame>.json`, docs/formats.md).
//!
//! The model comes from `--model` or, without it, the pipeline's built-in model. Frames are
//! loaded lazily and processed in parallel; `--timings` prints the per-stage cost table.
//!
//! A frame that fails (unreadable image, detection error) does not stop the run: every other
//! frame is written, the failures go to `<out>/failures.json`, and the command exits with status
//! 3 (see `exit_status.rs`). `--resume` continues a killed run: frames whose file it would write
//! unchanged are skipped; a folder of another run is refused (the folder rules are the facade's,
//! `pomona::prepare_detection_folder`, shared with the Python Dask runner). `--shard I/N`
//! processes task `I`'s share of the frames, for array jobs on a cluster (see `shard.rs`).
//!
//! `--rrd OUT.rrd` also writes a rerun recording of the run (see `recording.rs`), recorded from
//! the worker threads as frames finish and closed before the command returns.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::detect_input::DetectInput;
use crate::detection_run::{detect_frames, keep_rule, load_detector, thread_pool};
use crate::error_line::error_line;
use crate::exit_status::FramesFailed;
use crate::overlay::{shown, view_of, write_overlay};
use crate::progress::progress_bar;
use crate::recording::{self, RunDescription};
use crate::robot_recording::RecordingArgs;
use crate::shard::Shard;
use anyhow::{bail, Context, Result};
use pomona::{
    prepare_detection_folder, write_failures, Detection, FailedFrame, ModelSource, Pipeline,
    RunIdentity, StageTimings,
};

/// Arguments of `pomona detect`.
#[derive(Debug, Clone, clap::Args)]
#[command(group(clap::ArgGroup::new("input").required(true).args(["data", "recording"])))]
pub struct DetectArgs {
    /// Pipeline (detection method), e.g. `shape-fit`.
    #[arg(long, value_name = "NAME")]
    pub pipeline: String,
    /// Model file from `pomona train` (default: the pipeline's built-in model).
    #[arg(long, value_name = "MODEL")]
    pub model: Option<PathBuf>,
    /// Dataset folder; every frame is processed, with or without truth.
    #[arg(long, value_name = "DIR")]
    pub data: Option<PathBuf>,
    /// A recording (ROS 2 MCAP, ROS 1 bag or RealSense bag) instead of a dataset: every synchronised colour/depth frame is
    /// processed, its file named by the colour stamp (19-digit ns) and holding `stamp_ns` and
    /// `frame_id`. Topics and tolerance as for `pomona extract`.
    #[arg(long, value_name = "FILE")]
    pub recording: Option<PathBuf>,
    /// Topics and synchronisation of `--recording`.
    #[command(flatten)]
    pub topics: RecordingArgs,
    /// Output folder for `<frame>.json` detection files (created if missing).
    #[arg(long, value_name = "DETDIR")]
    pub out: PathBuf,
    /// Print mean time per stage and per frame.
    #[arg(long)]
    pub timings: bool,
    /// Worker threads (default: all cores); never changes the detections.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
    /// Override a stage parameter of the model, KEY=VALUE (dotted keys, JSON values); repeat.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<pomona::ParamOverride>,
    /// Also draw each frame's truth (green) and detections scoring at least 0 (red, score and
    /// diameter) on its colour image, written as `<DIR>/<frame>.png`.
    #[arg(long, value_name = "DIR")]
    pub overlay: Option<PathBuf>,
    /// Keep detections whose calibrated confidence is at least C (0 keeps all). Default: the
    /// model's operating confidence; a model without calibration keeps detections scoring ≥ 0
    /// (its classifier's boundary).
    #[arg(long, value_name = "C")]
    pub min_confidence: Option<f64>,
    /// Continue an interrupted run: skip frames whose detection file exists and was made by the
    /// same pipeline, model, `--set` and threshold. (Without it, such files are rewritten; files
    /// made differently are an error either way.)
    #[arg(long)]
    pub resume: bool,
    /// Also write a rerun recording of the run to OUT.rrd (view it with `rerun OUT.rrd`): per
    /// frame the images, the point cloud, truth (green) and detections (red; those below the
    /// confidence threshold faint), on a `frame` timeline. Needs the `rerun` build feature
    /// (`--features rerun`; the release binary has it).
    #[arg(long, value_name = "OUT.rrd")]
    pub rrd: Option<PathBuf>,
    /// Process only task I's share (0-based) of N: every N-th frame of the sorted frame list
    /// from frame I, so N tasks writing into one --out produce the files of one whole run.
    /// Failures go to `failures.shard-I-of-N.json`.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<Shard>,
}

/// What a detection run did.
#[derive(Debug, Clone)]
pub struct DetectSummary {
    /// Frames processed (= files written).
    pub frames: usize,
    /// Frames skipped because `--resume` found their file already written.
    pub resumed: usize,
    /// Frames that failed (listed in `failures.json`).
    pub failed: usize,
    /// Detections written over all frames (those kept at the confidence threshold).
    pub detections: usize,
    /// Stage times merged over frames.
    pub timings: StageTimings,
    /// Mean detection time per frame, milliseconds (single-frame cost).
    pub ms_per_frame: Option<f64>,
    /// Which model was used.
    pub model: ModelSource,
}

/// Warns about `.json` files in `out` that belong to no frame of the dataset (left from another
/// run): `pomona eval` would refuse the folder.
fn warn_foreign_files(out: &Path, frames: &[String]) {
    let Ok(entries) = std::fs::read_dir(out) else {
        return;
    };
    let known: std::collections::HashSet<&str> = frames.iter().map(String::as_str).collect();
    let foreign = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            pomona_eval::detection_file_frame(p, |f| known.contains(f))
                .is_some_and(|f| !known.contains(f))
        })
        .count();
    if foreign > 0 {
        eprintln!(
            "warning: {} holds {foreign} detection file(s) for frames this dataset does not have \
             (from another run?); `pomona eval` will refuse the folder until they are removed",
            out.display()
        );
    }
}

/// Runs `pomona detect` with the registered pipelines.
///
/// # Errors
/// See [`run_with`].
pub fn run(args: &DetectArgs) -> Result<()> {
    run_with(&pomona::pipelines(), args).map(|_| ())
}

/// Runs `pomona detect` choosing the pipeline from `pipelines` (tests pass their own).
///
/// # Errors
/// Unknown pipeline, no model (no `--model` and no built-in one), a model for another pipeline
/// or version, a colour-less dataset for a colour pipeline, unreadable frames, detection
/// failures and unwritable output, each naming the file or frame.
pub fn run_with(pipelines: &[Box<dyn Pipeline>], args: &DetectArgs) -> Result<DetectSummary> {
    let pipeline = pomona::find_pipeline(pipelines, &args.pipeline)?;
    let input = DetectInput::open(
        args.data.as_deref(),
        args.recording.as_deref(),
        &args.topics,
    )?;
    let dataset = input.dataset();
    if dataset.is_none() && (args.overlay.is_some() || args.rrd.is_some()) {
        bail!(
            "--overlay and --rrd need a dataset folder; write the recording as one with \
             `pomona extract FILE --out DATASET` and run on --data DATASET"
        );
    }
    input.check(pipeline)?;
    if let Some(warning) = input.depth_unit_warning() {
        eprintln!("warning: {warning}");
    }
    let detector = load_detector(pipeline, args.model.as_deref(), &args.set)?;
    let keep = keep_rule(&detector, args.min_confidence)?;
    let model = detector.model_for_color(input.has_color()).clone();
    let name = pipeline.name();
    let identity = detector.run_identity(input.has_color(), keep);
    let (frames, resumed) = frames_to_run(args, &input, &identity)?;
    let description = RunDescription {
        pipeline: name,
        model_id: &model.id,
        keep,
    };
    let writer = FrameWriter {
        args,
        input: &input,
        detector: &detector,
        keep,
        name,
        recording: match dataset {
            Some(dataset) => recording::open(args.rrd.as_deref(), dataset, &description)?,
            None => None,
        },
    };
    if let Some(dir) = &args.overlay {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create overlay folder {}", dir.display()))?;
    }

    let pool = thread_pool(args.threads.map(|n| n as usize))?;
    let bar = progress_bar(frames.len(), "detecting");
    let started = Instant::now();
    let batch = pool.install(|| {
        detect_frames(
            &detector,
            frames.len(),
            |i| {
                let stem = &frames[i];
                let frame = input.load_frame(stem)?;
                Ok((format!("{}/{stem}", input.path().display()), frame, ()))
            },
            |i, result| writer.write(&frames[i], &result.detections),
            &|| bar.inc(1),
        )
    });
    bar.finish_and_clear();
    if let Some(recording) = writer.recording {
        recording.finish()?;
    }
    let wall = started.elapsed().as_secs_f64();
    let failures: Vec<FailedFrame> = batch
        .failed
        .iter()
        .map(|f| FailedFrame {
            frame: frames[f.index].clone(),
            file: f.file().map(Path::to_owned),
            error: error_line(&f.error),
        })
        .collect();
    for f in &failures {
        eprintln!("error: frame {}: {}", f.frame, f.error);
    }
    let shard = args.shard.map(|s| (s.index, s.count));
    let report = write_failures(&args.out, shard, name, frames.len(), &failures)?;
    let kept = |d: &Detection| keep.keeps(d);
    let found: Vec<&[Detection]> = batch
        .done
        .iter()
        .map(|(_, r, ())| r.detections.as_slice())
        .collect();
    let summary = DetectSummary {
        frames: batch.totals.frames,
        resumed,
        failed: failures.len(),
        detections: found
            .iter()
            .flat_map(|d| d.iter())
            .filter(|d| kept(d))
            .count(),
        ms_per_frame: batch.totals.ms_per_frame(),
        timings: batch.totals.timings,
        model: model.source.clone(),
    };
    warn_foreign_files(&args.out, input.frames());
    let thresholds = (keep, model.operating_confidence);
    print_summary(
        args,
        &input.path(),
        name,
        &summary,
        &found,
        thresholds,
        wall,
    );
    if let Some(report) = report {
        return Err(FramesFailed {
            failed: failures.len(),
            total: frames.len(),
            report,
        }
        .into());
    }
    Ok(summary)
}

/// The frames this run detects on: the shard's share of the dataset (all of it without
/// `--shard`), less those `--resume` finds done; and how many it skipped for that. Checks the
/// output folder first ([`pomona::prepare_detection_folder`]).
///
/// # Errors
/// An output folder holding detections made differently, or one that cannot be read.
fn frames_to_run(
    args: &DetectArgs,
    input: &DetectInput,
    identity: &RunIdentity<'_>,
) -> Result<(Vec<String>, usize)> {
    let mine: Vec<String> = match args.shard {
        Some(shard) => shard.select(input.frames()).into_iter().cloned().collect(),
        None => input.frames().to_vec(),
    };
    let already = prepare_detection_folder(&args.out, &mine, identity)?;
    let total = mine.len();
    let frames: Vec<String> = mine
        .into_iter()
        .filter(|f| !(args.resume && already.contains(f)))
        .collect();
    let resumed = total - frames.len();
    Ok((frames, resumed))
}

/// What happens to one frame's detections: its detection file, its part of the recording, its
/// overlay. Shared by the worker threads.
struct FrameWriter<'a> {
    args: &'a DetectArgs,
    input: &'a DetectInput,
    detector: &'a pomona::Detector,
    keep: pomona::KeepRule,
    name: &'static str,
    recording: Option<recording::RunRecording>,
}

impl FrameWriter<'_> {
    fn write(&self, stem: &str, detections: &[Detection]) -> Result<()> {
        let (args, input) = (self.args, self.input);
        let mut record = self
            .detector
            .frame_record(stem, input.has_color(), detections, self.keep);
        input.annotate(stem, &mut record)?;
        pomona_io::write_json(&args.out.join(format!("{stem}.json")), &record)?;
        // Recordings and overlays need a dataset's files (checked before the run).
        let Some(dataset) = input.dataset() else {
            return Ok(());
        };
        if let Some(recording) = &self.recording {
            let kept = |d: &Detection| self.keep.keeps(d);
            recording.record_frame(dataset, stem, detections, &kept)?;
        }
        let Some(dir) = &args.overlay else {
            return Ok(());
        };
        let (image, truth) = view_of(dataset, stem)?;
        let (shown, kept_words) = match self.keep {
            pomona::KeepRule::All => (shown(detections, 0.0), "scoring ≥ 0".to_owned()),
            keep => (
                record.detections.clone(),
                format!("with {}", keep.describe()),
            ),
        };
        write_overlay(
            &dir.join(format!("{stem}.png")),
            &image,
            dataset.camera(),
            truth.as_ref(),
            &shown,
            0.5,
            &format!("{stem}: {} ({} {kept_words})", self.name, shown.len()),
        )
    }
}

/// The run's closing lines: what was made and kept, where it went, and the stage timings.
fn print_summary(
    args: &DetectArgs,
    input: &Path,
    name: &str,
    summary: &DetectSummary,
    found: &[&[Detection]],
    (keep, operating): (pomona::KeepRule, Option<f64>),
    wall_s: f64,
) {
    let all: usize = found.iter().map(|d| d.len()).sum();
    let written = summary.detections;
    let kept_note = match (keep, operating) {
        (pomona::KeepRule::Confidence(c), Some(op)) if c == op => {
            format!("{written} kept at the model's operating confidence {c:.3}")
        }
        (pomona::KeepRule::Confidence(c), _) => format!("{written} kept at confidence ≥ {c:.3}"),
        (pomona::KeepRule::Score(s), _) => format!(
            "{written} kept at score ≥ {s}: the model has no confidence calibration, so the \
             classifier's boundary; --min-confidence 0 keeps all"
        ),
        (pomona::KeepRule::All, _) => format!("all {written} kept"),
    };
    let resumed_note = if summary.resumed > 0 {
        format!(" ({} already done, skipped)", summary.resumed)
    } else {
        String::new()
    };
    let shard_note = args
        .shard
        .map_or(String::new(), |s| format!(" (shard {s})"));
    println!(
        "`{name}` ({}) made {all} detections ({kept_note}) in {} frame(s){shard_note} of \
         {}{resumed_note} in {wall_s:.1} s; detection files in {}",
        summary.model,
        summary.frames,
        input.display(),
        args.out.display()
    );
    if let Some(rrd) = &args.rrd {
        println!(
            "recording in {} (view it with `rerun {}`)",
            rrd.display(),
            rrd.display()
        );
    }
    if args.timings {
        print!("{}", summary.timings.table());
        if let Some(ms) = summary.ms_per_frame {
            println!(
                "{ms:.2} ms/frame (single-frame detection time, loading and writing excluded)"
            );
        }
    }
}
