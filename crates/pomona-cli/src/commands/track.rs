//! `pomona track`: follow the target fruit through every approach sequence of a folder made by
//! `pomona synth --approach`, with seed 004's approach tracker (§3.3,
//! `pomona_colorcontour::ApproachTracker`; by default with the local contour re-detection,
//! `--set redetect="off"` for the paper's tracker alone), and score it. The tracker uses the
//! model's colour table and, for the re-detection, its stage parameters.
//!
//! Per sequence (`DIR/seq-*/`, a dataset with `approach.json` naming the target):
//! * the track starts from the first frame's `color-contour` detection nearest the target's
//!   truth centre, at any confidence (`--init detection`, the default: the robot chose that
//!   detection as its target; if it is another fruit, the sequence fails), or from the truth
//!   circle itself (`--init truth`);
//! * every frame, first included, is passed to the tracker; only `update` is timed (image
//!   decoding is not), on one thread;
//! * success: the last frame's estimate lies within 0.3 target radii of the target's truth
//!   centre (truth circles are projected from `center_m` and `diameter_m`: centre = projection
//!   of the centre, radius = f·r/√(d² − r²), the sphere's apparent radius on the optical axis).
//!
//! Writes `TRACKDIR/<sequence>.json` (every frame's estimate, status, time and error) and prints
//! `success_rate` and `ms_per_frame`; `--json` also writes that summary as a file
//! (docs/formats.md).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use pomona_colorcontour::{
    ApproachTracker, ColorContourParams, ColorContourStageParams, HSigmaLut, TrackParams,
    TrackStatus, PIPELINE_NAME,
};
use pomona_core::nalgebra::Point2;
use pomona_core::{FruitTruth, PinholeCamera};
use pomona_io::{write_json, Dataset};
use pomona_learn::ModelFile;
use pomona_synth::{ApproachRecord, APPROACH_FILE};
use serde::Serialize;

use crate::detection_run::load_detector;

/// A last-frame estimate is a success within this many target radii of the truth centre.
pub const SUCCESS_RADII: f64 = 0.3;

/// Arguments of `pomona track`.
#[derive(Debug, Clone, clap::Args)]
pub struct TrackArgs {
    /// Folder of approach sequences (`pomona synth --approach`): `DIR/seq-*/`.
    #[arg(long, value_name = "DIR")]
    pub data: PathBuf,
    /// Folder for one track file per sequence (created if missing; existing track files of the
    /// same names are replaced).
    #[arg(long, value_name = "TRACKDIR")]
    pub out: PathBuf,
    /// Also write the summary (success rate, time per frame, per-sequence results) here.
    #[arg(long, value_name = "REPORT")]
    pub json: Option<PathBuf>,
    /// `color-contour` model whose colour table classifies pixels and whose detector starts
    /// the track (default: the built-in model).
    #[arg(long, value_name = "MODEL")]
    pub model: Option<PathBuf>,
    /// Where the track starts in the first frame.
    #[arg(long, value_enum, default_value_t = InitArg::Detection)]
    pub init: InitArg,
    /// Override a tracker parameter, KEY=VALUE (dotted keys of `TrackParams`, JSON values, e.g.
    /// `max_radius_change=1.2` or `edge_scan.gap_px=3`); repeat.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<pomona::ParamOverride>,
}

/// `--init` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum InitArg {
    /// The first frame's detection nearest the target's truth circle.
    Detection,
    /// The target's truth circle in the first frame.
    Truth,
}

/// One frame of a track file.
#[derive(Debug, Clone, Serialize)]
pub struct TrackedFrame {
    /// Frame name.
    pub frame: String,
    /// Estimated centre, pixels.
    pub center_px: [f64; 2],
    /// Estimated radius, pixels.
    pub radius_px: f64,
    /// `confirmed`, `searched`, `redetected` or `lost`.
    pub status: TrackStatus,
    /// 5×5 checks made.
    pub probes: usize,
    /// Time of the tracker's update, milliseconds.
    pub ms: f64,
    /// The target's truth circle (absent when it is not visible in this frame).
    pub truth_center_px: Option<[f64; 2]>,
    /// Its radius, pixels.
    pub truth_radius_px: Option<f64>,
    /// Centre error over the truth radius.
    pub error_radii: Option<f64>,
}

/// `TRACKDIR/<sequence>.json`.
#[derive(Debug, Clone, Serialize)]
pub struct SequenceTrack {
    /// Sequence folder name.
    pub sequence: String,
    /// Truth id of the target.
    pub target_id: String,
    /// How the track started.
    pub init: InitArg,
    /// The start circle: centre and radius, pixels (absent when no detection was made).
    pub init_circle_px: Option<[f64; 3]>,
    /// Whether the last frame's estimate is within 0.3 radii of the truth centre.
    pub success: bool,
    /// Why the sequence failed without tracking, if it did.
    pub failure: Option<String>,
    /// Every frame.
    pub frames: Vec<TrackedFrame>,
}

/// The summary printed and written with `--json`.
#[derive(Debug, Clone, Serialize)]
pub struct TrackReport {
    /// Sequences tracked.
    pub sequences: usize,
    /// Sequences whose last estimate is within 0.3 radii of the truth.
    pub succeeded: usize,
    /// `succeeded / sequences`.
    pub success_rate: f64,
    /// Mean time of one tracker update, milliseconds (one thread, decoding excluded).
    pub ms_per_frame: f64,
    /// Median update time, milliseconds.
    pub ms_per_frame_median: f64,
    /// Slowest update, milliseconds.
    pub ms_per_frame_max: f64,
    /// Frames tracked.
    pub frames: usize,
    /// Frames found by the spiral search.
    pub searched_frames: usize,
    /// Frames lost.
    pub lost_frames: usize,
    /// Frames found by the local contour re-detection (`redetect` not `off`).
    pub redetected_frames: usize,
    /// How tracks started.
    pub init: InitArg,
    /// The tracker's parameters (defaults with `--set` applied).
    pub params: TrackParams,
    /// Per sequence: name, success and the last frame's error in radii.
    pub per_sequence: Vec<SequenceResult>,
}

/// One sequence in the report.
#[derive(Debug, Clone, Serialize)]
pub struct SequenceResult {
    /// Sequence folder name.
    pub sequence: String,
    /// Success.
    pub success: bool,
    /// Last frame's centre error over the truth radius.
    pub final_error_radii: Option<f64>,
}

/// The target's truth circle in a frame: projected centre and apparent radius, pixels.
pub fn truth_circle(camera: &PinholeCamera, fruit: &FruitTruth) -> Option<(Point2<f64>, f64)> {
    let c = fruit.center_m?;
    let r = 0.5 * fruit.diameter_m?;
    let d = c.coords.norm();
    if d <= r {
        return None;
    }
    let f = camera.mean_focal_px();
    Some((camera.project(&c)?, f * r / (d * d - r * r).sqrt()))
}

/// The sequence folders of `data`, sorted.
fn sequences(data: &Path) -> Result<Vec<PathBuf>> {
    let entries =
        std::fs::read_dir(data).with_context(|| format!("cannot list {}", data.display()))?;
    let mut dirs = Vec::new();
    for entry in entries {
        let entry = entry.with_context(|| format!("cannot list {}", data.display()))?;
        let path = entry.path();
        let named = entry.file_name().to_string_lossy().starts_with("seq-");
        if named && path.join(APPROACH_FILE).is_file() {
            dirs.push(path);
        }
    }
    dirs.sort();
    if dirs.is_empty() {
        bail!(
            "{} holds no approach sequences (seq-*/ folders with {APPROACH_FILE}); make some \
             with `pomona synth --approach N`",
            data.display()
        );
    }
    Ok(dirs)
}

/// The colour-contour model file: `--model` or the built-in one.
fn model_file(path: Option<&Path>) -> Result<ModelFile> {
    match path {
        Some(p) => Ok(ModelFile::load(p, PIPELINE_NAME)?),
        None => {
            let pipeline = pomona::pipeline(PIPELINE_NAME)?;
            let text = pipeline
                .default_model()
                .context("color-contour ships no built-in model")?;
            let label = format!("<built-in model of {PIPELINE_NAME}>");
            Ok(ModelFile::from_json(
                text,
                Path::new(&label),
                PIPELINE_NAME,
            )?)
        }
    }
}

/// The tracker's default parameters with `overrides` applied (keys as in its JSON form).
///
/// # Errors
/// An unknown key, a value of the wrong type, or parameters the tracker refuses.
fn track_params(overrides: &[pomona::ParamOverride]) -> Result<TrackParams> {
    let mut json = serde_json::to_value(TrackParams::default())?;
    pomona::apply_overrides(&mut json, overrides, "the tracker")?;
    let params: TrackParams =
        serde_json::from_value(json).context("the tracker's parameters after --set")?;
    if let Some(reason) = params.invalid_reason() {
        bail!("invalid tracker parameters after --set: {reason}");
    }
    Ok(params)
}

/// Tracks one sequence.
fn track_sequence(
    dir: &Path,
    args: &TrackArgs,
    params: TrackParams,
    (table, stage): (&(HSigmaLut, u8), &ColorContourParams),
    detector: &pomona::Detector,
) -> Result<SequenceTrack> {
    let name = dir
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let record_path = dir.join(APPROACH_FILE);
    let record: ApproachRecord = serde_json::from_str(
        &std::fs::read_to_string(&record_path)
            .with_context(|| format!("cannot read {}", record_path.display()))?,
    )
    .with_context(|| format!("{} is not an approach record", record_path.display()))?;
    let dataset = Dataset::open(dir)?;
    let camera = *dataset.camera();
    let target_in = |stem: &str| -> Result<Option<(Point2<f64>, f64)>> {
        let truth = dataset.load_truth(stem)?;
        Ok(truth
            .and_then(|t| t.fruits.into_iter().find(|f| f.id == record.target_id))
            .and_then(|f| truth_circle(&camera, &f)))
    };
    let mut track = SequenceTrack {
        sequence: name,
        target_id: record.target_id.clone(),
        init: args.init,
        init_circle_px: None,
        success: false,
        failure: None,
        frames: Vec::new(),
    };
    let Some(first) = dataset.frames().first() else {
        track.failure = Some("the sequence has no frames".into());
        return Ok(track);
    };
    let Some((target_c, target_r)) = target_in(first)? else {
        track.failure = Some(format!(
            "the target (id `{}`) is not in the first frame's truth: not visible there, or not a \
             fruit of this sequence",
            record.target_id
        ));
        return Ok(track);
    };
    let start = match args.init {
        InitArg::Truth => Some((target_c, target_r)),
        InitArg::Detection => {
            let frame = dataset.load_frame(first)?;
            detector
                .detect(&frame)?
                .iter()
                .filter_map(|d| d.bbox_px)
                .map(|b| {
                    let c = Point2::new(0.5 * (b.xmin + b.xmax), 0.5 * (b.ymin + b.ymax));
                    (c, 0.5 * (b.xmax - b.xmin).max(b.ymax - b.ymin))
                })
                .min_by(|a, b| (a.0 - target_c).norm().total_cmp(&(b.0 - target_c).norm()))
        }
    };
    let Some((c0, r0)) = start else {
        track.failure = Some("no detection in the first frame".into());
        return Ok(track);
    };
    track.init_circle_px = Some([c0.x, c0.y, r0]);
    let (lut, threshold) = table.clone();
    let mut tracker = ApproachTracker::from_table(lut, threshold, stage, params, c0, r0)
        .context("cannot start the tracker")?;
    for stem in dataset.frames() {
        let color = dataset
            .load_color(stem)?
            .with_context(|| format!("frame {stem} of {} has no colour image", dir.display()))?;
        let started = Instant::now();
        let est = tracker.update(&color);
        let ms = started.elapsed().as_secs_f64() * 1e3;
        let truth = target_in(stem)?;
        track.frames.push(TrackedFrame {
            frame: stem.clone(),
            center_px: [est.center_px.x, est.center_px.y],
            radius_px: est.radius_px,
            status: est.status,
            probes: est.probes,
            ms,
            truth_center_px: truth.map(|(c, _)| [c.x, c.y]),
            truth_radius_px: truth.map(|(_, r)| r),
            error_radii: truth.map(|(c, r)| (est.center_px - c).norm() / r),
        });
    }
    track.success = track
        .frames
        .last()
        .and_then(|f| f.error_radii)
        .is_some_and(|e| e <= SUCCESS_RADII);
    Ok(track)
}

/// Runs `pomona track`.
///
/// # Errors
/// No sequences in `--data`, an unreadable sequence, model or frame (the message names it), or
/// an output file that could not be written.
pub fn run(args: &TrackArgs) -> Result<TrackReport> {
    let params = track_params(&args.set)?;
    let dirs = sequences(&args.data)?;
    let model = model_file(args.model.as_deref())?;
    let stage = ColorContourStageParams::from_model(&model).context("the model's parameters")?;
    let table = stage.color_table().context("the model's colour table")?;
    let pipeline = pomona::pipeline(PIPELINE_NAME)?;
    let detector = load_detector(pipeline.as_ref(), args.model.as_deref(), &[])?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let mut per_sequence = Vec::new();
    let mut times = Vec::new();
    let (mut searched, mut lost, mut redetected) = (0, 0, 0);
    for dir in &dirs {
        let track = track_sequence(dir, args, params, (&table, &stage.params), &detector)
            .with_context(|| format!("tracking {}", dir.display()))?;
        write_json(&args.out.join(format!("{}.json", track.sequence)), &track)?;
        if let Some(reason) = &track.failure {
            eprintln!("{}: not tracked: {reason}", dir.display());
        }
        for f in &track.frames {
            times.push(f.ms);
            searched += usize::from(f.status == TrackStatus::Searched);
            lost += usize::from(f.status == TrackStatus::Lost);
            redetected += usize::from(f.status == TrackStatus::Redetected);
        }
        per_sequence.push(SequenceResult {
            sequence: track.sequence.clone(),
            success: track.success,
            final_error_radii: track.frames.last().and_then(|f| f.error_radii),
        });
    }
    let succeeded = per_sequence.iter().filter(|s| s.success).count();
    let mut sorted = times.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
    let report = TrackReport {
        sequences: per_sequence.len(),
        succeeded,
        success_rate: succeeded as f64 / per_sequence.len().max(1) as f64,
        // A fold from +0 (an empty `sum` of floats is −0, printed "-0.0000").
        ms_per_frame: times.iter().fold(0.0, |a, b| a + b) / times.len().max(1) as f64,
        ms_per_frame_median: median,
        ms_per_frame_max: times.iter().copied().fold(0.0, f64::max),
        frames: times.len(),
        searched_frames: searched,
        lost_frames: lost,
        redetected_frames: redetected,
        init: args.init,
        params,
        per_sequence,
    };
    println!(
        "tracked {} sequences ({} frames, init {}): success_rate {:.3} ({} of {}), ms_per_frame \
         {:.4} (median {:.4}, max {:.3}), {} frames found by search, {} by re-detection, {} lost",
        report.sequences,
        report.frames,
        match args.init {
            InitArg::Detection => "detection",
            InitArg::Truth => "truth",
        },
        report.success_rate,
        report.succeeded,
        report.sequences,
        report.ms_per_frame,
        report.ms_per_frame_median,
        report.ms_per_frame_max,
        report.searched_frames,
        report.redetected_frames,
        report.lost_frames
    );
    if let Some(path) = &args.json {
        write_json(path, &report)?;
    }
    Ok(report)
}
