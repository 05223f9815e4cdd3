//! Feature matrices: [`Samples`] (rows of equal length, stored flat and row-major) and
//! [`TrainingSet`] (samples with a boolean label each, `true` = positive = fruit).
//!
//! Flat storage keeps kernel evaluations cache-friendly and makes batched prediction a matter of
//! splitting one slice; rows are validated once (finite, equal length) so the solver need not.

use serde::{Deserialize, Serialize};

use crate::LearnError;

/// A matrix of feature vectors, one row per sample, all values finite.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Samples {
    n_features: usize,
    values: Vec<f64>,
}

impl Samples {
    /// Wraps row-major `values` with `n_features` columns.
    ///
    /// # Errors
    /// [`LearnError::InvalidSamples`] when `n_features` is 0 or does not divide the length,
    /// [`LearnError::NonFiniteFeature`] for NaN or infinite values.
    pub fn new(n_features: usize, values: Vec<f64>) -> Result<Self, LearnError> {
        if n_features == 0 {
            return Err(LearnError::InvalidSamples(
                "zero features per sample".into(),
            ));
        }
        if values.len() % n_features != 0 {
            return Err(LearnError::InvalidSamples(format!(
                "{} values is not a multiple of {n_features} features",
                values.len()
            )));
        }
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(LearnError::NonFiniteFeature {
                row: k / n_features,
                feature: k % n_features,
                value: values[k],
            });
        }
        Ok(Self { n_features, values })
    }

    /// Builds samples from rows of equal length.
    ///
    /// # Errors
    /// As [`Samples::new`]; also [`LearnError::InvalidSamples`] for an empty list or rows of
    /// different lengths.
    pub fn from_rows<R: AsRef<[f64]>>(rows: &[R]) -> Result<Self, LearnError> {
        let Some(first) = rows.first() else {
            return Err(LearnError::InvalidSamples("no rows".into()));
        };
        let n = first.as_ref().len();
        let mut values = Vec::with_capacity(n * rows.len());
        for (i, r) in rows.iter().enumerate() {
            let r = r.as_ref();
            if r.len() != n {
                return Err(LearnError::InvalidSamples(format!(
                    "row {i} has {} features, row 0 has {n}",
                    r.len()
                )));
            }
            values.extend_from_slice(r);
        }
        Self::new(n, values)
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.values.len() / self.n_features
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Features per sample.
    pub fn n_features(&self) -> usize {
        self.n_features
    }

    /// Sample `i` (panics when out of range, like slice indexing).
    pub fn row(&self, i: usize) -> &[f64] {
        &self.values[i * self.n_features..(i + 1) * self.n_features]
    }

    /// All samples in order.
    pub fn rows(&self) -> std::slice::ChunksExact<'_, f64> {
        self.values.chunks_exact(self.n_features)
    }

    /// The flat row-major values.
    pub fn as_slice(&self) -> &[f64] {
        &self.values
    }

    /// The samples at `indices`, in that order.
    pub fn select(&self, indices: &[usize]) -> Self {
        let mut values = Vec::with_capacity(indices.len() * self.n_features);
        for &i in indices {
            values.extend_from_slice(self.row(i));
        }
        Self {
            n_features: self.n_features,
            values,
        }
    }

    pub(crate) fn from_parts_unchecked(n_features: usize, values: Vec<f64>) -> Self {
        Self { n_features, values }
    }
}

/// Samples with a binary label each: `true` = positive class (fruit), `false` = negative.
#[derive(Debug, Clone, PartialEq)]
pub struct TrainingSet {
    samples: Samples,
    labels: Vec<bool>,
}

impl TrainingSet {
    /// Pairs samples with labels.
    ///
    /// # Errors
    /// [`LearnError::LabelCount`] when the counts differ.
    pub fn new(samples: Samples, labels: Vec<bool>) -> Result<Self, LearnError> {
        if samples.len() != labels.len() {
            return Err(LearnError::LabelCount {
                samples: samples.len(),
                labels: labels.len(),
            });
        }
        Ok(Self { samples, labels })
    }

    /// Builds a training set from rows and labels.
    ///
    /// # Errors
    /// As [`Samples::from_rows`] and [`TrainingSet::new`].
    pub fn from_rows<R: AsRef<[f64]>>(rows: &[R], labels: Vec<bool>) -> Result<Self, LearnError> {
        Self::new(Samples::from_rows(rows)?, labels)
    }

    /// The feature vectors.
    pub fn samples(&self) -> &Samples {
        &self.samples
    }

    /// The labels.
    pub fn labels(&self) -> &[bool] {
        &self.labels
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.labels.is_empty()
    }

    /// `(positives, negatives)`.
    pub fn class_counts(&self) -> (usize, usize) {
        let p = self.labels.iter().filter(|&&l| l).count();
        (p, self.labels.len() - p)
    }

    /// The samples at `indices`, in that order.
    pub fn select(&self, indices: &[usize]) -> Self {
        Self {
            samples: self.samples.select(indices),
            labels: indices.iter().map(|&i| self.labels[i]).collect(),
        }
    }
}
