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

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use pomona_core::{Detection, FrameDetections};
use pomona_eval::{evaluate, write_pr_plot, EvalConfig, EvalReport, FrameInput};
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
    let data_dir = args.out.join("data");
    let mut spec = demo_spec(args.frames, args.seed);
    spec.threads = args.threads.map(|n| n as usize);
    let pool = thread_pool(spec.threads)?;

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
    let camera = *dataset.camera();
    let stems = dataset.frames().to_vec();
    let config = EvalConfig::default();

    let overlay_dir = args.out.join("overlay");
    std::fs::create_dir_all(&overlay_dir)
        .with_context(|| format!("cannot create {}", overlay_dir.display()))?;
    let load_view = |stem: &str| view_of(&dataset, stem);
    pool.install(|| {
        stems.par_iter().try_for_each(|stem| -> Result<()> {
            let (image, truth) = load_view(stem)?;
            let n = truth.as_ref().map_or(0, |t| t.fruits.len());
            write_overlay(
                &overlay_dir.join(format!("{stem}.png")),
                &image,
                &camera,
                truth.as_ref(),
                &[],
                config.min_visibility,
                &format!("{stem}: truth ({n} fruit)"),
            )
        })
    })?;

    let mut results = Vec::new();
    let mut without = Vec::new();
    for pipeline in pipelines {
        let name = pipeline.name();
        if pipeline.default_model().is_none() {
            without.push(name.to_owned());
            continue;
        }
        let detector = load_detector(pipeline.as_ref(), None, &[])?;
        let operating_confidence = detector.operating_confidence();
        let config = EvalConfig {
            min_confidence: operating_confidence,
            ..config
        };
        let det_dir = args.out.join(name).join("detections");
        let ovl_dir = args.out.join(name).join("overlay");
        for dir in [&det_dir, &ovl_dir] {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
        }
        let bar = progress_bar(stems.len(), name);
        let (frames, totals) = pool
            .install(|| {
                detect_frames(
                    &detector,
                    stems.len(),
                    |i| {
                        let frame = dataset.load_frame(&stems[i])?;
                        let truth = dataset.load_truth(&stems[i])?;
                        Ok((format!("{}/{}", data_dir.display(), stems[i]), frame, truth))
                    },
                    |i, result| {
                        let record = FrameDetections {
                            frame: stems[i].clone(),
                            pipeline: name.to_owned(),
                            detections: result.detections.clone(),
                            operating_confidence,
                            min_confidence: None,
                            model_id: Some(result.model.id.clone()),
                        };
                        pomona_io::write_json(
                            &det_dir.join(format!("{}.json", stems[i])),
                            &record,
                        )?;
                        Ok(())
                    },
                    &|| bar.inc(1),
                )
            })
            .all_or_first_error()?;
        bar.finish_and_clear();
        pool.install(|| {
            stems
                .par_iter()
                .zip(&frames)
                .try_for_each(|(stem, (result, _))| -> Result<()> {
                    let (image, truth) = load_view(stem)?;
                    let shown: Vec<Detection> = result
                        .detections
                        .iter()
                        .filter(|d| config.keeps(d))
                        .cloned()
                        .collect();
                    write_overlay(
                        &ovl_dir.join(format!("{stem}.png")),
                        &image,
                        &camera,
                        truth.as_ref(),
                        &shown,
                        config.min_visibility,
                        &format!(
                            "{stem}: {name} ({} at {})",
                            shown.len(),
                            config.operating_point()
                        ),
                    )
                })
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
        let report = evaluate(&inputs, &camera, &config)?;
        if let Some(curve) = &report.pr_curve {
            let title = format!("{name} on {} demo frames", report.frames);
            // The curve is over scores: mark the lowest score at the operating point.
            let marked = inputs
                .iter()
                .flat_map(|f| &f.detections)
                .filter(|d| config.keeps(d))
                .map(|d| d.score)
                .reduce(f64::min)
                .unwrap_or(config.threshold);
            write_pr_plot(&args.out.join(name).join("pr.png"), curve, &title, marked)?;
        }
        println!("\n### `{name}` (built-in model)\n");
        print!("{}", report.to_markdown());
        if let Some(ms) = totals.ms_per_frame() {
            println!("detection: {ms:.1} ms/frame");
        }
        results.push(DemoPipeline {
            pipeline: name.to_owned(),
            detections: totals.detections,
            detect_ms_per_frame: totals.ms_per_frame(),
            report,
        });
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
            data_dir.display()
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
