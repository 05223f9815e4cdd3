//! `pomona demo`: the README's first command. Renders a small synthetic scene set (Kinect v2,
//! mixed fruit, the `wide` domain's randomised worlds with time-of-flight multipath noise), runs
//! every registered pipeline that has a built-in model, evaluates each at its model's operating
//! confidence (score ≥ 0 for an uncalibrated model), and writes everything needed to look at
//! the result:
//!
//! ```text
//! <out>/data/                       the synthetic dataset (pomona synth layout)
//! <out>/overlay/<frame>.png         the colour image with the truth (green)
//! <out>/<pipeline>/detections/      one <frame>.json per frame, every detection (docs/formats.md)
//! <out>/<pipeline>/overlay/<frame>.png   truth (green) and detections at the operating point (red, score | diameter)
//! <out>/<pipeline>/pr.png           precision-recall curve
//! <out>/report.json                 settings, and per pipeline the evaluation and ms/frame
//! ```
//!
//! With no pipeline that has a built-in model it still renders the data and truth overlays, and
//! says so.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use pomona_core::{Detection, FrameDetections, PinholeCamera};
use pomona_eval::{
    evaluate, match_frame, write_pr_plot, EvalConfig, EvalReport, FrameInput, TruthStatus,
};
use pomona_io::Dataset;
use pomona_pipeline::Pipeline;
use pomona_synth::{
    generate_dataset, CameraPreset, DatasetSpec, Domain, FruitChoice, NoiseModel, SceneSpec,
};
use rayon::prelude::*;
use serde::Serialize;

use crate::detection_run::{detect_frames, load_detector, thread_pool};
use crate::overlay::{view_of, write_overlay};
use crate::progress::progress_bar;

/// Arguments of `pomona demo`.
#[derive(Debug, Clone, clap::Args)]
pub struct DemoArgs {
    /// Output folder; created if missing. A non-empty folder is only reused when it holds an
    /// earlier demo (its report.json), whose outputs are replaced.
    #[arg(long, value_name = "DIR", default_value = "pomona-demo")]
    pub out: PathBuf,
    /// Number of synthetic frames.
    #[arg(long, value_name = "N", default_value_t = 6,
          value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub frames: u32,
    /// Seed of the synthetic scenes.
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores); never changes the output.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=1024))]
    pub threads: Option<u64>,
}

/// One pipeline's demo result.
#[derive(Debug, Clone, Serialize)]
pub struct DemoPipeline {
    /// Pipeline name.
    pub pipeline: String,
    /// Detections over all frames.
    pub detections: usize,
    /// Mean detection time per frame, milliseconds (single-frame cost).
    pub detect_ms_per_frame: Option<f64>,
    /// The evaluation.
    pub report: EvalReport,
    /// Per fruit kind in the truth: the scored fruit of that kind and how many were found at the
    /// operating point (the built-in models were trained on different fruit: color-contour's on
    /// oranges only).
    pub found_by_kind: BTreeMap<String, KindFound>,
}

/// Fruit of one kind scored and found.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct KindFound {
    /// Scored fruit of the kind (visible enough; the others are ignored).
    pub fruits: usize,
    /// Of those, found at the operating point.
    pub found: usize,
}

/// `report.json` of a demo.
#[derive(Debug, Clone, Serialize)]
pub struct DemoReport {
    /// Always `"pomona-demo"` (marks the folder as a demo output).
    pub demo: String,
    /// Frames rendered.
    pub frames: u32,
    /// Scene seed.
    pub seed: u64,
    /// Camera preset.
    pub camera: String,
    /// Depth noise model.
    pub noise: String,
    /// Dataset folder, relative to the output folder.
    pub dataset: String,
    /// Evaluation parameters.
    pub eval: EvalConfig,
    /// Results of the pipelines that have a built-in model.
    pub pipelines: Vec<DemoPipeline>,
    /// Registered pipelines skipped because they have no built-in model.
    pub without_builtin_model: Vec<String>,
}

/// Makes `out` ready: missing or empty, or an earlier demo whose outputs are removed.
fn prepare_output(out: &Path, pipelines: &[Box<dyn Pipeline>]) -> Result<()> {
    if !out.exists() {
        return Ok(());
    }
    if !out.is_dir() {
        bail!("{} exists and is not a folder", out.display());
    }
    let mut entries =
        std::fs::read_dir(out).with_context(|| format!("cannot list {}", out.display()))?;
    if entries.next().is_none() {
        return Ok(());
    }
    let is_demo = std::fs::read_to_string(out.join("report.json"))
        .is_ok_and(|t| t.contains("\"pomona-demo\""));
    if !is_demo {
        bail!(
            "{} is not empty and does not hold an earlier demo (no report.json); choose another --out",
            out.display()
        );
    }
    let mut stale: Vec<PathBuf> = ["data", "overlay", "report.json"]
        .iter()
        .map(|n| out.join(n))
        .collect();
    stale.extend(pipelines.iter().map(|p| out.join(p.name())));
    for path in stale {
        let removed = if path.is_dir() {
            std::fs::remove_dir_all(&path)
        } else if path.exists() {
            std::fs::remove_file(&path)
        } else {
            Ok(())
        };
        removed.with_context(|| format!("cannot remove {}", path.display()))?;
    }
    Ok(())
}

/// The scenes of the demo.
pub fn demo_spec(frames: u32, seed: u64) -> DatasetSpec {
    let scene = SceneSpec {
        fruit: FruitChoice::Mixed,
        camera: CameraPreset::KinectV2.camera(),
        noise: NoiseModel::for_camera(CameraPreset::KinectV2),
        domain: Domain::Wide,
        ..SceneSpec::default()
    };
    DatasetSpec::new(scene, frames, seed)
}

/// The rendered demo dataset.
struct DemoData {
    data_dir: PathBuf,
    dataset: Dataset,
    camera: PinholeCamera,
    stems: Vec<String>,
}

/// Renders the demo scenes into `<out>/data` and opens them.
fn render(args: &DemoArgs) -> Result<DemoData> {
    let data_dir = args.out.join("data");
    let mut spec = demo_spec(args.frames, args.seed);
    spec.threads = args.threads.map(|n| n as usize);
    let bar = progress_bar(args.frames as usize, "rendering");
    let synth = generate_dataset(&spec, &data_dir, &|_| bar.inc(1))
        .with_context(|| format!("rendering the demo scenes into {}", data_dir.display()))?;
    bar.finish_and_clear();
    println!(
        "Rendered {} synthetic Kinect v2 frames (mixed fruit, wide domain, time-of-flight noise, seed {}) with \
         {} visible fruit into {}",
        synth.frames,
        args.seed,
        synth.fruits,
        data_dir.display()
    );
    let dataset = Dataset::open(&data_dir)
        .with_context(|| format!("cannot open dataset {}", data_dir.display()))?;
    Ok(DemoData {
        camera: *dataset.camera(),
        stems: dataset.frames().to_vec(),
        data_dir,
        dataset,
    })
}

/// Draws each frame's truth on its colour image into `dir` (in parallel, in the current pool).
fn write_truth_overlays(demo: &DemoData, dir: &Path, config: &EvalConfig) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    demo.stems.par_iter().try_for_each(|stem| -> Result<()> {
        let (image, truth) = view_of(&demo.dataset, stem)?;
        let n = truth.as_ref().map_or(0, |t| t.fruits.len());
        write_overlay(
            &dir.join(format!("{stem}.png")),
            &image,
            &demo.camera,
            truth.as_ref(),
            &[],
            config.min_visibility,
            &format!("{stem}: truth ({n} fruit)"),
        )
    })
}

/// Detects with `pipeline`'s built-in model on every demo frame, writes its detections, overlays
/// and PR curve under `<out>/<pipeline>/`, prints and returns its scores.
fn run_pipeline(demo: &DemoData, pipeline: &dyn Pipeline, out: &Path) -> Result<DemoPipeline> {
    let name = pipeline.name();
    let detector = load_detector(pipeline, None, &[])?;
    let config = EvalConfig {
        min_confidence: detector.operating_confidence(),
        ..EvalConfig::default()
    };
    let det_dir = out.join(name).join("detections");
    let ovl_dir = out.join(name).join("overlay");
    for dir in [&det_dir, &ovl_dir] {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let stems = &demo.stems;
    let bar = progress_bar(stems.len(), name);
    let (frames, totals) = detect_frames(
        &detector,
        stems.len(),
        |i| {
            let frame = demo.dataset.load_frame(&stems[i])?;
            let truth = demo.dataset.load_truth(&stems[i])?;
            let label = format!("{}/{}", demo.data_dir.display(), stems[i]);
            Ok((label, frame, truth))
        },
        |i, result| {
            let record = FrameDetections {
                frame: stems[i].clone(),
                pipeline: name.to_owned(),
                detections: result.detections.clone(),
                operating_confidence: result.model.operating_confidence,
                min_confidence: None,
                min_score: None,
                model_id: Some(result.model.id.clone()),
                stamp_ns: None,
                frame_id: None,
            };
            pomona_io::write_json(&det_dir.join(format!("{}.json", stems[i])), &record)?;
            Ok(())
        },
        &|| bar.inc(1),
    )
    .all_or_first_error()?;
    bar.finish_and_clear();
    stems
        .par_iter()
        .zip(&frames)
        .try_for_each(|(stem, (result, _))| -> Result<()> {
            let (image, truth) = view_of(&demo.dataset, stem)?;
            let shown: Vec<Detection> = result
                .detections
                .iter()
                .filter(|d| config.keeps(d))
                .cloned()
                .collect();
            let title = format!(
                "{stem}: {name} ({} at {})",
                shown.len(),
                config.operating_point()
            );
            write_overlay(
                &ovl_dir.join(format!("{stem}.png")),
                &image,
                &demo.camera,
                truth.as_ref(),
                &shown,
                config.min_visibility,
                &title,
            )
        })?;
    let inputs: Vec<FrameInput> = stems
        .iter()
        .zip(frames)
        .filter_map(|(stem, (result, truth))| {
            truth.map(|truth| FrameInput {
                frame: stem.clone(),
                truth,
                detections: result.detections,
            })
        })
        .collect();
    let report = evaluate(&inputs, &demo.camera, &config)?;
    if let Some(curve) = &report.pr_curve {
        let title = format!("{name} on {} demo frames", report.frames);
        let marked = config.operating_score(&inputs);
        write_pr_plot(&out.join(name).join("pr.png"), curve, &title, marked)?;
    }
    let found_by_kind = found_by_kind(&inputs, &demo.camera, &config);
    println!("\n### `{name}` (built-in model)\n");
    print!("{}", report.to_markdown());
    let by_kind: Vec<String> = found_by_kind
        .iter()
        .map(|(kind, k)| format!("{kind} {} of {}", k.found, k.fruits))
        .collect();
    if !by_kind.is_empty() {
        println!("found by kind: {}", by_kind.join(", "));
    }
    if let Some(ms) = totals.ms_per_frame() {
        println!("detection: {ms:.1} ms/frame");
    }
    Ok(DemoPipeline {
        pipeline: name.to_owned(),
        detections: totals.detections,
        detect_ms_per_frame: totals.ms_per_frame(),
        report,
        found_by_kind,
    })
}

/// Per kind of fruit in the truth, the scored fruit and those found at `config`'s operating
/// point, from the evaluation's own matching (a fruit is found when a detection kept at the
/// operating point took it).
fn found_by_kind(
    inputs: &[FrameInput],
    camera: &PinholeCamera,
    config: &EvalConfig,
) -> BTreeMap<String, KindFound> {
    let mut by_kind: BTreeMap<String, KindFound> = BTreeMap::new();
    for input in inputs {
        let matched = match_frame(&input.truth, &input.detections, camera, config);
        for (fruit, status) in input.truth.fruits.iter().zip(&matched.truth) {
            let found = match status {
                TruthStatus::Ignored => continue,
                TruthStatus::Missed => false,
                TruthStatus::Found { by } => config.keeps(&input.detections[*by]),
            };
            let entry = by_kind.entry(fruit.kind.clone()).or_insert(KindFound {
                fruits: 0,
                found: 0,
            });
            entry.fruits += 1;
            entry.found += usize::from(found);
        }
    }
    by_kind
}

/// Runs `pomona demo` with the registered pipelines.
///
/// # Errors
/// See [`run_with`].
pub fn run(args: &DemoArgs) -> Result<()> {
    run_with(&pomona::pipelines(), args).map(|_| ())
}

/// Runs `pomona demo` with `pipelines` (tests pass their own).
///
/// # Errors
/// An output folder that is neither empty nor an earlier demo, rendering or writing failures
/// (naming the file), a built-in model that does not load, detection failures.
pub fn run_with(pipelines: &[Box<dyn Pipeline>], args: &DemoArgs) -> Result<DemoReport> {
    let started = Instant::now();
    prepare_output(&args.out, pipelines)?;
    let pool = thread_pool(args.threads.map(|n| n as usize))?;
    let demo = render(args)?;
    let config = EvalConfig::default();
    let overlay_dir = args.out.join("overlay");
    pool.install(|| write_truth_overlays(&demo, &overlay_dir, &config))?;

    let mut results = Vec::new();
    let mut without = Vec::new();
    for pipeline in pipelines {
        if pipeline.default_model().is_none() {
            without.push(pipeline.name().to_owned());
            continue;
        }
        results.push(pool.install(|| run_pipeline(&demo, pipeline.as_ref(), &args.out))?);
    }

    let report = DemoReport {
        demo: "pomona-demo".into(),
        frames: args.frames,
        seed: args.seed,
        camera: CameraPreset::KinectV2.name().into(),
        noise: NoiseModel::Tof.name().into(),
        dataset: "data".into(),
        eval: config,
        pipelines: results,
        without_builtin_model: without,
    };
    pomona_io::write_json(&args.out.join("report.json"), &report)?;
    if report.pipelines.is_empty() {
        let registered = if pipelines.is_empty() {
            "no detector is registered in this build yet".to_owned()
        } else {
            format!(
                "no registered pipeline ({}) has a built-in model yet",
                pomona::pipeline_names(pipelines)
            )
        };
        println!(
            "\nNo detector model is embedded yet: {registered}. The dataset and truth overlays \
             were written; train a model with `pomona train` and run `pomona detect` on {}.",
            demo.data_dir.display()
        );
    }
    println!(
        "\nDemo written to {} in {:.1} s: overlays in {}/, report in {}",
        args.out.display(),
        started.elapsed().as_secs_f64(),
        overlay_dir.display(),
        args.out.join("report.json").display()
    );
    Ok(report)
}
