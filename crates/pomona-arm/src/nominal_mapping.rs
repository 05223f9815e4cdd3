//! The mapping the seed replaces with a network: locate the target from its two image positions
//! by the rotated-camera equations (Eqs. 17–18, [`RotatedStereo::locate_paper`]) and turn the
//! point into encoder readings by the exact inverse kinematics of the nominal arm — both under
//! the nominal model (no lens distortion, camera exactly on the link, encoders without offsets).
//! It is exact on the ideal robot and the baseline `pomona arm eval` compares the network with.

use crate::{ArmError, ArmJoints, RotatedStereo, ShotPixels};

/// Eq. 18 + exact nominal kinematics on one rig.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NominalMapping {
    /// The rig as designed; the left shot is its primary view.
    pub stereo: RotatedStereo,
}

impl NominalMapping {
    /// The nominal encoder readings for a target seen at `pixels`.
    ///
    /// # Errors
    /// [`ArmError::NoStereoPoint`] when Eq. 18 gives no point in front of both shots (or the
    /// point is the hub itself).
    pub fn readings(&self, pixels: &ShotPixels) -> Result<ArmJoints, ArmError> {
        let in_camera = self.stereo.locate_paper(&pixels.left, &pixels.right)?;
        ArmJoints::reaching(&self.stereo.point_in_hub(&in_camera)).ok_or(ArmError::NoStereoPoint {
            method: "paper",
            primary: [pixels.left.x, pixels.left.y],
            stereo: [pixels.right.x, pixels.right.y],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{
        ArmRig, ArmSimulation, CalibrationErrors, CalibrationMagnitudes, EndPositionError,
    };

    #[test]
    fn exact_on_the_ideal_robot_and_off_with_calibration_errors() {
        let rig = ArmRig::default();
        let mapping = NominalMapping {
            stereo: rig.stereo().unwrap(),
        };
        let ideal = ArmSimulation::new(rig, CalibrationErrors::none());
        let samples = ideal.random_samples(200, 9).unwrap();
        let exact = EndPositionError::measure(&ideal, &samples, |p| mapping.readings(p).ok());
        let exact = exact.unwrap();
        assert!(exact.failed == 0 && exact.max < 1e-6, "{exact:?}");
        let errors = CalibrationErrors::draw(&CalibrationMagnitudes::default(), 9);
        let real = ArmSimulation::new(rig, errors);
        let samples = real.random_samples(200, 9).unwrap();
        let off = EndPositionError::measure(&real, &samples, |p| mapping.readings(p).ok());
        assert!(off.unwrap().median > 5.0, "{off:?}");
    }
}
