//! `pomona track`: follow the target fruit through every approach sequence of a folder made by
//! `pomona synth --approach`, with seed 004's approach tracker (§3.3, the facade's
//! `pomona::Tracker`; by default with the local contour re-detection,
//! `--set redetect="off" --set max_search_radii=null --set min_fruit_share=0 --set
//! patch_shift=null --set max_jump_radii=null` for the paper's tracker alone), and score it.
//! The tracker uses the model's colour table and, for the re-detection, its stage parameters.
//!
//! Per sequence (`DIR/seq-*/`, a dataset with `approach.json` naming the target):
//! * the track starts from the first frame's `color-contour` detection nearest the target's
//!   truth centre, at any confidence (`--init detection`, the default: the robot chose that
//!   detection as its target; if it is another fruit, the sequence fails), or from the truth
//!   circle itself (`--init truth`);
//! * every frame, first included, is passed to the tracker; only `update` is timed (image
//!   decoding is not), on one thread;
//! * success: the last frame's estimate lies within 0.3 target radii of the target's truth
//!   circle's centre, the same circle `pomona eval --2d` scores against
//!   ([`pomona_core::FruitTruth::image_circle`]: the truth's `center_px` and `radius_px`, which
//!   `pomona synth` writes as the circle of the sphere's outline, else the sphere projected,
//!   else the box).
//!
//! Writes `TRACKDIR/<sequence>.json` (every frame's estimate, status, time and error) and prints
//! `success_rate` and `ms_per_frame`, and how many tracks started on their target (the start
//! circle's centre within half the target's truth radius, the hit rule of `pomona eval --2d`: a
//! track that starts on another fruit fails by its detector, not by the tracker); `--json` also
//! writes that summary as a file (docs/formats.md).
//!
//! **Your own frames** (`--start X,Y[,R]`): `--data` is then one dataset — any colour frames in
//! name order, for example extracted from a recording with `pomona extract` — and the fruit at
//! pixel (X, Y) of the first frame is followed: from the detection whose circle covers that pixel
//! (centred nearest it), or from the circle of radius R there. The track is
//! `TRACKDIR/track.json`; it is scored only when the dataset has truth and a truth fruit's circle
//! contains the start pixel.
//! `--overlay DIR` draws every frame's estimate (red) and the target's truth (green).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use pomona_colorcontour::{TrackParams, TrackStatus, PIPELINE_NAME};
use pomona_core::nalgebra::Point2;
use pomona_core::ImageCircle;
use pomona_io::{write_json, Dataset};
use pomona_synth::{ApproachRecord, APPROACH_FILE};
use serde::Serialize;

use crate::detection_run::load_detector;
use crate::number_pair::parse_number_pair;
use crate::overlay::write_track_overlay;
use crate::progress::progress_bar;

/// A last-frame estimate is a success within this many target radii of the truth centre.
pub const SUCCESS_RADII: f64 = 0.3;
/// A track starts on its target when the start circle's centre lies within this many target
/// radii of the truth centre (the hit rule of `pomona eval --2d`).
pub const ON_TARGET_RADII: f64 = 0.5;

/// Arguments of `pomona track`.
#[derive(Debug, Clone, clap::Args)]
pub struct TrackArgs {
    /// Folder of approach sequences (`pomona synth --approach`): `DIR/seq-*/`; with `--start`,
    /// one dataset.
    #[arg(long, value_name = "DIR")]
    pub data: PathBuf,
    /// Folder for one track file per sequence (`track.json` with `--start`; created if missing;
    /// existing track files of the same names are replaced).
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
    /// Follow one fruit through a dataset of your own (`--data` is then one dataset, frames in
    /// name order): the first frame's detection whose circle covers pixel X,Y (the one centred
    /// nearest it), or the circle of radius R pixels there. The track is written to
    /// `TRACKDIR/track.json`.
    #[arg(long, value_name = "X,Y[,R]", value_parser = parse_start, conflicts_with = "init")]
    pub start: Option<StartCircle>,
    /// Also draw every frame's estimate (red) and the target's truth circle (green) on its
    /// colour image: `DIR/<sequence>/<frame>.png` (with `--start`: `DIR/<frame>.png`).
    #[arg(long, value_name = "DIR")]
    pub overlay: Option<PathBuf>,
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

/// `--start`: a pixel of the first frame, and the start circle's radius if given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartCircle {
    /// The pixel, (x, y).
    pub at_px: Point2<f64>,
    /// The start circle's radius, pixels (`None`: start from the nearest detection).
    pub radius_px: Option<f64>,
}

fn parse_start(s: &str) -> Result<StartCircle, String> {
    let example = "X,Y or X,Y,R in pixels (e.g. 320,240 or 320,240,25)";
    let (xy, radius) = match s.matches(',').count() {
        2 => match s.rsplit_once(',') {
            Some((xy, r)) => (xy, Some(r)),
            None => (s, None),
        },
        _ => (s, None),
    };
    let (x, y) = parse_number_pair(xy, example)?;
    let radius_px = radius
        .map(|r| {
            r.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| format!("the radius `{r}` is not a positive number"))
        })
        .transpose()?;
    Ok(StartCircle {
        at_px: Point2::new(x, y),
        radius_px,
    })
}

/// How a track started, as recorded in track files and reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum StartedFrom {
    /// A detection of the first frame.
    Detection,
    /// The target's truth circle.
    Truth,
    /// A circle given with `--start X,Y,R`.
    Circle,
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
    /// Truth id of the target (absent for a `--start` track with no truth fruit there).
    pub target_id: Option<String>,
    /// How the track started.
    pub init: StartedFrom,
    /// The start circle: centre and radius, pixels (absent when no detection was made).
    pub init_circle_px: Option<[f64; 3]>,
    /// The start circle's centre error over the target's truth radius, first frame.
    pub init_error_radii: Option<f64>,
    /// Whether the last frame's estimate is within 0.3 radii of the truth centre (absent when
    /// the target has no truth).
    pub success: Option<bool>,
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
    /// `succeeded` over the sequences whose target has truth (absent when none has).
    pub success_rate: Option<f64>,
    /// Sequences whose start circle lies within 0.5 target radii of the truth centre.
    pub started_on_target: usize,
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
    /// Frames whose estimate is the last circle moved with the image patch around it, the
    /// circle found being too far from it (`patch_shift`).
    pub predicted_frames: usize,
    /// How tracks started.
    pub init: StartedFrom,
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
    /// Success (absent when the target has no truth).
    pub success: Option<bool>,
    /// The start circle's centre error over the truth radius.
    pub init_error_radii: Option<f64>,
    /// Last frame's centre error over the truth radius.
    pub final_error_radii: Option<f64>,
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

/// What every track shares: the loaded tracker (the model's colour table and stages, the
/// tracker's parameters) and the detector that starts tracks.
struct Tracking<'a> {
    tracker: &'a pomona::Tracker,
    /// The detector tracks start from; loaded only when a track starts from a detection.
    detector: Option<&'a pomona::Detector>,
    /// Where overlays go (`--overlay`), if anywhere.
    overlay: Option<PathBuf>,
}

impl Tracking<'_> {
    /// The first frame's detection whose centre is nearest `point`, as a circle.
    fn detection_nearest(
        &self,
        dataset: &Dataset,
        first: &str,
        point: Point2<f64>,
    ) -> Result<Option<ImageCircle>> {
        let detector = self
            .detector
            .context("a track starts from a detection, but no detector was loaded")?;
        let frame = dataset.load_frame(first)?;
        let distance = |c: &ImageCircle| (c.center_px - point).norm();
        Ok(detector
            .detect(&frame)?
            .iter()
            .filter_map(|d| d.image_circle(dataset.camera()))
            .min_by(|a, b| distance(a).total_cmp(&distance(b))))
    }

    /// Follows the fruit from `start` through every frame of `dataset`, scored against the truth
    /// fruit `track.target_id` where it has truth; fills `track`'s frames and success.
    fn follow(
        &self,
        dataset: &Dataset,
        start: ImageCircle,
        track: &mut SequenceTrack,
        overlay_dir: Option<&Path>,
    ) -> Result<()> {
        let camera = *dataset.camera();
        let target_in = |stem: &str| -> Result<Option<ImageCircle>> {
            let Some(id) = &track.target_id else {
                return Ok(None);
            };
            Ok(dataset
                .load_truth(stem)?
                .and_then(|t| t.fruits.into_iter().find(|f| &f.id == id))
                .and_then(|f| f.image_circle(&camera)))
        };
        let error_radii = |estimate: &ImageCircle, truth: &ImageCircle| {
            estimate.center_distance_px(truth) / truth.radius_px
        };
        track.init_circle_px = Some([start.center_px.x, start.center_px.y, start.radius_px]);
        if let Some(first) = dataset.frames().first() {
            track.init_error_radii = target_in(first)?.map(|t| error_radii(&start, &t));
        }
        let mut tracker = self.tracker.start(start)?;
        if let Some(dir) = overlay_dir {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
        }
        for stem in dataset.frames() {
            let color = dataset.load_color(stem)?.with_context(|| {
                format!(
                    "frame {stem} of {} has no colour image",
                    dataset.root().display()
                )
            })?;
            let started = Instant::now();
            let est = tracker.update(&color);
            let ms = started.elapsed().as_secs_f64() * 1e3;
            let truth = target_in(stem)?;
            let estimate = ImageCircle {
                center_px: est.center_px,
                radius_px: est.radius_px,
            };
            if let Some(dir) = overlay_dir {
                let status = serde_json::to_value(est.status)?;
                let title = format!(
                    "{} {stem}: {}",
                    track.sequence,
                    status.as_str().unwrap_or_default()
                );
                write_track_overlay(
                    &dir.join(format!("{stem}.png")),
                    &color,
                    &estimate,
                    truth.as_ref(),
                    &title,
                )?;
            }
            track.frames.push(TrackedFrame {
                frame: stem.clone(),
                center_px: [est.center_px.x, est.center_px.y],
                radius_px: est.radius_px,
                status: est.status,
                probes: est.probes,
                ms,
                truth_center_px: truth.map(|t| [t.center_px.x, t.center_px.y]),
                truth_radius_px: truth.map(|t| t.radius_px),
                error_radii: truth.map(|t| error_radii(&estimate, &t)),
            });
        }
        track.success = track.target_id.as_ref().map(|_| {
            track
                .frames
                .last()
                .and_then(|f| f.error_radii)
                .is_some_and(|e| e <= SUCCESS_RADII)
        });
        Ok(())
    }

    /// Tracks one approach sequence (`dir/approach.json` names the target).
    fn approach(&self, dir: &Path, init: InitArg) -> Result<SequenceTrack> {
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
        let mut track = SequenceTrack {
            sequence: name,
            target_id: Some(record.target_id.clone()),
            init: match init {
                InitArg::Detection => StartedFrom::Detection,
                InitArg::Truth => StartedFrom::Truth,
            },
            init_circle_px: None,
            init_error_radii: None,
            success: Some(false),
            failure: None,
            frames: Vec::new(),
        };
        let Some(first) = dataset.frames().first() else {
            track.failure = Some("the sequence has no frames".into());
            return Ok(track);
        };
        let target = dataset
            .load_truth(first)?
            .and_then(|t| t.fruits.into_iter().find(|f| f.id == record.target_id))
            .and_then(|f| f.image_circle(&camera));
        let Some(target) = target else {
            track.failure = Some(format!(
                "the target (id `{}`) is not in the first frame's truth: not visible there, or \
                 not a fruit of this sequence",
                record.target_id
            ));
            return Ok(track);
        };
        let start = match init {
            InitArg::Truth => Some(target),
            InitArg::Detection => self.detection_nearest(&dataset, first, target.center_px)?,
        };
        let Some(start) = start else {
            track.failure = Some("no detection in the first frame".into());
            return Ok(track);
        };
        let overlay = self.overlay.as_ref().map(|d| d.join(&track.sequence));
        self.follow(&dataset, start, &mut track, overlay.as_deref())?;
        Ok(track)
    }

    /// Tracks the fruit at `start` through the dataset `data` (`--start`).
    fn own(&self, data: &Path, start: StartCircle) -> Result<SequenceTrack> {
        let dataset = Dataset::open(data)?;
        let camera = *dataset.camera();
        let first = dataset
            .frames()
            .first()
            .with_context(|| format!("{} has no frames", data.display()))?;
        let p = start.at_px;
        if !camera.contains(&p) {
            bail!(
                "--start {},{} lies outside the {}×{} frames of {}",
                p.x,
                p.y,
                camera.width,
                camera.height,
                data.display()
            );
        }
        // The truth fruit under the start pixel, if the dataset has truth: the target.
        let target_id = dataset
            .load_truth(first)?
            .and_then(|t| {
                t.fruits
                    .into_iter()
                    .filter_map(|f| f.image_circle(&camera).map(|c| (c, f.id)))
                    .filter(|(c, _)| c.contains(&p))
                    .min_by(|(a, _), (b, _)| {
                        (a.center_px - p)
                            .norm()
                            .total_cmp(&(b.center_px - p).norm())
                    })
            })
            .map(|(_, id)| id);
        let (from, circle) = match start.radius_px {
            Some(radius_px) => (
                StartedFrom::Circle,
                ImageCircle {
                    center_px: p,
                    radius_px,
                },
            ),
            None => match self.detection_nearest(&dataset, first, p)? {
                Some(c) if c.contains(&p) => (StartedFrom::Detection, c),
                nearest => bail!(
                    "no detection of the first frame ({first}) of {} covers pixel {},{}{}; give \
                     the start circle's radius to start there anyway (--start X,Y,R)",
                    data.display(),
                    p.x,
                    p.y,
                    nearest.map_or_else(String::new, |c| format!(
                        " (the nearest is centred at {:.0},{:.0} with radius {:.0} px)",
                        c.center_px.x, c.center_px.y, c.radius_px
                    ))
                ),
            },
        };
        let mut track = SequenceTrack {
            sequence: data
                .file_name()
                .map_or_else(|| "track".to_string(), |n| n.to_string_lossy().into_owned()),
            target_id,
            init: from,
            init_circle_px: None,
            init_error_radii: None,
            success: None,
            failure: None,
            frames: Vec::new(),
        };
        self.follow(&dataset, circle, &mut track, self.overlay.as_deref())?;
        Ok(track)
    }
}

/// Runs `pomona track`.
///
/// # Errors
/// No sequences in `--data` (or, with `--start`, not a dataset or a start outside its frames),
/// an unreadable sequence, model or frame (the message names it), or an output file that could
/// not be written.
pub fn run(args: &TrackArgs) -> Result<TrackReport> {
    let dirs = match args.start {
        Some(_) => Vec::new(),
        None => sequences(&args.data)?,
    };
    let mut builder = pomona::Tracker::builder().overrides(args.set.iter().cloned());
    if let Some(path) = &args.model {
        builder = builder.model_file(path);
    }
    let tracker = builder.build()?;
    // The detector (its colour table takes a while to compile) only when a track starts from a
    // detection: `--init detection`, or `--start X,Y` without a radius.
    let from_detection = args
        .start
        .map_or(args.init == InitArg::Detection, |s| s.radius_px.is_none());
    let detector = if from_detection {
        let pipeline = pomona::pipeline(PIPELINE_NAME)?;
        Some(load_detector(
            pipeline.as_ref(),
            args.model.as_deref(),
            &[],
        )?)
    } else {
        None
    };
    let tracking = Tracking {
        tracker: &tracker,
        detector: detector.as_ref(),
        overlay: args.overlay.clone(),
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let mut tracks = Vec::new();
    if let Some(start) = args.start {
        let track = tracking
            .own(&args.data, start)
            .with_context(|| format!("tracking {}", args.data.display()))?;
        write_json(&args.out.join("track.json"), &track)?;
        tracks.push(track);
    }
    let bar = (!dirs.is_empty()).then(|| progress_bar(dirs.len(), "tracking"));
    for dir in &dirs {
        let track = tracking
            .approach(dir, args.init)
            .with_context(|| format!("tracking {}", dir.display()))?;
        write_json(&args.out.join(format!("{}.json", track.sequence)), &track)?;
        if let Some(reason) = &track.failure {
            let say = || eprintln!("{}: not tracked: {reason}", dir.display());
            match &bar {
                Some(bar) => bar.suspend(say),
                None => say(),
            }
        }
        tracks.push(track);
        if let Some(bar) = &bar {
            bar.inc(1);
        }
    }
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let report = TrackReport::of(&tracks, *tracker.params());
    let rate = report
        .success_rate
        .map_or_else(|| "–".to_string(), |r| format!("{r:.3}"));
    println!(
        "tracked {} sequences ({} frames, init {}): success_rate {rate} ({} of {}; {} started on \
         the target), ms_per_frame {:.4} (median {:.4}, max {:.3}), {} frames found by search, {} \
         by re-detection, {} by the image patch alone, {} lost",
        report.sequences,
        report.frames,
        serde_json::to_value(report.init)?
            .as_str()
            .unwrap_or_default(),
        report.succeeded,
        tracks.iter().filter(|t| t.success.is_some()).count(),
        report.started_on_target,
        report.ms_per_frame,
        report.ms_per_frame_median,
        report.ms_per_frame_max,
        report.searched_frames,
        report.redetected_frames,
        report.predicted_frames,
        report.lost_frames
    );
    if let Some(path) = &args.json {
        write_json(path, &report)?;
    }
    Ok(report)
}

impl TrackReport {
    /// The summary of `tracks`, tracked with `params`.
    fn of(tracks: &[SequenceTrack], params: TrackParams) -> Self {
        let times: Vec<f64> = tracks
            .iter()
            .flat_map(|t| &t.frames)
            .map(|f| f.ms)
            .collect();
        let count = |status| {
            tracks
                .iter()
                .flat_map(|t| &t.frames)
                .filter(|f| f.status == status)
                .count()
        };
        let scored = tracks.iter().filter(|t| t.success.is_some()).count();
        let succeeded = tracks.iter().filter(|t| t.success == Some(true)).count();
        let mut sorted = times.clone();
        sorted.sort_by(f64::total_cmp);
        Self {
            sequences: tracks.len(),
            succeeded,
            success_rate: (scored > 0).then(|| succeeded as f64 / scored as f64),
            started_on_target: tracks
                .iter()
                .filter(|t| t.init_error_radii.is_some_and(|e| e <= ON_TARGET_RADII))
                .count(),
            // A fold from +0 (an empty `sum` of floats is −0, printed "-0.0000").
            ms_per_frame: times.iter().fold(0.0, |a, b| a + b) / times.len().max(1) as f64,
            ms_per_frame_median: pomona_core::quantile(&sorted, 0.5).unwrap_or(0.0),
            ms_per_frame_max: times.iter().copied().fold(0.0, f64::max),
            frames: times.len(),
            searched_frames: count(TrackStatus::Searched),
            lost_frames: count(TrackStatus::Lost),
            redetected_frames: count(TrackStatus::Redetected),
            predicted_frames: count(TrackStatus::Predicted),
            init: tracks.first().map_or(StartedFrom::Detection, |t| t.init),
            params,
            per_sequence: tracks
                .iter()
                .map(|t| SequenceResult {
                    sequence: t.sequence.clone(),
                    success: t.success,
                    init_error_radii: t.init_error_radii,
                    final_error_radii: t.frames.last().and_then(|f| f.error_radii),
                })
                .collect(),
        }
    }
}
