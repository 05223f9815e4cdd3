//! Study: can a linear function of the cascade's fixed-frame features stand in front of the
//! cascade's RBF SVM and drop boxes it would drop anyway?
//!
//! Fits a ridge regression of the built-in cascade's decision value on its features over the
//! boxes of the FIT datasets, sets the gate threshold at the lowest linear score of any FIT box
//! whose RBF value reaches `--margin` below the cascade threshold, and reports for every TEST
//! dataset the share of boxes the gate drops and how many boxes passing the RBF cascade it would
//! have dropped.
//!
//! ```sh
//! cargo run --release -p pomona-symmetry --example cascade_gate_study -- \
//!     --fit /tmp/a --fit /tmp/b --test /tmp/c --test ../shared/data/ak-apples
//! ```
#![allow(clippy::unwrap_used, clippy::expect_used)]

use clap::Parser;
use pomona_core::nalgebra::{DMatrix, DVector, Point3};
use pomona_learn::ModelFile;
use pomona_pipeline::Pipeline;
use pomona_symmetry::{FixedFrame, ReferenceFrame, StageParams, Stages, SymmetryPipeline};

#[derive(Parser, Debug)]
struct Args {
    #[arg(long)]
    fit: Vec<String>,
    #[arg(long)]
    test: Vec<String>,
    /// Keep every FIT box whose RBF value is at least `min_score - margin`.
    #[arg(long, default_value_t = 0.25)]
    margin: f64,
    /// Ridge penalty.
    #[arg(long, default_value_t = 1e-3)]
    ridge: f64,
    /// Kernel centres of the reduced expansion (0: linear in the features).
    #[arg(long, default_value_t = 0)]
    centres: usize,
}

/// (fixed-frame features, RBF cascade value) of every box of a dataset.
fn boxes(dir: &str, stages: &Stages, rbf: &pomona_learn::SvmClassifier) -> Vec<(Vec<f64>, f64)> {
    let data = pomona_io::Dataset::open(dir).unwrap();
    let params = stages.params();
    let fs = pomona_symmetry::FeatureStage::new(
        pomona_symmetry::FrameKind::Fixed,
        stages.sliding_box().half_m(),
        params.cascade.histogram,
    );
    let mut out = Vec::new();
    for name in data.frames() {
        let frame = data.load_frame(name).unwrap();
        let cloud = stages.normal_stage().cloud(&frame).unwrap();
        let patches = stages.sliding_box().patches(&cloud, None);
        let feats: Vec<Vec<f64>> = patches
            .iter()
            .filter_map(|p| {
                FixedFrame
                    .frame(p, &Point3::origin())
                    .map(|f| fs.describe(p, &f))
            })
            .collect();
        let rows: Vec<&[f64]> = feats.iter().map(Vec::as_slice).collect();
        let values = rbf.decision_values(&rows).unwrap();
        out.extend(feats.into_iter().zip(values));
    }
    out
}

fn main() {
    let args = Args::parse();
    let text = SymmetryPipeline::default().default_model().unwrap();
    let model: ModelFile = serde_json::from_str(text).unwrap();
    let params: StageParams = serde_json::from_value(model.stage_params.clone()).unwrap();
    let stages = Stages::new(&params).unwrap();
    let rbf = params.cascade.classifier.as_ref().unwrap().classifier();
    let scaler = rbf.scaler.clone();
    let min_score = params.cascade.min_score;
    let scaled = |x: &[f64]| -> Vec<f64> {
        let mut out = vec![0.0; x.len()];
        match &scaler {
            Some(s) => s.transform_row(x, &mut out).unwrap(),
            None => out.copy_from_slice(x),
        }
        out
    };

    let fit: Vec<(Vec<f64>, f64)> = args
        .fit
        .iter()
        .flat_map(|d| boxes(d, &stages, &rbf))
        .collect();
    let gamma = rbf.svm.gamma;
    let centres: Vec<Vec<f64>> = match fit.len().checked_div(args.centres) {
        Some(step) => fit
            .iter()
            .step_by(step.max(1))
            .take(args.centres)
            .map(|(x, _)| scaled(x))
            .collect(),
        None => Vec::new(),
    };
    let design = |x: &[f64]| -> Vec<f64> {
        let z = scaled(x);
        let mut row = if centres.is_empty() {
            z
        } else {
            centres
                .iter()
                .map(|c| {
                    let d2: f64 = c.iter().zip(&z).map(|(a, b)| (a - b) * (a - b)).sum();
                    (-gamma * d2).exp()
                })
                .collect()
        };
        row.push(1.0);
        row
    };
    let n = design(&fit[0].0).len();
    let mut ata = DMatrix::<f64>::zeros(n, n);
    let mut atb = DVector::<f64>::zeros(n);
    for (x, y) in &fit {
        let r = DVector::from_vec(design(x));
        ata += &r * r.transpose();
        atb += &r * *y;
    }
    for i in 0..n - 1 {
        ata[(i, i)] += args.ridge * fit.len() as f64;
    }
    let w = ata.cholesky().unwrap().solve(&atb);
    let linear = |x: &[f64]| -> f64 { DVector::from_vec(design(x)).dot(&w) };
    let keep_floor = min_score - args.margin;
    let threshold = fit
        .iter()
        .filter(|(_, y)| *y >= keep_floor)
        .map(|(x, _)| linear(x))
        .fold(f64::INFINITY, f64::min);
    let residual: Vec<f64> = fit.iter().map(|(x, y)| (linear(x) - y).abs()).collect();
    println!(
        "fit: {} boxes, {} at RBF >= {keep_floor}; gate threshold {threshold:.3}; mean |residual| {:.3}",
        fit.len(),
        fit.iter().filter(|(_, y)| *y >= keep_floor).count(),
        residual.iter().sum::<f64>() / residual.len() as f64
    );
    for d in args.fit.iter().chain(&args.test) {
        let b = boxes(d, &stages, &rbf);
        let dropped = b.iter().filter(|(x, _)| linear(x) < threshold).count();
        let passing = b.iter().filter(|(_, y)| *y >= min_score).count();
        let lost = b
            .iter()
            .filter(|(x, y)| *y >= min_score && linear(x) < threshold)
            .count();
        println!(
            "{d}: {} boxes, gate drops {dropped} ({:.0} %), RBF passes {passing}, of which the gate drops {lost}",
            b.len(),
            100.0 * dropped as f64 / b.len().max(1) as f64
        );
    }
}
