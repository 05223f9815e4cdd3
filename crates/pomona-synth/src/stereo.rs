//! The divergent stereo rig of the colour-contour method (seed 004, §4.2): one camera takes two
//! pictures, rotated about a vertical axis through a pivot behind it.
//!
//! # Convention
//! All in the primary camera's frame (OpenCV: x right, y down, z forward, metres):
//!
//! * The **pivot** is the point `(0, 0, -d)`, `d` = [`StereoRig::pivot_distance_m`] behind the
//!   primary camera's centre; the rotation axis is vertical (parallel to the camera y axis).
//! * The two views lie at `∓β` about their bisector, so the **stereo view** is the primary camera
//!   rotated by `2β` about that axis, turning right (towards +x): its centre is at
//!   `(d·sin 2β, 0, d·cos 2β − d)` and it looks along `(sin 2β, 0, cos 2β)`. The optical axes
//!   diverge; the baseline is `2·d·sin β`.
//! * `rig.json` stores `beta_rad`, `pivot_m`, `baseline_m` and `stereo_from_camera`, a 4×4
//!   row-major rigid transform taking a point in the primary camera frame to the stereo camera
//!   frame: `X_stereo = T · X_primary` (homogeneous). Its rotation is `R_y(−2β)`.
//! * The stereo view's truth (`stereo/truth/*.json`) is in the stereo camera frame; fruit ids
//!   match the primary view's, so views can be paired by id.
//!
//! # Relation to the seed's Eqs. 17–18
//! Take the bisector frame: origin at the pivot, Z forward along the bisector, X to its right.
//! With normalised image coordinates mirrored in x (`x = −(u − cx) / fx`, so `f = 1`) and
//! `f + Z0 = d`, the primary view is the seed's left image and the stereo view its right
//! image: Eq. 17 holds exactly and Eq. 18 returns the Z of a point from its two x coordinates
//! (tested below).

#[cfg(test)]
use nalgebra::Vector3;
use nalgebra::{Isometry3, Matrix4, Point3, Rotation3, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};

use crate::SynthError;

/// Rotation half-angle and pivot distance of the two-view rig.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StereoRig {
    /// Half the angle between the two views, `β`, radians.
    pub beta_rad: f64,
    /// Distance from the primary camera centre back to the pivot, metres.
    pub pivot_distance_m: f64,
}

impl Default for StereoRig {
    /// β = 4°, pivot 0.3 m behind the camera: a 42 mm baseline.
    fn default() -> Self {
        Self {
            beta_rad: 4f64.to_radians(),
            pivot_distance_m: 0.3,
        }
    }
}

/// Contents of `rig.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigFile {
    /// Half-angle between the views, radians.
    pub beta_rad: f64,
    /// Pivot of the rotation in the primary camera frame, metres.
    pub pivot_m: [f64; 3],
    /// Distance between the two camera centres, metres.
    pub baseline_m: f64,
    /// Rigid transform from the primary camera frame to the stereo camera frame, row-major.
    pub stereo_from_camera: [[f64; 4]; 4],
    /// Folder of the second view, relative to the dataset root.
    pub stereo_dataset: String,
    /// One-line statement of the convention.
    pub convention: String,
}

impl StereoRig {
    /// Checks `0 < β < 45°` and a finite positive pivot distance.
    ///
    /// # Errors
    /// [`SynthError::InvalidParameter`] otherwise.
    pub fn validate(&self) -> Result<(), SynthError> {
        if !(self.beta_rad > 0.0 && self.beta_rad < std::f64::consts::FRAC_PI_4) {
            return Err(SynthError::InvalidParameter {
                name: "beta_rad",
                reason: format!("must be in (0, π/4), got {}", self.beta_rad),
            });
        }
        if !(self.pivot_distance_m.is_finite() && self.pivot_distance_m > 0.0) {
            return Err(SynthError::InvalidParameter {
                name: "pivot_distance_m",
                reason: format!("must be finite and positive, got {}", self.pivot_distance_m),
            });
        }
        Ok(())
    }

    /// The pivot in the primary camera frame.
    pub fn pivot(&self) -> Point3<f64> {
        Point3::new(0.0, 0.0, -self.pivot_distance_m)
    }

    /// Distance between the two camera centres, `2·d·sin β`.
    pub fn baseline_m(&self) -> f64 {
        2.0 * self.pivot_distance_m * self.beta_rad.sin()
    }

    /// Pose of the stereo camera: maps primary-camera (scene) points into the stereo frame.
    pub fn stereo_from_camera(&self) -> Isometry3<f64> {
        let m = self.stereo_from_camera_matrix();
        let rotation = Rotation3::from_matrix_unchecked(m.fixed_view::<3, 3>(0, 0).into_owned());
        let translation = Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]);
        Isometry3::from_parts(translation, UnitQuaternion::from_rotation_matrix(&rotation))
    }

    /// [`StereoRig::stereo_from_camera`] as an exact homogeneous matrix (what `rig.json` holds).
    pub fn stereo_from_camera_matrix(&self) -> Matrix4<f64> {
        // The camera moves by +2β about the vertical axis through the pivot p; points move the
        // other way: X ↦ R_y(−2β)·(X − p) + p. Written out so the matrix has exact 0s and 1s.
        let (s, c) = (2.0 * self.beta_rad).sin_cos();
        let d = self.pivot_distance_m;
        Matrix4::new(
            c,
            0.0,
            -s,
            -d * s, //
            0.0,
            1.0,
            0.0,
            0.0, //
            s,
            0.0,
            c,
            d * c - d, //
            0.0,
            0.0,
            0.0,
            1.0,
        )
    }

    /// The `rig.json` record.
    pub fn to_file(&self) -> RigFile {
        let m = self.stereo_from_camera_matrix();
        let mut rows = [[0.0; 4]; 4];
        for (r, row) in rows.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x = m[(r, c)];
            }
        }
        let p = self.pivot();
        RigFile {
            beta_rad: self.beta_rad,
            pivot_m: [p.x, p.y, p.z],
            baseline_m: self.baseline_m(),
            stereo_from_camera: rows,
            stereo_dataset: "stereo".to_string(),
            convention: "stereo view = primary camera rotated by 2*beta_rad about the vertical \
                         (camera y) axis through pivot_m, turning towards +x; \
                         X_stereo = stereo_from_camera * X_camera"
                .to_string(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stereo_camera_sits_right_of_the_primary_and_looks_right() {
        let rig = StereoRig::default();
        let t = rig.stereo_from_camera();
        let centre = t.inverse() * Point3::origin();
        let b = 2.0 * rig.beta_rad;
        let d = rig.pivot_distance_m;
        assert!((centre - Point3::new(d * b.sin(), 0.0, d * b.cos() - d)).norm() < 1e-12);
        assert!(((centre - Point3::origin()).norm() - rig.baseline_m()).abs() < 1e-12);
        let forward = t.inverse().rotation * Vector3::z();
        assert!((forward - Vector3::new(b.sin(), 0.0, b.cos())).norm() < 1e-12);
        // The pivot is fixed by the motion.
        assert!((t * rig.pivot() - rig.pivot()).norm() < 1e-12);
        let file = rig.to_file();
        assert_eq!(file.stereo_from_camera[3], [0.0, 0.0, 0.0, 1.0]);
        // Same as composing the motion from its parts.
        let p = rig.pivot().coords;
        let motion = Translation3::from(p)
            * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), b)
            * Translation3::from(-p);
        let diff = motion.inverse().to_homogeneous() - rig.stereo_from_camera_matrix();
        assert!(diff.norm() < 1e-12);
    }

    #[test]
    fn seed_equation_18_recovers_depth_from_the_two_views() {
        let rig = StereoRig {
            beta_rad: 6f64.to_radians(),
            pivot_distance_m: 0.25,
        };
        let (sb, cb) = rig.beta_rad.sin_cos();
        let d = rig.pivot_distance_m;
        let pose = rig.stereo_from_camera();
        for (x, z) in [(0.05, 0.9), (-0.2, 1.1), (0.1, 0.6), (0.0, 1.5)] {
            // Bisector frame → primary camera frame.
            let p = rig.pivot() + Vector3::new(cb, 0.0, -sb) * x + Vector3::new(sb, 0.0, cb) * z;
            let q = pose * p;
            let (xl, xr) = (-p.x / p.z, -q.x / q.z);
            // Eq. 17 with f = 1 and f + Z0 = d.
            assert!((xl - (x * cb + z * sb) / (d - z * cb + x * sb)).abs() < 1e-12);
            assert!((xr - (x * cb - z * sb) / (d - z * cb - x * sb)).abs() < 1e-12);
            // Eq. 18.
            let a = cb - xl * sb;
            let b = cb + xr * sb;
            let c = (sb - xr * cb) * (xl * sb - cb);
            let dd = (xl * cb + sb) * (cb + xr * sb);
            let z_rec = d * (xr * a - xl * b) / (c - dd);
            assert!((z_rec - z).abs() < 1e-9, "{z_rec} vs {z}");
        }
    }

    #[test]
    fn matches_the_seed_projection_equations() {
        // A point on the bisector at distance L from the pivot projects symmetrically: the two
        // views see it at x = ∓f·tan β (with our primary view = the seed's left view).
        let rig = StereoRig::default();
        let beta = rig.beta_rad;
        let d = rig.pivot_distance_m;
        let bisector = Vector3::new(beta.sin(), 0.0, beta.cos());
        let x = rig.pivot() + bisector * (d + 0.6);
        let left = x.x / x.z;
        let xs = rig.stereo_from_camera() * x;
        let right = xs.x / xs.z;
        assert!((left - right).abs() > 0.0);
        assert!((left + right).abs() < 1e-12, "{left} {right}");
    }
}
