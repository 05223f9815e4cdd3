//! Histograms of surface normals in a symmetry (or fixed) frame (seed 000 §3.2, Eqs. 7–9).
//!
//! Each point `x` with normal `n_x` is described by two angles that depend only on the plane
//! `(p, n_p)`: `θ = acos(n_x · n_p)` in `[0, π]` (Eq. 7), and `φ` in `[0, 2π)`, the signed angle in
//! the plane from the projected normal `n̄_x` to the direction from the projected point `x̄` to the
//! centre `p` (Eqs. 8–9). The seeds give the unsigned angle plus "π depending on a direction";
//! their direction term `n_p · (p − x̄)` is identically zero (both vectors lie in the plane), so
//! we take the sign from `n_p · (n̄_x × (p − x̄))`, which is what the signed angle means.
//!
//! The box is split into spatio-angular bins by `|distance to the plane|` (over `[0, box/2]`) and
//! the angle between `x̄ − p` and `r` (over `[0, π]`). Every bin holds one histogram of θ and one
//! of φ, each normalised to sum 1 (all zeros when the bin is empty); the feature vector is their
//! concatenation, bin by bin.

use std::f64::consts::{PI, TAU};

use pomona_pipeline::{PipelineError, Stage};
use rayon::prelude::*;

use crate::{BoxPatch, FrameKind, HistogramParams, LocalFrame};

/// Per-bin pairs of 1D histograms, the common container of both feature kinds.
#[derive(Debug, Clone, PartialEq)]
pub struct BinnedHistograms {
    params: HistogramParams,
    counts: Vec<f64>,
}

impl BinnedHistograms {
    /// All-zero histograms.
    pub fn new(params: HistogramParams) -> Self {
        Self {
            params,
            counts: vec![0.0; params.feature_len()],
        }
    }

    /// Adds one point: spatial bin from `distance_frac` and `angle_frac` (both in `[0, 1]`,
    /// clamped), first and second histogram bins from `first_frac` and `second_frac`.
    pub fn add(&mut self, distance_frac: f64, angle_frac: f64, first_frac: f64, second_frac: f64) {
        let p = &self.params;
        let bin = |f: f64, n: usize| ((f * n as f64).floor().max(0.0) as usize).min(n - 1);
        let spatial =
            bin(distance_frac, p.distance_bins) * p.angle_bins + bin(angle_frac, p.angle_bins);
        let base = spatial * (p.first_bins + p.second_bins);
        self.counts[base + bin(first_frac, p.first_bins)] += 1.0;
        self.counts[base + p.first_bins + bin(second_frac, p.second_bins)] += 1.0;
    }

    /// The feature vector: every histogram normalised to sum 1 (empty ones stay zero).
    pub fn into_features(mut self) -> Vec<f64> {
        let (f, s) = (self.params.first_bins, self.params.second_bins);
        for chunk in self.counts.chunks_mut(f + s) {
            let (a, b) = chunk.split_at_mut(f);
            for h in [a, b] {
                let total: f64 = h.iter().sum();
                if total > 0.0 {
                    h.iter_mut().for_each(|v| *v /= total);
                }
            }
        }
        self.counts
    }
}

/// Eqs. 7–9 and the spatio-angular binning of seed 000 for one box.
pub fn normal_histogram(
    patch: &BoxPatch,
    frame: &LocalFrame,
    half_box_m: f64,
    params: HistogramParams,
) -> Vec<f64> {
    let mut h = BinnedHistograms::new(params);
    let p = frame.origin;
    let n_p = frame.normal.into_inner();
    for (x, n) in patch.points.iter().zip(&patch.normals) {
        let n = n.into_inner();
        let d = (x - p).dot(&n_p);
        let x_bar = x - n_p * d;
        let n_bar = n - n_p * n.dot(&n_p);
        let theta = n.dot(&n_p).clamp(-1.0, 1.0).acos();
        let to_centre = p - x_bar;
        let phi = match (n_bar.try_normalize(1e-9), to_centre.try_normalize(1e-9)) {
            (Some(a), Some(b)) => n_p.dot(&a.cross(&b)).atan2(a.dot(&b)).rem_euclid(TAU),
            _ => 0.0,
        };
        let angle = match (-to_centre).try_normalize(1e-9) {
            Some(dir) => dir.dot(&frame.reference).clamp(-1.0, 1.0).acos(),
            None => 0.0,
        };
        h.add(d.abs() / half_box_m, angle / PI, theta / PI, phi / TAU);
    }
    h.into_features()
}

/// Stage `features`: one feature vector per box that has a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeatureStage {
    kind: FrameKind,
    half_box_m: f64,
    params: HistogramParams,
}

impl FeatureStage {
    /// Features for frames of `kind` (viewer frames get seed 001's features, the others seed
    /// 000's).
    pub fn new(kind: FrameKind, half_box_m: f64, params: HistogramParams) -> Self {
        Self {
            kind,
            half_box_m,
            params,
        }
    }

    /// Length of every feature vector.
    pub fn feature_len(&self) -> usize {
        self.params.feature_len()
    }

    /// Features of one box.
    pub fn describe(&self, patch: &BoxPatch, frame: &LocalFrame) -> Vec<f64> {
        match self.kind {
            FrameKind::Viewer => crate::viewer_features(patch, frame, self.half_box_m, self.params),
            FrameKind::Symmetry | FrameKind::Fixed => {
                normal_histogram(patch, frame, self.half_box_m, self.params)
            }
        }
    }

    /// Features of every box with a frame (parallel, order-preserving).
    pub fn features(
        &self,
        patches: &[BoxPatch],
        frames: &[Option<LocalFrame>],
    ) -> Vec<Option<Vec<f64>>> {
        patches
            .par_iter()
            .zip(frames.par_iter())
            .map(|(p, f)| f.as_ref().map(|f| self.describe(p, f)))
            .collect()
    }
}

impl Stage<(&[BoxPatch], &[Option<LocalFrame>]), Vec<Option<Vec<f64>>>> for FeatureStage {
    fn name(&self) -> &'static str {
        "features"
    }

    fn run(
        &self,
        (patches, frames): (&[BoxPatch], &[Option<LocalFrame>]),
    ) -> Result<Vec<Option<Vec<f64>>>, PipelineError> {
        Ok(self.features(patches, frames))
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Point3, Unit, Vector3};

    use super::*;
    use crate::{plane_frame, FixedFrame, ReferenceFrame};

    #[test]
    fn histograms_are_normalised_per_bin() {
        let params = HistogramParams::default();
        let mut h = BinnedHistograms::new(params);
        h.add(0.1, 0.1, 0.2, 0.3);
        h.add(0.1, 0.1, 0.9, 0.3);
        h.add(0.9, 0.9, 1.0, 1.0); // upper edges clamp into the last bins
        let f = h.into_features();
        assert_eq!(f.len(), params.feature_len());
        let per = params.first_bins + params.second_bins;
        for bin in f.chunks(per) {
            let (a, b) = bin.split_at(params.first_bins);
            for hist in [a, b] {
                let s: f64 = hist.iter().sum();
                assert!(s == 0.0 || (s - 1.0).abs() < 1e-12);
            }
        }
        assert_eq!(f[1], 0.5); // θ = 0.2 → bin 1 of 6, half of that bin's points
        assert_eq!(f[f.len() - 1], 1.0);
    }

    #[test]
    fn angles_match_hand_computation() {
        // Plane x = 0 through p; a point at +x on the plane side with normal pointing +x:
        // θ = 0; projected normal vanishes (φ := 0).
        let p = Point3::new(0.0, 0.0, 1.0);
        let frame = plane_frame(p, Vector3::x_axis(), &Point3::origin()).unwrap();
        let one = |x: Point3<f64>, n: Vector3<f64>| BoxPatch {
            center: p,
            points: vec![x],
            normals: vec![Unit::new_normalize(n)],
        };
        let params = HistogramParams {
            distance_bins: 1,
            angle_bins: 1,
            first_bins: 4,
            second_bins: 4,
        };
        let f = normal_histogram(
            &one(p + Vector3::new(0.02, 0.0, 0.0), Vector3::x()),
            &frame,
            0.06,
            params,
        );
        assert_eq!(&f[..4], &[1.0, 0.0, 0.0, 0.0]);
        // A point above the centre (−y) with its normal pointing up, away from p: θ = π/2,
        // φ = π (normal opposite to the direction to the centre).
        let f = normal_histogram(
            &one(p + Vector3::new(0.0, -0.03, 0.0), -Vector3::y()),
            &frame,
            0.06,
            params,
        );
        assert_eq!(&f[..4], &[0.0, 0.0, 1.0, 0.0]);
        assert_eq!(&f[4..], &[0.0, 0.0, 1.0, 0.0]);
        // Fixed frame gives the same on this geometry (n_p = x there too).
        let fixed = FixedFrame
            .frame(&one(p, Vector3::x()), &Point3::origin())
            .unwrap();
        assert_eq!(fixed.normal, Vector3::x_axis());
    }
}
