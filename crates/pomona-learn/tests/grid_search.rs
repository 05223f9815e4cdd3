//! Cross-validated grid search: picks the known-best cell and is deterministic.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use pomona_learn::{CellSelection, CvMetric, GridAxis, GridSearchParams, SvmParams, TrainingSet};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// XOR of four tight blobs: a near-linear kernel (γ = 2⁻¹⁵) cannot separate it, a very narrow
/// kernel (γ = 2¹⁵, with features scaled to [-1, 1]) memorises the training folds and answers the
/// majority class on held-out points, γ = 2⁰ separates it perfectly.
fn xor(seed: u64) -> TrainingSet {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut rows = Vec::new();
    let mut labels = Vec::new();
    for (cx, cy) in [(-1.0, -1.0), (1.0, 1.0), (-1.0, 1.0), (1.0, -1.0)] {
        for _ in 0..15 {
            rows.push([cx + rng.gen_range(-0.3..0.3), cy + rng.gen_range(-0.3..0.3)]);
            labels.push(cx * cy > 0.0);
        }
    }
    TrainingSet::from_rows(&rows, labels).unwrap()
}

fn params() -> GridSearchParams {
    GridSearchParams {
        log2_c: GridAxis {
            start: 3.0,
            stop: 3.0,
            step: 1.0,
        },
        log2_gamma: GridAxis {
            start: -15.0,
            stop: 15.0,
            step: 15.0,
        },
        folds: 5,
        fine: false,
        seed: 11,
        metric: CvMetric::Accuracy,
        selection: CellSelection::Best,
        base: SvmParams::default(),
    }
}

#[test]
fn picks_the_known_best_gamma() {
    let result = params().check().unwrap().fit(&xor(1)).unwrap();
    assert_eq!(result.cells.len(), 3);
    assert_eq!((result.best.log2_c, result.best.log2_gamma), (3.0, 0.0));
    assert_eq!(result.best.score, 1.0);
    let by_gamma = |g: f64| {
        result
            .cells
            .iter()
            .find(|c| c.log2_gamma == g)
            .unwrap()
            .score
    };
    assert!(
        by_gamma(-15.0) < 0.8 && by_gamma(15.0) < 0.8,
        "{:?}",
        result.cells
    );
    // The returned model is retrained with the best cell.
    assert_eq!(result.model.svm.gamma, 1.0);
}

#[test]
fn default_axes_are_libsvm_grid_defaults() {
    let p = GridSearchParams::default();
    let c = p.log2_c.values();
    let g = p.log2_gamma.values();
    assert_eq!(c.first(), Some(&-5.0));
    assert_eq!(c.last(), Some(&15.0));
    assert_eq!(c.len(), 11);
    assert_eq!(g.first(), Some(&3.0));
    assert_eq!(g.last(), Some(&-15.0));
    assert_eq!(g.len(), 10);
}

#[test]
fn fine_pass_refines_around_the_best_cell_and_is_deterministic() {
    let mut p = params();
    p.fine = true;
    p.metric = CvMetric::BalancedAccuracy;
    let a = p.check().unwrap().fit(&xor(2)).unwrap();
    let b = p.check().unwrap().fit(&xor(2)).unwrap();
    assert_eq!(a.cells, b.cells);
    assert_eq!(a.best, b.best);
    // 3 coarse cells + a 7×7 fine grid (step 15/4) around the best, minus the centre.
    assert_eq!(a.cells.len(), 3 + 48);
    assert!((a.best.log2_gamma).abs() <= 3.0 * 15.0 / 4.0);
    assert_eq!(a.best.score, 1.0);
}

#[test]
fn too_few_samples_per_fold_is_an_error() {
    let data = TrainingSet::from_rows(
        &[[0.0], [1.0], [2.0], [3.0]],
        vec![true, false, true, false],
    )
    .unwrap();
    assert!(params().check().unwrap().fit(&data).is_err());
    let mut p = params();
    p.folds = 1;
    assert!(p.check().is_err());
}
