//! The robot of seed 004 §4 in numbers: one arm carrying a camera that takes two shots rotated
//! ±β about the hub, the pixel coordinates of a target in the two shots, and the encoder
//! readings that put the end of the telescopic link on it — with hidden calibration errors
//! ([`CalibrationErrors`]) that the nominal model does not know.
//!
//! # Frames
//! * **Hub frame** (the arm's reference, where targets live): origin at the hub, x right,
//!   y down, z forward, metres.
//! * **Link frame** of joints (α, θ): the hub frame turned by `R_link = R_y(α) · R_x(π/2 − θ)`,
//!   so its z axis is the link direction `(sin θ sin α, −cos θ, sin θ cos α)` of
//!   [`ArmJoints::to_point_in_hub`]; at α = 0, θ = 90° it is the hub frame.
//! * **Camera frame** of a shot (OpenCV: x right, y down, z forward): nominally the link frame
//!   moved `pivot_m` (the seed's `f + Z0`) along the link's z axis, i.e. the camera looks along
//!   the link with the hub `pivot_m` behind it. The true camera is further moved by
//!   `camera_offset_m` and turned by `camera_rotation_rad`, both in the link frame:
//!   `point_in_hub = R_link (R_mount · point_in_camera + (0, 0, d) + offset)`.
//! * **Shots**: the arm is commanded to encoder readings α = ∓β (left, right), θ = 90°; the
//!   true joints are the readings minus the encoder offsets. With no errors the left shot is
//!   the primary view of `pomona_synth::StereoRig` and the right shot its stereo view (pivot
//!   `d` behind the camera, the two views at ∓β about the bisector, which is the hub's z axis).
//! * **Pixels**: the rig's [`PinholeCamera`] with the lens's distortion (normalised coordinates
//!   `(X/Z, Y/Z)` in the camera frame, radially distorted, then `u = fx·x + cx`,
//!   `v = fy·y + cy`; pixel centres are integers). A target is *seen* when it is at least
//!   `min_depth_m` in front of both shots and falls inside both images.
//! * **Encoder readings** for a target: the exact inverse kinematics ([`ArmJoints::reaching`])
//!   of the target plus the encoder offsets; the end of the link for readings `q` is the forward
//!   kinematics at `q − offsets`.

use nalgebra::{Isometry3, Point2, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use pomona_core::PinholeCamera;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::{ArmError, ArmJoints, ArmLimits, CalibrationErrors, RotatedStereo};

/// The camera and the two-shot geometry of one arm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ArmRig {
    /// Intrinsics of the camera as designed (without distortion: the lens's distortion is one
    /// of the [`CalibrationErrors`]); default 640 × 480 with fx = fy = 320 px (90° horizontal
    /// field of view: the seed's wide-angle optics).
    pub camera: PinholeCamera,
    /// Distance from the hub (the rotation pivot) to the camera centre along the link, metres
    /// (the seed's `f + Z0`); default 0.2 m.
    pub pivot_m: f64,
    /// Half the angle between the two shots, radians; default 10°.
    pub beta_rad: f64,
    /// Nearest depth in front of a shot's camera that counts as seen, metres; default 0.3 m
    /// (a working distance: nearer fruit do not fit whole in the image, and there depth from
    /// disparity changes fastest, so the seed's robot would not aim from there).
    pub min_depth_m: f64,
}

impl Default for ArmRig {
    fn default() -> Self {
        Self {
            camera: PinholeCamera {
                width: 640,
                height: 480,
                fx: 320.0,
                fy: 320.0,
                cx: 319.5,
                cy: 239.5,
                distortion: None,
            },
            pivot_m: 0.2,
            beta_rad: 10f64.to_radians(),
            min_depth_m: 0.3,
        }
    }
}

impl ArmRig {
    /// The rig as the nominal model knows it: Eqs. 17–18 and triangulation on these shots
    /// (the left shot is its primary view, the right shot its stereo view, and its hub frame is
    /// this module's).
    ///
    /// # Errors
    /// As [`RotatedStereo::new`].
    pub fn stereo(&self) -> Result<RotatedStereo, ArmError> {
        RotatedStereo::new(self.beta_rad, self.pivot_m, self.camera)
    }

    /// Checks the rig ([`ArmRig::stereo`]), a camera without distortion and a finite positive
    /// minimum depth.
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] naming the first bad value.
    pub fn validate(&self) -> Result<(), ArmError> {
        self.stereo()?;
        if let Some(d) = self.camera.distortion {
            return Err(ArmError::InvalidParameter {
                name: "camera.distortion",
                value: d.k1,
                reason: "the rig's camera is the nominal one; give the lens's k1, k2 as calibration errors",
            });
        }
        if !(self.min_depth_m > 0.0 && self.min_depth_m.is_finite()) {
            return Err(ArmError::InvalidParameter {
                name: "min_depth_m",
                value: self.min_depth_m,
                reason: "must be finite and > 0",
            });
        }
        Ok(())
    }
}

/// Which of the two shots.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shot {
    /// Taken at α = −β (the seed's left image).
    Left,
    /// Taken at α = +β (the seed's right image).
    Right,
}

/// A target's pixel coordinates in the two shots, `(xL, yL)` and `(xR, yR)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ShotPixels {
    /// In the left shot, pixels.
    pub left: Point2<f64>,
    /// In the right shot, pixels.
    pub right: Point2<f64>,
}

impl ShotPixels {
    /// `[xL, yL, xR, yR]`, the network's input order.
    pub fn to_array(&self) -> [f64; 4] {
        [self.left.x, self.left.y, self.right.x, self.right.y]
    }
}

/// One target as the robot experiences it: where it is, what the shots see, what the encoders
/// read with the end of the link on it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmSample {
    /// The target, in the hub frame.
    pub target_in_hub: Point3<f64>,
    /// Its pixel coordinates in the two shots.
    pub pixels: ShotPixels,
    /// The encoder readings that put the end of the link on it.
    pub readings: ArmJoints,
}

/// One arm with its camera, limits and (hidden) calibration errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArmSimulation {
    /// Camera and shot geometry.
    pub rig: ArmRig,
    /// Joint limits (of the true joints).
    pub limits: ArmLimits,
    /// The robot's calibration errors; [`CalibrationErrors::none`] for the nominal model.
    pub errors: CalibrationErrors,
}

impl ArmSimulation {
    /// The robot with these errors, default limits.
    pub fn new(rig: ArmRig, errors: CalibrationErrors) -> Self {
        Self {
            rig,
            limits: ArmLimits::default(),
            errors,
        }
    }

    /// What the nominal model knows: the same rig and limits, no calibration errors.
    pub fn nominal(&self) -> Self {
        Self {
            errors: CalibrationErrors::none(),
            ..*self
        }
    }

    /// The encoder readings at which `shot` is taken: α = ∓β, θ = 90°, r at its minimum.
    pub fn shot_readings(&self, shot: Shot) -> ArmJoints {
        let alpha_rad = match shot {
            Shot::Left => -self.rig.beta_rad,
            Shot::Right => self.rig.beta_rad,
        };
        ArmJoints {
            alpha_rad,
            theta_rad: std::f64::consts::FRAC_PI_2,
            r_m: self.limits.r_m.0,
        }
    }

    /// The true joints when the encoders read `readings`.
    pub fn true_joints(&self, readings: &ArmJoints) -> ArmJoints {
        ArmJoints {
            alpha_rad: readings.alpha_rad - self.errors.alpha_offset_rad,
            theta_rad: readings.theta_rad - self.errors.theta_offset_rad,
            r_m: readings.r_m - self.errors.r_offset_m,
        }
    }

    /// The camera of `shot` in the hub frame: maps a point in the camera frame to the hub frame.
    pub fn camera_in_hub(&self, shot: Shot) -> Isometry3<f64> {
        let q = self.true_joints(&self.shot_readings(shot));
        let link = Rotation3::from_axis_angle(&Vector3::y_axis(), q.alpha_rad)
            * Rotation3::from_axis_angle(
                &Vector3::x_axis(),
                std::f64::consts::FRAC_PI_2 - q.theta_rad,
            );
        let centre_in_link = Vector3::new(0.0, 0.0, self.rig.pivot_m) + self.errors.camera_offset_m;
        Isometry3::from_parts(
            Translation3::from(link * centre_in_link),
            UnitQuaternion::from_rotation_matrix(&(link * self.errors.camera_rotation())),
        )
    }

    /// The target's pixel in `shot`, `None` when it is not in front of the camera by
    /// `min_depth_m` or falls outside the image.
    pub fn project_in(&self, shot: Shot, point_in_hub: &Point3<f64>) -> Option<Point2<f64>> {
        let p = self
            .camera_in_hub(shot)
            .inverse_transform_point(point_in_hub);
        if !(p.z >= self.rig.min_depth_m && p.coords.iter().all(|v| v.is_finite())) {
            return None;
        }
        let cam = PinholeCamera {
            distortion: self.errors.distortion(),
            ..self.rig.camera
        };
        let pixel = cam.project(&p)?;
        cam.contains(&pixel).then_some(pixel)
    }

    /// The target's pixels in both shots, `None` unless both see it.
    pub fn project(&self, point_in_hub: &Point3<f64>) -> Option<ShotPixels> {
        Some(ShotPixels {
            left: self.project_in(Shot::Left, point_in_hub)?,
            right: self.project_in(Shot::Right, point_in_hub)?,
        })
    }

    /// The encoder readings that put the end of the link on the target (exact inverse kinematics
    /// plus the encoder offsets); `None` when the true joints are outside the limits.
    pub fn encoder_readings(&self, point_in_hub: &Point3<f64>) -> Option<ArmJoints> {
        let q = ArmJoints::reaching(point_in_hub).filter(|q| self.limits.allows(q))?;
        Some(ArmJoints {
            alpha_rad: q.alpha_rad + self.errors.alpha_offset_rad,
            theta_rad: q.theta_rad + self.errors.theta_offset_rad,
            r_m: q.r_m + self.errors.r_offset_m,
        })
    }

    /// Where the end of the link is when the encoders read `readings` (forward kinematics of
    /// the true robot).
    pub fn end_position(&self, readings: &ArmJoints) -> Point3<f64> {
        self.true_joints(readings).to_point_in_hub()
    }

    /// The target as the robot experiences it; `None` unless the arm reaches it and both shots
    /// see it.
    pub fn sample(&self, point_in_hub: &Point3<f64>) -> Option<ArmSample> {
        Some(ArmSample {
            target_in_hub: *point_in_hub,
            pixels: self.project(point_in_hub)?,
            readings: self.encoder_readings(point_in_hub)?,
        })
    }

    /// The training set of the seed: a regular grid of `counts = [nα, nθ, nr]` targets over the
    /// joint ranges (end points included), kept where the arm reaches them and both shots see
    /// them.
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] when a count is below 2.
    pub fn grid_samples(&self, counts: [usize; 3]) -> Result<Vec<ArmSample>, ArmError> {
        if let Some(&n) = counts.iter().find(|&&n| n < 2) {
            return Err(ArmError::InvalidParameter {
                name: "grid counts",
                value: n as f64,
                reason: "each joint needs at least 2 grid values",
            });
        }
        let steps = |(lo, hi): (f64, f64), n: usize| {
            (0..n).map(move |i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
        };
        let l = &self.limits;
        let mut samples = Vec::new();
        for alpha_rad in steps(l.alpha_rad, counts[0]) {
            for theta_rad in steps(l.theta_rad, counts[1]) {
                for r_m in steps(l.r_m, counts[2]) {
                    let target = ArmJoints {
                        alpha_rad,
                        theta_rad,
                        r_m,
                    }
                    .to_point_in_hub();
                    samples.extend(self.sample(&target));
                }
            }
        }
        Ok(samples)
    }

    /// `n` targets drawn uniformly over the joint ranges (so off any grid), kept where the arm
    /// reaches them and both shots see them; same seed, same targets.
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] when 1000 × `n` draws do not find `n` seen targets.
    pub fn random_samples(&self, n: usize, seed: u64) -> Result<Vec<ArmSample>, ArmError> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let l = &self.limits;
        let mut samples = Vec::with_capacity(n);
        for _ in 0..n.saturating_mul(1000) {
            if samples.len() == n {
                break;
            }
            let target = ArmJoints {
                alpha_rad: rng.gen_range(l.alpha_rad.0..=l.alpha_rad.1),
                theta_rad: rng.gen_range(l.theta_rad.0..=l.theta_rad.1),
                r_m: rng.gen_range(l.r_m.0..=l.r_m.1),
            }
            .to_point_in_hub();
            samples.extend(self.sample(&target));
        }
        if samples.len() < n {
            return Err(ArmError::InvalidParameter {
                name: "random targets",
                value: n as f64,
                reason: "the working space seen by both shots is too small to draw them",
            });
        }
        Ok(samples)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CalibrationMagnitudes;

    fn ideal() -> ArmSimulation {
        ArmSimulation::new(ArmRig::default(), CalibrationErrors::none())
    }

    /// Back-projects a pixel of `shot` at the given depth in that shot's camera (no distortion).
    fn back_project(
        sim: &ArmSimulation,
        shot: Shot,
        pixel: &Point2<f64>,
        depth: f64,
    ) -> Point3<f64> {
        let p = sim.rig.camera.back_project(pixel.x, pixel.y, depth);
        sim.camera_in_hub(shot) * p
    }

    #[test]
    fn projection_round_trip_without_calibration_errors() {
        let sim = ideal();
        let samples = sim.grid_samples([9, 7, 11]).unwrap();
        assert!(samples.len() > 100, "{} seen grid targets", samples.len());
        for s in &samples {
            for (shot, pixel) in [(Shot::Left, s.pixels.left), (Shot::Right, s.pixels.right)] {
                let depth = sim
                    .camera_in_hub(shot)
                    .inverse_transform_point(&s.target_in_hub)
                    .z;
                let back = back_project(&sim, shot, &pixel, depth);
                assert!((back - s.target_in_hub).norm() < 1e-12, "{s:?}");
            }
            // Exact kinematics: readings are the joints, and they reach the target.
            assert!((sim.end_position(&s.readings) - s.target_in_hub).norm() < 1e-12);
        }
    }

    #[test]
    fn ideal_shots_are_the_stereo_rigs_two_views() {
        let sim = ideal();
        let d = sim.rig.pivot_m;
        let b = sim.rig.beta_rad;
        let left = sim.camera_in_hub(Shot::Left);
        let right = sim.camera_in_hub(Shot::Right);
        // Centres d from the hub at ∓β; the right shot is the left turned 2β to the right.
        let cl = left.translation.vector;
        assert!((cl - Vector3::new(-d * b.sin(), 0.0, d * b.cos())).norm() < 1e-12);
        let turn = (left.rotation.inverse() * right.rotation).scaled_axis();
        assert!((turn - Vector3::new(0.0, 2.0 * b, 0.0)).norm() < 1e-12);
        // A point straight ahead appears left of centre in the right shot, right in the left.
        let px = sim.project(&Point3::new(0.0, 0.0, 1.0)).unwrap();
        assert!(px.left.x > sim.rig.camera.cx && px.right.x < sim.rig.camera.cx);
    }

    #[test]
    fn calibration_errors_move_pixels_and_readings_but_keep_the_end_on_the_target() {
        let errors = CalibrationErrors::draw(&CalibrationMagnitudes::default(), 3);
        let sim = ArmSimulation::new(ArmRig::default(), errors);
        let target = Point3::new(0.1, -0.05, 0.8);
        let true_sample = sim.sample(&target).unwrap();
        let nominal_sample = sim.nominal().sample(&target).unwrap();
        assert!((true_sample.pixels.left - nominal_sample.pixels.left).norm() > 1.0);
        assert!((true_sample.readings.r_m - nominal_sample.readings.r_m).abs() > 1e-3);
        assert!((sim.end_position(&true_sample.readings) - target).norm() < 1e-12);
        // The nominal readings miss the target on the true robot.
        assert!((sim.end_position(&nominal_sample.readings) - target).norm() > 1e-3);
    }

    #[test]
    fn random_samples_are_seeded_seen_and_bad_grids_rejected() {
        let sim = ideal();
        let a = sim.random_samples(50, 1).unwrap();
        assert_eq!(a, sim.random_samples(50, 1).unwrap());
        assert_ne!(a, sim.random_samples(50, 2).unwrap());
        assert!(a.iter().all(|s| sim.project(&s.target_in_hub).is_some()));
        assert!(sim.grid_samples([1, 5, 5]).is_err());
    }
}
