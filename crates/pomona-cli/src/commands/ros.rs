//! `pomona ros`: run a detector as a ROS 2 node (`pomona_ros::FruitNode`) until interrupted or
//! for `--duration-s` seconds.
//!
//! It subscribes to the RealSense ROS 2 driver's colour, aligned depth and camera-info topics
//! (flags change them) and publishes `vision_msgs/Detection3DArray` on `~/detections` and RViz
//! markers on `~/markers`, stamped with the colour image's header. The DDS domain is
//! `--domain-id`, else `ROS_DOMAIN_ID`, else 0. Every `--status-every-s` seconds a line on stderr
//! gives frames received and published, frames dropped as stale, failures and latency medians;
//! `--json` writes the final counters and medians (docs/formats.md).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};
use pomona_io::write_json;
use pomona_recording::{DEFAULT_COLOR_TOPIC, DEFAULT_DEPTH_TOPIC, DEFAULT_INFO_TOPIC};
use pomona_ros::{FruitNode, LatencySummary, NodeConfig, NodeStats};
use serde::Serialize;

use crate::detection_run::{keep_rule, load_detector};

/// Arguments of `pomona ros`.
#[derive(Debug, Clone, clap::Args)]
pub struct RosArgs {
    /// Pipeline to run (`shape-fit`, `symmetry`, `viewer-pose`, `color-contour`).
    #[arg(long, value_name = "NAME")]
    pub pipeline: String,
    /// Model file (default: the pipeline's built-in model).
    #[arg(long, value_name = "MODEL")]
    pub model: Option<PathBuf>,
    /// Stage-parameter overrides, as for `detect`.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<pomona::ParamOverride>,
    /// Publish detections whose calibrated confidence is at least C (0 publishes all). Default:
    /// the model's operating confidence; a model without calibration publishes those scoring
    /// ≥ 0 (its classifier's boundary).
    #[arg(long, value_name = "C")]
    pub min_confidence: Option<f64>,
    /// Colour image topic (`sensor_msgs/Image`, rgb8 or bgr8).
    #[arg(long, value_name = "TOPIC", default_value = DEFAULT_COLOR_TOPIC)]
    pub color_topic: String,
    /// Depth image aligned to colour (`sensor_msgs/Image`, 16UC1 mm or 32FC1 m).
    #[arg(long, value_name = "TOPIC", default_value = DEFAULT_DEPTH_TOPIC)]
    pub depth_topic: String,
    /// Colour camera info (`sensor_msgs/CameraInfo`).
    #[arg(long, value_name = "TOPIC", default_value = DEFAULT_INFO_TOPIC)]
    pub info_topic: String,
    /// Detections output (`vision_msgs/Detection3DArray`); `~/` is the node's private namespace.
    #[arg(long, value_name = "TOPIC", default_value = "~/detections")]
    pub detections_topic: String,
    /// RViz markers output (`visualization_msgs/MarkerArray`).
    #[arg(long, value_name = "TOPIC", default_value = "~/markers")]
    pub markers_topic: String,
    /// Publish no markers.
    #[arg(long)]
    pub no_markers: bool,
    /// Largest difference between a colour and a depth header stamp of one frame, ms.
    #[arg(long, value_name = "MS", default_value_t = 20.0)]
    pub sync_tolerance_ms: f64,
    /// Node name.
    #[arg(long, value_name = "NAME", default_value = "pomona")]
    pub node_name: String,
    /// Node namespace.
    #[arg(long, value_name = "NS", default_value = "/")]
    pub namespace: String,
    /// DDS domain id, 0–232 [default: $ROS_DOMAIN_ID, else 0].
    #[arg(long, value_name = "ID")]
    pub domain_id: Option<u16>,
    /// Stop after this many seconds (default: run until Ctrl-C).
    #[arg(long, value_name = "S")]
    pub duration_s: Option<f64>,
    /// Seconds between status lines on stderr (0: none).
    #[arg(long, value_name = "S", default_value_t = 5.0)]
    pub status_every_s: f64,
    /// Write the final counters and latency medians to this JSON file.
    #[arg(long, value_name = "REPORT")]
    pub json: Option<PathBuf>,
}

/// The final report of a run (`--json`).
#[derive(Debug, Clone, Serialize)]
pub struct RosReport {
    /// The pipeline run.
    pub pipeline: String,
    /// Resolved topics: colour, depth, camera info.
    pub input_topics: [String; 3],
    /// Resolved detections topic.
    pub detections_topic: String,
    /// Seconds the node ran.
    pub run_s: f64,
    /// Messages received on colour, depth, camera info.
    pub received: [u64; 3],
    /// Frames published.
    pub published: u64,
    /// Published frames per second over the run.
    pub published_fps: f64,
    /// Synchronised frames replaced before detection started (detection slower than the camera).
    pub dropped_stale: u64,
    /// Colour images without depth within the tolerance.
    pub unmatched_color: u64,
    /// Frames that failed.
    pub failed: u64,
    /// The latest failure.
    pub last_error: Option<String>,
    /// Medians over the last 1000 published frames.
    pub latency: Option<LatencySummary>,
}

fn domain_id(args: &RosArgs) -> Result<u16> {
    if let Some(id) = args.domain_id {
        return Ok(id);
    }
    match std::env::var("ROS_DOMAIN_ID") {
        Ok(v) if !v.trim().is_empty() => v
            .trim()
            .parse()
            .with_context(|| format!("ROS_DOMAIN_ID is `{v}`, not a domain id (0–232)")),
        _ => Ok(0),
    }
}

fn status_line(stats: &NodeStats, run_s: f64) -> String {
    let latency = stats.latency_summary().map_or_else(String::new, |l| {
        format!(
            ", latency median {:.1} ms (detection {:.1} ms)",
            l.latency_ms_median, l.detect_ms_median
        )
    });
    format!(
        "{:.0} s: {} colour images, {} frames published ({:.1}/s), {} dropped as stale, {} failed{latency}",
        run_s,
        stats.received[0],
        stats.published,
        stats.published as f64 / run_s.max(1e-9),
        stats.dropped_stale,
        stats.failed,
    )
}

/// Runs the node.
///
/// # Errors
/// A bad flag, model or topic name, a DDS participant that cannot start, a node thread that
/// panicked, or an unwritable report.
pub fn run(args: &RosArgs) -> Result<()> {
    let ms = args.sync_tolerance_ms;
    if !(ms.is_finite() && ms >= 0.0) {
        bail!("--sync-tolerance-ms must be a finite number ≥ 0 (got {ms})");
    }
    for (flag, v) in [
        ("--status-every-s", Some(args.status_every_s)),
        ("--duration-s", args.duration_s),
    ] {
        if v.is_some_and(|v| !(v.is_finite() && v >= 0.0)) {
            bail!("{flag} must be a finite number ≥ 0");
        }
    }
    let pipelines = pomona::pipelines();
    let pipeline = pomona::find_pipeline(&pipelines, &args.pipeline)?;
    let detector = load_detector(pipeline, args.model.as_deref(), &args.set)?;
    // Checked here for a clear message; the node applies the same rule.
    keep_rule(&detector, args.min_confidence)?;
    let config = NodeConfig {
        node_name: args.node_name.clone(),
        namespace: args.namespace.clone(),
        domain_id: domain_id(args)?,
        input: pomona_recording::RecordingTopics {
            color: args.color_topic.clone(),
            depth: args.depth_topic.clone(),
            camera_info: args.info_topic.clone(),
        },
        detections_topic: args.detections_topic.clone(),
        markers_topic: (!args.no_markers).then(|| args.markers_topic.clone()),
        sync_tolerance_ns: (ms * 1e6).round() as u64,
        min_confidence: args.min_confidence,
        ..NodeConfig::default()
    };
    let domain = config.domain_id;
    let node = FruitNode::start(detector, config).context("cannot start the ROS 2 node")?;
    let topics = node.topics().clone();
    eprintln!(
        "pomona ros: {} on domain {domain}; in {}, {}, {}; out {}{}",
        pipeline.name(),
        topics.input[0],
        topics.input[1],
        topics.input[2],
        topics.detections,
        topics
            .markers
            .as_deref()
            .map_or_else(String::new, |m| format!(", {m}")),
    );

    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let interrupted = Arc::clone(&interrupted);
        ctrlc::set_handler(move || interrupted.store(true, Ordering::SeqCst))
            .context("cannot install the Ctrl-C handler")?;
    }
    let started = Instant::now();
    let mut next_status = args.status_every_s;
    loop {
        std::thread::sleep(Duration::from_millis(50));
        let run_s = started.elapsed().as_secs_f64();
        if interrupted.load(Ordering::SeqCst) || args.duration_s.is_some_and(|d| run_s >= d) {
            break;
        }
        if args.status_every_s > 0.0 && run_s >= next_status {
            eprintln!("{}", status_line(&node.stats(), run_s));
            next_status += args.status_every_s;
        }
    }
    let stats = node.shutdown()?;
    let run_s = started.elapsed().as_secs_f64();
    eprintln!("{}", status_line(&stats, run_s));
    if let Some(e) = &stats.last_error {
        eprintln!("last failure: {e}");
    }
    if let Some(path) = &args.json {
        let report = RosReport {
            pipeline: pipeline.name().to_owned(),
            input_topics: topics.input,
            detections_topic: topics.detections,
            run_s,
            received: stats.received,
            published: stats.published,
            published_fps: stats.published as f64 / run_s.max(1e-9),
            dropped_stale: stats.dropped_stale,
            unmatched_color: stats.sync.unmatched_color,
            failed: stats.failed,
            last_error: stats.last_error.clone(),
            latency: stats.latency_summary(),
        };
        write_json(path, &report)?;
    }
    Ok(())
}
