//! Intrinsics of the depth cameras users most often own, so `--camera kinect-v2` renders frames
//! with the right size and field of view. Colour and depth are rendered registered on one grid,
//! and the principal point sits at the image centre (no distortion).

use pomona_core::PinholeCamera;
use serde::{Deserialize, Serialize};

/// A named camera model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CameraPreset {
    /// Microsoft Kinect v2 depth camera: 512×424, fx = fy = 365 px (about 70° HFOV).
    KinectV2,
    /// MESA SwissRanger SR4000 time-of-flight camera: 176×144, 43.6° horizontal field of view.
    Sr4000,
    /// Intel RealSense D435 (depth aligned to colour): 640×480, fx = fy = 615 px.
    D435,
    /// Microsoft Azure Kinect, colour-registered 1080p: 1920×1080, fx = fy = 917 px.
    AzureKinect,
}

impl CameraPreset {
    /// All presets, in CLI order.
    pub const ALL: [CameraPreset; 4] = [
        CameraPreset::KinectV2,
        CameraPreset::Sr4000,
        CameraPreset::D435,
        CameraPreset::AzureKinect,
    ];

    /// The name used on the command line and in `synth.json`.
    pub fn name(self) -> &'static str {
        match self {
            CameraPreset::KinectV2 => "kinect-v2",
            CameraPreset::Sr4000 => "sr4000",
            CameraPreset::D435 => "d435",
            CameraPreset::AzureKinect => "azure-kinect",
        }
    }

    /// The pinhole intrinsics of this preset, principal point at the image centre.
    pub fn camera(self) -> PinholeCamera {
        let (width, height, f) = match self {
            CameraPreset::KinectV2 => (512, 424, 365.0),
            // 43.6° HFOV: fx = (176 / 2) / tan(21.8°) ≈ 220.0 px.
            CameraPreset::Sr4000 => (176, 144, 88.0 / 21.8_f64.to_radians().tan()),
            CameraPreset::D435 => (640, 480, 615.0),
            CameraPreset::AzureKinect => (1920, 1080, 917.0),
        };
        PinholeCamera {
            width,
            height,
            fx: f,
            fy: f,
            cx: (width as f64 - 1.0) / 2.0,
            cy: (height as f64 - 1.0) / 2.0,
            distortion: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_are_valid_and_match_their_datasheets() {
        for p in CameraPreset::ALL {
            p.camera().validate().unwrap();
        }
        let sr = CameraPreset::Sr4000.camera();
        assert!((sr.horizontal_fov_rad().to_degrees() - 43.6).abs() < 0.05);
        assert_eq!((sr.width, sr.height), (176, 144));
        assert_eq!(CameraPreset::KinectV2.camera().fx, 365.0);
        assert_eq!(CameraPreset::AzureKinect.camera().width, 1920);
    }
}
