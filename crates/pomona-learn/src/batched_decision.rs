//! Batched RBF decision values: the scoring path detectors run on every candidate of a frame.
//!
//! [`SvmClassifier::decision_value`] sums each squared distance to a support vector in one
//! strict left-to-right chain, which the compiler cannot vectorise, and reads every support
//! vector once per sample. [`SvmClassifier::decision_values`] instead takes samples
//! [`DECISION_BLOCK`] at a time, so each support vector is read once per block, and computes the
//! squared distance with four independent partial sums. Blocks run in parallel. The value of a
//! sample does not depend on the block it falls in or on the thread count; it differs from
//! `decision_value` only by rounding (≈ 1e-15 relative).
//!
//! Measured in the `symmetry` detector (Kinect v2, 6 frames, 1201 boxes/frame, one thread): its
//! classifier stage went from 37.4 ms to 16.9 ms per frame when it adopted this scheme.
//!
//! Training and cross-validation keep the sequential sums of [`SvmClassifier::decision_function`]
//! so that model files stay bit-identical.

use rayon::prelude::*;

use crate::{LearnError, SvmClassifier};

/// Samples scored together against each support vector.
pub const DECISION_BLOCK: usize = 8;

/// `‖a − b‖²` with four independent partial sums (fixed order, so deterministic).
fn squared_distance(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            let d = x[k] - y[k];
            acc[k] += d * d;
        }
    }
    for (x, y) in ra.iter().zip(rb) {
        let d = x - y;
        acc[0] += d * d;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

impl SvmClassifier {
    /// Decision values of many raw (unscaled) samples, in order, computed in parallel blocks of
    /// [`DECISION_BLOCK`] (see the module docs); the result does not depend on the thread count.
    ///
    /// ```
    /// use pomona_learn::{SvmParams, TrainingSet};
    /// let rows: Vec<Vec<f64>> = (0..20).map(|i| vec![i as f64, 1.0]).collect();
    /// let labels: Vec<bool> = (0..20).map(|i| i >= 10).collect();
    /// let data = TrainingSet::from_rows(&rows, labels)?;
    /// let model = SvmParams::default().check()?.fit(&data)?;
    /// let probes = [[2.0, 1.0], [17.0, 1.0]];
    /// let values = model.decision_values(&probes.iter().map(|p| &p[..]).collect::<Vec<_>>())?;
    /// assert!(values[0] < 0.0 && values[1] > 0.0);
    /// # Ok::<(), pomona_learn::LearnError>(())
    /// ```
    ///
    /// # Errors
    /// [`LearnError::FeatureCount`] when a sample has the wrong number of features.
    pub fn decision_values(&self, samples: &[&[f64]]) -> Result<Vec<f64>, LearnError> {
        Ok(samples
            .par_chunks(DECISION_BLOCK)
            .map(|rows| self.block_decision_values(rows))
            .collect::<Result<Vec<_>, _>>()?
            .concat())
    }

    /// Decision values of one block of raw samples.
    fn block_decision_values(&self, rows: &[&[f64]]) -> Result<Vec<f64>, LearnError> {
        let n = self.n_features();
        let scaled: Vec<Vec<f64>> = rows
            .iter()
            .map(|x| {
                if x.len() != n {
                    return Err(LearnError::FeatureCount {
                        expected: n,
                        found: x.len(),
                    });
                }
                match &self.scaler {
                    Some(s) => {
                        let mut out = vec![0.0; n];
                        s.transform_row(x, &mut out)?;
                        Ok(out)
                    }
                    None => Ok(x.to_vec()),
                }
            })
            .collect::<Result<_, _>>()?;
        let svm = &self.svm;
        let mut sums = vec![0.0; rows.len()];
        for (sv, coef) in svm.support_vectors.chunks_exact(n).zip(&svm.coef) {
            for (sum, x) in sums.iter_mut().zip(&scaled) {
                *sum += coef * (-svm.gamma * squared_distance(sv, x)).exp();
            }
        }
        Ok(sums.into_iter().map(|s| s - svm.rho).collect())
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use crate::{LearnError, MinMaxScaler, RbfSvm, Samples, SvmClassifier};

    fn classifier(rng: &mut ChaCha8Rng, n: usize, scaled: bool) -> SvmClassifier {
        let n_sv = 37;
        let scaler = scaled.then(|| {
            let rows: Vec<f64> = (0..n * 5).map(|_| rng.gen_range(-3.0..3.0)).collect();
            MinMaxScaler::fit(&Samples::new(n, rows).unwrap())
        });
        SvmClassifier {
            scaler,
            svm: RbfSvm {
                n_features: n,
                gamma: 0.05,
                rho: 0.3,
                support_vectors: (0..n * n_sv).map(|_| rng.gen_range(-1.0..1.0)).collect(),
                coef: (0..n_sv).map(|i| if i < 20 { -0.7 } else { 0.9 }).collect(),
                n_support_negative: 20,
                n_support_positive: n_sv - 20,
                probability: None,
            },
            info: None,
        }
    }

    #[test]
    fn batched_values_match_the_single_sample_value() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for (n, scaled) in [(10, false), (168, true), (3, true)] {
            let c = classifier(&mut rng, n, scaled);
            let rows: Vec<Vec<f64>> = (0..29)
                .map(|_| (0..n).map(|_| rng.gen_range(-1.0..1.0)).collect())
                .collect();
            let refs: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
            let values = c.decision_values(&refs).unwrap();
            assert_eq!(values.len(), rows.len());
            for (row, v) in rows.iter().zip(&values) {
                let expected = c.decision_value(row).unwrap();
                assert!((v - expected).abs() <= 1e-12 * (1.0 + expected.abs()));
            }
            assert!(c.decision_values(&[]).unwrap().is_empty());
        }
    }

    #[test]
    fn wrong_length_sample_is_an_error() {
        let mut rng = ChaCha8Rng::seed_from_u64(6);
        let c = classifier(&mut rng, 4, false);
        let good = [0.0; 4];
        let bad = [0.0; 3];
        let err = c.decision_values(&[&good, &good, &bad]).unwrap_err();
        assert!(matches!(
            err,
            LearnError::FeatureCount {
                expected: 4,
                found: 3
            }
        ));
    }
}
