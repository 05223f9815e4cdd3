//! Seed 004's second arm in synthetic data: arm B carries its own camera rig, so every frame is
//! also rendered from arm B's two shots, and every fruit's truth says which arm can reach it.
//!
//! Frames: arm A's hub is the pivot of the primary view's rig ([`StereoRig`]); its hub frame is
//! the rig's bisector frame (`pomona_arm::RotatedStereo`: origin at the pivot, z along the
//! bisector of the two shots). Arm B's hub sits at [`TwoArmCell::b_hub_in_a`] in arm A's hub
//! frame with the same orientation, and its rig is arm A's moved with it, so arm B's cameras are
//! arm A's translated by that offset (expressed in the primary camera frame).
//!
//! Truth: with two arms, each fruit of every view's truth carries
//! `"reach": {"a": joints or null, "b": joints or null}` — the [`ArmJoints`] with which each
//! arm reaches the fruit centre within the cell's limits ([`TwoArmCell::reach`]), `null` when it
//! cannot.

use nalgebra::{Isometry3, Point3, Translation3};
use pomona_arm::{ArmJoints, RotatedStereo, TwoArmCell};
use pomona_core::{FrameTruth, PinholeCamera};

use crate::{StereoRig, SynthError};

/// Folder of arm B's views (its primary view; its second shot in `arm-b/stereo/`).
pub const ARM_B_DATASET: &str = "arm-b";

/// The two-arm geometry of a dataset: arm A's rig and the cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoArmViews {
    rig: RotatedStereo,
    cell: TwoArmCell,
}

impl TwoArmViews {
    /// The geometry of `cell` with both arms carrying `rig` and `camera`.
    ///
    /// # Errors
    /// [`SynthError::InvalidParameter`] for an invalid rig or camera.
    pub fn new(
        rig: &StereoRig,
        camera: &PinholeCamera,
        cell: TwoArmCell,
    ) -> Result<Self, SynthError> {
        rig.validate()?;
        let rig = RotatedStereo::new(rig.beta_rad, rig.pivot_distance_m, *camera).map_err(|e| {
            SynthError::InvalidParameter {
                name: "stereo rig",
                reason: e.to_string(),
            }
        })?;
        if !cell.b_hub_in_a.iter().all(|v| v.is_finite()) {
            return Err(SynthError::InvalidParameter {
                name: "arm spacing",
                reason: "arm B's hub must be finite".to_string(),
            });
        }
        Ok(Self { rig, cell })
    }

    /// Arm B's primary camera pose: maps scene points (arm A's primary camera frame) into it.
    pub fn arm_b_from_scene(&self) -> Isometry3<f64> {
        let offset_in_camera = self.rig.hub_from_camera().inverse().rotation * self.cell.b_hub_in_a;
        Isometry3::from_parts(Translation3::from(-offset_in_camera), Default::default())
    }

    /// Arm B's second shot: maps scene points into it.
    pub fn arm_b_stereo_from_scene(&self) -> Isometry3<f64> {
        self.rig.stereo_from_camera() * self.arm_b_from_scene()
    }

    /// The joints with which arm A and arm B reach `point_in_scene` (arm A's primary camera
    /// frame), `None` for an arm that cannot.
    pub fn reach(&self, point_in_scene: &Point3<f64>) -> [Option<ArmJoints>; 2] {
        self.cell.reach(&self.rig.point_in_hub(point_in_scene))
    }

    /// Adds `reach` to every fruit of `truth`, whose centres are in the frame that
    /// `view_from_scene` maps scene points into.
    pub fn annotate(&self, truth: &mut FrameTruth, view_from_scene: &Isometry3<f64>) {
        for fruit in &mut truth.fruits {
            let Some(center) = fruit.center_m else {
                continue;
            };
            let [a, b] = self.reach(&(view_from_scene.inverse() * center));
            let joints = |q: Option<ArmJoints>| {
                q.and_then(|q| serde_json::to_value(q).ok())
                    .unwrap_or(serde_json::Value::Null)
            };
            fruit.extra.insert(
                "reach".to_string(),
                serde_json::json!({"a": joints(a), "b": joints(b)}),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn views() -> TwoArmViews {
        let camera = PinholeCamera::new(64, 48, 50.0, 50.0, 31.5, 23.5).unwrap();
        TwoArmViews::new(&StereoRig::default(), &camera, TwoArmCell::default()).unwrap()
    }

    #[test]
    fn arm_b_sees_from_its_hub_offset() {
        let v = views();
        // Arm B's hub, placed in the scene, lands where arm A's hub lands in arm A's frame.
        let hub_b_in_scene = v.rig.hub_from_camera().inverse() * Point3::from(v.cell.b_hub_in_a);
        let pivot = v.rig.pivot_in_camera();
        assert!((v.arm_b_from_scene() * hub_b_in_scene - pivot).norm() < 1e-12);
        // Same orientation.
        let d = v.arm_b_from_scene().rotation * Vector3::z();
        assert!((d - Vector3::z()).norm() < 1e-12);
    }

    #[test]
    fn reach_follows_the_cell_and_is_recorded_per_fruit() {
        let v = views();
        // One metre straight ahead of arm A's hub: A reaches it level; B (0.6 m to the right)
        // would have to turn 31° left, inside ±40°.
        let ahead = v.rig.hub_from_camera().inverse() * Point3::new(0.0, 0.0, 1.0);
        let [a, b] = v.reach(&ahead);
        let a = a.unwrap();
        assert!(a.alpha_rad.abs() < 1e-12 && (a.r_m - 1.0).abs() < 1e-12);
        assert!(b.unwrap().alpha_rad < 0.0);
        // Far to the left: only A.
        let left = v.rig.hub_from_camera().inverse() * Point3::new(-0.5, 0.0, 0.8);
        let [a, b] = v.reach(&left);
        assert!(a.is_some() && b.is_none());
        let mut truth: FrameTruth = serde_json::from_value(serde_json::json!({
            "complete": true,
            "fruits": [{"id": "0", "kind": "orange", "center_m": [left.x, left.y, left.z]}]
        }))
        .unwrap();
        v.annotate(&mut truth, &Isometry3::identity());
        let reach = &truth.fruits[0].extra["reach"];
        assert!(reach["b"].is_null() && reach["a"]["r_m"].as_f64().unwrap() > 0.9);
        // The same fruit seen from arm B's view gives the same answer.
        let pose = v.arm_b_from_scene();
        let mut seen_by_b = truth.clone();
        seen_by_b.fruits[0].center_m = Some(pose * left);
        seen_by_b.fruits[0].extra.clear();
        v.annotate(&mut seen_by_b, &pose);
        assert_eq!(seen_by_b.fruits[0].extra["reach"], *reach);
    }
}
