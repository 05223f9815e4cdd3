//! The evaluation report: JSON with stable keys, and a short Markdown summary.
//!
//! Key order and names are fixed (`frames, fruits, ignored, tolerance_m, ap_voc11, ap, precision,
//! recall, threshold, center_error_m, diameter_error_m, per_frame`, then supporting keys) so that
//! scripts and later releases can rely on them. A figure that cannot be measured is `null`, and
//! `null_reasons` says why (for example, frames whose truth is incomplete make precision
//! meaningless).

use std::collections::BTreeMap;
use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

use crate::{EvalConfig, PrCurve};

/// Centre error of true positives: metres (`center_error_m`), or truth radii in the image
/// (`center_error_radii`, 2D evaluation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CenterError {
    /// Median (`null` without true positives measured this way).
    pub median: Option<f64>,
    /// Mean.
    pub mean: Option<f64>,
}

/// Diameter error of true positives where both sides have a diameter, metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DiameterError {
    /// Mean absolute error.
    pub mean_abs: Option<f64>,
}

/// Figures of one frame at the threshold.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameReport {
    /// Frame stem.
    pub frame: String,
    /// Whether the frame's truth is complete.
    pub complete: bool,
    /// Counted truth fruit.
    pub fruits: usize,
    /// Ignored truth fruit.
    pub ignored: usize,
    /// Detections in the file (any score).
    pub detections: usize,
    /// True positives at the threshold.
    pub true_positives: usize,
    /// False positives at the threshold.
    pub false_positives: usize,
    /// Precision at the threshold (`null` for incomplete truth or no detections).
    pub precision: Option<f64>,
    /// Recall at the threshold (`null` without counted fruit).
    pub recall: Option<f64>,
    /// The counted truth fruit not found at the threshold, in truth order (absent in reports
    /// written before it existed).
    #[serde(default)]
    pub missed: Vec<MissedFruit>,
}

/// A counted truth fruit that no detection at the threshold found, and how near the detector
/// came: whether one of its detections below the threshold found it (a ranking miss, which a
/// lower threshold recovers) or none did (a detection miss), and how far the nearest detection
/// of any score lies from it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissedFruit {
    /// The fruit's truth id.
    pub id: String,
    /// Its kind.
    pub kind: String,
    /// The detection below the threshold that matched it, if any.
    pub below_threshold: Option<ScoreAndConfidence>,
    /// Distance, metres, from its truth centre to the nearest detection centre of any score
    /// (`null` without a 3D truth centre or without detections).
    pub nearest_detection_m: Option<f64>,
}

/// A detection's classifier score and calibrated confidence.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScoreAndConfidence {
    /// Raw classifier score.
    pub score: f64,
    /// Calibrated confidence, when the model has one.
    pub confidence: Option<f64>,
}

/// The whole evaluation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EvalReport {
    /// Frames evaluated.
    pub frames: usize,
    /// Counted truth fruit.
    pub fruits: usize,
    /// Ignored truth fruit (too occluded or not locatable).
    pub ignored: usize,
    /// Match tolerance, metres.
    pub tolerance_m: f64,
    /// PASCAL VOC 11-point AP.
    pub ap_voc11: Option<f64>,
    /// All-point AP.
    pub ap: Option<f64>,
    /// Precision at the threshold.
    pub precision: Option<f64>,
    /// Recall at the threshold.
    pub recall: Option<f64>,
    /// Score threshold of the operating point (used when `min_confidence` is `None`).
    pub threshold: f64,
    /// Confidence threshold of the operating point, when it is one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_confidence: Option<f64>,
    /// For a 2D evaluation (`pomona eval --2d`): the match radius as a fraction of the truth
    /// circle's radius (`tolerance_m` is then unused).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_fraction_2d: Option<f64>,
    /// Centre error of true positives at the threshold.
    pub center_error_m: CenterError,
    /// For a 2D evaluation: the distance between matched circle centres, in truth radii.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center_error_radii: Option<CenterError>,
    /// Diameter error of true positives at the threshold.
    pub diameter_error_m: DiameterError,
    /// Per-frame figures, in frame order.
    pub per_frame: Vec<FrameReport>,
    /// Visibility below which truth was ignored.
    pub min_visibility: f64,
    /// The depth band, metres, outside which truth and unmatched detections were ignored.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_range_m: Option<(f64, f64)>,
    /// True positives at the threshold.
    pub true_positives: usize,
    /// False positives at the threshold.
    pub false_positives: usize,
    /// Why figures are `null`, keyed by figure name.
    pub null_reasons: BTreeMap<String, String>,
    /// The precision/recall curve (`null` when precision cannot be measured).
    pub pr_curve: Option<PrCurve>,
}

fn fmt_ratio(v: Option<f64>) -> String {
    v.map_or_else(|| "n/a".into(), |v| format!("{v:.3}"))
}

fn fmt_mm(v: Option<f64>) -> String {
    v.map_or_else(|| "n/a".into(), |v| format!("{:.1} mm", v * 1000.0))
}

impl EvalReport {
    /// The operating point of `precision` and `recall` in words.
    pub fn operating_point(&self) -> String {
        EvalConfig {
            tolerance_m: self.tolerance_m,
            min_visibility: self.min_visibility,
            threshold: self.threshold,
            min_confidence: self.min_confidence,
            radius_fraction_2d: self.radius_fraction_2d,
            depth_range_m: self.depth_range_m,
        }
        .operating_point()
    }

    /// A short Markdown summary (a heading, a table, and the reasons for any `n/a`).
    pub fn to_markdown(&self) -> String {
        let mut s = String::new();
        let tolerance = match self.radius_fraction_2d {
            Some(f) => format!("matched in the image within {f} truth radii"),
            None => format!("tolerance {:.0} mm", self.tolerance_m * 1000.0),
        };
        let tolerance = match self.depth_range_m {
            Some((near, far)) => format!("{tolerance}, fruit {near}–{far} m deep"),
            None => tolerance,
        };
        let _ = writeln!(
            s,
            "## Evaluation: {} frames, {} fruits ({} ignored), {tolerance}\n",
            self.frames, self.fruits, self.ignored,
        );
        let _ = writeln!(s, "| metric | value |\n|---|---|");
        let rows = [
            ("AP (VOC 11-point)", fmt_ratio(self.ap_voc11)),
            ("AP (all points)", fmt_ratio(self.ap)),
            (
                &*format!("precision at {}", self.operating_point()),
                fmt_ratio(self.precision),
            ),
            (
                &*format!("recall at {}", self.operating_point()),
                fmt_ratio(self.recall),
            ),
            (
                "true / false positives",
                format!("{} / {}", self.true_positives, self.false_positives),
            ),
            ("centre error median", fmt_mm(self.center_error_m.median)),
            ("centre error mean", fmt_mm(self.center_error_m.mean)),
            (
                "diameter error mean abs",
                fmt_mm(self.diameter_error_m.mean_abs),
            ),
            ("missed: never detected / only below the threshold", {
                let missed = self.per_frame.iter().flat_map(|f| &f.missed);
                let below = missed
                    .clone()
                    .filter(|m| m.below_threshold.is_some())
                    .count();
                format!("{} / {below}", missed.count() - below)
            }),
        ];
        let radii = |v: Option<f64>| v.map_or_else(|| "n/a".into(), |v| format!("{v:.3} r"));
        let rows_2d = self.center_error_radii.map(|e| {
            [
                ("centre error median (truth radii)", radii(e.median)),
                ("centre error mean (truth radii)", radii(e.mean)),
            ]
        });
        for (k, v) in rows.into_iter().chain(rows_2d.into_iter().flatten()) {
            let _ = writeln!(s, "| {k} | {v} |");
        }
        if !self.null_reasons.is_empty() {
            let _ = writeln!(s);
            for (k, v) in &self.null_reasons {
                let _ = writeln!(s, "* `{k}` n/a: {v}");
            }
        }
        s
    }
}
