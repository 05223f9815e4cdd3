//! Behaviour of the RBF C-SVC on problems with known answers.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use pomona_learn::{ClassWeights, LearnError, Samples, SvmParams, TrainingSet};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn blobs(centres: &[([f64; 2], bool)], per_blob: usize, spread: f64, seed: u64) -> TrainingSet {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut rows = Vec::new();
    let mut labels = Vec::new();
    for &(c, label) in centres {
        for _ in 0..per_blob {
            rows.push([
                c[0] + spread * rng.gen_range(-1.0..1.0),
                c[1] + spread * rng.gen_range(-1.0..1.0),
            ]);
            labels.push(label);
        }
    }
    TrainingSet::from_rows(&rows, labels).unwrap()
}

fn accuracy(model: &pomona_learn::SvmClassifier, data: &TrainingSet) -> f64 {
    let p = model.predict(data.samples()).unwrap();
    p.iter().zip(data.labels()).filter(|(a, b)| a == b).count() as f64 / data.len() as f64
}

#[test]
fn separable_data_is_classified_perfectly_with_margin() {
    let data = blobs(&[([-2.0, 0.0], false), ([2.0, 0.0], true)], 30, 0.5, 1);
    let model = SvmParams::default()
        .c(10.0)
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    assert_eq!(accuracy(&model, &data), 1.0);
    assert!(model.info.as_ref().unwrap().converged);
    // Far points get confident scores of the right sign.
    assert!(model.decision_value(&[-3.0, 0.0]).unwrap() < -0.5);
    assert!(model.decision_value(&[3.0, 0.0]).unwrap() > 0.5);
    // A separable problem needs only a few support vectors.
    assert!(model.svm.n_support() < 20, "{} SVs", model.svm.n_support());
}

#[test]
fn xor_needs_the_kernel_and_gets_it() {
    let data = blobs(
        &[
            ([-1.0, -1.0], true),
            ([1.0, 1.0], true),
            ([-1.0, 1.0], false),
            ([1.0, -1.0], false),
        ],
        25,
        0.4,
        2,
    );
    let model = SvmParams::default()
        .c(10.0)
        .gamma(1.0)
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    assert_eq!(accuracy(&model, &data), 1.0);
    let test = blobs(
        &[
            ([-1.0, -1.0], true),
            ([1.0, 1.0], true),
            ([-1.0, 1.0], false),
            ([1.0, -1.0], false),
        ],
        25,
        0.4,
        3,
    );
    assert!(accuracy(&model, &test) >= 0.98);
    // A nearly linear kernel (tiny gamma) cannot solve XOR.
    let linear = SvmParams::default()
        .c(1.0)
        .gamma(1e-4)
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    assert!(accuracy(&linear, &data) < 0.8);
}

#[test]
fn class_weights_recover_the_minority_class() {
    // Overlapping classes, five negatives per positive (seed 002's ratio).
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let mut rows = Vec::new();
    let mut labels = Vec::new();
    for i in 0..300 {
        let positive = i % 6 == 0;
        let centre = if positive { 0.6 } else { -0.6 };
        rows.push([centre + rng.gen_range(-1.5..1.5), rng.gen_range(-1.0..1.0)]);
        labels.push(positive);
    }
    let data = TrainingSet::from_rows(&rows, labels).unwrap();
    let recall = |m: &pomona_learn::SvmClassifier| {
        let p = m.predict(data.samples()).unwrap();
        let (tp, pos) = p
            .iter()
            .zip(data.labels())
            .fold((0, 0), |(tp, pos), (&p, &l)| {
                (tp + usize::from(p && l), pos + usize::from(l))
            });
        tp as f64 / pos as f64
    };
    let base = SvmParams::default().c(1.0).gamma(1.0);
    let plain = base.clone().check().unwrap().fit(&data).unwrap();
    let balanced = base
        .clone()
        .class_weights(ClassWeights::Balanced)
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    let fixed = base
        .class_weights(ClassWeights::Fixed {
            positive: 5.0,
            negative: 1.0,
        })
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    assert!(
        recall(&balanced) > recall(&plain) + 0.2,
        "{} vs {}",
        recall(&balanced),
        recall(&plain)
    );
    assert!(recall(&fixed) > recall(&plain) + 0.2);
    // Balanced weights for 50 positives of 300: C+ = 300/100 = 3, C- = 300/500 = 0.6.
    assert_eq!(balanced.info.as_ref().unwrap().penalties, (3.0, 0.6));
}

#[test]
fn probabilities_are_monotone_in_the_score_and_calibrated_at_the_extremes() {
    let data = blobs(&[([-1.0, 0.0], false), ([1.0, 0.0], true)], 40, 1.2, 5);
    let model = SvmParams::default()
        .c(1.0)
        .probability(true)
        .seed(9)
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    let probe = Samples::from_rows(&[[-3.0, 0.0], [0.0, 0.0], [3.0, 0.0]]).unwrap();
    let p = model.probability(&probe).unwrap();
    assert!(
        p[0] < 0.2 && p[2] > 0.8 && p[0] < p[1] && p[1] < p[2],
        "{p:?}"
    );
    // Deterministic for a seed.
    let again = SvmParams::default()
        .c(1.0)
        .probability(true)
        .seed(9)
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    assert_eq!(again.svm.probability, model.svm.probability);
    let plain = SvmParams::default().check().unwrap().fit(&data).unwrap();
    assert!(matches!(
        plain.probability(&probe),
        Err(LearnError::NoProbability)
    ));
}

#[test]
fn platt_fit_matches_hand_checked_limits() {
    // Perfectly ordered scores: the sigmoid must rise with the score.
    let dec = [-2.0, -1.0, -0.5, 0.5, 1.0, 2.0];
    let labels = [false, false, false, true, true, true];
    let s = pomona_learn::PlattSigmoid::fit(&dec, &labels);
    assert!(s.a < 0.0);
    assert!(
        (s.probability(0.0) - 0.5).abs() < 1e-6,
        "symmetric data: P(0) = 0.5"
    );
    assert!(s.probability(-1e6) >= 0.0 && s.probability(1e6) <= 1.0);
}

#[test]
fn batched_prediction_equals_one_by_one() {
    let data = blobs(&[([-1.0, 0.0], false), ([1.0, 0.0], true)], 100, 1.0, 6);
    let model = SvmParams::default().check().unwrap().fit(&data).unwrap();
    let batch = model.decision_function(data.samples()).unwrap();
    for (i, row) in data.samples().rows().enumerate() {
        assert_eq!(batch[i], model.decision_value(row).unwrap());
    }
}

#[test]
fn bad_input_is_rejected() {
    assert!(SvmParams::default().c(0.0).check().is_err());
    assert!(SvmParams::default().gamma(f64::NAN).check().is_err());
    assert!(Samples::from_rows(&[[1.0, f64::INFINITY]]).is_err());
    assert!(Samples::from_rows(&[vec![1.0], vec![1.0, 2.0]]).is_err());
    assert!(TrainingSet::from_rows(&[[1.0]], vec![true, false]).is_err());
    let one_class = TrainingSet::from_rows(&[[1.0], [2.0]], vec![true, true]).unwrap();
    assert!(matches!(
        SvmParams::default().check().unwrap().fit(&one_class),
        Err(LearnError::OneClass { .. })
    ));
    let data = blobs(&[([-1.0, 0.0], false), ([1.0, 0.0], true)], 5, 0.5, 7);
    let model = SvmParams::default().check().unwrap().fit(&data).unwrap();
    assert!(matches!(
        model.decision_value(&[1.0]),
        Err(LearnError::FeatureCount {
            expected: 2,
            found: 1
        })
    ));
}
