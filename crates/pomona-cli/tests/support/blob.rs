//! `blob`: a small but real detector, used only by the CLI tests to drive `train`,
//! `detect`, `experiment` and `demo` end to end without shipping it in the binary.
//!
//! Two candidate generators (the second only when the pipeline's `needs_color` is set):
//! * depth only: local depth minima (on a pixel grid, within a window of `window_m` at their
//!   depth) grown into blobs of pixels at most `span_m` behind the minimum with smooth depth
//!   steps — weak in leafy scenes, where leaves are the nearest surfaces;
//! * colour: connected components of fruit-coloured pixels (red clearly above green) with smooth
//!   depth, which finds red and orange fruit among green leaves.
//!
//! Each blob gives a centre (blob centroid back-projected at front depth + radius), a diameter,
//! and six features — diameter, depth relief / radius, contrast with the surrounding ring (or
//! fill of its box), roundness, depth, generator — classified by an RBF SVM trained on candidates labelled
//! by distance to truth centres. Scores are SVM decision values; 3D NMS at `nms_m`.

#![allow(dead_code)]

use std::collections::VecDeque;
use std::time::Instant;

use pomona_core::nalgebra::Point3;
use pomona_core::{ColorImage, Detection, FrameTruth, PixelBox, RgbdFrame};
use pomona_learn::{ClassWeights, SvmClassifier, SvmParams, TrainingSet};
use pomona_pipeline::{
    Detector, FrameSource, ModelFile, Pipeline, PipelineError, StageTimings, TrainOptions,
};
use serde::{Deserialize, Serialize};

/// Pipeline name.
pub const NAME: &str = "blob";

/// Stage parameters stored in the model.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BlobParams {
    /// Half-width of the local-minimum window, metres at the candidate's depth.
    pub window_m: f64,
    /// Largest depth behind the minimum that still belongs to the blob.
    pub span_m: f64,
    /// Largest depth step between neighbouring blob pixels.
    pub step_m: f64,
    /// Largest blob radius, metres.
    pub max_radius_m: f64,
    /// Grid step of the minimum search, pixels.
    pub grid_px: u32,
    /// NMS distance between detection centres, metres.
    pub nms_m: f64,
    /// Distance to a truth centre under which a training candidate is positive.
    pub positive_m: f64,
    /// Add candidates from fruit-coloured blobs to those from depth minima.
    pub use_color: bool,
}

impl Default for BlobParams {
    fn default() -> Self {
        Self {
            window_m: 0.03,
            span_m: 0.05,
            step_m: 0.015,
            max_radius_m: 0.07,
            grid_px: 2,
            nms_m: 0.04,
            positive_m: 0.04,
            use_color: false,
        }
    }
}

/// The pipeline; `needs_color` (which also selects the colour candidates) and `default_model`
/// are settable so tests can exercise the colour check and the built-in-model path.
#[derive(Debug, Clone, Default)]
pub struct BlobPipeline {
    /// Whether to claim colour is needed (it is not used).
    pub needs_color: bool,
    /// Built-in model JSON.
    pub default_model: Option<&'static str>,
}

impl BlobPipeline {
    /// The colour variant: needs colour, adds colour-blob candidates.
    pub fn colour() -> Self {
        Self {
            needs_color: true,
            default_model: None,
        }
    }
}

struct Candidate {
    center: Point3<f64>,
    diameter_m: f64,
    bbox: Option<PixelBox>,
    features: [f64; 6],
}

fn candidates(frame: &RgbdFrame, p: &BlobParams) -> Vec<Candidate> {
    let mut out = depth_candidates(frame, p);
    if let Some(color) = frame.color().filter(|_| p.use_color) {
        out.extend(color_candidates(frame, color, p));
    }
    out
}

fn color_candidates(frame: &RgbdFrame, color: &ColorImage, p: &BlobParams) -> Vec<Candidate> {
    let depth = frame.depth();
    let cam = frame.camera();
    let (w, h) = (depth.width() as i64, depth.height() as i64);
    let fruity = |u: i64, v: i64| -> Option<f64> {
        let [r, g, _] = color.get(u as u32, v as u32)?;
        let z = depth.get(u as u32, v as u32)?;
        (f64::from(r) > 1.3 * f64::from(g) && r > 70).then_some(f64::from(z))
    };
    let mut label = vec![false; (w * h) as usize];
    let mut out = Vec::new();
    for v0 in 0..h {
        for u0 in 0..w {
            if label[(v0 * w + u0) as usize] {
                continue;
            }
            let Some(z_seed) = fruity(u0, v0) else {
                continue;
            };
            label[(v0 * w + u0) as usize] = true;
            let mut queue = VecDeque::from([(u0, v0, z_seed)]);
            let mut pix: Vec<(i64, i64, f64)> = Vec::new();
            while let Some((qu, qv, qz)) = queue.pop_front() {
                pix.push((qu, qv, qz));
                for (nu, nv) in [(qu + 1, qv), (qu - 1, qv), (qu, qv + 1), (qu, qv - 1)] {
                    if nu < 0 || nv < 0 || nu >= w || nv >= h || label[(nv * w + nu) as usize] {
                        continue;
                    }
                    let Some(nz) = fruity(nu, nv) else { continue };
                    if (nz - qz).abs() > p.step_m {
                        continue;
                    }
                    label[(nv * w + nu) as usize] = true;
                    queue.push_back((nu, nv, nz));
                }
            }
            if pix.len() < 15 {
                continue;
            }
            let n = pix.len() as f64;
            let mut zs: Vec<f64> = pix.iter().map(|q| q.2).collect();
            zs.sort_by(f64::total_cmp);
            let z_front = zs[zs.len() / 10];
            let z_med = zs[zs.len() / 2];
            let (umin, umax) = pix
                .iter()
                .fold((i64::MAX, i64::MIN), |a, q| (a.0.min(q.0), a.1.max(q.0)));
            let (vmin, vmax) = pix
                .iter()
                .fold((i64::MAX, i64::MIN), |a, q| (a.0.min(q.1), a.1.max(q.1)));
            let (bw, bh) = ((umax - umin + 1) as f64, (vmax - vmin + 1) as f64);
            let diameter_m = bw.max(bh) * z_front / cam.fx;
            let cu = pix.iter().map(|q| q.0 as f64).sum::<f64>() / n;
            let cv = pix.iter().map(|q| q.1 as f64).sum::<f64>() / n;
            out.push(Candidate {
                center: cam.back_project(cu, cv, z_front + 0.5 * diameter_m),
                diameter_m,
                bbox: PixelBox::new(umin as f64, vmin as f64, umax as f64, vmax as f64).ok(),
                features: [
                    diameter_m,
                    (z_med - z_front) / (0.5 * diameter_m),
                    n / (bw * bh),
                    bw.min(bh) / bw.max(bh),
                    z_front,
                    1.0,
                ],
            });
        }
    }
    out
}

fn depth_candidates(frame: &RgbdFrame, p: &BlobParams) -> Vec<Candidate> {
    let depth = frame.depth();
    let cam = frame.camera();
    let (w, h) = (depth.width() as i64, depth.height() as i64);
    let at = |u: i64, v: i64| -> Option<f64> {
        if u < 0 || v < 0 || u >= w || v >= h {
            return None;
        }
        depth.get(u as u32, v as u32).map(f64::from)
    };
    let step = i64::from(p.grid_px.max(1));
    let mut out = Vec::new();
    let mut visited = vec![u32::MAX; (w * h) as usize];
    let mut seed_id = 0u32;
    for v in (0..h).step_by(step as usize) {
        for u in (0..w).step_by(step as usize) {
            let Some(z0) = at(u, v) else { continue };
            let r = ((cam.fx * p.window_m / z0) as i64).clamp(2, 40);
            let mut is_min = true;
            'win: for dv in (-r..=r).step_by(step as usize) {
                for du in (-r..=r).step_by(step as usize) {
                    if (du, dv) == (0, 0) {
                        continue;
                    }
                    if let Some(z) = at(u + du, v + dv) {
                        let earlier = (dv, du) < (0, 0);
                        if z < z0 || (z == z0 && earlier) {
                            is_min = false;
                            break 'win;
                        }
                    }
                }
            }
            if !is_min {
                continue;
            }
            // Grow the blob.
            seed_id += 1;
            let max_r = cam.fx * p.max_radius_m / z0;
            let mut queue = VecDeque::from([(u, v, z0)]);
            visited[(v * w + u) as usize] = seed_id;
            let (mut n, mut su, mut sv, mut sz) = (0.0, 0.0, 0.0, 0.0);
            let (mut umin, mut umax, mut vmin, mut vmax) = (u, u, v, v);
            while let Some((qu, qv, qz)) = queue.pop_front() {
                n += 1.0;
                su += qu as f64;
                sv += qv as f64;
                sz += qz;
                umin = umin.min(qu);
                umax = umax.max(qu);
                vmin = vmin.min(qv);
                vmax = vmax.max(qv);
                for (nu, nv) in [(qu + 1, qv), (qu - 1, qv), (qu, qv + 1), (qu, qv - 1)] {
                    let Some(nz) = at(nu, nv) else { continue };
                    let idx = (nv * w + nu) as usize;
                    let dist = (((nu - u).pow(2) + (nv - v).pow(2)) as f64).sqrt();
                    if visited[idx] == seed_id
                        || nz > z0 + p.span_m
                        || (nz - qz).abs() > p.step_m
                        || dist > max_r
                    {
                        continue;
                    }
                    visited[idx] = seed_id;
                    queue.push_back((nu, nv, nz));
                }
            }
            if n < 12.0 {
                continue;
            }
            let (cu, cv) = (su / n, sv / n);
            let r_eq_px = (n / std::f64::consts::PI).sqrt();
            let diameter_m = 2.0 * r_eq_px * z0 / cam.fx;
            let relief = (sz / n - z0) / (0.5 * diameter_m);
            let mut ring: Vec<f64> = (0..16)
                .map(|k| {
                    let a = f64::from(k) * std::f64::consts::PI / 8.0;
                    let ru = (cu + 1.4 * r_eq_px * a.cos()).round() as i64;
                    let rv = (cv + 1.4 * r_eq_px * a.sin()).round() as i64;
                    at(ru, rv).map_or(0.3, |z| (z - z0).clamp(0.0, 0.3))
                })
                .collect();
            ring.sort_by(f64::total_cmp);
            let contrast = ring[ring.len() / 2];
            let (bw, bh) = ((umax - umin + 1) as f64, (vmax - vmin + 1) as f64);
            let roundness = bw.min(bh) / bw.max(bh);
            out.push(Candidate {
                center: cam.back_project(cu, cv, z0 + 0.5 * diameter_m),
                diameter_m,
                bbox: PixelBox::new(umin as f64, vmin as f64, umax as f64, vmax as f64).ok(),
                features: [diameter_m, relief, contrast, roundness, z0, 0.0],
            });
        }
    }
    out
}

fn label(c: &Candidate, truth: &FrameTruth, positive_m: f64) -> bool {
    truth
        .fruits
        .iter()
        .filter_map(|f| f.center_m)
        .any(|t| (t - c.center).norm() <= positive_m)
}

impl Pipeline for BlobPipeline {
    fn name(&self) -> &'static str {
        NAME
    }

    fn needs_color(&self) -> bool {
        self.needs_color
    }

    fn train(
        &self,
        frames: &dyn FrameSource,
        options: &TrainOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<ModelFile, PipelineError> {
        let params = BlobParams {
            use_color: self.needs_color,
            ..BlobParams::default()
        };
        let (mut rows, mut labels) = (Vec::new(), Vec::new());
        for i in 0..frames.len() {
            let f = frames.load(i)?;
            for c in candidates(&f.frame, &params) {
                labels.push(label(&c, &f.truth, params.positive_m));
                rows.push(c.features.to_vec());
            }
            progress(i + 1, frames.len());
        }
        let positives = labels.iter().filter(|&&l| l).count();
        if positives == 0 || positives == labels.len() {
            return Err(PipelineError::NotEnoughTrainingData {
                pipeline: NAME,
                reason: format!("{positives} positive of {} candidates", labels.len()),
            });
        }
        let data = TrainingSet::from_rows(&rows, labels)?;
        let svm = SvmParams::default()
            .c(4.0)
            .gamma(0.5)
            .class_weights(ClassWeights::Balanced)
            .seed(options.seed)
            .check()?
            .fit(&data)?;
        let stage =
            serde_json::to_value(&params).map_err(|e| PipelineError::StageParams(e.to_string()))?;
        Ok(ModelFile::new(NAME, stage, &svm))
    }

    fn default_model(&self) -> Option<&'static str> {
        self.default_model
    }

    fn load(&self, model: &ModelFile) -> Result<Box<dyn Detector>, PipelineError> {
        let params: BlobParams = serde_json::from_value(model.stage_params.clone())
            .map_err(|e| PipelineError::StageParams(e.to_string()))?;
        Ok(Box::new(BlobDetector {
            params,
            svm: model.classifier(),
            needs_color: self.needs_color,
        }))
    }
}

struct BlobDetector {
    params: BlobParams,
    svm: SvmClassifier,
    needs_color: bool,
}

impl Detector for BlobDetector {
    fn pipeline(&self) -> &'static str {
        NAME
    }

    fn detect(
        &self,
        frame: &RgbdFrame,
        timings: &mut StageTimings,
    ) -> Result<Vec<Detection>, PipelineError> {
        if self.needs_color && frame.color().is_none() {
            return Err(PipelineError::MissingColor { pipeline: NAME });
        }
        let start = Instant::now();
        let cands = candidates(frame, &self.params);
        timings.add("blob-candidates", start.elapsed());
        let start = Instant::now();
        let mut scored = Vec::with_capacity(cands.len());
        for c in cands {
            let score = self.svm.decision_value(&c.features)?;
            scored.push((score, c));
        }
        timings.add("svm", start.elapsed());
        let start = Instant::now();
        scored.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut kept: Vec<Detection> = Vec::new();
        for (score, c) in scored {
            if kept
                .iter()
                .all(|k| (k.center_m - c.center).norm() > self.params.nms_m)
            {
                kept.push(Detection {
                    diameter_m: Some(c.diameter_m),
                    bbox_px: c.bbox,
                    ..Detection::new(c.center, score)
                });
            }
        }
        timings.add("nms", start.elapsed());
        Ok(kept)
    }
}
