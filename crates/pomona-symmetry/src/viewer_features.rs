//! Seed 001's features (§2.2) in a viewer frame.
//!
//! Points are binned by their distance to the `u`–`w` plane through the box centre `c` (over
//! `[0, box/2]`) and by the angle between `x − c` and `u` (over `[0, π]`). Per bin, one histogram
//! of the angle between the normal and `u`, one of the angle between the normal and the unit
//! vector from `c` to the point (both over `[0, π]`), each normalised to sum 1.

use crate::normal_histogram::{fraction_bin, AngleBins};
use crate::{BinnedHistograms, BoxPatch, HistogramParams, LocalFrame};

/// Features of one box in a viewer frame (`frame.reference` = `u`, `frame.normal` = `u × w`).
pub fn viewer_features(
    patch: &BoxPatch,
    frame: &LocalFrame,
    half_box_m: f64,
    params: HistogramParams,
) -> Vec<f64> {
    viewer_features_with(&AngleBins::new(&params), patch, frame, half_box_m, params)
}

/// [`viewer_features`] with the bin tables of `params` already built.
pub(crate) fn viewer_features_with(
    bins: &AngleBins,
    patch: &BoxPatch,
    frame: &LocalFrame,
    half_box_m: f64,
    params: HistogramParams,
) -> Vec<f64> {
    let mut h = BinnedHistograms::new(params);
    let c = frame.origin;
    let u = frame.reference.into_inner();
    let m = frame.normal.into_inner();
    // Each angle is only binned: from its cosine (the same bins as binning `acos`).
    let cosine = |a: &nalgebra::Vector3<f64>, b: &nalgebra::Vector3<f64>| a.dot(b).clamp(-1.0, 1.0);
    for (x, n) in patch.points.iter().zip(&patch.normals) {
        let n = n.into_inner();
        let d = x - c;
        let dist = d.dot(&m).abs();
        let Some(ray) = d.try_normalize(1e-9) else {
            continue;
        };
        h.add_bins([
            fraction_bin(dist / half_box_m, params.distance_bins),
            bins.angle.bin(cosine(&ray, &u)),
            bins.first.bin(cosine(&n, &u)),
            bins.second.bin(cosine(&n, &ray)),
        ]);
    }
    h.into_features()
}

#[cfg(test)]
mod tests {
    use nalgebra::{Point3, Unit, Vector3};

    use super::*;
    use crate::{ReferenceFrame, ViewerFrame};

    #[test]
    fn point_in_front_of_centre_facing_viewer() {
        let c = Point3::new(0.0, 0.0, 1.0);
        let patch = BoxPatch {
            center: c,
            points: vec![Point3::new(0.0, 0.0, 0.96)],
            normals: vec![Unit::new_normalize(-Vector3::z())],
        };
        let frame = ViewerFrame.frame(&patch, &Point3::origin()).unwrap();
        let params = HistogramParams {
            distance_bins: 2,
            angle_bins: 2,
            first_bins: 2,
            second_bins: 2,
        };
        let f = viewer_features(&patch, &frame, 0.06, params);
        // On the u–w plane (distance bin 0), along u (angle bin 0), normal along u (angle 0) and
        // along the ray (angle 0).
        assert_eq!(&f[..4], &[1.0, 0.0, 1.0, 0.0]);
        assert!(f[4..].iter().all(|&v| v == 0.0));
    }
}
