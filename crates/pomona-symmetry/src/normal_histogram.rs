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
        self.add_bins([
            fraction_bin(distance_frac, p.distance_bins),
            fraction_bin(angle_frac, p.angle_bins),
            fraction_bin(first_frac, p.first_bins),
            fraction_bin(second_frac, p.second_bins),
        ]);
    }

    /// Adds one point by its four bins (distance, angle, first, second), each within range.
    pub(crate) fn add_bins(&mut self, [distance, angle, first, second]: [usize; 4]) {
        let p = &self.params;
        let base = (distance * p.angle_bins + angle) * (p.first_bins + p.second_bins);
        self.counts[base + first] += 1.0;
        self.counts[base + p.first_bins + second] += 1.0;
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

/// The bin of `fraction` (clamped to `[0, 1]`) among `n` equal bins.
pub(crate) fn fraction_bin(fraction: f64, n: usize) -> usize {
    ((fraction * n as f64).floor().max(0.0) as usize).min(n - 1)
}

/// The bin of the angle `acos(t)` among `n` equal bins of `[0, π]` — what
/// `fraction_bin(t.acos() / π, n)` gives — found by comparing `t` with the cosines of the inner
/// bin edges (`acos` is decreasing), without the `acos`. The two agree wherever `t` is more than
/// [`AcosBins::EDGE_GUARD`] from an edge cosine (the rounding of `acos(t) / π · n` is about
/// 1e-15, and `|d acos / dt| ≥ 1`); within it the formula decides, so the bins are exactly the
/// formula's.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct AcosBins {
    n: usize,
    /// `cos(j π / n)` for `j = 1 … n − 1`, decreasing.
    edge_cosines: Vec<f64>,
}

impl AcosBins {
    /// Distance from an edge cosine within which the formula is used.
    const EDGE_GUARD: f64 = 1e-9;

    pub(crate) fn new(n: usize) -> Self {
        Self {
            n,
            edge_cosines: (1..n).map(|j| (j as f64 * PI / n as f64).cos()).collect(),
        }
    }

    /// The bin of `acos(t)`, `t` in `[−1, 1]`.
    pub(crate) fn bin(&self, t: f64) -> usize {
        let mut bin = 0;
        for &c in &self.edge_cosines {
            if (t - c).abs() <= Self::EDGE_GUARD {
                return fraction_bin(t.acos() / PI, self.n);
            }
            bin += usize::from(t < c);
        }
        bin
    }
}

/// The bin of the angle `atan2(y, x)` taken in `[0, 2π)` among `n` equal bins — what
/// `fraction_bin(y.atan2(x).rem_euclid(2π) / 2π, n)` gives — found by sign tests against the
/// bin edges' directions instead of the `atan2`: a point of the upper half-plane is past an edge
/// of the upper half when it lies counter-clockwise of it (cross product > 0) and past no edge of
/// the lower half; a point of the lower half is past every edge of the upper half, and past an
/// edge of its own half when counter-clockwise of it. Within [`SectorBins::EDGE_GUARD`] (relative to
/// `|x| + |y|`) of an edge or of the x axis, and for non-finite input, the formula decides, so
/// the bins are exactly the formula's (whose rounding is about 1e-15 of a turn).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SectorBins {
    n: usize,
    /// `(cos θ_j, sin θ_j)` of the inner edges `θ_j = 2π j / n`, `j = 1 … n − 1`, in the upper
    /// half-plane (`θ_j ∈ (0, π]` as rounded: `sin θ_j > 0`, or `= 0` with `cos θ_j > 0`).
    upper_edges: Vec<(f64, f64)>,
    /// The other inner edges, in the lower half-plane.
    lower_edges: Vec<(f64, f64)>,
}

impl SectorBins {
    /// Relative distance from an edge or the x axis within which the formula is used.
    const EDGE_GUARD: f64 = 1e-9;

    pub(crate) fn new(n: usize) -> Self {
        let (upper_edges, lower_edges) = (1..n)
            .map(|j| {
                let t = j as f64 * TAU / n as f64;
                (t.cos(), t.sin())
            })
            .partition(|&(c, s)| s > 0.0 || (s == 0.0 && c > 0.0));
        Self {
            n,
            upper_edges,
            lower_edges,
        }
    }

    /// The formula the bins reproduce.
    fn by_formula(&self, y: f64, x: f64) -> usize {
        fraction_bin(y.atan2(x).rem_euclid(TAU) / TAU, self.n)
    }

    /// The bin of the direction `(x, y)`.
    pub(crate) fn bin(&self, y: f64, x: f64) -> usize {
        let guard = Self::EDGE_GUARD * (x.abs() + y.abs());
        if !(x.is_finite() && y.is_finite()) || y.abs() <= guard {
            return self.by_formula(y, x);
        }
        // The other half's edges: every one passed by a lower point, none by an upper one.
        let (own_half, passed) = if y > 0.0 {
            (&self.upper_edges, 0)
        } else {
            (&self.lower_edges, self.upper_edges.len())
        };
        let mut bin = passed;
        for &(c, s) in own_half {
            let cross = c * y - s * x;
            if cross.abs() <= guard {
                return self.by_formula(y, x);
            }
            bin += usize::from(cross > 0.0);
        }
        bin
    }
}

/// The bin tables of one [`HistogramParams`]' angles, built once per feature stage rather than
/// per box.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct AngleBins {
    /// The spatial angle (`angle_bins` over `[0, π]`).
    pub(crate) angle: AcosBins,
    /// The first histogram (`first_bins` over `[0, π]`).
    pub(crate) first: AcosBins,
    /// The second histogram over `[0, π]` (viewer features).
    pub(crate) second: AcosBins,
    /// The second histogram over `[0, 2π)` (φ of the symmetry and fixed frames).
    pub(crate) phi: SectorBins,
}

impl AngleBins {
    pub(crate) fn new(params: &HistogramParams) -> Self {
        Self {
            angle: AcosBins::new(params.angle_bins),
            first: AcosBins::new(params.first_bins),
            second: AcosBins::new(params.second_bins),
            phi: SectorBins::new(params.second_bins),
        }
    }
}

/// Eqs. 7–9 and the spatio-angular binning of seed 000 for one box. The angles are only ever
/// binned: θ and the angle to the reference from their cosines ([`AcosBins`]), φ from its sine
/// and cosine ([`SectorBins`]) — the same bins, without an `acos` or `atan2` per point.
pub fn normal_histogram(
    patch: &BoxPatch,
    frame: &LocalFrame,
    half_box_m: f64,
    params: HistogramParams,
) -> Vec<f64> {
    normal_histogram_with(&AngleBins::new(&params), patch, frame, half_box_m, params)
}

/// [`normal_histogram`] with the bin tables of `params` already built.
pub(crate) fn normal_histogram_with(
    bins: &AngleBins,
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
        let theta_bin = bins.first.bin(n.dot(&n_p).clamp(-1.0, 1.0));
        let to_centre = p - x_bar;
        let phi_bin = match (n_bar.try_normalize(1e-9), to_centre.try_normalize(1e-9)) {
            (Some(a), Some(b)) => bins.phi.bin(n_p.dot(&a.cross(&b)), a.dot(&b)),
            _ => 0,
        };
        let angle_bin = match (-to_centre).try_normalize(1e-9) {
            Some(dir) => bins.angle.bin(dir.dot(&frame.reference).clamp(-1.0, 1.0)),
            None => 0,
        };
        h.add_bins([
            fraction_bin(d.abs() / half_box_m, params.distance_bins),
            angle_bin,
            theta_bin,
            phi_bin,
        ]);
    }
    h.into_features()
}

/// Stage `features`: one feature vector per box that has a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureStage {
    kind: FrameKind,
    half_box_m: f64,
    params: HistogramParams,
    bins: AngleBins,
}

impl FeatureStage {
    /// Features for frames of `kind` (viewer frames get seed 001's features, the others seed
    /// 000's).
    pub fn new(kind: FrameKind, half_box_m: f64, params: HistogramParams) -> Self {
        Self {
            kind,
            half_box_m,
            params,
            bins: AngleBins::new(&params),
        }
    }

    /// Length of every feature vector.
    pub fn feature_len(&self) -> usize {
        self.params.feature_len()
    }

    /// Features of one box.
    pub fn describe(&self, patch: &BoxPatch, frame: &LocalFrame) -> Vec<f64> {
        match self.kind {
            FrameKind::Viewer => crate::viewer_features::viewer_features_with(
                &self.bins,
                patch,
                frame,
                self.half_box_m,
                self.params,
            ),
            FrameKind::Symmetry | FrameKind::Fixed => {
                normal_histogram_with(&self.bins, patch, frame, self.half_box_m, self.params)
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

    /// The sector bins are the formula's everywhere: on a fine circle of directions at two
    /// lengths, on and a few ulps around every edge direction and both axes, and for zero and
    /// non-finite input.
    #[test]
    fn sector_bins_equal_the_formula() {
        for n in [1, 2, 3, 4, 6, 8, 17] {
            let bins = SectorBins::new(n);
            let mut probes: Vec<(f64, f64)> = Vec::new();
            for i in 0..20_000 {
                let t = i as f64 * TAU / 20_000.0;
                probes.extend([(t.sin(), t.cos()), (3.0 * t.sin(), 3.0 * t.cos())]);
            }
            let edges = bins.upper_edges.iter().chain(&bins.lower_edges);
            let mut directions: Vec<(f64, f64)> = edges.map(|&(c, s)| (s, c)).collect();
            directions.extend([
                (0.0, 1.0),
                (0.0, -1.0),
                (-0.0, -1.0),
                (1.0, 0.0),
                (-1.0, 0.0),
            ]);
            for (y, x) in directions {
                let step = |v: f64, k: i64| f64::from_bits(v.to_bits().wrapping_add(k as u64));
                for k in -3..=3 {
                    probes.extend([(step(y, k), x), (y, step(x, k)), (y + k as f64 * 1e-10, x)]);
                }
            }
            probes.extend([(0.0, 0.0), (-0.0, 0.0), (f64::NAN, 1.0), (1.0, f64::NAN)]);
            for (y, x) in probes {
                assert_eq!(bins.bin(y, x), bins.by_formula(y, x), "n {n} y {y} x {x}");
            }
        }
    }

    /// The comparison bins are the formula's everywhere: on a fine grid, at every edge cosine
    /// and one and a few ulps either side of it, and at ±1.
    #[test]
    fn acos_bins_equal_the_formula() {
        for n in [1, 2, 3, 4, 6, 8, 17] {
            let bins = AcosBins::new(n);
            let mut probes: Vec<f64> = (0..=20_000).map(|i| -1.0 + i as f64 / 10_000.0).collect();
            for &c in &bins.edge_cosines {
                let mut t = c;
                for _ in 0..4 {
                    probes.extend([t, -t]);
                    t = f64::from_bits(t.to_bits() + 1);
                }
                let mut t = c;
                for _ in 0..4 {
                    t = f64::from_bits(t.to_bits() - 1);
                    probes.push(t);
                }
                probes.extend([c + 2e-9, c - 2e-9]);
            }
            for t in probes {
                let t = t.clamp(-1.0, 1.0);
                assert_eq!(bins.bin(t), fraction_bin(t.acos() / PI, n), "n {n} t {t}");
            }
        }
    }

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
