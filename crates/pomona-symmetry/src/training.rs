//! Training of the `symmetry` and `viewer-pose` classifiers.
//!
//! Positives are boxes centred on truth fruit (plus jittered copies, since at detection time box
//! centres sit on the stride grid), negatives are random accepted boxes of the sliding box (same
//! early rejection as detection, no pruning) whose centres are far from every fruit, plus a few
//! "hard" ones just beyond that distance (overlapping a fruit off-centre). Random choices use
//! ChaCha8 seeded by the training seed and the frame index, so the training set does not depend
//! on the thread count. The RBF C-SVC is chosen by cross-validated grid search
//! (`TrainOptions::folds`; see docs/learning-and-evaluation.md for the fold count). After the
//! first fit, hard-negative mining adds false boxes and refits (see `hard_negative_mining.rs`).
//! Last, with the centre refinement on, the trained detector runs on the training frames and
//! the refinement's radius calibration is learnt from its fits that lie inside an annotated
//! fruit (see `centre_refinement.rs`).

use std::sync::atomic::{AtomicUsize, Ordering};

use nalgebra::{Point3, Vector3};
use pomona_consensus::RadiusCalibration;
use pomona_learn::{
    ClassWeights, CvMetric, GridAxis, GridSearchParams, ModelFile, SvmClassifier, SvmParams,
    TrainingSet,
};
use pomona_pipeline::{FrameSource, PipelineError, StageTimings, TrainOptions};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::hard_negative_mining::mine_hard_negatives;
use crate::{BoxDetector, CascadeClassifier, StageParams, Stages, WorkingRange};

/// Positive and negative feature vectors of one training frame, for the main classifier and
/// (empty unless the cascade is on) for the cascade's fixed-frame classifier.
struct FrameSamples {
    positives: Vec<Vec<f64>>,
    negatives: Vec<Vec<f64>>,
    cascade_positives: Vec<Vec<f64>>,
    cascade_negatives: Vec<Vec<f64>>,
}

/// Positive and negative feature vectors of one training frame.
fn frame_samples(
    stages: &Stages,
    frames: &dyn FrameSource,
    index: usize,
    seed: u64,
) -> Result<FrameSamples, PipelineError> {
    let p = stages.params();
    let labelled = frames.load(index)?;
    let cloud = stages.normals.cloud(&labelled.frame)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(index as u64);
    let stride = p.boxes.stride_m;
    let fruit_centres: Vec<Point3<f64>> = labelled
        .truth
        .fruits
        .iter()
        .filter_map(|f| f.center_m)
        .collect();
    let mut positive_centres = Vec::new();
    for fruit in &labelled.truth.fruits {
        let (Some(c), vis) = (fruit.center_m, fruit.visibility.unwrap_or(1.0)) else {
            continue;
        };
        if vis < p.training.min_visibility {
            continue;
        }
        positive_centres.push(c);
        for _ in 0..p.training.positive_jitters {
            let j = Vector3::from_fn(|_, _| rng.gen_range(-0.5..=0.5) * stride);
            positive_centres.push(c + j);
        }
    }
    let min_d = p.training.negative_min_distance_m;
    let nearest_fruit = |c: &Point3<f64>| {
        fruit_centres
            .iter()
            .map(|f| (f - c).norm())
            .fold(f64::INFINITY, f64::min)
    };
    let (mut near, mut far): (Vec<Point3<f64>>, Vec<Point3<f64>>) = (Vec::new(), Vec::new());
    for c in stages.boxes.centres(&cloud, None) {
        let d = nearest_fruit(&c);
        if d >= 2.0 * min_d {
            far.push(c);
        } else if d >= min_d {
            near.push(c);
        }
    }
    let mut candidates = pick(&mut rng, far, p.training.negatives_per_frame);
    candidates.extend(pick(&mut rng, near, p.training.hard_negatives_per_frame));
    let (positives, cascade_positives) =
        stages.describe_centres_with_cascade(&cloud, &positive_centres);
    let (negatives, cascade_negatives) = stages.describe_centres_with_cascade(&cloud, &candidates);
    Ok(FrameSamples {
        positives,
        negatives,
        cascade_positives,
        cascade_negatives,
    })
}

/// `params` with `boxes.max_range_m` widened to the annotated fruit when
/// `training.working_range` says so ([`WorkingRange::FromTruth`]).
fn with_working_range(
    params: &StageParams,
    frames: &dyn FrameSource,
) -> Result<StageParams, PipelineError> {
    let mut params = params.clone();
    if params.training.working_range == WorkingRange::FromTruth {
        let farthest_m = (0..frames.len())
            .into_par_iter()
            .map(|i| {
                Ok(frames
                    .truth(i)?
                    .fruits
                    .iter()
                    .filter_map(|f| f.center_m)
                    .map(|c| c.coords.norm())
                    .fold(0.0, f64::max))
            })
            .collect::<Result<Vec<f64>, PipelineError>>()?
            .into_iter()
            .fold(0.0, f64::max);
        let boxes = &mut params.boxes;
        boxes.max_range_m = boxes.max_range_m.max(farthest_m);
    }
    Ok(params)
}

/// A seeded random subset of `items` of size at most `n` (partial Fisher–Yates).
fn pick(rng: &mut ChaCha8Rng, mut items: Vec<Point3<f64>>, n: usize) -> Vec<Point3<f64>> {
    let want = n.min(items.len());
    for i in 0..want {
        let j = rng.gen_range(i..items.len());
        items.swap(i, j);
    }
    items.truncate(want);
    items
}

/// Trains the classifier of pipeline `name` with `params` on `frames`.
pub(crate) fn train(
    name: &'static str,
    params: &StageParams,
    frames: &dyn FrameSource,
    options: &TrainOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<ModelFile, PipelineError> {
    let params = &with_working_range(params, frames)?;
    let stages = Stages::new(params)?;
    let total = frames.len();
    let done = AtomicUsize::new(0);
    let per_frame: Vec<FrameSamples> = (0..total)
        .into_par_iter()
        .map(|i| {
            let r = frame_samples(&stages, frames, i, options.seed);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            r
        })
        .collect::<Result<_, _>>()?;
    let mut samples = SampleSets::default();
    for f in per_frame {
        samples.main.0.extend(f.positives);
        samples.main.1.extend(f.negatives);
        samples.cascade.0.extend(f.cascade_positives);
        samples.cascade.1.extend(f.cascade_negatives);
    }
    let mut models = TrainedModels {
        main: fit_classifier(name, &samples.main, options)?,
        cascade: match stages.cascade_features {
            Some(_) => Some(fit_classifier(name, &samples.cascade, options)?),
            None => None,
        },
    };
    mine_hard_negatives(name, &stages, frames, options, &mut samples, &mut models)?;
    let mut params = params.clone();
    params.refinement.radius_calibration = None;
    if params.refinement.enabled {
        params.refinement.radius_calibration =
            learn_radius_calibration(name, &params, &models, frames)?;
    }
    model_file(name, &params, &models)
}

/// The refinement's radius calibration (see `centre_refinement.rs`): the detector of `params`
/// (no calibration yet) and `models` runs on every training frame; per annotated fruit with a
/// centre and a diameter, the nearest detection with a fitted sphere whose centre lies inside
/// the fruit gives one (fitted radius, annotated radius) pair. Truth marked incomplete is fine
/// here: only fits on annotated fruit are used. `None` with fewer than
/// [`pomona_consensus::MIN_CALIBRATION_SAMPLES`] pairs.
fn learn_radius_calibration(
    name: &'static str,
    params: &StageParams,
    models: &TrainedModels,
    frames: &dyn FrameSource,
) -> Result<Option<RadiusCalibration>, PipelineError> {
    let detector = BoxDetector::from_model(name, &model_file(name, params, models)?)?;
    let per_frame: Vec<Vec<(f64, f64)>> = (0..frames.len())
        .into_par_iter()
        .map(|i| {
            let labelled = frames.load(i)?;
            let found = detector
                .detect_frame(&labelled.frame, &mut StageTimings::default())?
                .detections;
            Ok(labelled
                .truth
                .fruits
                .iter()
                .filter_map(|fruit| {
                    let (c, truth_radius_m) = (fruit.center_m?, fruit.diameter_m? / 2.0);
                    found
                        .iter()
                        .filter_map(|d| Some(((d.center_m - c).norm(), d.diameter_m? / 2.0)))
                        .filter(|&(distance_m, _)| distance_m <= truth_radius_m)
                        .min_by(|a, b| a.0.total_cmp(&b.0))
                        .map(|(_, fitted_radius_m)| (fitted_radius_m, truth_radius_m))
                })
                .collect())
        })
        .collect::<Result<_, PipelineError>>()?;
    Ok(RadiusCalibration::fit(&per_frame.concat()))
}

/// Positive and negative rows (`(positives, negatives)`) of the main classifier and of the
/// cascade's fixed-frame classifier (empty unless the cascade is on).
#[derive(Default)]
pub(crate) struct SampleSets {
    pub(crate) main: (Vec<Vec<f64>>, Vec<Vec<f64>>),
    pub(crate) cascade: (Vec<Vec<f64>>, Vec<Vec<f64>>),
}

/// The main classifier and, when the cascade is on, the cascade's.
pub(crate) struct TrainedModels {
    pub(crate) main: SvmClassifier,
    pub(crate) cascade: Option<SvmClassifier>,
}

/// The model file: `params` with the cascade's classifier, and the main classifier.
fn model_file(
    name: &'static str,
    params: &StageParams,
    models: &TrainedModels,
) -> Result<ModelFile, PipelineError> {
    let mut params = params.clone();
    if let Some(c) = &models.cascade {
        params.cascade.classifier = Some(CascadeClassifier::from_classifier(c));
    }
    let mut stage_params =
        serde_json::to_value(&params).map_err(|e| PipelineError::StageParams(e.to_string()))?;
    if params.training.hard_negative_rounds == 0 {
        // Without mining the training keys are exactly those written before mining existed (and
        // read back as `hard_negative_rounds: 0`).
        if let Some(training) = stage_params
            .get_mut("training")
            .and_then(|v| v.as_object_mut())
        {
            training.remove("hard_negative_rounds");
            training.remove("max_hard_negatives_per_frame");
        }
    }
    Ok(ModelFile::new(name, stage_params, &models.main))
}

/// RBF C-SVC on positive and negative rows, by cross-validated grid search (balanced class
/// weights, balanced accuracy).
pub(crate) fn fit_classifier(
    name: &'static str,
    (positives, negatives): &(Vec<Vec<f64>>, Vec<Vec<f64>>),
    options: &TrainOptions,
) -> Result<SvmClassifier, PipelineError> {
    let (n_pos, n_neg) = (positives.len(), negatives.len());
    if n_pos < 2 || n_neg < 2 {
        return Err(PipelineError::NotEnoughTrainingData {
            pipeline: name,
            reason: format!("{n_pos} positive and {n_neg} negative boxes (need 2 of each)"),
        });
    }
    let mut labels = vec![true; n_pos];
    labels.extend(std::iter::repeat_n(false, n_neg));
    let mut rows = positives.clone();
    rows.extend(negatives.iter().cloned());
    let data = TrainingSet::from_rows(&rows, labels)?;
    let folds = options.folds.clamp(2, n_pos.min(n_neg));
    let grid = if options.full_grid {
        GridSearchParams::default()
    } else {
        GridSearchParams {
            log2_c: GridAxis {
                start: 1.0,
                stop: 7.0,
                step: 2.0,
            },
            log2_gamma: GridAxis {
                start: -3.0,
                stop: -9.0,
                step: 2.0,
            },
            fine: false,
            ..GridSearchParams::default()
        }
    };
    let search = GridSearchParams {
        folds,
        seed: options.seed,
        metric: CvMetric::BalancedAccuracy,
        base: SvmParams::default().class_weights(ClassWeights::Balanced),
        ..grid
    }
    .check()?
    .fit(&data)?;
    Ok(search.model)
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::{DepthImage, FrameTruth, PinholeCamera, RgbdFrame};
    use pomona_pipeline::LabelledFrame;

    /// A tiny frame whose truth holds fruit centred at `centres`.
    fn frame_with_fruit(centres: &[[f64; 3]]) -> LabelledFrame {
        let camera = PinholeCamera::new(2, 2, 1.0, 1.0, 0.5, 0.5).unwrap();
        let depth = DepthImage::from_meters(2, 2, vec![1.0; 4]).unwrap();
        let fruits: Vec<serde_json::Value> = centres
            .iter()
            .enumerate()
            .map(|(i, c)| serde_json::json!({"id": i.to_string(), "kind": "apple", "center_m": c}))
            .collect();
        let truth: FrameTruth =
            serde_json::from_value(serde_json::json!({"complete": false, "fruits": fruits}))
                .unwrap();
        LabelledFrame {
            name: "t".into(),
            frame: RgbdFrame::new(camera, depth, None).unwrap(),
            truth,
            mask: None,
        }
    }

    #[test]
    fn the_working_range_reaches_the_farthest_annotated_fruit_and_never_shrinks() {
        let params = StageParams::symmetry();
        assert_eq!(params.training.working_range, WorkingRange::FromTruth);
        assert_eq!(params.boxes.max_range_m, 1.6);
        let far = vec![
            frame_with_fruit(&[[0.0, 0.0, 1.0]]),
            frame_with_fruit(&[[0.6, 0.0, 1.8], [0.0, 0.0, 0.5]]),
        ];
        let widened = with_working_range(&params, &far).unwrap();
        assert!((widened.boxes.max_range_m - (0.36f64 + 1.8 * 1.8).sqrt()).abs() < 1e-12);
        let near = vec![frame_with_fruit(&[[0.0, 0.0, 0.9]])];
        assert_eq!(with_working_range(&params, &near).unwrap(), params);
        let mut fixed = params.clone();
        fixed.training.working_range = WorkingRange::Fixed;
        assert_eq!(with_working_range(&fixed, &far).unwrap(), fixed);
    }

    #[test]
    fn zero_rounds_leave_no_mining_keys_and_read_back_as_zero() {
        let mut p = StageParams::viewer_pose();
        assert_eq!(p.training.hard_negative_rounds, 1);
        p.training.hard_negative_rounds = 0;
        let mut json = serde_json::to_value(&p).unwrap();
        let t = json["training"].as_object_mut().unwrap();
        t.remove("hard_negative_rounds");
        t.remove("max_hard_negatives_per_frame");
        let back: StageParams = serde_json::from_value(json).unwrap();
        assert_eq!(back, p);
    }
}
