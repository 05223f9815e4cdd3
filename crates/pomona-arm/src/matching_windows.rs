//! The epipolar windows of seed 004's stereo matching (Eq. 10): which pairs of centres, one per
//! view, can be the same fruit at all.
//!
//! # Disparity in this project's convention
//! The seed's disparity is `ΔX = x_r − x_l` in its mirrored image x; in pixels that is
//! `ΔX = u_primary − u_stereo` (the stereo view is turned towards +x, so every fruit moves left
//! in it), positive for every point in front of both views, and `ΔY = |v_stereo − v_primary|`.
//!
//! # Derivation of the bounds (Eq. 10) from the rig and the working volume
//! The seed takes `ΔX_0` and `ΔX_M` as the disparities of the farthest and nearest reachable
//! points. With rotated views the disparity is not a function of depth alone, so the bounds are
//! computed over the whole working volume: every point at a hub distance in
//! `[near_m, far_m]` seen by both views. Along one primary-view ray the stereo view sees the
//! point move monotonically towards the epipole as it recedes (a point at infinity keeps only
//! the rotation's shift, `u_stereo` of the rotated direction), so the part of the ray the stereo
//! view sees is one interval and the ray's extremes lie at its two ends: the nearest point seen
//! by both views gives the largest disparity, the farthest the smallest. The ends are the volume's
//! own (`near_m`, `far_m`) when the stereo view sees them; with a long lever or a wide turn the
//! nearest points leave the stereo image, and the end is then found along the ray
//! ([`RAY_SAMPLES`] hub distances, then bisection to a tenth of a millimetre). The bounds are
//! the extremes over rays on a grid of primary pixels (every [`WORKING_VOLUME_GRID_PX`] pixels
//! and the image border). The vertical offset of an ideal
//! pinhole pair is not zero off the centre row (the two views see the point at different depths),
//! so `ΔY_M` is the largest offset over the same samples. Each bound is then widened by a margin
//! in pixels for what the geometry leaves out — the detector's centre error and, as the seed
//! says of `ΔY_M`, lens effects determined by experiment.

use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};

use crate::{ArmError, RotatedStereo};

/// Spacing of the primary-view pixel grid on which the working volume is sampled.
pub const WORKING_VOLUME_GRID_PX: u32 = 8;

/// Hub distances sampled along each ray to find the part of it both views see.
pub const RAY_SAMPLES: usize = 32;

/// Bisection steps that place an end of the seen part of a ray (the range `far − near` halves
/// each step: 2 m becomes under 0.1 mm).
const BISECTION_STEPS: usize = 16;

/// The Eq. 10 windows, in pixels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MatchingWindows {
    /// `ΔX_0`: smallest disparity `u_primary − u_stereo` of a reachable point (the farthest).
    pub min_disparity_px: f64,
    /// `ΔX_M`: largest disparity (the nearest reachable point).
    pub max_disparity_px: f64,
    /// `ΔY_M`: largest vertical offset `|v_stereo − v_primary|`.
    pub max_vertical_offset_px: f64,
}

impl MatchingWindows {
    /// Whether the pair (primary centre, stereo centre) passes Eq. 10; its disparity if so.
    pub fn disparity_if_admissible(
        &self,
        primary: &Point2<f64>,
        stereo: &Point2<f64>,
    ) -> Option<f64> {
        let dx = primary.x - stereo.x;
        let dy = (stereo.y - primary.y).abs();
        (self.admits_disparity(dx) && dy <= self.max_vertical_offset_px).then_some(dx)
    }

    /// Whether the disparity `dx` (pixels) lies in the Eq. 10 disparity window, whatever the
    /// rows.
    pub fn admits_disparity(&self, dx: f64) -> bool {
        dx >= self.min_disparity_px && dx <= self.max_disparity_px
    }

    /// The windows of `rig` for fruit at hub distances in `[near_m, far_m]`, each widened by
    /// `margin_px` (see the module docs for the derivation).
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] when the distances are not finite with
    /// `pivot distance < near_m < far_m`, the margin is negative, or no point of the volume is
    /// seen by both views.
    pub fn for_rig(
        rig: &RotatedStereo,
        near_m: f64,
        far_m: f64,
        margin_px: f64,
    ) -> Result<Self, ArmError> {
        if !(near_m.is_finite() && near_m > rig.pivot_distance_m) {
            return Err(ArmError::InvalidParameter {
                name: "near_m",
                value: near_m,
                reason: "must be finite and beyond the camera (more than the pivot distance)",
            });
        }
        if !(far_m.is_finite() && far_m > near_m) {
            return Err(ArmError::InvalidParameter {
                name: "far_m",
                value: far_m,
                reason: "must be finite and greater than near_m",
            });
        }
        if !(margin_px.is_finite() && margin_px >= 0.0) {
            return Err(ArmError::InvalidParameter {
                name: "margin_px",
                value: margin_px,
                reason: "must be finite and non-negative",
            });
        }
        let cam = &rig.camera;
        let axis = |size: u32| {
            let last = size - 1;
            (0..last)
                .step_by(WORKING_VOLUME_GRID_PX as usize)
                .chain(std::iter::once(last))
                .map(f64::from)
        };
        let mut bounds: Option<(f64, f64, f64)> = None;
        for v in axis(cam.height) {
            for u in axis(cam.width) {
                let primary = Point2::new(u, v);
                let ray = cam.normalised(&primary).push(1.0);
                let offsets = |hub_distance_m: f64| -> Option<(f64, f64)> {
                    let depth = depth_at_hub_distance(&ray, rig.pivot_distance_m, hub_distance_m)?;
                    let (seen, stereo) = rig.project_pair(&Point3::from(ray * depth))?;
                    cam.contains(&stereo)
                        .then(|| (seen.x - stereo.x, (stereo.y - seen.y).abs()))
                };
                for (dx, dy) in seen_ends(near_m, far_m, offsets) {
                    bounds = Some(match bounds {
                        None => (dx, dx, dy),
                        Some((lo, hi, y)) => (lo.min(dx), hi.max(dx), y.max(dy)),
                    });
                }
            }
        }
        let (lo, hi, dy) = bounds.ok_or(ArmError::InvalidParameter {
            name: "far_m",
            value: far_m,
            reason: "no point of the working volume is seen by both views",
        })?;
        Ok(Self {
            min_disparity_px: lo - margin_px,
            max_disparity_px: hi + margin_px,
            max_vertical_offset_px: dy + margin_px,
        })
    }
}

/// The (disparity, vertical offset) at the two ends of the part of `[near_m, far_m]` where
/// `offsets` (a point of one ray at a hub distance, `None` when the stereo view does not see it)
/// is defined; empty when no sample is seen. The seen part is one interval (see the module
/// docs), so its ends are the first and last seen samples moved by bisection towards the unseen
/// neighbours.
fn seen_ends(
    near_m: f64,
    far_m: f64,
    offsets: impl Fn(f64) -> Option<(f64, f64)>,
) -> Vec<(f64, f64)> {
    let at = |i: usize| near_m + (far_m - near_m) * i as f64 / (RAY_SAMPLES - 1) as f64;
    let Some(first) = (0..RAY_SAMPLES).find(|&i| offsets(at(i)).is_some()) else {
        return Vec::new();
    };
    let last = (first..RAY_SAMPLES)
        .rev()
        .find(|&i| offsets(at(i)).is_some())
        .unwrap_or(first);
    // Moves the end `seen` towards `unseen` while staying on the seen side.
    let bisect = |mut seen: f64, mut unseen: f64| {
        for _ in 0..BISECTION_STEPS {
            let mid = 0.5 * (seen + unseen);
            if offsets(mid).is_some() {
                seen = mid;
            } else {
                unseen = mid;
            }
        }
        seen
    };
    let near_end = if first == 0 {
        near_m
    } else {
        bisect(at(first), at(first - 1))
    };
    let far_end = if last == RAY_SAMPLES - 1 {
        far_m
    } else {
        bisect(at(last), at(last + 1))
    };
    [near_end, far_end]
        .into_iter()
        .filter_map(offsets)
        .collect()
}

/// Depth `t` (primary camera z) at which the ray `t·ray` (with `ray.z = 1`) lies
/// `hub_distance_m` from the pivot `(0, 0, −d)`; `None` if it never does in front of the camera.
fn depth_at_hub_distance(
    ray: &nalgebra::Vector3<f64>,
    pivot_distance_m: f64,
    hub_distance_m: f64,
) -> Option<f64> {
    // |t·ray − pivot|² = r²  ⇔  t²|ray|² + 2·t·d + d² − r² = 0 (ray.z = 1, pivot = −d·z).
    let a = ray.norm_squared();
    let d = pivot_distance_m;
    let disc = d * d - a * (d * d - hub_distance_m * hub_distance_m);
    if disc < 0.0 {
        return None;
    }
    let t = (-d + disc.sqrt()) / a;
    (t > 0.0).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::PinholeCamera;

    fn rig() -> RotatedStereo {
        let camera = PinholeCamera::new(640, 480, 525.0, 525.0, 319.5, 239.5).unwrap();
        RotatedStereo::new(4f64.to_radians(), 0.3, camera).unwrap()
    }

    #[test]
    fn every_point_of_the_working_volume_passes_and_the_bounds_are_tight() {
        let (exact, lo, hi) = assert_windows_cover_the_volume(&rig(), 0.8, 1.8);
        assert!(
            lo - exact.min_disparity_px < 2.0 && exact.max_disparity_px - hi < 6.0,
            "{exact:?}: seen {lo}..{hi}"
        );
        // Nearer fruit means larger disparities.
        let nearer = MatchingWindows::for_rig(&rig(), 0.5, 1.8, 0.0).unwrap();
        assert!(nearer.max_disparity_px > exact.max_disparity_px);
    }

    #[test]
    fn a_long_lever_whose_near_points_leave_the_stereo_view_keeps_the_seen_ones() {
        // β = 8°, hub 0.8 m behind the lens: points 0.2 m in front of the camera are far
        // outside the stereo image, so the largest disparity is where the rays enter it.
        let camera = PinholeCamera::new(640, 480, 615.0, 615.0, 319.5, 239.5).unwrap();
        let rig = RotatedStereo::new(8f64.to_radians(), 0.8, camera).unwrap();
        let (exact, _, hi) = assert_windows_cover_the_volume(&rig, 1.0, 2.8);
        // Sample points reach far beyond the far end's disparity (about 250 px, all the window
        // held when only the volume's ends were tried); the bound is a corner-to-corner
        // disparity, at most the image width.
        assert!(hi > 500.0, "{hi}");
        assert!(exact.max_disparity_px <= 640.0, "{exact:?}");
    }

    /// Points spread over hub distances `[near, far]` that both views see pass the windows
    /// (with half a pixel for the grid sampling); returns the exact windows and the smallest and
    /// largest disparity of the points.
    fn assert_windows_cover_the_volume(
        rig: &RotatedStereo,
        near: f64,
        far: f64,
    ) -> (MatchingWindows, f64, f64) {
        let exact = MatchingWindows::for_rig(rig, near, far, 0.0).unwrap();
        assert!(exact.min_disparity_px > 0.0, "{exact:?}");
        assert!(exact.max_disparity_px > exact.min_disparity_px);
        // Random-ish points inside the volume seen by both views pass with a small tolerance
        // for the grid sampling; the extremes are nearly attained.
        let tolerant = MatchingWindows::for_rig(rig, near, far, 0.5).unwrap();
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let mut seen = 0;
        for i in 0..4000 {
            let f = f64::from(i);
            let r = near + (far - near) * ((f * 0.618_034) % 1.0);
            let az = ((f * 0.414_214) % 1.0 - 0.5) * 1.2;
            let el = ((f * 0.732_051) % 1.0 - 0.5) * 0.9;
            let hub = Point3::new(
                r * el.cos() * az.sin(),
                r * el.sin(),
                r * el.cos() * az.cos(),
            );
            let p = rig.hub_from_camera().inverse() * hub;
            let Some((a, b)) = rig.project_pair(&p) else {
                continue;
            };
            if !(rig.camera.contains(&a) && rig.camera.contains(&b)) {
                continue;
            }
            seen += 1;
            let dx = tolerant.disparity_if_admissible(&a, &b);
            assert!(dx.is_some(), "{p} → {a} {b} outside {tolerant:?}");
            lo = lo.min(a.x - b.x);
            hi = hi.max(a.x - b.x);
        }
        assert!(seen > 200, "only {seen} sample points seen by both views");
        (exact, lo, hi)
    }

    #[test]
    fn windows_reject_wrong_sign_and_vertical_offset() {
        let w = MatchingWindows {
            min_disparity_px: 10.0,
            max_disparity_px: 50.0,
            max_vertical_offset_px: 3.0,
        };
        let p = Point2::new(300.0, 200.0);
        assert_eq!(
            w.disparity_if_admissible(&p, &Point2::new(280.0, 202.0)),
            Some(20.0)
        );
        assert!(w
            .disparity_if_admissible(&p, &Point2::new(320.0, 200.0))
            .is_none());
        assert!(w
            .disparity_if_admissible(&p, &Point2::new(295.0, 200.0))
            .is_none());
        assert!(w
            .disparity_if_admissible(&p, &Point2::new(240.0, 200.0))
            .is_none());
        assert!(w
            .disparity_if_admissible(&p, &Point2::new(280.0, 196.0))
            .is_none());
    }

    #[test]
    fn bad_volumes_are_rejected() {
        let rig = rig();
        assert!(MatchingWindows::for_rig(&rig, 0.2, 1.0, 1.0).is_err());
        assert!(MatchingWindows::for_rig(&rig, 1.0, 0.9, 1.0).is_err());
        assert!(MatchingWindows::for_rig(&rig, 0.8, 1.0, -1.0).is_err());
        assert!(MatchingWindows::for_rig(&rig, 0.8, f64::NAN, 1.0).is_err());
    }
}
