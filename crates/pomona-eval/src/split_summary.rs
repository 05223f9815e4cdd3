//! Summaries over repeated train/test splits (seed 000's protocol: several random image-level
//! splits, results reported as mean ± standard deviation, curves averaged at equal recall).
//!
//! `pomona experiment` calls [`evaluate`](crate::evaluate) once per split and then this.

use serde::{Deserialize, Serialize};

use crate::{EvalReport, PrCurve};

/// Mean and sample standard deviation of a figure over the splits where it is defined.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MeanSd {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (`n − 1` denominator; 0 for a single split).
    pub sd: f64,
    /// Number of splits that had the figure.
    pub n: usize,
}

impl MeanSd {
    /// Mean ± sd of the defined values; `None` when no value is defined.
    ///
    /// ```
    /// let m = pomona_eval::MeanSd::of([Some(0.5), None, Some(0.7)]).unwrap();
    /// assert!((m.mean - 0.6).abs() < 1e-12 && (m.sd - 0.02f64.sqrt()).abs() < 1e-12);
    /// assert_eq!(m.n, 2);
    /// ```
    pub fn of(values: impl IntoIterator<Item = Option<f64>>) -> Option<Self> {
        let v: Vec<f64> = values.into_iter().flatten().collect();
        if v.is_empty() {
            return None;
        }
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let sd = if v.len() > 1 {
            (v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0)).sqrt()
        } else {
            0.0
        };
        Some(Self {
            mean,
            sd,
            n: v.len(),
        })
    }
}

/// Figures of several splits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SplitSummary {
    /// Number of splits.
    pub splits: usize,
    /// VOC 11-point AP.
    pub ap_voc11: Option<MeanSd>,
    /// All-point AP.
    pub ap: Option<MeanSd>,
    /// Precision at the threshold.
    pub precision: Option<MeanSd>,
    /// Recall at the threshold.
    pub recall: Option<MeanSd>,
    /// Median centre error, metres.
    pub center_error_median_m: Option<MeanSd>,
    /// Median centre error in truth radii (2D evaluations only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center_error_median_radii: Option<MeanSd>,
    /// Average curve: interpolated precision (max precision at recall ≥ r) averaged over splits
    /// at r = 0, 0.01, …, 1; `None` when a split has no curve.
    pub mean_pr_curve: Option<Vec<(f64, f64)>>,
}

impl SplitSummary {
    /// Summarises the reports of the splits.
    pub fn new(reports: &[EvalReport]) -> Self {
        let fig = |f: fn(&EvalReport) -> Option<f64>| MeanSd::of(reports.iter().map(f));
        let curves: Option<Vec<&PrCurve>> = reports.iter().map(|r| r.pr_curve.as_ref()).collect();
        let mean_pr_curve = curves.filter(|c| !c.is_empty()).map(|curves| {
            (0..=100)
                .map(|i| {
                    let r = f64::from(i) / 100.0;
                    let p = curves
                        .iter()
                        .map(|c| {
                            c.points
                                .iter()
                                .filter(|p| p.recall >= r)
                                .map(|p| p.precision)
                                .fold(0.0, f64::max)
                        })
                        .sum::<f64>()
                        / curves.len() as f64;
                    (r, p)
                })
                .collect()
        });
        Self {
            splits: reports.len(),
            ap_voc11: fig(|r| r.ap_voc11),
            ap: fig(|r| r.ap),
            precision: fig(|r| r.precision),
            recall: fig(|r| r.recall),
            center_error_median_m: fig(|r| r.center_error_m.median),
            center_error_median_radii: fig(|r| r.center_error_radii.and_then(|e| e.median)),
            mean_pr_curve,
        }
    }
}
