//! The size prior: what the annotated training fruit say about how large the fruit are, how
//! far from the camera they hang and whether they are round or elongated, and the stage
//! parameters that follow from it.
//!
//! Seed 002 sets its radius limits, depth limit and minimum cluster size by hand for one crop
//! and one sensor. With `size_prior: from-truth` (the default), training measures them instead,
//! so one `pomona train` call works for apples at 1–2 m as well as for peppers at 0.5 m:
//!
//! * **radius ranges**: the observed radii (`diameter_m / 2`) of the training fruit, widened by
//!   [`RADIUS_MARGIN`] (10 %) on each side — caliper spread of fruit the training set has not
//!   seen, and the fitting noise of a visible cap; spheres take the round fruit's range,
//!   cylinders the elongated fruit's;
//! * **shapes**: spheres only when every training fruit is round (`height_m` at most
//!   [`ELONGATED_RATIO`] × `diameter_m`), cylinders only when every one is elongated, both when
//!   mixed; when some fruit have no `height_m` (e.g. synthetic truth) the configured choice is
//!   kept and both radius ranges come from every fruit;
//! * **depth limit**: widened to the deepest training fruit centre plus [`DEPTH_MARGIN`] (15 %)
//!   when that lies beyond the configured `max_depth_m` (the arm's reach, 1.5 m in the paper);
//!   never narrowed below it. Fruit are where the robot works, not only where the training
//!   frames happened to be taken: a limit learnt from near training frames dropped every fruit
//!   of a farther test scene (the cross-domain matrix's far band, `docs/results.md`). The
//!   symmetry detectors' working range follows the same rule. Between the training fruit and
//!   the reach the classifier has seen no fruit, and background it never met there (soil under
//!   a camera trained on crop rows) can score as fruit, so there the detector also asks for a
//!   curved surface ([`crate::CurvatureCheck`] from that depth on);
//! * **minimum cluster**: a cluster must cover [`MIN_VISIBLE_FRACTION`] (15 %) of the image
//!   area of the smallest expected fruit at the cluster's own depth
//!   ([`crate::MinFruitArea`]), instead of a fixed pixel count;
//! * **largest cluster**: when oversized clusters are split ([`crate::OversizedSplit`], opt-in),
//!   the largest expected fruit is the upper end of the widest radius range.
//!
//! Only annotated fruit with a diameter and a 3D centre count; kinds listed in
//! `reference_kinds` (default `reference_ball`: the white calibration spheres annotated beside
//! the apples of `ak-apples`) are not crop and are left out. With `size_prior: fixed` the
//! configured parameters are used unchanged (seed 002's behaviour).
//!
//! The normal-deviation check of the sphere estimator is not learnt: whether it helps depends
//! on the sensor's normal noise, which the truth does not record; it stays as configured
//! (off by default).

use pomona_consensus::ShapeChoice;
use pomona_core::FruitTruth;
use serde::{Deserialize, Serialize};

use crate::{CurvatureCheck, MinFruitArea, ShapeFitParams};

/// Radius ranges are the observed `[min, max]` widened by this fraction on each side.
pub const RADIUS_MARGIN: f64 = 0.1;
/// The depth limit is the deepest training fruit centre times `1 +` this.
pub const DEPTH_MARGIN: f64 = 0.15;
/// A fruit is elongated when its `height_m` exceeds its `diameter_m` by more than this factor.
pub const ELONGATED_RATIO: f64 = 1.25;
/// A cluster must cover this fraction of the smallest fruit's projected disc at its depth.
pub const MIN_VISIBLE_FRACTION: f64 = 0.15;

/// Where training takes the size-dependent stage parameters from.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SizePriorMode {
    /// Measured on the annotated training fruit ([`SizePrior`]).
    #[default]
    FromTruth,
    /// The configured values, unchanged.
    Fixed,
}

/// Sizes and depths of the annotated training fruit (stored in the model for the record; the
/// stage parameters it implies are stored beside it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SizePrior {
    /// Fruit measured.
    pub fruits: usize,
    /// Of these, round (`height_m ≤ 1.25 diameter_m`).
    pub round: usize,
    /// Elongated.
    pub elongated: usize,
    /// Radius `(min, max)` of the fruit a sphere may fit (round or unknown shape), metres.
    pub sphere_radius_m: Option<(f64, f64)>,
    /// Radius `(min, max)` of the fruit a cylinder may fit (elongated or unknown), metres.
    pub cylinder_radius_m: Option<(f64, f64)>,
    /// Deepest fruit centre (camera z), metres.
    pub max_center_depth_m: f64,
}

fn widen((lo, hi): (f64, f64)) -> (f64, f64) {
    (lo * (1.0 - RADIUS_MARGIN), hi * (1.0 + RADIUS_MARGIN))
}

fn extend(range: &mut Option<(f64, f64)>, r: f64) {
    *range = Some(match *range {
        Some((lo, hi)) => (lo.min(r), hi.max(r)),
        None => (r, r),
    });
}

impl SizePrior {
    /// Measures the annotated fruit that have a positive diameter and a 3D centre, skipping
    /// kinds in `reference_kinds`; `None` when there is none.
    pub fn from_truth<'a>(
        fruits: impl IntoIterator<Item = &'a FruitTruth>,
        reference_kinds: &[String],
    ) -> Option<Self> {
        let mut prior = Self {
            fruits: 0,
            round: 0,
            elongated: 0,
            sphere_radius_m: None,
            cylinder_radius_m: None,
            max_center_depth_m: 0.0,
        };
        for f in fruits {
            if reference_kinds.contains(&f.kind) {
                continue;
            }
            let (Some(center), Some(d)) = (f.center_m, f.diameter_m) else {
                continue;
            };
            if !(d.is_finite() && d > 0.0 && center.z.is_finite() && center.z > 0.0) {
                continue;
            }
            let r = d / 2.0;
            prior.fruits += 1;
            prior.max_center_depth_m = prior.max_center_depth_m.max(center.z);
            let height = f.extra.get("height_m").and_then(serde_json::Value::as_f64);
            match height.filter(|h| h.is_finite() && *h > 0.0) {
                Some(h) if h > ELONGATED_RATIO * d => {
                    prior.elongated += 1;
                    extend(&mut prior.cylinder_radius_m, r);
                }
                Some(_) => {
                    prior.round += 1;
                    extend(&mut prior.sphere_radius_m, r);
                }
                None => {
                    extend(&mut prior.sphere_radius_m, r);
                    extend(&mut prior.cylinder_radius_m, r);
                }
            }
        }
        (prior.fruits > 0).then_some(prior)
    }

    /// The shapes to fit: spheres only for all-round fruit, cylinders only for all-elongated,
    /// `None` (keep the configured choice) when some fruit's shape is unknown.
    pub fn shapes(&self) -> Option<ShapeChoice> {
        if self.round + self.elongated < self.fruits {
            return None;
        }
        Some(match (self.round > 0, self.elongated > 0) {
            (true, false) => ShapeChoice::Sphere,
            (false, true) => ShapeChoice::Cylinder,
            _ => ShapeChoice::Both,
        })
    }

    /// Sphere radius range with the margin, metres.
    pub fn sphere_range_m(&self) -> Option<(f64, f64)> {
        self.sphere_radius_m.map(widen)
    }

    /// Cylinder radius range with the margin, metres.
    pub fn cylinder_range_m(&self) -> Option<(f64, f64)> {
        self.cylinder_radius_m.map(widen)
    }

    /// Sets the size-dependent stage parameters of `params` (see the module docs) and records
    /// the prior in `params.learnt_size_prior`.
    pub fn apply(&self, params: &mut ShapeFitParams) {
        if let Some(range) = self.sphere_range_m() {
            params.shapes.sphere.radius_range_m = range;
        }
        if let Some(range) = self.cylinder_range_m() {
            params.shapes.cylinder.radius_range_m = range;
        }
        if let Some(shapes) = self.shapes() {
            params.shapes.shapes = shapes;
        }
        let fruit_depth_m = self.max_center_depth_m * (1.0 + DEPTH_MARGIN);
        if fruit_depth_m < params.max_depth_m {
            params.curvature = Some(CurvatureCheck {
                from_depth_m: fruit_depth_m,
                ..params.curvature.unwrap_or_default()
            });
        } else {
            params.max_depth_m = fruit_depth_m;
        }
        let ranges = [self.sphere_range_m(), self.cylinder_range_m()];
        let largest = ranges.iter().flatten().map(|r| r.1).fold(0.0, f64::max);
        if let Some(split) = params
            .regions
            .split_oversized
            .as_mut()
            .filter(|_| largest > 0.0)
        {
            split.radius_m = largest;
        }
        let smallest = ranges
            .iter()
            .flatten()
            .map(|r| r.0)
            .fold(f64::INFINITY, f64::min);
        if smallest.is_finite() && smallest > 0.0 {
            params.regions.min_fruit_area = Some(MinFruitArea {
                radius_m: smallest,
                fraction: MIN_VISIBLE_FRACTION,
            });
        }
        params.learnt_size_prior = Some(self.clone());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fruit(kind: &str, d: f64, h: Option<f64>, z: Option<f64>) -> FruitTruth {
        let mut json = serde_json::json!({"id": "x", "kind": kind, "diameter_m": d});
        if let Some(h) = h {
            json["height_m"] = h.into();
        }
        if let Some(z) = z {
            json["center_m"] = serde_json::json!([0.0, 0.0, z]);
        }
        serde_json::from_value(json).unwrap()
    }

    fn close(a: (f64, f64), b: (f64, f64)) -> bool {
        (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12
    }

    #[test]
    fn round_fruit_give_sphere_ranges_and_depth() {
        let refs = vec!["reference_ball".to_string()];
        let fruits = [
            fruit("apple", 0.06, Some(0.058), Some(1.2)),
            fruit("apple", 0.08, Some(0.07), Some(1.8)),
            fruit("apple", 0.07, Some(0.07), Some(1.5)),
            // A reference ball and a fruit without centre do not count.
            fruit("reference_ball", 0.12, Some(0.12), Some(2.5)),
            fruit("apple", 0.2, Some(0.2), None),
        ];
        let prior = SizePrior::from_truth(&fruits, &refs).unwrap();
        assert_eq!((prior.fruits, prior.round, prior.elongated), (3, 3, 0));
        assert!(close(prior.sphere_radius_m.unwrap(), (0.03, 0.04)));
        assert!(close(prior.sphere_range_m().unwrap(), (0.027, 0.044)));
        assert_eq!(prior.cylinder_radius_m, None);
        assert_eq!(prior.shapes(), Some(ShapeChoice::Sphere));
        let mut params = ShapeFitParams::default();
        let cylinder_before = params.shapes.cylinder.radius_range_m;
        prior.apply(&mut params);
        assert!(close(params.shapes.sphere.radius_range_m, (0.027, 0.044)));
        assert_eq!(params.shapes.cylinder.radius_range_m, cylinder_before);
        assert_eq!(params.shapes.shapes, ShapeChoice::Sphere);
        assert!((params.max_depth_m - 1.8 * 1.15).abs() < 1e-12);
        let area = params.regions.min_fruit_area.unwrap();
        assert!((area.radius_m - 0.027).abs() < 1e-12);
        assert_eq!(area.fraction, MIN_VISIBLE_FRACTION);
        // Oversized clusters are split only when asked for.
        assert_eq!(params.regions.split_oversized, None);
        assert_eq!(params.learnt_size_prior, Some(prior));
        // Asked for, the largest training fruit, with the margin, is the limit (only spheres
        // are fitted here).
        let mut split = ShapeFitParams::default();
        split.regions.split_oversized = Some(crate::OversizedSplit::for_radius(0.08));
        SizePrior::from_truth(&fruits, &refs)
            .unwrap()
            .apply(&mut split);
        let radius_m = split.regions.split_oversized.map(|s| s.radius_m);
        assert!((radius_m.unwrap() - 0.044).abs() < 1e-12);
    }

    #[test]
    fn elongated_and_unknown_shapes() {
        let long = [
            fruit("eggplant", 0.06, Some(0.2), Some(0.8)),
            fruit("eggplant", 0.07, Some(0.25), Some(0.9)),
        ];
        let prior = SizePrior::from_truth(&long, &[]).unwrap();
        assert_eq!(prior.shapes(), Some(ShapeChoice::Cylinder));
        assert!(close(prior.cylinder_range_m().unwrap(), (0.027, 0.0385)));
        assert_eq!(prior.sphere_radius_m, None);
        // Near training fruit leave the configured reach as it is; a shorter configured reach
        // is widened to the training fruit.
        let mut params = ShapeFitParams::default();
        prior.apply(&mut params);
        assert_eq!(params.max_depth_m, ShapeFitParams::default().max_depth_m);
        let check = params.curvature.expect("checked beyond the training fruit");
        assert!((check.from_depth_m - 0.9 * 1.15).abs() < 1e-12);
        let mut params = ShapeFitParams {
            max_depth_m: 0.5,
            ..ShapeFitParams::default()
        };
        prior.apply(&mut params);
        assert!((params.max_depth_m - 0.9 * 1.15).abs() < 1e-12);
        assert_eq!(params.curvature, None);
        let mixed = [long[0].clone(), fruit("apple", 0.07, Some(0.07), Some(1.0))];
        let prior = SizePrior::from_truth(&mixed, &[]).unwrap();
        assert_eq!(prior.shapes(), Some(ShapeChoice::Both));
        // Synthetic truth has no height: both ranges from every fruit, shapes as configured.
        let unknown = [
            fruit("pepper", 0.08, None, Some(0.6)),
            fruit("pepper", 0.1, None, Some(0.7)),
        ];
        let prior = SizePrior::from_truth(&unknown, &[]).unwrap();
        assert_eq!(prior.shapes(), None);
        assert!(close(prior.sphere_radius_m.unwrap(), (0.04, 0.05)));
        assert!(close(prior.cylinder_radius_m.unwrap(), (0.04, 0.05)));
        let mut params = ShapeFitParams::default();
        prior.apply(&mut params);
        assert_eq!(params.shapes.shapes, ShapeChoice::Both);
        assert!(SizePrior::from_truth(&[fruit("apple", 0.07, None, None)], &[]).is_none());
    }
}
