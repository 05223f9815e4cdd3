//! The `shape-fit` pipeline: training (colour model, candidates labelled against truth, GPCD,
//! cross-validated SVM) and the detector that chains the stages.

use pomona_consensus::nalgebra::{Point2, Point3};
use pomona_consensus::{Cylinder, Shape};
use pomona_core::{Detection, FrameTruth, FruitTruth, PinholeCamera, PixelBox, RgbdFrame};
use pomona_learn::{
    BatchedClassifier, GridAxis, GridSearchParams, ModelFile, Samples, SvmClassifier, SvmParams,
    TrainingSet,
};
use pomona_pipeline::{
    params_from_json, params_to_json, run_stage, Detector, DoubleCurvatureCheck, FrameSource,
    FruitCheck, LabelledFrame, Pipeline, PipelineError, StageTimings, TrainOptions,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::cell::Cell;
use std::time::{Duration, Instant};

use crate::candidate::cores_within_larger_radius;
use crate::curvature_check::rms;
use crate::negative_selection::{cap_negatives, hardest_negatives};
use crate::stages::{
    drop_pieces_of_colour_fruit, pixel_colors, usable, BackProjectionStage, ClassifierStage,
    ColorMaskStage, DepthProposalStage, DepthProposals, DescriptorStage, ProposalScreenStage,
    RegionGrowingStage, ShapeChecks, ShapeSource, ShapeStage,
};
use crate::{
    Candidate, CoaxialMergeParams, ColorBayes, ColorHistograms, ColorLut, GpcdParams, LabelRule,
    RadiusCalibration, ShapeFitParams, SizePrior, SizePriorMode,
};

/// Name of the pipeline on the command line and in model files.
pub const PIPELINE_NAME: &str = "shape-fit";

/// What the model file's `stage_params` holds for this pipeline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShapeFitStageParams {
    /// Stage parameters used in training.
    pub params: ShapeFitParams,
    /// The colour model; `None` for a depth-only model.
    pub color_model: Option<ColorBayes>,
}

/// The shape-fit method (seed 002). `params` are used for training; a loaded model carries its
/// own.
#[derive(Debug, Clone, Default)]
pub struct ShapeFitPipeline {
    /// Stage parameters for training.
    pub params: ShapeFitParams,
}

/// Counts training pixels: fruit pixels from the instance mask when present, otherwise from the
/// truth boxes; all other pixels with depth are background. Pixels in the boxes of reference
/// objects (`reference_kinds`) are neither.
fn color_histograms(
    lf: &LabelledFrame,
    bins: usize,
    reference_kinds: &[String],
) -> ColorHistograms {
    let mut h = ColorHistograms::new(bins);
    let Some(color) = lf.frame.color() else {
        return h;
    };
    let w = color.width();
    let (references, fruits): (Vec<_>, Vec<_>) = lf
        .truth
        .fruits
        .iter()
        .partition(|f| reference_kinds.contains(&f.kind));
    let boxes: Vec<PixelBox> = fruits.iter().filter_map(|f| f.bbox_px).collect();
    let reference_boxes: Vec<PixelBox> = references.iter().filter_map(|f| f.bbox_px).collect();
    for (i, rgb) in color.pixels().enumerate() {
        let (u, v) = ((i as u32) % w, (i as u32) / w);
        let p = Point2::new(u as f64, v as f64);
        if reference_boxes.iter().any(|b| b.contains(&p)) {
            continue;
        }
        let fruit = match &lf.mask {
            Some(m) => m.get(u, v).is_some_and(|id| id > 0),
            None => boxes.iter().any(|b| b.contains(&p)),
        };
        h.add(rgb, fruit);
    }
    h
}

/// Training label of a candidate: `Some(true)` positive, `Some(false)` negative, `None` left
/// out of training.
///
/// * Candidates within `positive_tolerance_m` of a reference object (`reference_kinds`) are
///   left out: round like fruit but not crop.
/// * Complete truth: the label of `params.label_rule` (see [`LabelRule`]) with
///   `params.positive_tolerance_m` — every candidate that is not a fruit is a negative.
/// * Incomplete truth (`"complete": false`): see [`incomplete_label`].
fn label(
    c: &Candidate,
    lf: &LabelledFrame,
    params: &ShapeFitParams,
    fruit_color: Option<f64>,
) -> Option<bool> {
    let center = c.shape.center();
    let camera = lf.frame.camera();
    let is_reference = |f: &&FruitTruth| params.reference_kinds.contains(&f.kind);
    if lf
        .truth
        .fruits
        .iter()
        .filter(is_reference)
        .any(|f| near(&center, f, camera, params.positive_tolerance_m))
    {
        return None;
    }
    if !lf.truth.complete {
        return incomplete_label(c, lf, params, fruit_color);
    }
    let on_one_fruit = |mask: &pomona_core::InstanceMask| {
        let ids = mask.as_slice();
        let mut counts = std::collections::HashMap::<u16, usize>::new();
        for &p in &c.pixels {
            if let Some(&id) = ids.get(p).filter(|&&id| id > 0) {
                *counts.entry(id).or_default() += 1;
            }
        }
        counts.values().any(|&n| 2 * n > c.pixels.len())
    };
    let by_centre = || is_positive(&center, &lf.truth, camera, params.positive_tolerance_m);
    match (&lf.mask, params.label_rule) {
        (Some(mask), LabelRule::MaskMajority) => Some(on_one_fruit(mask)),
        (Some(mask), LabelRule::CenterIgnoringPieces) => {
            if by_centre() {
                Some(true)
            } else if on_one_fruit(mask) {
                None
            } else {
                Some(false)
            }
        }
        _ => Some(by_centre()),
    }
}

/// Whether `center` is within `tolerance_m` of the fruit's centre or, for a fruit without a
/// centre, projects into its box.
fn near(center: &Point3<f64>, f: &FruitTruth, camera: &PinholeCamera, tolerance_m: f64) -> bool {
    match (f.center_m, f.bbox_px) {
        (Some(c), _) => (c - center).norm() <= tolerance_m,
        (None, Some(b)) => camera.project(center).is_some_and(|p| b.contains(&p)),
        (None, None) => false,
    }
}

/// An incomplete frame's truth names only some of the fruit in view, so "matches no annotated
/// fruit" does not mean "is not a fruit". The rule:
///
/// 1. positive: the centre is within `positive_tolerance_m` of an annotated fruit's 3D centre
///    (fruit without `center_m` are never matched: their box cannot say where in depth the
///    fruit is, so candidates projecting into such a box are left out);
/// 2. a *plausible fruit* ([`plausible_fruit`]: size inside the prior and, with a colour
///    model, the colour of the annotated fruit) is left out — it may well be an unannotated
///    fruit;
/// 3. any other candidate is a negative when it lies in an annotated object's neighbourhood
///    (centre within [`NEIGHBOURHOOD_TOLERANCES`] × `positive_tolerance_m` of its centre: the
///    leaves and branches the annotator saw next to the fruit), or is clearly not a fruit
///    anywhere (size outside the prior, or the colour model rejects its pixels: mean posterior
///    below the mask threshold);
/// 4. everything else is left out.
fn incomplete_label(
    c: &Candidate,
    lf: &LabelledFrame,
    params: &ShapeFitParams,
    fruit_color: Option<f64>,
) -> Option<bool> {
    let center = c.shape.center();
    let camera = lf.frame.camera();
    let crop = || {
        lf.truth
            .fruits
            .iter()
            .filter(|f| !params.reference_kinds.contains(&f.kind))
    };
    if crop().any(|f| {
        f.center_m
            .is_some_and(|t| (t - center).norm() <= params.positive_tolerance_m)
    }) {
        return Some(true);
    }
    if crop().any(|f| f.center_m.is_none() && near(&center, f, camera, 0.0)) {
        return None;
    }
    let size_ok = size_in_prior(&c.shape, params);
    let color_ok = fruit_color.is_none_or(|p| p >= PLAUSIBLE_POSTERIOR);
    if size_ok && color_ok {
        return None;
    }
    let neighbourhood = NEIGHBOURHOOD_TOLERANCES * params.positive_tolerance_m;
    let in_neighbourhood = lf
        .truth
        .fruits
        .iter()
        .filter_map(|f| f.center_m)
        .any(|t| (t - center).norm() <= neighbourhood);
    let clearly_not = !size_ok || fruit_color.is_some_and(|p| p < params.color.threshold);
    (in_neighbourhood || clearly_not).then_some(false)
}

/// An annotated object's neighbourhood in incomplete truth, in positive tolerances (2 × 50 mm:
/// an apple's own diameter and a leaf's length around its centre).
const NEIGHBOURHOOD_TOLERANCES: f64 = 2.0;

/// Mean colour posterior at which a candidate of plausible size counts as a possible fruit in
/// incomplete truth (the model finds its pixels at least as likely fruit as background).
const PLAUSIBLE_POSTERIOR: f64 = 0.5;

/// Whether the candidate's shape and radius fit the stage's size prior: a sphere (cylinder)
/// when spheres (cylinders) are fitted at all, with a radius inside their range.
fn size_in_prior(shape: &Shape, params: &ShapeFitParams) -> bool {
    use pomona_consensus::ShapeChoice;
    let inside = |r: f64, (lo, hi): (f64, f64)| r >= lo && r <= hi;
    match shape {
        Shape::Sphere(s) => {
            params.shapes.shapes != ShapeChoice::Cylinder
                && inside(s.radius_m, params.shapes.sphere.radius_range_m)
        }
        Shape::Cylinder(cy) => {
            params.shapes.shapes != ShapeChoice::Sphere
                && inside(cy.radius_m, params.shapes.cylinder.radius_range_m)
        }
    }
}

/// Mean colour posterior of the candidate's pixels, `None` without a colour model or image.
fn mean_posterior(c: &Candidate, lut: Option<&ColorLut>, frame: &RgbdFrame) -> Option<f64> {
    let (lut, color) = (lut?, frame.color()?);
    let values: Vec<f64> = pixel_colors(Some(color), &c.pixels)
        .into_iter()
        .map(|rgb| f64::from(lut.posterior(rgb)))
        .collect();
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

/// Whether a candidate centre is a fruit of the truth: within the tolerance of a truth centre,
/// or (truth without centre) projecting into its box.
fn is_positive(
    center: &Point3<f64>,
    truth: &FrameTruth,
    camera: &PinholeCamera,
    tolerance_m: f64,
) -> bool {
    truth.fruits.iter().any(|f| match (f.center_m, f.bbox_px) {
        (Some(c), _) => (c - center).norm() <= tolerance_m,
        (None, Some(b)) => camera.project(center).is_some_and(|p| b.contains(&p)),
        (None, None) => false,
    })
}

impl ShapeFitPipeline {
    /// Training pass 1: the colour model (only when frames have colour) and the size prior
    /// learnt from the truth diameters (when `size_prior` is `from-truth`).
    fn colour_and_size_prior(
        &self,
        frames: &dyn FrameSource,
        use_color: bool,
    ) -> Result<(Option<ColorBayes>, Option<SizePrior>), PipelineError> {
        let from_truth = self.params.size_prior == SizePriorMode::FromTruth;
        if !use_color && !from_truth {
            return Ok((None, None));
        }
        let refs = &self.params.reference_kinds;
        let per_frame: Result<Vec<FramePrior>, PipelineError> = (0..frames.len())
            .into_par_iter()
            .map(|i| {
                if !use_color {
                    // The size prior alone: the annotations are enough.
                    return frames.truth(i).map(|t| (None, t.fruits));
                }
                frames.load(i).map(|lf| {
                    let h = color_histograms(&lf, self.params.color.bins, refs);
                    (Some(h), lf.truth.fruits)
                })
            })
            .collect();
        let mut total = ColorHistograms::new(self.params.color.bins);
        let mut fruits = Vec::new();
        for (h, f) in per_frame? {
            if let Some(h) = h {
                total.merge(&h);
            }
            fruits.extend(f);
        }
        let color_model = if use_color {
            Some(ColorBayes::fit(&total, &self.params.color).ok_or_else(|| {
                not_enough("colour training needs fruit and background pixels".into())
            })?)
        } else {
            None
        };
        let prior = if from_truth {
            SizePrior::from_truth(&fruits, refs)
        } else {
            None
        };
        Ok((color_model, prior))
    }

    fn stages(
        &self,
        stage: &ShapeFitStageParams,
        use_color: bool,
    ) -> Result<Stages, PipelineError> {
        let p = &stage.params;
        usable(p.problem())?;
        let normals = p
            .normals
            .check()
            .map_err(|e| PipelineError::InvalidParameter {
                name: "normals".into(),
                reason: e.to_string(),
            })?;
        let proposals =
            (use_color && p.depth_proposals.enabled).then(|| DepthProposalStage::of_params(p));
        Ok(Stages {
            proposals,
            screen: None,
            mask: ColorMaskStage {
                lut: stage
                    .color_model
                    .as_ref()
                    .filter(|_| use_color)
                    .map(|m| m.compile(p.color.lut_bits)),
                threshold: p.color.threshold as f32,
                max_depth_m: p.max_depth_m as f32,
            },
            regions: RegionGrowingStage { params: p.regions },
            checks: ShapeChecks::default(),
            shapes: ShapeStage {
                normals,
                shapes: p.shapes,
                lattice: p.cluster_lattice,
            },
            descriptor: DescriptorStage {
                params: p.gpcd,
                use_color,
                normals,
            },
        })
    }
}

/// The stages before the classifier (shared by training and detection).
struct Stages {
    mask: ColorMaskStage,
    /// Depth proposals (colour models with them switched on).
    proposals: Option<DepthProposalStage>,
    /// The screen of the proposals (a loaded detector's, when switched on).
    screen: Option<ProposalScreenStage>,
    regions: RegionGrowingStage,
    shapes: ShapeStage,
    /// The checks of the shapes (a loaded detector's; training sees every shape, as in the
    /// paper).
    checks: ShapeChecks,
    descriptor: DescriptorStage,
}

impl Stages {
    /// The detector's candidates: the mask's clusters' and the depth proposals'.
    fn candidates(
        &self,
        frame: &RgbdFrame,
        t: &mut StageTimings,
    ) -> Result<CandidateSet, PipelineError> {
        self.candidates_with(&self.mask, self.proposals.as_ref(), frame, t)
    }

    /// Candidates of `mask`'s clusters, then of `proposals`' clusters when given.
    fn candidates_with(
        &self,
        mask: &ColorMaskStage,
        proposals: Option<&DepthProposalStage>,
        frame: &RgbdFrame,
        t: &mut StageTimings,
    ) -> Result<CandidateSet, PipelineError> {
        let keep = run_stage(mask, frame, t)?;
        let clusters = run_stage(&self.regions, (frame, keep.as_slice()), t)?;
        let cloud = run_stage(&BackProjectionStage, frame, t)?;
        let shapes = run_stage(&self.shapes, (frame, &cloud, clusters.as_slice()), t)?;
        let mut candidates = self
            .checks
            .admitted(ShapeSource::ColourMask, frame, shapes, t)?;
        let first_proposal = candidates.len();
        if let Some(proposals) = proposals {
            let DepthProposals { clusters, regrown } =
                run_stage(proposals, (frame, keep.as_slice()), t)?;
            for (mut clusters, is_regrown) in [(clusters, false), (regrown, true)] {
                if clusters.is_empty() {
                    continue;
                }
                if let Some(screen) = &self.screen {
                    clusters = run_stage(screen, (frame, &cloud, clusters.as_slice()), t)?;
                }
                let shapes = run_stage(&self.shapes, (frame, &cloud, clusters.as_slice()), t)?;
                let mut admitted =
                    self.checks
                        .admitted(ShapeSource::DepthProposal, frame, shapes, t)?;
                if is_regrown {
                    drop_pieces_of_colour_fruit(&candidates[..first_proposal], &mut admitted);
                }
                candidates.extend(admitted);
            }
        }
        let features = run_stage(&self.descriptor, (frame, &cloud, candidates.as_slice()), t)?;
        Ok(CandidateSet {
            candidates,
            features,
            first_proposal,
        })
    }
}

/// One frame's candidates and their descriptors; those from `first_proposal` on come from depth
/// proposals.
struct CandidateSet {
    candidates: Vec<Candidate>,
    features: Vec<Vec<f64>>,
    first_proposal: usize,
}

impl Pipeline for ShapeFitPipeline {
    fn name(&self) -> &'static str {
        PIPELINE_NAME
    }

    fn needs_color(&self) -> bool {
        false
    }

    fn train_params(&self) -> serde_json::Value {
        params_to_json(&self.params)
    }

    fn with_train_params(
        &self,
        params: serde_json::Value,
    ) -> Result<Box<dyn Pipeline>, PipelineError> {
        Ok(Box::new(Self {
            params: params_from_json(params)?,
        }))
    }

    fn default_model(&self) -> Option<&'static str> {
        Some(include_str!("../models/default.json")).filter(|s| !s.trim().is_empty())
    }

    fn default_depth_only_model(&self) -> Option<&'static str> {
        Some(include_str!("../models/default-depth.json")).filter(|s| !s.trim().is_empty())
    }

    fn train(
        &self,
        frames: &dyn FrameSource,
        options: &TrainOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<ModelFile, PipelineError> {
        if frames.is_empty() {
            return Err(not_enough("no frames with truth".into()));
        }
        usable(self.params.problem())?;
        let use_color = frames.load(0)?.frame.color().is_some();
        let (color_model, prior) = self.colour_and_size_prior(frames, use_color)?;
        let mut params = self.params.clone();
        params.shapes.seed = options.seed;
        if let Some(prior) = &prior {
            prior.apply(&mut params);
        }
        let mut stage_params = ShapeFitStageParams {
            params,
            color_model,
        };
        let stages = self.stages(&stage_params, use_color)?;
        let (values, labels, pairs) =
            labelled_candidates(frames, &stages, &stage_params.params, use_color, progress)?;
        if self.params.size_prior == SizePriorMode::FromTruth {
            stage_params.params.radius_calibration = RadiusCalibration::fit(&pairs);
        }
        fit_classifier(stage_params, values, labels, options)
    }

    fn complete_stage_params(
        &self,
        stage_params: &serde_json::Value,
    ) -> Result<serde_json::Value, PipelineError> {
        pomona_pipeline::complete_with_defaults::<ShapeFitStageParams>(stage_params)
    }

    fn load(&self, model: &ModelFile) -> Result<Box<dyn Detector>, PipelineError> {
        let stage_params: ShapeFitStageParams = serde_json::from_value(model.stage_params.clone())
            .map_err(|e| PipelineError::StageParams(e.to_string()))?;
        let use_color = stage_params.color_model.is_some();
        let mut stages = self.stages(&stage_params, use_color)?;
        let p = &stage_params.params;
        let svm = BatchedClassifier::new(model.classifier())?;
        if let (Some(min_score), Some(_)) = (p.depth_proposals.screen_min_score, &stages.proposals)
        {
            stages.screen = Some(ProposalScreenStage {
                normals: stages.shapes.normals,
                gpcd: GpcdParams {
                    max_points: p.depth_proposals.screen_points,
                    ..p.gpcd
                },
                use_color,
                svm: svm.clone(),
                min_score,
            });
        }
        stages.checks = ShapeChecks::of_params(p)?;
        Ok(Box::new(ShapeFitDetector {
            stages,
            classifier: ClassifierStage { svm },
            merge_radius_m: stage_params.params.merge_radius_m,
            coaxial_merge: stage_params.params.coaxial_merge,
            calibration: stage_params.params.radius_calibration,
            sphere_range_m: stage_params.params.shapes.sphere.radius_range_m,
            double_curvature: stage_params.params.double_curvature,
        }))
    }
}

/// The error for training data that gives nothing to learn from.
fn not_enough(reason: String) -> PipelineError {
    PipelineError::NotEnoughTrainingData {
        pipeline: PIPELINE_NAME,
        reason,
    }
}

/// Training pass 2: every frame's candidates, their descriptors and labels, and the (fitted,
/// true) radius pairs of positives. With a colour model, candidates found without the colour
/// mask are added too: the mask removes most leaves, so without them the classifier would see
/// almost no negatives (none at all for clean, red fruit) and could not learn to reject the
/// leaves that do pass the mask (green fruit among leaves).
fn labelled_candidates(
    frames: &dyn FrameSource,
    stages: &Stages,
    params: &ShapeFitParams,
    use_color: bool,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<LabelledFeatures, PipelineError> {
    let n = frames.len();
    let depth_only = ColorMaskStage {
        lut: None,
        ..stages.mask.clone()
    };
    let done = std::sync::atomic::AtomicUsize::new(0);
    let per_frame: Result<Vec<LabelledFeatures>, PipelineError> = (0..n)
        .into_par_iter()
        .map(|i| {
            let lf = frames.load(i)?;
            if use_color && lf.frame.color().is_none() {
                return Err(PipelineError::MissingColor {
                    pipeline: PIPELINE_NAME,
                });
            }
            let mut t = StageTimings::default();
            // The depth-only pass below holds every depth proposal.
            let CandidateSet {
                mut candidates,
                mut features,
                ..
            } = stages.candidates_with(&stages.mask, None, &lf.frame, &mut t)?;
            if use_color {
                let more = stages.candidates_with(&depth_only, None, &lf.frame, &mut t)?;
                candidates.extend(more.candidates);
                features.extend(more.features);
            }
            let lut = stages.mask.lut.as_ref();
            let mut pairs = Vec::new();
            let (features, labels) = candidates
                .iter()
                .zip(features)
                .filter_map(|(c, f)| {
                    let color = mean_posterior(c, lut, &lf.frame);
                    let l = label(c, &lf, params, color)?;
                    if l {
                        pairs.extend(radius_pair(c, &lf.truth, params));
                    }
                    Some((f, l))
                })
                .unzip();
            progress(
                done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1,
                n,
            );
            Ok((features, labels, pairs))
        })
        .collect();
    let (mut values, mut labels, mut pairs) = (Vec::new(), Vec::new(), Vec::new());
    for (f, l, r) in per_frame? {
        values.extend(f);
        labels.extend(l);
        pairs.extend(r);
    }
    Ok((values, labels, pairs))
}

/// Caps the negatives, grid-searches the RBF SVM on the descriptors, mines hard negatives for
/// `hard_negative_rounds` rounds (see [`crate::negative_selection`]) and packages the model.
fn fit_classifier(
    stage_params: ShapeFitStageParams,
    values: Vec<Vec<f64>>,
    labels: Vec<bool>,
    options: &TrainOptions,
) -> Result<ModelFile, PipelineError> {
    let p = &stage_params.params;
    let positives = labels.iter().filter(|&&l| l).count();
    let mut chosen = cap_negatives(&labels, p.max_negatives_per_positive, options.seed);
    let mut model = grid_search(&values, &labels, &chosen, p, options)?;
    let per_round = (p.hard_negatives_per_positive * positives as f64).ceil() as usize;
    for _ in 0..p.hard_negative_rounds {
        let rows: Vec<&[f64]> = values.iter().map(Vec::as_slice).collect();
        let scores = model.decision_values(&rows)?;
        let hard = hardest_negatives(&labels, &chosen, &scores, per_round);
        if hard.is_empty() {
            break;
        }
        chosen.extend(hard);
        chosen.sort_unstable();
        model = grid_search(&values, &labels, &chosen, p, options)?;
    }
    let stage_json = serde_json::to_value(&stage_params)
        .map_err(|e| PipelineError::StageParams(e.to_string()))?;
    Ok(ModelFile::new(PIPELINE_NAME, stage_json, &model))
}

/// The cross-validated grid search of the RBF SVM on the `chosen` candidates.
fn grid_search(
    values: &[Vec<f64>],
    labels: &[bool],
    chosen: &[usize],
    params: &ShapeFitParams,
    options: &TrainOptions,
) -> Result<SvmClassifier, PipelineError> {
    let positives = chosen.iter().filter(|&&i| labels[i]).count();
    if positives < 2 || chosen.len() - positives < 2 {
        return Err(not_enough(format!(
            "{positives} positive and {} negative candidates",
            chosen.len() - positives
        )));
    }
    let rows: Vec<f64> = chosen
        .iter()
        .flat_map(|&i| values[i].iter().copied())
        .collect();
    let chosen_labels = chosen.iter().map(|&i| labels[i]).collect();
    let data = TrainingSet::new(Samples::new(crate::GPCD_LEN, rows)?, chosen_labels)?;
    let (log2_c, log2_gamma) = if options.full_grid {
        let d = GridSearchParams::default();
        (d.log2_c, d.log2_gamma)
    } else {
        (
            GridAxis {
                start: -1.0,
                stop: 11.0,
                step: 2.0,
            },
            GridAxis {
                start: 1.0,
                stop: -9.0,
                step: 2.0,
            },
        )
    };
    let search = GridSearchParams {
        log2_c,
        log2_gamma,
        folds: options.folds,
        fine: options.full_grid,
        seed: options.seed,
        metric: params.cv_metric,
        selection: params.cv_selection,
        base: SvmParams::default()
            .class_weights(params.class_weights)
            .seed(options.seed),
    }
    .check()?
    .fit(&data)?;
    Ok(search.model)
}

/// One frame's colour counts (with colour) and annotated fruit, for the colour model and the
/// size prior.
type FramePrior = (Option<ColorHistograms>, Vec<FruitTruth>);

/// Descriptors of one frame's candidates, their training labels, and the (fitted, true) radius
/// pairs of its positive spheres.
type LabelledFeatures = (Vec<Vec<f64>>, Vec<bool>, Vec<(f64, f64)>);

/// `(fitted radius, caliper radius)` of a sphere candidate and the nearest annotated crop fruit
/// with a centre within the positive tolerance and a diameter.
fn radius_pair(c: &Candidate, truth: &FrameTruth, params: &ShapeFitParams) -> Option<(f64, f64)> {
    let Shape::Sphere(s) = &c.shape else {
        return None;
    };
    truth
        .fruits
        .iter()
        .filter(|f| !params.reference_kinds.contains(&f.kind))
        .filter_map(|f| Some(((f.center_m? - s.center).norm(), f.diameter_m?)))
        .filter(|(d, _)| *d <= params.positive_tolerance_m)
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, diameter)| (s.radius_m, diameter / 2.0))
}

/// A trained shape-fit detector.
pub struct ShapeFitDetector {
    stages: Stages,
    classifier: ClassifierStage,
    merge_radius_m: f64,
    coaxial_merge: CoaxialMergeParams,
    calibration: Option<RadiusCalibration>,
    sphere_range_m: (f64, f64),
    /// Asked of every sphere merging would keep.
    double_curvature: DoubleCurvatureCheck,
}

fn detection(c: &Candidate, shape: &Shape, score: f64, camera: &PinholeCamera) -> Detection {
    let (center_m, fruit_axis) = match shape {
        Shape::Sphere(s) => (s.center, None),
        Shape::Cylinder(cy) => (cy.midpoint(), Some(cy.axis)),
    };
    let w = camera.width as usize;
    let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
    for &i in &c.pixels {
        let (u, v) = ((i % w) as f64, (i / w) as f64);
        lo = (lo.0.min(u), lo.1.min(v));
        hi = (hi.0.max(u), hi.1.max(v));
    }
    Detection {
        center_m,
        score,
        diameter_m: Some(2.0 * shape.radius_m()),
        fruit_axis,
        symmetry_plane_normal: None,
        bbox_px: PixelBox::new(lo.0, lo.1, hi.0, hi.1).ok(),
        center_px: None,
        radius_px: None,
        kind: None,
        support_points: Some(c.points.len()),
        fit_rms_m: fit_rms_m(shape, &c.points),
        confidence: None,
    }
}

/// RMS distance of `points` from the surface of `shape`; `None` without points.
fn fit_rms_m(shape: &Shape, points: &[Point3<f64>]) -> Option<f64> {
    (!points.is_empty()).then(|| rms(points, |p| shape.signed_distance(p)))
}

/// The union of two pieces of one long fruit: cylinders whose axes agree within
/// `max_axis_angle_deg`, whose midpoints are within `max_axis_offset_radii` radii of each
/// other's axis, and whose extents along the axis overlap or leave a gap of at most
/// `max_gap_radii` radii (see [`CoaxialMergeParams`] for the defaults and where they come from).
fn coaxial_union(a: &Cylinder, b: &Cylinder, rule: &CoaxialMergeParams) -> Option<Cylinder> {
    let radius = a.radius_m.max(b.radius_m);
    let max_offset_m = rule.max_axis_offset_radii * radius;
    if a.axis.dot(&b.axis).abs() < rule.max_axis_angle_deg.to_radians().cos()
        || a.distance_to_axis(&b.midpoint()) > max_offset_m
        || b.distance_to_axis(&a.midpoint()) > max_offset_m
    {
        return None;
    }
    let ((alo, ahi), (blo, bhi)) = (a.extent_m?, b.extent_m?);
    let along_a = |t: f64| (b.axis_point + b.axis.into_inner() * t - a.axis_point).dot(&a.axis);
    let (b0, b1) = (along_a(blo), along_a(bhi));
    let (blo, bhi) = (b0.min(b1), b0.max(b1));
    let max_gap_m = rule.max_gap_radii * radius;
    if blo > ahi + max_gap_m || bhi < alo - max_gap_m {
        return None;
    }
    Some(Cylinder {
        extent_m: Some((alo.min(blo), ahi.max(bhi))),
        ..*a
    })
}

/// Two fruit cannot fill the same space. Scanning candidates by decreasing score, a candidate is
/// dropped when its core and a kept one's lie within the larger radius of each other
/// ([`cores_within_larger_radius`], the rule that also drops the regrown proposals' pieces of
/// colour fruit) or the centres are closer than `radius_m`; a cylinder that continues a kept cylinder
/// ([`coaxial_union`] under `coaxial`) extends it instead — unless its index is `first_proposal`
/// or later: a depth proposal is as often a stem or leaf in line with the fruit as a piece of
/// it, and on the synthetic eggplants such extensions moved detected centres out of tolerance
/// (AP 0.757 → 0.702 with every proposal scored far below every mask candidate). Not in the paper, which counts split
/// fruit as false positives (its Discussion); `radius_m <= 0` switches merging off. A candidate
/// that would be kept is asked `admits` first: refused, it is dropped and suppresses nothing.
/// Returns the kept indices with their (possibly extended) shapes.
fn merge_overlapping(
    candidates: &[Candidate],
    scores: &[f64],
    radius_m: f64,
    coaxial: &CoaxialMergeParams,
    first_proposal: usize,
    admits: impl Fn(&Shape) -> bool,
) -> Vec<(usize, Shape)> {
    let mut order: Vec<usize> = (0..candidates.len()).collect();
    if radius_m <= 0.0 {
        return order
            .into_iter()
            .filter(|&i| admits(&candidates[i].shape))
            .map(|i| (i, candidates[i].shape))
            .collect();
    }
    order.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]).then(a.cmp(&b)));
    let mut kept: Vec<(usize, Shape)> = Vec::with_capacity(order.len());
    'candidates: for i in order {
        let si = &candidates[i].shape;
        let ci = si.center();
        for (_, sk) in kept.iter_mut() {
            if let (Shape::Cylinder(k), Shape::Cylinder(c), true) = (&*sk, si, i < first_proposal) {
                if let Some(union) = coaxial_union(k, c, coaxial) {
                    *sk = Shape::Cylinder(union);
                    continue 'candidates;
                }
            }
            if (sk.center() - ci).norm() < radius_m || cores_within_larger_radius(sk, si) {
                continue 'candidates;
            }
        }
        if admits(si) {
            kept.push((i, *si));
        }
    }
    kept
}

impl Detector for ShapeFitDetector {
    fn pipeline(&self) -> &'static str {
        PIPELINE_NAME
    }

    fn detect(
        &self,
        frame: &RgbdFrame,
        timings: &mut StageTimings,
    ) -> Result<Vec<Detection>, PipelineError> {
        let CandidateSet {
            mut candidates,
            features,
            first_proposal,
        } = self.stages.candidates(frame, timings)?;
        let scores = run_stage(&self.classifier, features.as_slice(), timings)?;
        if let Some(cal) = &self.calibration {
            for c in &mut candidates {
                c.shape = cal.apply(&c.shape, &c.points, self.sphere_range_m);
            }
        }
        // The double-curvature check runs inside merging, on the spheres it would keep; its
        // time is reported as a stage of its own.
        let checking = Cell::new(Duration::ZERO);
        let kept = merge_overlapping(
            &candidates,
            &scores,
            self.merge_radius_m,
            &self.coaxial_merge,
            first_proposal,
            |shape| match shape {
                // Switched off, it admits every sphere: nothing to time.
                Shape::Sphere(_) if !self.double_curvature.enabled => true,
                Shape::Sphere(s) => {
                    let start = Instant::now();
                    let admitted = self.double_curvature.admits(frame, &s.center, s.radius_m);
                    checking.set(checking.get() + start.elapsed());
                    admitted
                }
                Shape::Cylinder(_) => true,
            },
        );
        if self.double_curvature.enabled {
            timings.add(DoubleCurvatureCheck::STAGE, checking.get());
        }
        Ok(kept
            .into_iter()
            .map(|(i, shape)| detection(&candidates[i], &shape, scores[i], frame.camera()))
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ball(x: f64, r: f64) -> Candidate {
        let sphere = pomona_consensus::Sphere {
            center: Point3::new(x, 0.0, 1.0),
            radius_m: r,
        };
        Candidate {
            shape: Shape::Sphere(sphere),
            pixels: vec![],
            points: vec![],
            normals: None,
        }
    }

    /// [`merge_overlapping`] with every candidate admitted.
    fn merged(
        candidates: &[Candidate],
        scores: &[f64],
        radius_m: f64,
        coaxial: &CoaxialMergeParams,
        first_proposal: usize,
    ) -> Vec<(usize, Shape)> {
        merge_overlapping(
            candidates,
            scores,
            radius_m,
            coaxial,
            first_proposal,
            |_| true,
        )
    }

    #[test]
    fn overlapping_candidates_keep_the_best() {
        // 0 and 1 overlap (1's centre is within 0's 40 mm radius); 2 is far; 3 is 20 mm from 2.
        let c = [
            ball(0.0, 0.04),
            ball(0.035, 0.02),
            ball(0.3, 0.03),
            ball(0.32, 0.005),
        ];
        let coaxial = CoaxialMergeParams::default();
        let kept: Vec<usize> = merged(&c, &[1.0, 2.0, 0.5, 0.1], 0.03, &coaxial, usize::MAX)
            .into_iter()
            .map(|k| k.0)
            .collect();
        assert_eq!(kept, vec![1, 2]);
        assert_eq!(
            merged(&c, &[1.0, 2.0, 0.5, 0.1], 0.0, &coaxial, usize::MAX).len(),
            4
        );
    }

    #[test]
    fn both_built_in_models_check_that_spheres_bend_both_ways() {
        let pipeline = ShapeFitPipeline::default();
        for json in [
            pipeline.default_model(),
            pipeline.default_depth_only_model(),
        ] {
            let model: serde_json::Value = serde_json::from_str(json.unwrap()).unwrap();
            let params: ShapeFitParams =
                serde_json::from_value(model["stage_params"]["params"].clone()).unwrap();
            assert_eq!(
                params.double_curvature,
                DoubleCurvatureCheck {
                    patch_radii: crate::BUILT_IN_DOUBLE_CURVATURE_PATCH_RADII,
                    ..DoubleCurvatureCheck::default()
                }
            );
        }
    }

    #[test]
    fn a_refused_candidate_is_dropped_and_suppresses_nothing() {
        // 1 scores best and would suppress 0, whose centre lies within its radius; refused, it
        // leaves 0 (and the far 2) kept.
        let c = [ball(0.0, 0.04), ball(0.035, 0.02), ball(0.3, 0.03)];
        let coaxial = CoaxialMergeParams::default();
        let not_1 = |s: &Shape| (s.center().x - 0.035).abs() > 1e-9;
        let kept = |radius_m: f64| -> Vec<usize> {
            merge_overlapping(&c, &[1.0, 2.0, 0.5], radius_m, &coaxial, usize::MAX, not_1)
                .into_iter()
                .map(|k| k.0)
                .collect()
        };
        assert_eq!(kept(0.03), vec![0, 2]);
        // Without merging every candidate is asked, too.
        assert_eq!(kept(0.0), vec![0, 2]);
    }

    fn piece(lo: f64, hi: f64) -> Candidate {
        let axis = pomona_consensus::nalgebra::Vector3::y_axis();
        let cyl = Cylinder {
            axis_point: Point3::new(0.0, 0.0, 1.0),
            axis,
            radius_m: 0.03,
            extent_m: Some((lo, hi)),
        };
        Candidate {
            shape: Shape::Cylinder(cyl),
            pixels: vec![],
            points: vec![],
            normals: None,
        }
    }

    #[test]
    fn pieces_of_one_long_fruit_are_joined() {
        // Two pieces of one eggplant with a 40 mm gap (a leaf), and one 200 mm further on.
        let c = [piece(0.0, 0.06), piece(0.10, 0.15), piece(0.35, 0.40)];
        let coaxial = CoaxialMergeParams::default();
        let kept = merged(&c, &[2.0, 1.0, 0.5], 0.03, &coaxial, usize::MAX);
        assert_eq!(kept.len(), 2);
        let Shape::Cylinder(joined) = &kept[0].1 else {
            panic!("not a cylinder")
        };
        assert_eq!(joined.extent_m, Some((0.0, 0.15)));
        assert!((joined.midpoint().y - 0.075).abs() < 1e-12);
        // The 40 mm gap is 1.33 radii: a stricter gap bound keeps the pieces apart.
        let strict = CoaxialMergeParams {
            max_gap_radii: 1.0,
            ..coaxial
        };
        assert_eq!(
            merged(&c, &[2.0, 1.0, 0.5], 0.03, &strict, usize::MAX).len(),
            3
        );
    }

    #[test]
    fn a_long_fruit_fills_a_capsule_not_a_padded_box() {
        // A kept eggplant along y from 0 to 0.15 m, radius 30 mm. A 20 mm ball 20 mm past its
        // end and 15 mm off its axis is a piece of it (25 mm from the axis segment); one as far
        // past the end but 25 mm off the axis (32 mm from the segment, beyond both radii) is a
        // fruit beside its rounded end, though inside its radius padded along the axis.
        let beyond_the_end = |off_axis_m: f64| Candidate {
            shape: Shape::Sphere(pomona_consensus::Sphere {
                center: Point3::new(off_axis_m, 0.17, 1.0),
                radius_m: 0.02,
            }),
            ..ball(0.0, 0.02)
        };
        let coaxial = CoaxialMergeParams::default();
        let kept = |other: Candidate| {
            merged(&[piece(0.0, 0.15), other], &[2.0, 1.0], 0.03, &coaxial, 2).len()
        };
        assert_eq!(kept(beyond_the_end(0.015)), 1);
        assert_eq!(kept(beyond_the_end(0.025)), 2);
    }

    fn frame(truth_json: &str) -> LabelledFrame {
        let cam = PinholeCamera::new(100, 100, 100.0, 100.0, 50.0, 50.0).unwrap();
        let depth = pomona_core::DepthImage::from_u16(100, 100, &[1000; 10_000], 0.001).unwrap();
        LabelledFrame {
            name: "f".into(),
            frame: RgbdFrame::new(cam, depth, None).unwrap(),
            truth: serde_json::from_str(truth_json).unwrap(),
            mask: None,
        }
    }

    fn at(x: f64, y: f64, r: f64) -> Candidate {
        let mut c = ball(x, r);
        if let Shape::Sphere(s) = &mut c.shape {
            s.center.y = y;
        }
        c
    }

    const INCOMPLETE: &str = r#"{"complete": false, "fruits": [
        {"id": "a", "kind": "apple", "diameter_m": 0.07, "center_m": [0, 0, 1]},
        {"id": "n", "kind": "apple", "diameter_m": 0.07, "center_m": null,
         "bbox_px": [70, 70, 90, 90]},
        {"id": "b", "kind": "reference_ball", "diameter_m": 0.12, "center_m": [-0.3, 0, 1]}]}"#;

    #[test]
    fn incomplete_truth_never_makes_a_plausible_fruit_a_negative() {
        let lf = frame(INCOMPLETE);
        let p = ShapeFitParams::default();
        let (red, green, unsure) = (Some(0.9), Some(0.01), Some(0.3));
        // On the annotated apple: positive.
        assert_eq!(label(&at(0.02, 0.0, 0.035), &lf, &p, red), Some(true));
        // An unannotated apple touching the annotated one (80 mm away, apple-sized, red):
        // left out, never a negative; without colour (depth-only model) likewise.
        assert_eq!(label(&at(0.08, 0.0, 0.035), &lf, &p, red), None);
        assert_eq!(label(&at(0.08, 0.0, 0.035), &lf, &p, None), None);
        // A leaf at the same place (green): a negative.
        assert_eq!(label(&at(0.08, 0.0, 0.035), &lf, &p, green), Some(false));
        // Far from any annotation: a red apple-sized candidate and an uncertain colour are left
        // out; green, or a size outside the prior, is clearly not a fruit.
        assert_eq!(label(&at(0.0, -0.4, 0.035), &lf, &p, red), None);
        assert_eq!(label(&at(0.0, -0.4, 0.035), &lf, &p, unsure), None);
        assert_eq!(label(&at(0.0, -0.4, 0.035), &lf, &p, green), Some(false));
        assert_eq!(label(&at(0.0, -0.4, 0.2), &lf, &p, red), Some(false));
        // Under a fruit without centre (`center_m: null`, box 70–90 px, i.e. x, y in 0.2–0.4 m
        // at 1 m): never matched, never a negative, even green.
        assert_eq!(label(&at(0.3, 0.3, 0.035), &lf, &p, red), None);
        assert_eq!(label(&at(0.3, 0.3, 0.035), &lf, &p, green), None);
        // On the reference ball: neither positive nor negative.
        assert_eq!(label(&at(-0.29, 0.0, 0.035), &lf, &p, green), None);
        // Complete truth keeps the old rule: everything off the fruit is a negative.
        let complete = frame(&INCOMPLETE.replace("false", "true"));
        assert_eq!(
            label(&at(0.08, 0.0, 0.035), &complete, &p, red),
            Some(false)
        );
        assert_eq!(label(&at(0.02, 0.0, 0.035), &complete, &p, red), Some(true));
    }

    #[test]
    fn pieces_of_a_fruit_are_left_out_only_by_the_piece_rule() {
        // One fruit centred at (0, 0, 1) whose mask covers the image's left half (ids 1).
        let mut lf = frame(
            r#"{"complete": true, "fruits": [
                {"id": "e", "kind": "eggplant", "diameter_m": 0.06, "center_m": [0, 0, 1]}]}"#,
        );
        let ids: Vec<u16> = (0..10_000).map(|i| u16::from(i % 100 < 50)).collect();
        lf.mask = Some(pomona_core::InstanceMask::from_ids(100, 100, ids).unwrap());
        let with_pixels = |x: f64, pixels: Vec<usize>| Candidate {
            pixels,
            ..ball(x, 0.03)
        };
        let left: Vec<usize> = (0..100).map(|r| r * 100 + 10).collect();
        let right: Vec<usize> = (0..100).map(|r| r * 100 + 90).collect();
        let centre_rule = ShapeFitParams {
            label_rule: LabelRule::CenterWithinTolerance,
            ..ShapeFitParams::default()
        };
        let piece_rule = ShapeFitParams {
            label_rule: LabelRule::CenterIgnoringPieces,
            ..ShapeFitParams::default()
        };
        // A piece: on the fruit's pixels, centre 90 mm from the fruit's.
        let piece = with_pixels(0.09, left.clone());
        assert_eq!(label(&piece, &lf, &centre_rule, None), Some(false));
        assert_eq!(label(&piece, &lf, &piece_rule, None), None);
        // Off the fruit: a negative under both; on the fruit near its centre: a positive.
        let leaf = with_pixels(0.09, right);
        assert_eq!(label(&leaf, &lf, &piece_rule, None), Some(false));
        let whole = with_pixels(0.01, left);
        assert_eq!(label(&whole, &lf, &piece_rule, None), Some(true));
        // Without a mask the piece rule is the centre rule.
        lf.mask = None;
        assert_eq!(label(&piece, &lf, &piece_rule, None), Some(false));
    }

    #[test]
    fn null_centres_and_references_do_not_enter_the_size_prior() {
        let lf = frame(INCOMPLETE);
        let p = ShapeFitParams::default();
        let prior = SizePrior::from_truth(&lf.truth.fruits, &p.reference_kinds).unwrap();
        assert_eq!(prior.fruits, 1);
        assert_eq!(prior.sphere_radius_m, Some((0.035, 0.035)));
        assert_eq!(prior.max_center_depth_m, 1.0);
        // A calibration pair only comes from a fruit with a centre and a diameter.
        assert_eq!(
            radius_pair(&at(0.01, 0.0, 0.04), &lf.truth, &p),
            Some((0.04, 0.035))
        );
        assert_eq!(radius_pair(&at(0.3, 0.3, 0.04), &lf.truth, &p), None);
        assert_eq!(radius_pair(&at(-0.3, 0.0, 0.04), &lf.truth, &p), None);
    }

    #[test]
    fn positives_by_centre_or_box() {
        let cam = PinholeCamera::new(100, 100, 100.0, 100.0, 50.0, 50.0).unwrap();
        let truth: FrameTruth = serde_json::from_str(
            r#"{"complete": true, "fruits": [{"id": "a", "kind": "x", "center_m": [0, 0, 1]},
                {"id": "b", "kind": "x", "bbox_px": [70, 70, 90, 90]}]}"#,
        )
        .unwrap();
        assert!(is_positive(
            &Point3::new(0.03, 0.0, 1.0),
            &truth,
            &cam,
            0.05
        ));
        assert!(!is_positive(
            &Point3::new(0.06, 0.0, 1.0),
            &truth,
            &cam,
            0.05
        ));
        assert!(is_positive(&Point3::new(0.3, 0.3, 1.0), &truth, &cam, 0.05));
    }
}
