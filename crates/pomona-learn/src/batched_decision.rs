//! Batched RBF decision values: the scoring path detectors run on every candidate of a frame.
//!
//! [`SvmClassifier::decision_value`] sums each squared distance to a support vector in one
//! strict left-to-right chain and reads every support vector once per sample.
//! [`SvmClassifier::decision_values`] instead scores samples [`DECISION_BLOCK`] at a time with
//! one matrix product per block: `‖x − s‖² = ‖x‖² + ‖s‖² − 2 x·s`, where the dot products of
//! every sample of the block with every support vector are one `nalgebra` GEMM (the
//! `matrixmultiply` kernels, which pick the CPU's SIMD width at run time). Blocks run in
//! parallel, each padded to the full block so that every product has the same shape: a sample's
//! value depends neither on the thread count nor on the other samples scored with it.
//!
//! The arithmetic is single precision where rounding cannot matter, which doubles the SIMD lanes
//! and halves the memory: the GEMM runs in `f32` on samples and support vectors both centred on
//! the support vectors' mean (distances do not change, and the dot products, hence their
//! rounding, shrink), and the kernel terms `yᵢαᵢ exp(−γ d²)` are taken eight support vectors at
//! a time with `wide::f32x8` (its `exp`: a degree-7 polynomial after range reduction, 0 below
//! e^−87), then summed in double precision. Norms and the centring stay in double precision.
//! A value differs from the sequential double-precision [`SvmClassifier::decision_value`] by up
//! to about 2e-8 of the coefficients' total weight `Σ|yᵢαᵢ|` (unit test: 1.9e-8 seen, asserted
//! below 1e-7); on the
//! built-in models' 24 held-out wide sets (`scripts/wide_builtin_eval.sh`, three pipelines)
//! scores moved by at most 1.7e-4 (shape-fit; 4e-5 symmetry, 1.4e-5 viewer-pose), and every AP,
//! precision and recall figure stayed the same to the printed three decimals but one: in one
//! viewer-pose frame a box crossed the merging threshold (88 → 87 detections, one centre 14 mm
//! away), and that set's all-point AP went 0.568 → 0.569. It may differ in the last bits between CPUs with and without FMA.
//!
//! Measured on 10 wide Kinect v2 frames (one thread, 3 December), per frame: the `symmetry`
//! cascade stage 58.4 ms (double precision, scalar `exp`) → 48.6 (vector `exp` in double) →
//! 37.3 (single-precision GEMM) → 24.6 ms (single-precision kernel terms); viewer-pose's
//! `classifier` 15.4 → 11.9 → 9.6 → 5.9 ms.
//!
//! Earlier, in the `symmetry` detector: its classifier stage went from 37.4 ms to 16.9 ms per
//! Kinect v2 frame (6 frames, 1201 boxes/frame, one thread) when it adopted blocks of 8 samples
//! with four partial sums per distance, and its cascade stage from 57.4 to 21.2 ms per frame (10
//! wide pepper frames, 2013 support vectors) with the matrix product; the criterion bench
//! `svm/decision_values_500x168_2288sv_1_thread` from 41.0 to 12.7 ms.
//!
//! Training and cross-validation keep the sequential sums of [`SvmClassifier::decision_function`]
//! so that model files stay bit-identical.

use nalgebra::DMatrix;
use rayon::prelude::*;
use wide::f32x8;

use crate::{LearnError, SvmClassifier};

/// Samples scored together by one matrix product against every support vector.
pub const DECISION_BLOCK: usize = 64;

/// Support vectors whose kernel values are computed together (`wide::f32x8`).
const LANES: usize = 8;

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
    /// [`LearnError::FeatureCount`] when a sample has the wrong number of features,
    /// [`LearnError::InconsistentModel`] when the support vectors do not match the coefficients.
    pub fn decision_values(&self, samples: &[&[f64]]) -> Result<Vec<f64>, LearnError> {
        if samples.is_empty() {
            return Ok(Vec::new());
        }
        self.decision_values_with(&SupportMatrix::of(self)?, samples)
    }

    /// [`SvmClassifier::decision_values`] with the support vectors already laid out.
    fn decision_values_with(
        &self,
        support: &SupportMatrix,
        samples: &[&[f64]],
    ) -> Result<Vec<f64>, LearnError> {
        Ok(samples
            .par_chunks(DECISION_BLOCK)
            .map(|rows| self.block_decision_values(support, rows))
            .collect::<Result<Vec<_>, _>>()?
            .concat())
    }

    /// Decision values of one block of raw samples.
    fn block_decision_values(
        &self,
        support: &SupportMatrix,
        rows: &[&[f64]],
    ) -> Result<Vec<f64>, LearnError> {
        let n = self.n_features();
        // Scaled samples, one per column (column-major: each sample contiguous). Always
        // DECISION_BLOCK columns, zero-padded, so every product has one shape and takes one
        // kernel path: a sample's value does not depend on how many others share its block.
        let mut scaled = DMatrix::<f64>::zeros(n, DECISION_BLOCK);
        for (x, mut column) in rows.iter().zip(scaled.column_iter_mut()) {
            if x.len() != n {
                return Err(LearnError::FeatureCount {
                    expected: n,
                    found: x.len(),
                });
            }
            let out = column.as_mut_slice();
            match &self.scaler {
                Some(s) => s.transform_row(x, out)?,
                None => out.copy_from_slice(x),
            }
        }
        // Centred on the support vectors' mean (distances unchanged, smaller norms).
        for mut column in scaled.column_iter_mut() {
            column -= &support.mean;
        }
        // dots[(j, i)] = s_j · x_i.
        let dots = &support.vectors * scaled.map(|v| v as f32);
        let neg_gamma = f32x8::splat(-self.svm.gamma as f32);
        let two = f32x8::splat(2.0);
        Ok(scaled
            .column_iter()
            .zip(dots.column_iter())
            .take(rows.len())
            .map(|(x, dots)| {
                let x_norm = f32x8::splat(x.norm_squared() as f32);
                // Kernel terms in single precision, summed in double.
                let mut sum = [0.0f64; LANES];
                for ((coef, s_norm), dot) in support
                    .coef
                    .iter()
                    .zip(&support.norms)
                    .zip(dots.as_slice().chunks_exact(LANES))
                {
                    let dot = f32x8::from(dot);
                    let d2 = (x_norm + *s_norm - two * dot).max(f32x8::ZERO);
                    let terms = *coef * (neg_gamma * d2).exp();
                    for (s, t) in sum.iter_mut().zip(terms.to_array()) {
                        *s += f64::from(t);
                    }
                }
                sum.iter().sum::<f64>() - self.svm.rho
            })
            .collect())
    }
}

/// A classifier with its support vectors laid out for batched scoring once, as a detector keeps
/// it to score every frame: [`SvmClassifier::decision_values`] lays them out on every call
/// (about a millisecond for 2000 support vectors of 168 features, twice a frame in the
/// `symmetry` detector). The values are those of `decision_values`, bit for bit.
#[derive(Debug, Clone)]
pub struct BatchedClassifier {
    classifier: SvmClassifier,
    support: SupportMatrix,
}

impl BatchedClassifier {
    /// Lays out `classifier`'s support vectors.
    ///
    /// # Errors
    /// [`LearnError::InconsistentModel`] when the support vectors do not match the coefficients.
    pub fn new(classifier: SvmClassifier) -> Result<Self, LearnError> {
        let support = SupportMatrix::of(&classifier)?;
        Ok(Self {
            classifier,
            support,
        })
    }

    /// The classifier.
    pub fn classifier(&self) -> &SvmClassifier {
        &self.classifier
    }

    /// Decision values of many raw (unscaled) samples, as [`SvmClassifier::decision_values`].
    ///
    /// # Errors
    /// [`LearnError::FeatureCount`] when a sample has the wrong number of features.
    pub fn decision_values(&self, samples: &[&[f64]]) -> Result<Vec<f64>, LearnError> {
        self.classifier.decision_values_with(&self.support, samples)
    }
}

/// The support vectors, centred on their mean, as the rows of one single-precision matrix, with
/// their squared norms and coefficients in lanes of [`LANES`]: built once per
/// [`SvmClassifier::decision_values`] call or [`BatchedClassifier`], shared by the blocks. (As
/// rows, so that the product with a block is a plain `*`, which `nalgebra` hands to its GEMM;
/// `tr_mul` would not.) The rows are padded with zero vectors of coefficient 0 to a whole number
/// of lanes, which add exactly 0 to every sum.
#[derive(Debug, Clone)]
struct SupportMatrix {
    /// `n_padded × n_features`, support vector `j` in row `j`, then zero rows.
    vectors: DMatrix<f32>,
    /// Mean support vector.
    mean: nalgebra::DVector<f64>,
    /// `‖s_j‖²`, [`LANES`] at a time.
    norms: Vec<f32x8>,
    /// `yⱼ αⱼ`, [`LANES`] at a time.
    coef: Vec<f32x8>,
}

impl SupportMatrix {
    /// # Errors
    /// [`LearnError::InconsistentModel`] when the support vector array does not hold
    /// `n_features` numbers per coefficient (model files are checked on load; this guards
    /// classifiers built in code).
    fn of(classifier: &SvmClassifier) -> Result<Self, LearnError> {
        let svm = &classifier.svm;
        let n = classifier.n_features();
        if svm.coef.len().checked_mul(n) != Some(svm.support_vectors.len()) {
            return Err(LearnError::InconsistentModel(
                "support vector array does not match coefficient count".into(),
            ));
        }
        let padded = svm.coef.len().div_ceil(LANES) * LANES;
        let mut vectors = DMatrix::zeros(padded, n);
        for (j, s) in svm.support_vectors.chunks_exact(n.max(1)).enumerate() {
            vectors.row_mut(j).copy_from_slice(s);
        }
        let k = svm.coef.len().max(1) as f64;
        let mean: nalgebra::DVector<f64> = vectors.row_sum().transpose() / k;
        for j in 0..svm.coef.len() {
            let mut row = vectors.row_mut(j);
            row -= mean.transpose();
        }
        let norms: Vec<f64> = vectors.row_iter().map(|s| s.norm_squared()).collect();
        let mut coef = svm.coef.clone();
        coef.resize(padded, 0.0);
        let lanes = |v: &[f64]| -> Vec<f32x8> {
            v.chunks_exact(LANES)
                .map(|c| f32x8::from(std::array::from_fn::<f32, LANES, _>(|k| c[k] as f32)))
                .collect()
        };
        Ok(Self {
            vectors: vectors.cast::<f32>(),
            mean,
            norms: lanes(&norms),
            coef: lanes(&coef),
        })
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::{BatchedClassifier, DECISION_BLOCK};
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
            // Single-precision dot products (see the module docs): within 1e-7 of the
            // coefficients' total weight (1.9e-8 seen).
            let weight: f64 = c.svm.coef.iter().map(|a| a.abs()).sum();
            for (row, v) in rows.iter().zip(&values) {
                let expected = c.decision_value(row).unwrap();
                assert!((v - expected).abs() <= 1e-7 * weight, "{v} {expected}");
            }
            assert!(c.decision_values(&[]).unwrap().is_empty());
        }
    }

    #[test]
    fn a_batched_classifier_scores_as_the_classifier() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let c = classifier(&mut rng, 12, true);
        let rows: Vec<Vec<f64>> = (0..70)
            .map(|_| (0..12).map(|_| rng.gen_range(-1.0..1.0)).collect())
            .collect();
        let refs: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
        let batched = BatchedClassifier::new(c.clone()).unwrap();
        assert_eq!(
            batched.decision_values(&refs).unwrap(),
            c.decision_values(&refs).unwrap()
        );
        assert!(batched.decision_values(&[]).unwrap().is_empty());
        let mut bad = c;
        bad.svm.coef.pop();
        assert!(matches!(
            BatchedClassifier::new(bad),
            Err(LearnError::InconsistentModel(_))
        ));
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

    #[test]
    fn a_value_does_not_depend_on_the_block_or_the_thread_count() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let c = classifier(&mut rng, 168, true);
        let rows: Vec<Vec<f64>> = (0..2 * DECISION_BLOCK + 5)
            .map(|_| (0..168).map(|_| rng.gen_range(-1.0..1.0)).collect())
            .collect();
        let refs: Vec<&[f64]> = rows.iter().map(Vec::as_slice).collect();
        let all = c.decision_values(&refs).unwrap();
        // Alone, and shifted to another place in another block, every sample scores the same bits.
        for (i, row) in refs.iter().enumerate().step_by(17) {
            assert_eq!(
                c.decision_values(&[row]).unwrap()[0].to_bits(),
                all[i].to_bits()
            );
        }
        let shifted = c.decision_values(&refs[3..]).unwrap();
        for (a, b) in all[3..].iter().zip(&shifted) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
        let one_thread = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| c.decision_values(&refs).unwrap());
        assert_eq!(one_thread, all);
    }

    #[test]
    fn an_inconsistent_classifier_is_an_error_not_a_panic() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let mut c = classifier(&mut rng, 4, false);
        c.svm.support_vectors.pop();
        let err = c.decision_values(&[&[0.0; 4]]).unwrap_err();
        assert!(matches!(err, LearnError::InconsistentModel(_)));
    }
}
