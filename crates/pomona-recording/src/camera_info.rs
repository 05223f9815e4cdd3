//! `sensor_msgs/CameraInfo`: the intrinsics the driver publishes beside each image, and their
//! conversion to Pomona's [`PinholeCamera`].
//!
//! The camera is read from `K` (fx = K[0], cx = K[2], fy = K[4], cy = K[5]). Of the distortion
//! models, `plumb_bob` and `rational_polynomial` whose k1, k2 are the only nonzero coefficients
//! map to Pomona's [`RadialDistortion`]; all-zero coefficients (or none) mean no distortion, as
//! RealSense colour streams report; any other nonzero coefficient is an error naming the model,
//! because silently dropping it would misplace every point.

use pomona_core::{PinholeCamera, RadialDistortion};
use serde::{Deserialize, Serialize};

use crate::cdr::{CdrError, CdrReader, CdrWriter};
use crate::message_fields::{FieldReader, FieldWriter};
use crate::ros1::{Ros1Reader, Ros1Writer};
use crate::{Header, Serialization};

/// The ROS schema name of [`CameraInfo`].
pub const CAMERA_INFO_SCHEMA: &str = "sensor_msgs/msg/CameraInfo";

/// `sensor_msgs/msg/RegionOfInterest`.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct RegionOfInterest {
    /// Leftmost column.
    pub x_offset: u32,
    /// Topmost row.
    pub y_offset: u32,
    /// Rows (0: the full image).
    pub height: u32,
    /// Columns (0: the full image).
    pub width: u32,
    /// Whether the region is to be rectified.
    pub do_rectify: bool,
}

/// `sensor_msgs/msg/CameraInfo`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct CameraInfo {
    /// Stamp and frame.
    pub header: Header,
    /// Rows of the calibrated image.
    pub height: u32,
    /// Columns of the calibrated image.
    pub width: u32,
    /// Distortion model name (`plumb_bob`, `rational_polynomial`, `equidistant`, ...).
    pub distortion_model: String,
    /// Distortion coefficients (plumb_bob: k1, k2, t1, t2, k3).
    pub d: Vec<f64>,
    /// Intrinsic matrix, row-major.
    pub k: [f64; 9],
    /// Rectification rotation, row-major.
    pub r: [f64; 9],
    /// Projection matrix, row-major 3×4.
    pub p: [f64; 12],
    /// Horizontal binning.
    pub binning_x: u32,
    /// Vertical binning.
    pub binning_y: u32,
    /// Region of interest.
    pub roi: RegionOfInterest,
}

/// Why camera info does not give a Pomona camera (the caller adds file, topic and stamp).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CameraInfoError {
    /// Coefficients Pomona's radial model cannot represent.
    #[error(
        "distortion model `{model}` with coefficients {d:?}: Pomona models only radial k1, k2 \
         (plumb_bob or rational_polynomial with the other coefficients zero)"
    )]
    Distortion {
        /// The model name.
        model: String,
        /// Its coefficients.
        d: Vec<f64>,
    },
    /// K does not give a valid camera.
    #[error("K = {k:?} for a {width}×{height} image is not a valid pinhole camera: {source}")]
    Intrinsics {
        /// The matrix, row-major.
        k: Vec<f64>,
        /// Columns.
        width: u32,
        /// Rows.
        height: u32,
        /// What is wrong.
        source: pomona_core::CoreError,
    },
}

impl CameraInfo {
    /// Reads a CDR camera-info message (ROS 2).
    ///
    /// # Errors
    /// [`CdrError`] for a truncated or malformed payload.
    pub fn read(payload: &[u8]) -> Result<Self, CdrError> {
        Self::read_as(payload, Serialization::Cdr)
    }

    /// Reads a camera-info message in `serialization`.
    ///
    /// # Errors
    /// [`CdrError`] for a truncated or malformed payload.
    pub fn read_as(payload: &[u8], serialization: Serialization) -> Result<Self, CdrError> {
        match serialization {
            Serialization::Cdr => Self::decode(&mut CdrReader::new(payload)?),
            Serialization::Ros1 => Self::decode(&mut Ros1Reader::new(payload)),
        }
    }

    /// Reads the fields from `r`. ROS 1 names the arrays `D`, `K`, `R`, `P`; the layout is the
    /// same.
    ///
    /// # Errors
    /// [`CdrError`] for a truncated or malformed payload.
    pub fn decode<'a>(r: &mut impl FieldReader<'a>) -> Result<Self, CdrError> {
        let (header, height, width) = r.sized_header()?;
        Ok(Self {
            header,
            height,
            width,
            distortion_model: r.string("distortion_model")?,
            d: r.f64_sequence("d")?,
            k: r.f64_array("k")?,
            r: r.f64_array("r")?,
            p: r.f64_array("p")?,
            binning_x: r.u32("binning_x")?,
            binning_y: r.u32("binning_y")?,
            roi: RegionOfInterest {
                x_offset: r.u32("roi.x_offset")?,
                y_offset: r.u32("roi.y_offset")?,
                height: r.u32("roi.height")?,
                width: r.u32("roi.width")?,
                do_rectify: r.u8("roi.do_rectify")? != 0,
            },
        })
    }

    /// The CDR payload (ROS 2).
    pub fn to_cdr(&self) -> Vec<u8> {
        let mut w = CdrWriter::new();
        self.encode(&mut w);
        w.into_bytes()
    }

    /// The ROS 1 payload.
    pub fn to_ros1(&self) -> Vec<u8> {
        let mut w = Ros1Writer::new();
        self.encode(&mut w);
        w.into_bytes()
    }

    /// Writes the fields to `w`.
    pub fn encode(&self, w: &mut impl FieldWriter) {
        w.sized_header(&self.header, self.height, self.width);
        w.string(&self.distortion_model);
        w.f64_sequence(&self.d);
        w.f64_array(&self.k);
        w.f64_array(&self.r);
        w.f64_array(&self.p);
        w.u32(self.binning_x);
        w.u32(self.binning_y);
        w.u32(self.roi.x_offset);
        w.u32(self.roi.y_offset);
        w.u32(self.roi.height);
        w.u32(self.roi.width);
        w.u8(u8::from(self.roi.do_rectify));
    }

    /// The camera info a driver would publish for `camera` (`plumb_bob`, its k1 and k2).
    pub fn from_camera(header: Header, camera: &PinholeCamera) -> Self {
        let (k1, k2) = camera.distortion.map_or((0.0, 0.0), |d| (d.k1, d.k2));
        let c = camera;
        Self {
            header,
            height: c.height,
            width: c.width,
            distortion_model: "plumb_bob".to_owned(),
            d: vec![k1, k2, 0.0, 0.0, 0.0],
            k: [c.fx, 0.0, c.cx, 0.0, c.fy, c.cy, 0.0, 0.0, 1.0],
            r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            p: [
                c.fx, 0.0, c.cx, 0.0, 0.0, c.fy, c.cy, 0.0, 0.0, 0.0, 1.0, 0.0,
            ],
            binning_x: 0,
            binning_y: 0,
            roi: RegionOfInterest::default(),
        }
    }

    /// The pinhole camera (from `K`) with its radial distortion.
    ///
    /// # Errors
    /// [`CameraInfoError::Distortion`] for nonzero coefficients other than `plumb_bob` /
    /// `rational_polynomial` k1, k2; [`CameraInfoError::Intrinsics`] for an invalid `K` or size.
    pub fn to_camera(&self) -> Result<PinholeCamera, CameraInfoError> {
        self.check_distortion()?;
        let invalid = |source| CameraInfoError::Intrinsics {
            k: self.k.to_vec(),
            width: self.width,
            height: self.height,
            source,
        };
        let distortion = self.radial_distortion().map_err(invalid)?;
        let k = &self.k;
        PinholeCamera::new(self.width, self.height, k[0], k[4], k[2], k[5])
            .and_then(|c| c.with_distortion(distortion))
            .map_err(invalid)
    }

    /// k1, k2 when nonzero (`None` when every coefficient is zero or there are none).
    fn radial_distortion(&self) -> Result<Option<RadialDistortion>, pomona_core::CoreError> {
        let k1 = self.d.first().copied().unwrap_or(0.0);
        let k2 = self.d.get(1).copied().unwrap_or(0.0);
        if k1 == 0.0 && k2 == 0.0 {
            return Ok(None);
        }
        let d = RadialDistortion { k1, k2 };
        d.validate()?;
        Ok(Some(d))
    }

    /// Whether the coefficients fit Pomona's radial model.
    fn check_distortion(&self) -> Result<(), CameraInfoError> {
        let radial_model = matches!(
            self.distortion_model.as_str(),
            // librealsense's name for the same forward model (k1, k2, p1, p2, k3).
            "plumb_bob" | "rational_polynomial" | "Brown Conrady"
        );
        let only_radial = self.d.iter().skip(2).all(|&c| c == 0.0);
        let any = self.d.iter().any(|&c| c != 0.0);
        if !any || (radial_model && only_radial) {
            Ok(())
        } else {
            Err(CameraInfoError::Distortion {
                model: self.distortion_model.clone(),
                d: self.d.clone(),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> PinholeCamera {
        PinholeCamera::new(640, 480, 615.5, 615.25, 320.5, 240.25).unwrap()
    }

    #[test]
    fn round_trips_and_gives_the_camera_back() {
        for distortion in [None, Some(RadialDistortion { k1: -0.2, k2: 0.05 })] {
            let cam = camera().with_distortion(distortion).unwrap();
            let info = CameraInfo::from_camera(Header::at(7, "cam"), &cam);
            let back = CameraInfo::read(&info.to_cdr()).unwrap();
            assert_eq!(back, info);
            assert_eq!(back.to_camera().unwrap(), cam);
            let ros1 = CameraInfo::read_as(&info.to_ros1(), Serialization::Ros1).unwrap();
            assert_eq!(ros1, info);
        }
    }

    #[test]
    fn unsupported_distortion_is_named() {
        let mut info = CameraInfo::from_camera(Header::default(), &camera());
        info.distortion_model = "equidistant".into();
        assert!(
            info.to_camera().is_ok(),
            "all-zero coefficients are no distortion"
        );
        info.d = vec![0.1, 0.0, 0.0, 0.0];
        let e = info.to_camera().unwrap_err().to_string();
        assert!(e.contains("equidistant"), "{e}");
        info.distortion_model = "plumb_bob".into();
        info.d = vec![0.1, 0.0, 0.001, 0.0, 0.0];
        assert!(
            info.to_camera().is_err(),
            "tangential terms are not modelled"
        );
        info.d = vec![];
        info.k[0] = 0.0;
        assert!(matches!(
            info.to_camera(),
            Err(CameraInfoError::Intrinsics { .. })
        ));
    }
}
