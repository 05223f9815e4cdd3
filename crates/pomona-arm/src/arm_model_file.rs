//! The file `pomona arm train` writes and `pomona arm eval` reads: the trained joint network
//! and everything needed to rebuild the simulated robot it was trained on.
//!
//! ```json
//! {"format": "pomona-arm-model", "version": 1,
//!  "calibration_seed": 0, "magnitudes": {...}, "rig": {...}, "limits": {...},
//!  "grid": [nα, nθ, nr], "training": {...}, "report": {...}, "network": {...}}
//! ```
//!
//! The robot's hidden calibration errors are not stored, only how they were drawn
//! (`magnitudes`, `calibration_seed`), so evaluation rebuilds the same robot. `format` and
//! `version` are checked before the rest is read, so another file fails with a clear message
//! rather than a missing-field error. Written atomically (`pomona_io::write_json`).

use std::path::Path;

use pomona_io::read_budget::{read_json_text, MAX_JSON_FILE_BYTES};
use serde::{Deserialize, Serialize};

use crate::{
    ArmError, ArmLimits, ArmRig, ArmSimulation, CalibrationErrors, CalibrationMagnitudes,
    JointNetwork, NetworkTraining, TrainingReport,
};

/// Value of the `format` key.
pub const ARM_MODEL_FORMAT: &str = "pomona-arm-model";
/// Format version this build writes and reads.
pub const ARM_MODEL_VERSION: u32 = 1;

/// Contents of an arm model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArmModelFile {
    /// Always [`ARM_MODEL_FORMAT`].
    pub format: String,
    /// Always [`ARM_MODEL_VERSION`] for files this build writes.
    pub version: u32,
    /// Seed the robot's calibration errors were drawn from.
    pub calibration_seed: u64,
    /// Sizes of the calibration errors (all zero: an ideal robot).
    pub magnitudes: CalibrationMagnitudes,
    /// Camera and shot geometry.
    pub rig: ArmRig,
    /// Joint limits.
    pub limits: ArmLimits,
    /// Training grid `[nα, nθ, nr]`.
    pub grid: [usize; 3],
    /// How the network was trained.
    pub training: NetworkTraining,
    /// What training reached.
    pub report: TrainingReport,
    /// The network.
    pub network: JointNetwork,
}

#[derive(Deserialize)]
struct Head {
    format: Option<serde_json::Value>,
    version: Option<serde_json::Value>,
}

impl ArmModelFile {
    /// The simulated robot the network was trained on (same calibration errors).
    pub fn simulation(&self) -> ArmSimulation {
        ArmSimulation {
            rig: self.rig,
            limits: self.limits,
            errors: CalibrationErrors::draw(&self.magnitudes, self.calibration_seed),
        }
    }

    /// Checks every part of a file read from disk.
    ///
    /// # Errors
    /// [`ArmError::InvalidParameter`] naming the first bad value.
    pub fn validate(&self) -> Result<(), ArmError> {
        self.magnitudes.validate()?;
        self.rig.validate()?;
        self.magnitudes.validate_lens(&self.rig.camera)?;
        self.limits.validate()?;
        self.network.validate()?;
        if self.network.hidden != self.training.hidden {
            return Err(ArmError::InvalidParameter {
                name: "network.hidden",
                value: self.network.hidden as f64,
                reason: "must equal training.hidden",
            });
        }
        Ok(())
    }

    /// Writes the file atomically (pretty JSON).
    ///
    /// # Errors
    /// [`ArmError::ModelWrite`]; whatever was at `path` is left untouched on failure.
    pub fn save(&self, path: &Path) -> Result<(), ArmError> {
        pomona_io::write_json(path, self).map_err(|source| ArmError::ModelWrite { source })
    }

    /// Reads and checks a model file.
    ///
    /// # Errors
    /// [`ArmError::ModelRead`] (missing, unreadable, over 2 MiB), [`ArmError::ModelJson`]
    /// (malformed JSON or a wrong field), [`ArmError::ModelVersion`] (another format or
    /// version), [`ArmError::ModelInvalid`] (impossible values); each names the file.
    pub fn load(path: &Path) -> Result<Self, ArmError> {
        let text =
            read_json_text(path, MAX_JSON_FILE_BYTES).map_err(|source| ArmError::ModelRead {
                path: path.to_owned(),
                source,
            })?;
        let json_error = |source| ArmError::ModelJson {
            path: path.to_owned(),
            source,
        };
        let head: Head = serde_json::from_str(&text).map_err(json_error)?;
        let format_ok = head.format.as_ref().and_then(|f| f.as_str()) == Some(ARM_MODEL_FORMAT);
        let version_ok =
            head.version.as_ref().and_then(|v| v.as_u64()) == Some(u64::from(ARM_MODEL_VERSION));
        if !(format_ok && version_ok) {
            let show =
                |v: Option<serde_json::Value>| v.map_or("nothing".to_owned(), |v| v.to_string());
            return Err(ArmError::ModelVersion {
                path: path.to_owned(),
                found: format!(
                    "format {} version {}",
                    show(head.format),
                    show(head.version)
                ),
                expected: ARM_MODEL_FORMAT,
                supported: ARM_MODEL_VERSION,
            });
        }
        let model: Self = serde_json::from_str(&text).map_err(json_error)?;
        model.validate().map_err(|e| ArmError::ModelInvalid {
            path: path.to_owned(),
            source: Box::new(e),
        })?;
        Ok(model)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::LinearScaling;

    fn model() -> ArmModelFile {
        ArmModelFile {
            format: ARM_MODEL_FORMAT.to_owned(),
            version: ARM_MODEL_VERSION,
            calibration_seed: 3,
            magnitudes: CalibrationMagnitudes::default(),
            rig: ArmRig::default(),
            limits: ArmLimits::default(),
            grid: [5, 4, 6],
            training: NetworkTraining::default(),
            report: TrainingReport {
                initial_rms: 0.5,
                final_rms: 1e-4,
                iterations: 10,
                samples: 40,
            },
            network: JointNetwork {
                hidden: 8,
                weights: (0..67).map(|i| f64::from(i) * 0.1 + 1.0 / 3.0).collect(),
                input_scaling: LinearScaling {
                    centre: vec![320.0, 240.0, 320.0, 240.0],
                    half_range: vec![300.0, 200.0, 300.0, 200.0],
                },
                output_scaling: LinearScaling {
                    centre: vec![0.0, 1.5, 0.8],
                    half_range: vec![0.7, 0.5, 0.5],
                },
            },
        }
    }

    #[test]
    fn round_trip_is_bit_exact_and_rebuilds_the_same_robot() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("arm.json");
        let m = model();
        m.save(&path).unwrap();
        let back = ArmModelFile::load(&path).unwrap();
        assert_eq!(back, m);
        assert_eq!(back.simulation(), m.simulation());
    }

    #[test]
    fn bad_files_give_errors_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.json");
        let message = |text: &str| {
            std::fs::write(&path, text).unwrap();
            let e = ArmModelFile::load(&path).unwrap_err().to_string();
            assert!(e.contains("bad.json"), "{e}");
            e
        };
        assert!(message("{not json").contains("not an arm model file"));
        assert!(message(r#"{"format": "pomona-model", "version": 1}"#).contains("pomona-arm-model"));
        let mut v = serde_json::to_value(model()).unwrap();
        v["version"] = 2.into();
        assert!(message(&v.to_string()).contains("version 2"));
        let mut v = serde_json::to_value(model()).unwrap();
        v["network"]["weights"] = serde_json::json!([1.0, 2.0]);
        assert!(message(&v.to_string()).contains("weights"));
        let mut v = serde_json::to_value(model()).unwrap();
        v.as_object_mut().unwrap().remove("rig");
        assert!(message(&v.to_string()).contains("rig"));
        let missing = ArmModelFile::load(&dir.path().join("absent.json")).unwrap_err();
        assert!(missing.to_string().contains("absent.json"));
    }
}
