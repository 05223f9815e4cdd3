//! `pomona eval`: score a folder of detections against a dataset's truth — PASCAL VOC 11-point
//! and all-point AP, precision and recall at a threshold, centre and diameter errors — as a
//! Markdown summary on stdout, optionally a JSON report and a precision-recall PNG.
//!
//! The semantics (greedy matching within a 3D tolerance, or in the image with `--2d`; ignored
//! low-visibility truth, 2D-box truth, incomplete frames) live in `pomona-eval`; this module only
//! reads files and reports.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use pomona_eval::{evaluate, load_detections, write_pr_plot, DetectionSet, EvalConfig, FrameInput};
use pomona_io::Dataset;

use crate::matching_args::MatchingArgs;

/// Frames listed by name in a warning before the rest are only counted.
const WARN_LIST: usize = 10;

/// Arguments of `pomona eval`.
#[derive(Debug, clap::Args)]
pub struct EvalArgs {
    /// Dataset folder (camera.json, depth/ and/or color/, truth/).
    #[arg(long)]
    pub data: PathBuf,
    /// Folder of detection files, one `<frame>.json` per frame.
    #[arg(long)]
    pub detections: PathBuf,
    /// How detections are matched to truth.
    #[command(flatten)]
    pub matching: MatchingArgs,
    /// Score threshold of the reported precision/recall. Default: the operating confidence the
    /// detection files record (calibrated models), otherwise score 0 (an SVM's boundary).
    #[arg(long, allow_negative_numbers = true, conflicts_with = "min_confidence")]
    pub threshold: Option<f64>,
    /// Confidence threshold (0–1) of the reported precision/recall; needs detections with a
    /// calibrated confidence.
    #[arg(long, value_name = "C")]
    pub min_confidence: Option<f64>,
    /// Write the full JSON report here.
    #[arg(long, value_name = "REPORT")]
    pub json: Option<PathBuf>,
    /// Write the precision-recall curve here as a PNG.
    #[arg(long, value_name = "PR.png")]
    pub plot: Option<PathBuf>,
    /// Evaluate one kind of object (repeat for several): truth of other kinds is left out, as a
    /// per-class VOC evaluation does, so e.g. `--kind apple` scores apples and not the reference
    /// balls annotated beside them. Default: every kind.
    #[arg(long, value_name = "KIND")]
    pub kind: Vec<String>,
}

fn warn_frames(frames: &[String], what: &str) {
    if frames.is_empty() {
        return;
    }
    let shown: Vec<&str> = frames.iter().take(WARN_LIST).map(String::as_str).collect();
    let more = frames
        .len()
        .checked_sub(WARN_LIST)
        .filter(|&n| n > 0)
        .map_or(String::new(), |n| format!(" and {n} more"));
    eprintln!(
        "warning: {} frame(s) {what}: {}{more}",
        frames.len(),
        shown.join(", ")
    );
}

/// Pairs each frame that has truth with its detections (taken out of `detections`), keeping
/// only truth of `kinds` when given; warns about frames without truth.
///
/// # Errors
/// Unreadable truth, no truth object of the requested kinds, or no frame with truth.
fn scored_frames(
    dataset: &Dataset,
    detections: &mut DetectionSet,
    kinds: &[String],
    data: &Path,
) -> Result<Vec<FrameInput>> {
    let mut frames = Vec::new();
    let mut without_truth = Vec::new();
    let (mut kept, mut left_out) = (0usize, 0usize);
    for frame in dataset.frames() {
        let Some(mut truth) = dataset.load_truth(frame)? else {
            without_truth.push(frame.clone());
            continue;
        };
        if !kinds.is_empty() {
            left_out += truth.keep_kinds(kinds);
            kept += truth.fruits.len();
        }
        frames.push(FrameInput {
            frame: frame.clone(),
            truth,
            detections: detections.take(frame),
        });
    }
    warn_frames(&without_truth, "have no truth file and are not evaluated");
    if !kinds.is_empty() {
        eprintln!(
            "evaluating kind(s) {}: {kept} truth object(s) kept, {left_out} of other kinds left out",
            kinds.join(", ")
        );
        if kept == 0 {
            bail!(
                "{}: no truth object has kind {} (check `pomona info`)",
                data.display(),
                kinds.join(" or ")
            );
        }
    }
    if frames.is_empty() {
        bail!(
            "{}: no frame has a truth file (truth/<frame>.json), nothing to evaluate",
            data.display()
        );
    }
    Ok(frames)
}

/// Runs `pomona eval`.
///
/// # Errors
/// Unreadable dataset, truth or detection files (naming the file), a detection file for a frame
/// the dataset does not have, a dataset without any truth, invalid parameters, unwritable outputs.
pub fn run(args: &EvalArgs) -> Result<()> {
    let dataset = Dataset::open(&args.data)
        .with_context(|| format!("cannot open dataset {}", args.data.display()))?;
    let mut detections = load_detections(&args.detections, &dataset)?;
    let operating_point = EvalConfig {
        threshold: args.threshold.unwrap_or(0.0),
        min_confidence: match (args.min_confidence, args.threshold) {
            (Some(c), _) => Some(c),
            (None, Some(_)) => None,
            (None, None) => detections.recorded_operating_confidence(),
        },
        ..EvalConfig::default()
    };
    let config = args.matching.config(operating_point, dataset.has_depth());
    config.validate()?;
    if args.min_confidence.is_none() && args.threshold.is_none() {
        if let Some(c) = config.min_confidence {
            eprintln!("operating point: the model's operating confidence {c:.3}, as the detection files record");
        }
    }
    warn_frames(
        &detections.missing,
        &format!(
            "have no detection file in {} and count as having no detections",
            args.detections.display()
        ),
    );
    let mut pipelines: Vec<String> = detections
        .by_frame
        .values()
        .map(|d| d.pipeline.clone())
        .collect();
    pipelines.sort();
    pipelines.dedup();
    if pipelines.len() > 1 {
        eprintln!(
            "warning: detection files come from several pipelines ({}); their scores may not be comparable",
            pipelines.join(", ")
        );
    }

    let frames = scored_frames(&dataset, &mut detections, &args.kind, &args.data)?;
    let report = evaluate(&frames, dataset.camera(), &config)?;
    if let Some(path) = &args.json {
        pomona_io::write_json(path, &report)?;
    }
    if let Some(path) = &args.plot {
        match &report.pr_curve {
            Some(curve) => {
                let title = format!(
                    "{} on {} frames",
                    if pipelines.is_empty() {
                        "detections".to_owned()
                    } else {
                        pipelines.join(" + ")
                    },
                    report.frames
                );
                let marked = config.operating_score(&frames);
                write_pr_plot(path, curve, &title, marked)?;
            }
            None => eprintln!(
                "warning: no precision-recall curve, {} not written: {}",
                path.display(),
                report
                    .null_reasons
                    .get("ap")
                    .map_or("AP is undefined", String::as_str)
            ),
        }
    }
    print!("{}", report.to_markdown());
    Ok(())
}
