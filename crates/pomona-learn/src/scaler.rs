//! Per-feature min-max scaling to `[lower, upper]` (default `[-1, 1]`), as LIBSVM's `svm-scale`.
//!
//! RBF kernels compare squared distances, so a feature measured in millimetres would drown one
//! measured in radians; scaling each feature to the same range first is LIBSVM's recommended
//! practice. The ranges learnt on the training data are stored in the model file and applied
//! unchanged at prediction time (values outside the training range extrapolate linearly, as
//! `svm-scale -r` does). A feature constant in training maps to 0 (`svm-scale` drops it, which
//! in LIBSVM's sparse format means 0).

use serde::{Deserialize, Serialize};

use crate::{LearnError, Samples};

/// Learnt per-feature ranges and the target interval.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MinMaxScaler {
    /// Target lower bound.
    pub lower: f64,
    /// Target upper bound.
    pub upper: f64,
    /// Per-feature minimum seen in training.
    pub min: Vec<f64>,
    /// Per-feature maximum seen in training.
    pub max: Vec<f64>,
}

impl MinMaxScaler {
    /// Learns the ranges of `samples` for the target interval `[-1, 1]`.
    pub fn fit(samples: &Samples) -> Self {
        let n = samples.n_features();
        let mut min = vec![f64::INFINITY; n];
        let mut max = vec![f64::NEG_INFINITY; n];
        for row in samples.rows() {
            for (k, &v) in row.iter().enumerate() {
                min[k] = min[k].min(v);
                max[k] = max[k].max(v);
            }
        }
        if samples.is_empty() {
            min.fill(0.0);
            max.fill(0.0);
        }
        Self {
            lower: -1.0,
            upper: 1.0,
            min,
            max,
        }
    }

    /// Number of features the scaler was fitted on.
    pub fn n_features(&self) -> usize {
        self.min.len()
    }

    /// Scales one value of feature `k` (exactly `svm-scale`'s formula).
    fn scale_value(&self, k: usize, v: f64) -> f64 {
        let (lo, hi) = (self.min[k], self.max[k]);
        if lo == hi {
            0.0
        } else if v == lo {
            self.lower
        } else if v == hi {
            self.upper
        } else {
            self.lower + (self.upper - self.lower) * (v - lo) / (hi - lo)
        }
    }

    /// Scales one sample into `out` (same length).
    ///
    /// # Errors
    /// [`LearnError::FeatureCount`] when `row` or `out` has the wrong length.
    pub fn transform_row(&self, row: &[f64], out: &mut [f64]) -> Result<(), LearnError> {
        if row.len() != self.n_features() || out.len() != row.len() {
            return Err(LearnError::FeatureCount {
                expected: self.n_features(),
                found: row.len(),
            });
        }
        for (k, (o, &v)) in out.iter_mut().zip(row).enumerate() {
            *o = self.scale_value(k, v);
        }
        Ok(())
    }

    /// Scales all samples.
    ///
    /// # Errors
    /// [`LearnError::FeatureCount`] when the feature count differs from training.
    pub fn transform(&self, samples: &Samples) -> Result<Samples, LearnError> {
        let n = self.n_features();
        if samples.n_features() != n {
            return Err(LearnError::FeatureCount {
                expected: n,
                found: samples.n_features(),
            });
        }
        let mut values = vec![0.0; samples.as_slice().len()];
        for (row, out) in samples.rows().zip(values.chunks_exact_mut(n)) {
            self.transform_row(row, out)?;
        }
        Ok(Samples::from_parts_unchecked(n, values))
    }

    pub(crate) fn validate(&self) -> Result<(), LearnError> {
        let ok = self.min.len() == self.max.len()
            && self.lower.is_finite()
            && self.upper.is_finite()
            && self.lower < self.upper
            && self
                .min
                .iter()
                .zip(&self.max)
                .all(|(a, b)| a.is_finite() && b.is_finite() && a <= b);
        if ok {
            Ok(())
        } else {
            Err(LearnError::InconsistentModel(
                "scaler ranges must be finite with min <= max and lower < upper".into(),
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_like_svm_scale() {
        let s = Samples::from_rows(&[[0.0, 5.0, 1.0], [10.0, 5.0, 3.0], [2.5, 5.0, 2.0]]).unwrap();
        let sc = MinMaxScaler::fit(&s);
        let t = sc.transform(&s).unwrap();
        assert_eq!(t.row(0), &[-1.0, 0.0, -1.0]);
        assert_eq!(t.row(1), &[1.0, 0.0, 1.0]);
        assert_eq!(t.row(2), &[-0.5, 0.0, 0.0]);
        let mut out = [0.0; 3];
        sc.transform_row(&[20.0, 7.0, 0.0], &mut out).unwrap();
        assert_eq!(out, [3.0, 0.0, -2.0]);
        assert!(sc.transform_row(&[1.0], &mut [0.0]).is_err());
    }
}
