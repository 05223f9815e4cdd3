//! Hard-negative mining (`training.hard_negative_rounds`, default 1; bootstrapping as in
//! Dalal–Triggs and Felzenszwalb et al.).
//!
//! After the first fit, each round runs the detector's box-scoring path — same sliding box,
//! highlight pruning mask and cascade as detection, up to each box's score (the main SVM's
//! decision value plus `cascade.score_weight` × the cascade's, as detection ranks boxes),
//! *before* merging (cheaper than merging and it yields every false box, not one per cluster) —
//! on every training frame. Boxes scoring ≥ 0 whose centre is at least
//! `training.negative_min_distance_m` from every truth fruit centre (every fruit, including those
//! too occluded to be positives, so they never become negatives) are taken best first, at most
//! `training.max_hard_negatives_per_frame` per frame and round, never the same box twice; their
//! features become extra negatives, and their fixed-frame features extra negatives of the
//! cascade's SVM when the cascade is on (it computed them anyway). Then both SVMs are refitted.
//! Frames with incomplete truth (`truth.complete == false`) or with a fruit without a 3D centre
//! are not mined: an unannotated fruit would become a negative. Mining has no random choice;
//! frames are mined in parallel but collected in frame order, so the model does not depend on
//! the thread count. A round that finds nothing ends the mining. With 0 rounds training is
//! exactly the one before mining existed (same classifier, no mining keys in the model).

use nalgebra::Point3;
use pomona_learn::BatchedClassifier;
use pomona_pipeline::{FrameSource, PipelineError, Stage, TrainOptions};
use rayon::prelude::*;

use crate::cascade::{box_score, Cascade};
use crate::classify::Classify;
use crate::training::{fit_classifier, SampleSets, TrainedModels};
use crate::{BoxPatch, PruningMask, SceneCloud, Stages};

/// Runs `training.hard_negative_rounds` rounds of mining on `frames`, adding the mined boxes to
/// `samples` and refitting `models` after each round that found any.
pub(crate) fn mine_hard_negatives(
    name: &'static str,
    stages: &Stages,
    frames: &dyn FrameSource,
    options: &TrainOptions,
    samples: &mut SampleSets,
    models: &mut TrainedModels,
) -> Result<(), PipelineError> {
    let total = frames.len();
    // Centres mined so far, per frame (a box is mined at most once).
    let mut mined: Vec<Vec<Point3<f64>>> = vec![Vec::new(); total];
    for round in 1..=stages.params.training.hard_negative_rounds {
        let main = BatchedClassifier::new(models.main.clone())?;
        let cascade = models
            .cascade
            .clone()
            .map(BatchedClassifier::new)
            .transpose()?;
        let per_frame: Vec<Option<Vec<MinedBox>>> = (0..total)
            .into_par_iter()
            .map(|i| mine_frame(stages, &main, cascade.as_ref(), frames, i, &mined[i]))
            .collect::<Result<_, _>>()?;
        let skipped = per_frame.iter().filter(|f| f.is_none()).count();
        let mut added = 0;
        for (i, boxes) in per_frame.into_iter().enumerate() {
            for b in boxes.into_iter().flatten() {
                mined[i].push(b.center);
                samples.main.1.push(b.features);
                if let Some(f) = b.cascade_features {
                    samples.cascade.1.push(f);
                }
                added += 1;
            }
        }
        eprintln!(
            "{name}: hard-negative round {round}: {added} false-positive boxes added as \
             negatives ({} negatives in all; {skipped} of {total} frames not mined: incomplete \
             truth or a fruit without a 3D centre)",
            samples.main.1.len()
        );
        if added == 0 {
            break;
        }
        models.main = fit_classifier(name, &samples.main, options)?;
        if models.cascade.is_some() {
            models.cascade = Some(fit_classifier(name, &samples.cascade, options)?);
        }
    }
    Ok(())
}

/// Decision value at or above which a box counts as a (false) detection when mining: the SVM's
/// own boundary.
const HARD_NEGATIVE_MIN_SCORE: f64 = 0.0;

/// A box mined as a hard negative: centre and features (main; fixed-frame when the cascade is
/// on).
struct MinedBox {
    center: Point3<f64>,
    features: Vec<f64>,
    cascade_features: Option<Vec<f64>>,
}

/// A box scored by the detector path: centre, score, features.
struct ScoredSample {
    center: Point3<f64>,
    score: f64,
    features: Vec<f64>,
    cascade_features: Option<Vec<f64>>,
}

/// A box's fixed-frame features and cascade decision value, when the cascade ran.
type Cascaded = Option<(Vec<f64>, f64)>;

/// Every box of `cloud` that the detector would score (same sliding box, pruning mask and
/// cascade as [`BoxDetector::detect_frame`]), with its score (the main decision value plus
/// `cascade.score_weight` × the cascade's, as in detection), before merging.
fn score_boxes(
    stages: &Stages,
    classifier: &BatchedClassifier,
    cascade: Option<&BatchedClassifier>,
    cloud: &SceneCloud,
    mask: Option<&PruningMask>,
) -> Result<Vec<ScoredSample>, PipelineError> {
    let patches = stages.boxes.patches(cloud, mask);
    let (patches, cascaded): (Vec<BoxPatch>, Vec<Cascaded>) =
        match (cascade, &stages.cascade_features) {
            (Some(classifier), Some(features)) => Cascade {
                classifier,
                features,
                min_score: stages.params.cascade.min_score,
            }
            .gate(patches)?
            .into_iter()
            .map(|(p, f, score)| (p, Some((f, score))))
            .unzip(),
            _ => {
                let n = patches.len();
                (patches, vec![None; n])
            }
        };
    let frames = stages.frames.frames(&patches);
    let features = stages.features.features(&patches, &frames);
    let scores = Classify { classifier }.run(&features)?;
    let weight = stages.params.cascade.score_weight;
    Ok(patches
        .iter()
        .zip(features)
        .zip(scores)
        .zip(cascaded)
        .filter_map(|(((p, f), s), cascaded)| {
            let (cascade_features, cascade_score) = cascaded.unzip();
            Some(ScoredSample {
                center: p.center,
                score: box_score(s?, cascade_score, weight),
                features: f?,
                cascade_features,
            })
        })
        .collect())
}

/// Indices of the boxes to mine, best first: score ≥ `min_score`, centre at least
/// `min_distance_m` from every fruit centre, not mined before (`already`), at most `cap`.
/// Ties keep the box order.
fn select_hard_negatives(
    boxes: &[(Point3<f64>, f64)],
    fruit_centres: &[Point3<f64>],
    min_distance_m: f64,
    min_score: f64,
    cap: usize,
    already: &[Point3<f64>],
) -> Vec<usize> {
    let mut picked: Vec<usize> = (0..boxes.len())
        .filter(|&i| {
            let (c, score) = boxes[i];
            score >= min_score
                && fruit_centres
                    .iter()
                    .all(|f| (f - c).norm() >= min_distance_m)
                && !already.contains(&c)
        })
        .collect();
    picked.sort_by(|&a, &b| boxes[b].1.total_cmp(&boxes[a].1));
    picked.truncate(cap);
    picked
}

/// The hard negatives of training frame `index` under the current classifiers, or `None` when
/// the frame is not mined: its truth is incomplete (an unannotated fruit would become a
/// negative) or some fruit has no 3D centre (distances to it are unknown).
fn mine_frame(
    stages: &Stages,
    classifier: &BatchedClassifier,
    cascade: Option<&BatchedClassifier>,
    frames: &dyn FrameSource,
    index: usize,
    already: &[Point3<f64>],
) -> Result<Option<Vec<MinedBox>>, PipelineError> {
    let labelled = frames.load(index)?;
    let truth = &labelled.truth;
    let Some(fruit_centres) = truth
        .fruits
        .iter()
        .map(|f| f.center_m)
        .collect::<Option<Vec<Point3<f64>>>>()
        .filter(|_| truth.complete)
    else {
        return Ok(None);
    };
    let cloud = stages.normals.cloud(&labelled.frame)?;
    let highlights = stages.highlight.run(&labelled.frame)?;
    let scored = score_boxes(
        stages,
        classifier,
        cascade,
        &cloud,
        highlights.as_ref().map(|h| &h.mask),
    )?;
    let t = &stages.params.training;
    let keys: Vec<(Point3<f64>, f64)> = scored.iter().map(|s| (s.center, s.score)).collect();
    let picked = select_hard_negatives(
        &keys,
        &fruit_centres,
        t.negative_min_distance_m,
        HARD_NEGATIVE_MIN_SCORE,
        t.max_hard_negatives_per_frame,
        already,
    );
    let mut scored: Vec<Option<ScoredSample>> = scored.into_iter().map(Some).collect();
    Ok(Some(
        picked
            .into_iter()
            .filter_map(|i| scored[i].take())
            .map(|s| MinedBox {
                center: s.center,
                features: s.features,
                cascade_features: s.cascade_features,
            })
            .collect(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::StageParams;
    use pomona_pipeline::{LabelledFrame, SyntheticFrames};
    use pomona_synth::{CameraPreset, NoiseModel, SceneSpec};

    #[test]
    fn selection_keeps_far_high_scoring_new_boxes_best_first() {
        let p = |x: f64| Point3::new(x, 0.0, 1.0);
        let fruit = [p(0.0)];
        let boxes = [
            (p(0.03), 5.0), // near a fruit
            (p(0.2), 0.5),  // far
            (p(0.3), -0.1), // below the threshold
            (p(0.4), 2.0),  // far, best
            (p(0.5), 0.5),  // far, ties with 1: box order
            (p(0.6), 3.0),  // already mined
            (p(0.06), 1.0), // exactly at the distance: allowed
        ];
        let picked = select_hard_negatives(&boxes, &fruit, 0.06, 0.0, 3, &[p(0.6)]);
        assert_eq!(picked, vec![3, 6, 1]);
        let all = select_hard_negatives(&boxes, &fruit, 0.06, 0.0, 10, &[]);
        assert_eq!(all, vec![5, 3, 6, 1, 4]);
        assert!(select_hard_negatives(&boxes, &fruit, 0.06, 0.0, 0, &[]).is_empty());
    }

    /// A classifier that scores every box +1 (no support vectors, ρ = −1).
    fn accept_all(n_features: usize) -> BatchedClassifier {
        BatchedClassifier::new(pomona_learn::SvmClassifier::constant(n_features, 1.0)).unwrap()
    }

    /// With a detector that accepts every box, mining takes exactly the cap of boxes per frame,
    /// every one far from every truth fruit (occluded ones included), with cascade features; a
    /// frame with incomplete truth gives none.
    #[test]
    fn mined_boxes_are_far_from_every_fruit_and_incomplete_frames_are_skipped() {
        let spec = SceneSpec {
            camera: CameraPreset::Sr4000.camera(),
            noise: NoiseModel::Tof,
            ..SceneSpec::default()
        };
        let mut frames: Vec<LabelledFrame> = SyntheticFrames {
            spec,
            seed: 11,
            first: 0,
            count: 2,
        }
        .load_all()
        .unwrap();
        frames[1].truth.complete = false;
        let mut params = StageParams::symmetry();
        params.training.max_hard_negatives_per_frame = 15;
        let stages = Stages::new(&params).unwrap();
        let main = accept_all(stages.features.feature_len());
        let cascade = accept_all(stages.cascade_features.as_ref().unwrap().feature_len());
        let mined = mine_frame(&stages, &main, Some(&cascade), &frames, 0, &[])
            .unwrap()
            .unwrap();
        assert_eq!(mined.len(), 15);
        let truth = &frames[0].truth;
        assert!(truth.fruits.len() > 1);
        for b in &mined {
            for f in &truth.fruits {
                let d = (f.center_m.unwrap() - b.center).norm();
                assert!(d >= params.training.negative_min_distance_m, "{d}");
            }
            assert_eq!(b.features.len(), main.classifier().n_features());
            assert_eq!(
                b.cascade_features.as_ref().map(Vec::len),
                Some(cascade.classifier().n_features())
            );
        }
        // Boxes mined before are not mined again.
        let before: Vec<Point3<f64>> = mined.iter().map(|b| b.center).collect();
        let again = mine_frame(&stages, &main, Some(&cascade), &frames, 0, &before)
            .unwrap()
            .unwrap();
        assert!(again.iter().all(|b| !before.contains(&b.center)));
        assert!(mine_frame(&stages, &main, Some(&cascade), &frames, 1, &[])
            .unwrap()
            .is_none());
    }
}
