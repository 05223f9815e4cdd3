//! The hidden calibration errors of the simulated robot (seed 004 §4.2): what the real arm and
//! camera have and the nominal model (Eq. 18 + exact kinematics) does not know.
//!
//! * **Encoder offsets**: an encoder reads the true joint plus an offset, `reading = joint +
//!   offset`, on α and θ (a fraction of a degree) and on r (a few millimetres).
//! * **Camera mounting**: the camera sits on the arm's link at the nominal pivot distance `d`
//!   ahead of the hub, but its centre is off by a small translation and its axes by a small
//!   rotation, both in the link frame (the hub frame turned with the arm, see
//!   [`crate::ArmSimulation`]).
//! * **Lens distortion**: radial ([`RadialDistortion`]), `x_d = x (1 + k1 ρ² + k2 ρ⁴)` on
//!   normalised image coordinates with `ρ² = x² + y²`.
//!
//! [`CalibrationMagnitudes`] holds the sizes (documented defaults); [`CalibrationErrors::draw`]
//! draws one robot from a seed: each offset gets a random sign and a magnitude uniform in
//! [½, 1] × its size, so every error is really there; the distortion coefficients are the
//! lens's and are taken as given.

use nalgebra::{Rotation3, Vector3};
use pomona_core::{PinholeCamera, RadialDistortion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::ArmError;

/// Sizes of the hidden calibration errors.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CalibrationMagnitudes {
    /// Azimuth encoder offset, radians; default 0.5°.
    pub alpha_offset_rad: f64,
    /// Elevation encoder offset, radians; default 0.5°.
    pub theta_offset_rad: f64,
    /// Extension encoder offset, metres; default 5 mm.
    pub r_offset_m: f64,
    /// Camera centre offset per axis of the link frame, metres; default 5 mm.
    pub camera_offset_m: f64,
    /// Camera rotation about each axis of the link frame, radians; default 0.5°.
    pub camera_rotation_rad: f64,
    /// First radial distortion coefficient of the lens; default −0.10 (barrel).
    pub k1: f64,
    /// Second radial distortion coefficient of the lens; default 0.02.
    pub k2: f64,
}

impl Default for CalibrationMagnitudes {
    fn default() -> Self {
        Self {
            alpha_offset_rad: 0.5f64.to_radians(),
            theta_offset_rad: 0.5f64.to_radians(),
            r_offset_m: 0.005,
            camera_offset_m: 0.005,
            camera_rotation_rad: 0.5f64.to_radians(),
            k1: -0.10,
            k2: 0.02,
        }
    }
}

impl CalibrationMagnitudes {
    /// No calibration error at all: the robot is its nominal model.
    pub fn none() -> Self {
        Self {
            alpha_offset_rad: 0.0,
            theta_offset_rad: 0.0,
            r_offset_m: 0.0,
            camera_offset_m: 0.0,
            camera_rotation_rad: 0.0,
            k1: 0.0,
            k2: 0.0,
        }
    }

    /// Checks that every size is finite and the offsets are not negative.
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] naming the first bad value.
    pub fn validate(&self) -> Result<(), ArmError> {
        for (name, value) in [
            ("alpha_offset_rad", self.alpha_offset_rad),
            ("theta_offset_rad", self.theta_offset_rad),
            ("r_offset_m", self.r_offset_m),
            ("camera_offset_m", self.camera_offset_m),
            ("camera_rotation_rad", self.camera_rotation_rad),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ArmError::InvalidParameter {
                    name,
                    value,
                    reason: "an error magnitude must be finite and ≥ 0",
                });
            }
        }
        for (name, value) in [("k1", self.k1), ("k2", self.k2)] {
            if !value.is_finite() {
                return Err(ArmError::InvalidParameter {
                    name,
                    value,
                    reason: "a distortion coefficient must be finite",
                });
            }
        }
        Ok(())
    }

    /// Checks that the lens distortion can be undone over the whole image of `camera` (the
    /// arm's camera without it): a lens whose model folds back inside the image would put
    /// targets at impossible pixels, and every later step would fail far from the cause.
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] naming `k1`.
    pub fn validate_lens(&self, camera: &PinholeCamera) -> Result<(), ArmError> {
        let distortion = RadialDistortion {
            k1: self.k1,
            k2: self.k2,
        };
        PinholeCamera {
            distortion: Some(distortion),
            ..*camera
        }
        .validate()
        .map_err(|_| ArmError::InvalidParameter {
            name: "k1",
            value: self.k1,
            reason: "with this k2, the lens distortion cannot be inverted over the camera's image \
                     (it folds back before the corners)",
        })
    }
}

/// One robot's actual calibration errors (drawn from [`CalibrationMagnitudes`] and a seed).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CalibrationErrors {
    /// Azimuth encoder offset (reading − joint), radians.
    pub alpha_offset_rad: f64,
    /// Elevation encoder offset, radians.
    pub theta_offset_rad: f64,
    /// Extension encoder offset, metres.
    pub r_offset_m: f64,
    /// Camera centre offset from its nominal place, in the link frame, metres.
    pub camera_offset_m: Vector3<f64>,
    /// Camera rotation from its nominal axes (axis × angle), in the link frame, radians.
    pub camera_rotation_rad: Vector3<f64>,
    /// First radial distortion coefficient.
    pub k1: f64,
    /// Second radial distortion coefficient.
    pub k2: f64,
}

impl CalibrationErrors {
    /// The error-free robot.
    pub fn none() -> Self {
        Self::draw(&CalibrationMagnitudes::none(), 0)
    }

    /// Draws one robot's errors: same magnitudes and seed, same errors.
    pub fn draw(magnitudes: &CalibrationMagnitudes, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut signed = |size: f64| {
            let sign = if rng.gen_bool(0.5) { 1.0 } else { -1.0 };
            sign * size * rng.gen_range(0.5..=1.0)
        };
        let alpha_offset_rad = signed(magnitudes.alpha_offset_rad);
        let theta_offset_rad = signed(magnitudes.theta_offset_rad);
        let r_offset_m = signed(magnitudes.r_offset_m);
        let camera_offset_m = Vector3::new(
            signed(magnitudes.camera_offset_m),
            signed(magnitudes.camera_offset_m),
            signed(magnitudes.camera_offset_m),
        );
        let camera_rotation_rad = Vector3::new(
            signed(magnitudes.camera_rotation_rad),
            signed(magnitudes.camera_rotation_rad),
            signed(magnitudes.camera_rotation_rad),
        );
        Self {
            alpha_offset_rad,
            theta_offset_rad,
            r_offset_m,
            camera_offset_m,
            camera_rotation_rad,
            k1: magnitudes.k1,
            k2: magnitudes.k2,
        }
    }

    /// The camera's rotation from its nominal axes, as a rotation matrix (camera → link).
    pub fn camera_rotation(&self) -> Rotation3<f64> {
        Rotation3::new(self.camera_rotation_rad)
    }

    /// The lens's radial distortion, `None` when both coefficients are zero.
    pub fn distortion(&self) -> Option<RadialDistortion> {
        (self.k1 != 0.0 || self.k2 != 0.0).then_some(RadialDistortion {
            k1: self.k1,
            k2: self.k2,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lens_that_folds_back_inside_the_image_is_refused_by_name() {
        let camera = crate::ArmRig::default().camera;
        assert!(CalibrationMagnitudes::default()
            .validate_lens(&camera)
            .is_ok());
        assert!(CalibrationMagnitudes::none().validate_lens(&camera).is_ok());
        let folded = CalibrationMagnitudes {
            k1: -3.0,
            ..CalibrationMagnitudes::default()
        };
        let err = folded.validate_lens(&camera).unwrap_err().to_string();
        assert!(
            err.contains("k1") && err.contains("cannot be inverted"),
            "{err}"
        );
    }

    #[test]
    fn draws_are_seeded_signed_and_within_half_to_full_size() {
        let m = CalibrationMagnitudes::default();
        let a = CalibrationErrors::draw(&m, 7);
        assert_eq!(a, CalibrationErrors::draw(&m, 7));
        assert_ne!(a, CalibrationErrors::draw(&m, 8));
        let within = |v: f64, size: f64| v.abs() >= 0.5 * size && v.abs() <= size;
        assert!(within(a.alpha_offset_rad, m.alpha_offset_rad));
        assert!(within(a.theta_offset_rad, m.theta_offset_rad));
        assert!(within(a.r_offset_m, m.r_offset_m));
        assert!(a
            .camera_offset_m
            .iter()
            .all(|&v| within(v, m.camera_offset_m)));
        assert!(a
            .camera_rotation_rad
            .iter()
            .all(|&v| within(v, m.camera_rotation_rad)));
        let none = CalibrationErrors::none();
        assert_eq!(none.distortion(), None);
        assert_eq!(none.camera_offset_m, Vector3::zeros());
    }

    #[test]
    fn barrel_distortion_pulls_points_inwards_and_bad_sizes_are_rejected() {
        let e = CalibrationErrors::draw(&CalibrationMagnitudes::default(), 1);
        let d = e
            .distortion()
            .unwrap()
            .distort(nalgebra::Vector2::new(0.8, 0.0));
        assert!(d.x < 0.8 && d.y == 0.0);
        let bad = CalibrationMagnitudes {
            r_offset_m: -1.0,
            ..CalibrationMagnitudes::default()
        };
        assert!(bad.validate().is_err());
        assert!(CalibrationMagnitudes::default().validate().is_ok());
    }
}
