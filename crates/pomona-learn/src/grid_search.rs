//! Cross-validated grid search over `log2 C` × `log2 γ`, LIBSVM `grid.py` style.
//!
//! The coarse grid defaults to `grid.py`'s (`log2 C` −5..15 step 2, `log2 γ` 3..−15 step −2);
//! an optional fine pass then searches a grid of a quarter of the coarse step around the selected
//! coarse cell. Each cell is scored by stratified k-fold cross-validation (scaling is refitted on
//! every training fold so held-out data never leaks into the ranges). Cells run in parallel but
//! every cell uses the same seeded folds, so the result is the same for any thread count; ties go
//! to the smaller `C`, then the smaller `γ` (the smoother model).
//!
//! Which cell is taken is a choice ([`CellSelection`]): the best score (`grid.py`), or the
//! one-standard-error rule (Hastie, Tibshirani and Friedman, *The Elements of Statistical
//! Learning*, §7.10): the smallest `C` — the most regularised model — whose score is within one
//! standard error of the best. An RBF SVM's cross-validated score is typically flat along a
//! ridge of `C · γ`, where the best cell is chosen by noise between cells that classify the
//! training distribution equally well but extrapolate very differently: a large `C` with a small
//! `γ` is a near-linear fit with large weights, a small `C` a bounded one (docs/results.md,
//! "The grid search's choice along the ridge").

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{stratified_folds, LearnError, SvmClassifier, SvmParams, TrainingSet};

/// An arithmetic range of exponents `start, start + step, …` up to and including `stop`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GridAxis {
    /// First exponent.
    pub start: f64,
    /// Last exponent (inclusive, when reached exactly).
    pub stop: f64,
    /// Step (its sign is taken from `stop − start`).
    pub step: f64,
}

impl GridAxis {
    /// The exponents of the axis.
    pub fn values(&self) -> Vec<f64> {
        let step = self.step.abs().copysign(self.stop - self.start);
        let n = if step == 0.0 {
            0
        } else {
            ((self.stop - self.start) / step + 1e-9).floor() as usize
        };
        (0..=n).map(|i| self.start + i as f64 * step).collect()
    }
}

/// What cross-validation maximises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum CvMetric {
    /// Fraction of correctly classified held-out samples (`grid.py`'s criterion).
    Accuracy,
    /// Mean of the per-class recalls; insensitive to class imbalance.
    BalancedAccuracy,
}

/// Which cell of the grid a search takes (see the module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CellSelection {
    /// The best cross-validated score (`grid.py`'s choice).
    #[default]
    Best,
    /// The smallest `C` whose score is within one standard error of the best cell's (the best
    /// cell's binomial standard error of the metric over the held-out predictions); among those
    /// of that `C`, the best score.
    OneStandardError,
}

/// Unchecked grid-search parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GridSearchParams {
    /// `log2 C` axis of the coarse grid.
    pub log2_c: GridAxis,
    /// `log2 γ` axis of the coarse grid.
    pub log2_gamma: GridAxis,
    /// Number of cross-validation folds.
    pub folds: usize,
    /// Whether to refine around the selected coarse cell.
    pub fine: bool,
    /// Seed of the fold assignment.
    pub seed: u64,
    /// Criterion.
    pub metric: CvMetric,
    /// Which cell is taken (default: the best score).
    #[serde(default)]
    pub selection: CellSelection,
    /// Everything else (class weights, scaling, tolerance, probabilities of the final model);
    /// its `c` and `gamma` are replaced by the grid values.
    pub base: SvmParams,
}

impl Default for GridSearchParams {
    fn default() -> Self {
        Self {
            log2_c: GridAxis {
                start: -5.0,
                stop: 15.0,
                step: 2.0,
            },
            log2_gamma: GridAxis {
                start: 3.0,
                stop: -15.0,
                step: 2.0,
            },
            folds: 5,
            fine: true,
            seed: 0,
            metric: CvMetric::Accuracy,
            selection: CellSelection::Best,
            base: SvmParams::default(),
        }
    }
}

impl GridSearchParams {
    /// Validates the parameters.
    ///
    /// # Errors
    /// [`LearnError::InvalidParameter`] for fewer than 2 folds, a non-finite axis or zero step,
    /// and the errors of [`SvmParams::check`] for `base`.
    pub fn check(&self) -> Result<ValidGridSearch, LearnError> {
        if self.folds < 2 {
            return Err(LearnError::InvalidParameter {
                name: "folds",
                value: self.folds as f64,
                reason: "cross-validation needs at least 2 folds",
            });
        }
        for (name, axis) in [("log2_c", self.log2_c), ("log2_gamma", self.log2_gamma)] {
            let ok = axis.start.is_finite()
                && axis.stop.is_finite()
                && axis.step.is_finite()
                && (axis.step != 0.0 || axis.start == axis.stop);
            if !ok {
                return Err(LearnError::InvalidParameter {
                    name,
                    value: axis.step,
                    reason: "axis bounds must be finite and the step non-zero",
                });
            }
        }
        self.base.check()?;
        Ok(ValidGridSearch(self.clone()))
    }
}

/// One evaluated grid cell.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GridCell {
    /// `log2 C`.
    pub log2_c: f64,
    /// `log2 γ`.
    pub log2_gamma: f64,
    /// Cross-validated score.
    pub score: f64,
    /// Binomial standard error of `score` over the held-out predictions.
    pub standard_error: f64,
}

/// Outcome of a grid search.
#[derive(Debug, Clone)]
pub struct GridSearchResult {
    /// The cell taken ([`GridSearchParams::selection`]: the best score by default).
    pub best: GridCell,
    /// Every evaluated cell, coarse then fine, in evaluation order.
    pub cells: Vec<GridCell>,
    /// The model retrained on all data with the best parameters.
    pub model: SvmClassifier,
}

/// Validated grid-search parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidGridSearch(GridSearchParams);

impl ValidGridSearch {
    /// Runs the search and retrains on all of `data` with the best cell.
    ///
    /// # Errors
    /// [`LearnError::OneClass`] when a class has fewer samples than folds.
    pub fn fit(&self, data: &TrainingSet) -> Result<GridSearchResult, LearnError> {
        let p = &self.0;
        let (pos, neg) = data.class_counts();
        if pos < p.folds || neg < p.folds {
            return Err(LearnError::OneClass {
                positives: pos,
                negatives: neg,
            });
        }
        let folds = stratified_folds(data.labels(), p.folds, p.seed);
        let coarse: Vec<(f64, f64)> = p
            .log2_c
            .values()
            .into_iter()
            .flat_map(|c| p.log2_gamma.values().into_iter().map(move |g| (c, g)))
            .collect();
        let mut cells = self.evaluate(data, &folds, &coarse)?;
        let mut best = select_cell(&cells, p.selection);
        if p.fine {
            let step_c = p.log2_c.step.abs() / 4.0;
            let step_g = p.log2_gamma.step.abs() / 4.0;
            let mut fine = Vec::new();
            for a in -3i32..=3 {
                for b in -3i32..=3 {
                    let cell = (
                        best.log2_c + f64::from(a) * step_c,
                        best.log2_gamma + f64::from(b) * step_g,
                    );
                    if !cells.iter().any(|c| (c.log2_c, c.log2_gamma) == cell) {
                        fine.push(cell);
                    }
                }
            }
            cells.extend(self.evaluate(data, &folds, &fine)?);
            best = select_cell(&cells, p.selection);
        }
        let model = p
            .base
            .clone()
            .c(best.log2_c.exp2())
            .gamma(best.log2_gamma.exp2())
            .check()?
            .fit(data)?;
        Ok(GridSearchResult { best, cells, model })
    }

    fn evaluate(
        &self,
        data: &TrainingSet,
        folds: &[usize],
        cells: &[(f64, f64)],
    ) -> Result<Vec<GridCell>, LearnError> {
        cells
            .par_iter()
            .map(|&(log2_c, log2_gamma)| {
                let params = self
                    .0
                    .base
                    .clone()
                    .c(log2_c.exp2())
                    .gamma(log2_gamma.exp2())
                    .probability(false)
                    .check()?;
                let (score, standard_error) =
                    cross_validate(&params, data, folds, self.0.folds, self.0.metric)?;
                Ok(GridCell {
                    log2_c,
                    log2_gamma,
                    score,
                    standard_error,
                })
            })
            .collect()
    }
}

/// Cross-validated score of one parameter setting with the given fold assignment, and its
/// binomial standard error over the held-out predictions (per class for balanced accuracy).
///
/// # Errors
/// As [`crate::ValidSvmParams::fit`].
pub(crate) fn cross_validate(
    params: &crate::ValidSvmParams,
    data: &TrainingSet,
    folds: &[usize],
    k: usize,
    metric: CvMetric,
) -> Result<(f64, f64), LearnError> {
    let mut correct = [0usize; 2];
    let mut total = [0usize; 2];
    for fold in 0..k {
        let train: Vec<usize> = (0..data.len()).filter(|&i| folds[i] != fold).collect();
        let test: Vec<usize> = (0..data.len()).filter(|&i| folds[i] == fold).collect();
        if test.is_empty() {
            continue;
        }
        let model = params.fit(&data.select(&train))?;
        let held_out = data.select(&test);
        let predicted = model.predict(held_out.samples())?;
        for (&p, &l) in predicted.iter().zip(held_out.labels()) {
            total[usize::from(l)] += 1;
            correct[usize::from(l)] += usize::from(p == l);
        }
    }
    Ok(score_and_error(metric, correct, total))
}

/// The metric of `correct` of `total` held-out predictions per class (negatives, positives) and
/// its binomial standard error (per class for balanced accuracy).
fn score_and_error(metric: CvMetric, correct: [usize; 2], total: [usize; 2]) -> (f64, f64) {
    let ratio = |a: usize, b: usize| if b == 0 { 0.0 } else { a as f64 / b as f64 };
    // Variance of a proportion of `b` trials, p (1 − p) / b (0 without trials).
    let variance = |a: usize, b: usize| {
        let p = ratio(a, b);
        p * (1.0 - p) / b.max(1) as f64
    };
    match metric {
        CvMetric::Accuracy => {
            let (a, b) = (correct[0] + correct[1], total[0] + total[1]);
            (ratio(a, b), variance(a, b).sqrt())
        }
        CvMetric::BalancedAccuracy => (
            0.5 * (ratio(correct[0], total[0]) + ratio(correct[1], total[1])),
            0.5 * (variance(correct[0], total[0]) + variance(correct[1], total[1])).sqrt(),
        ),
    }
}

/// The cell `selection` takes from `cells`.
fn select_cell(cells: &[GridCell], selection: CellSelection) -> GridCell {
    let best = best_cell(cells);
    match selection {
        CellSelection::Best => best,
        CellSelection::OneStandardError => {
            let floor = best.score - best.standard_error;
            let within = || cells.iter().filter(move |c| c.score >= floor);
            let smallest_c = within().map(|c| c.log2_c).fold(f64::INFINITY, f64::min);
            let of_that_c: Vec<GridCell> = within()
                .filter(|c| c.log2_c == smallest_c)
                .copied()
                .collect();
            best_cell(&of_that_c)
        }
    }
}

fn best_cell(cells: &[GridCell]) -> GridCell {
    let mut best = cells[0];
    for &c in &cells[1..] {
        let better = c.score > best.score
            || (c.score == best.score
                && (c.log2_c < best.log2_c
                    || (c.log2_c == best.log2_c && c.log2_gamma < best.log2_gamma)));
        if better {
            best = c;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell(log2_c: f64, log2_gamma: f64, score: f64) -> GridCell {
        GridCell {
            log2_c,
            log2_gamma,
            score,
            standard_error: 0.01,
        }
    }

    #[test]
    fn one_standard_error_takes_the_smallest_c_on_a_flat_ridge() {
        // A ridge of C·γ where the best score is at the largest C by a hair.
        let cells = [
            cell(-1.0, -3.0, 0.930),
            cell(-1.0, -1.0, 0.915),
            cell(3.0, -5.0, 0.9306),
            cell(11.0, -9.0, 0.9307),
            cell(-3.0, 1.0, 0.85),
        ];
        let best = select_cell(&cells, CellSelection::Best);
        assert_eq!((best.log2_c, best.log2_gamma), (11.0, -9.0));
        let chosen = select_cell(&cells, CellSelection::OneStandardError);
        assert_eq!((chosen.log2_c, chosen.log2_gamma), (-1.0, -3.0));
        // Outside one standard error the best stands.
        let steep = [cell(-1.0, -3.0, 0.90), cell(11.0, -9.0, 0.93)];
        let chosen = select_cell(&steep, CellSelection::OneStandardError);
        assert_eq!(chosen.log2_c, 11.0);
    }

    #[test]
    fn the_standard_error_is_binomial_per_class_for_balanced_accuracy() {
        // 90 of 100 negatives and 8 of 10 positives held out correctly.
        let (score, se) = score_and_error(CvMetric::BalancedAccuracy, [90, 8], [100, 10]);
        assert!((score - 0.85).abs() < 1e-12);
        let expected = 0.5 * (0.9 * 0.1 / 100.0 + 0.8 * 0.2 / 10.0_f64).sqrt();
        assert!((se - expected).abs() < 1e-12, "{se} against {expected}");
        let (score, se) = score_and_error(CvMetric::Accuracy, [90, 8], [100, 10]);
        assert!((score - 98.0 / 110.0).abs() < 1e-12);
        assert!((se - (score * (1.0 - score) / 110.0).sqrt()).abs() < 1e-12);
        assert_eq!(
            score_and_error(CvMetric::BalancedAccuracy, [0, 0], [0, 0]),
            (0.0, 0.0)
        );
    }
}
