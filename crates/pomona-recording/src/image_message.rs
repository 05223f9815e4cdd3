//! `sensor_msgs/Image`: one raw image (colour or depth) as the ROS driver publishes it, and its
//! conversion to Pomona's [`ColorImage`] and [`DepthImage`].
//!
//! Supported encodings: colour `rgb8`, `bgr8`, `rgba8` and `bgra8` (alpha dropped); depth `16UC1` (millimetres, 0 = no depth, as
//! the RealSense and Kinect drivers publish) and `32FC1` (metres; NaN, 0 and negatives = no
//! depth). `step` and the data length are checked against width and height before any pixel is
//! read; `is_bigendian` is honoured for the multi-byte depth encodings.

use pomona_core::{ColorImage, DepthImage};
use serde::{Deserialize, Serialize};

use crate::cdr::{CdrError, CdrReader, CdrWriter};
use crate::message_fields::{FieldReader, FieldWriter};
use crate::ros1::{Ros1Reader, Ros1Writer};
use crate::Header;

/// The ROS schema name of [`Image`].
pub const IMAGE_SCHEMA: &str = "sensor_msgs/msg/Image";

/// How a message payload is encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Serialization {
    /// CDR, as in ROS 2 MCAP recordings ([`crate::cdr`]).
    Cdr,
    /// ROS 1 serialisation, as in ROS 1 bags ([`crate::ros1`]).
    Ros1,
}

impl std::fmt::Display for Serialization {
    /// The message-encoding name: `cdr` (as MCAP channels say) or `ros1`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Cdr => "cdr",
            Self::Ros1 => "ros1",
        })
    }
}

/// Millimetres per metre: the unit of `16UC1` depth.
pub const DEPTH_16UC1_UNIT_M: f64 = 0.001;

/// `sensor_msgs/msg/Image`.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Image {
    /// Stamp and frame.
    pub header: Header,
    /// Rows.
    pub height: u32,
    /// Columns.
    pub width: u32,
    /// Pixel encoding (`rgb8`, `bgr8`, `16UC1`, `32FC1`, ...).
    pub encoding: String,
    /// 1 when multi-byte values are big-endian.
    pub is_bigendian: u8,
    /// Bytes per row (at least `width` × bytes per pixel).
    pub step: u32,
    /// Row-major pixel data, `step × height` bytes.
    pub data: Vec<u8>,
}

/// Why an image's pixels could not be converted (the caller adds file, topic and stamp).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ImageError {
    /// The encoding is none of the supported ones for this role.
    #[error("encoding `{encoding}` is not a supported {role} encoding ({supported})")]
    Encoding {
        /// The image's encoding.
        encoding: String,
        /// "colour" or "depth".
        role: &'static str,
        /// The supported encodings.
        supported: &'static str,
    },
    /// Width, height, step and data length disagree.
    #[error(
        "{width}×{height} {encoding} image has step {step} and {len} data bytes \
         (needs step ≥ {min_step} and step × height bytes)"
    )]
    Size {
        /// Columns.
        width: u32,
        /// Rows.
        height: u32,
        /// Encoding.
        encoding: String,
        /// Bytes per row.
        step: u32,
        /// Smallest valid step.
        min_step: u64,
        /// Data length.
        len: usize,
    },
    /// A raw depth image whose size is not its camera's.
    #[error(
        "{width}×{height} depth image but its camera info says {camera_width}×{camera_height}"
    )]
    CameraSize {
        /// Image columns.
        width: u32,
        /// Image rows.
        height: u32,
        /// Camera columns.
        camera_width: u32,
        /// Camera rows.
        camera_height: u32,
    },
    /// The pixels do not make a valid Pomona image.
    #[error("{0}")]
    Core(#[from] pomona_core::CoreError),
}

impl Image {
    /// Reads a CDR image message (ROS 2).
    ///
    /// # Errors
    /// [`CdrError`] for a truncated or malformed payload.
    pub fn read(payload: &[u8]) -> Result<Self, CdrError> {
        Self::read_as(payload, Serialization::Cdr)
    }

    /// Reads an image message in `serialization`. Bytes after `data` are ignored (RealSense
    /// bags append a `depth_units` float there).
    ///
    /// # Errors
    /// [`CdrError`] for a truncated or malformed payload.
    pub fn read_as(payload: &[u8], serialization: Serialization) -> Result<Self, CdrError> {
        match serialization {
            Serialization::Cdr => Self::decode(&mut CdrReader::new(payload)?),
            Serialization::Ros1 => Self::decode(&mut Ros1Reader::new(payload)),
        }
    }

    /// Reads the fields from `r`.
    ///
    /// # Errors
    /// [`CdrError`] for a truncated or malformed payload.
    pub fn decode<'a>(r: &mut impl FieldReader<'a>) -> Result<Self, CdrError> {
        let (header, height, width) = r.sized_header()?;
        Ok(Self {
            header,
            height,
            width,
            encoding: r.string("encoding")?,
            is_bigendian: r.u8("is_bigendian")?,
            step: r.u32("step")?,
            data: r.byte_sequence("data")?.to_vec(),
        })
    }

    /// Reads the header and the encoding of an image message, without its pixels (for
    /// synchronisation, without copying pixels).
    ///
    /// # Errors
    /// As [`Image::read_as`].
    pub fn read_encoding(
        payload: &[u8],
        serialization: Serialization,
    ) -> Result<(Header, String), CdrError> {
        fn head<'a>(r: &mut impl FieldReader<'a>) -> Result<(Header, String), CdrError> {
            let (header, _, _) = r.sized_header()?;
            Ok((header, r.string("encoding")?))
        }
        match serialization {
            Serialization::Cdr => head(&mut CdrReader::new(payload)?),
            Serialization::Ros1 => head(&mut Ros1Reader::new(payload)),
        }
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
        w.string(&self.encoding);
        w.u8(self.is_bigendian);
        w.u32(self.step);
        w.byte_sequence(&self.data);
    }

    /// An `rgb8` image (or `bgr8` when `bgr`) of `color`.
    pub fn from_color(header: Header, color: &ColorImage, bgr: bool) -> Self {
        let mut data = color.as_rgb().to_vec();
        if bgr {
            data.chunks_exact_mut(3).for_each(|p| p.swap(0, 2));
        }
        Self {
            header,
            height: color.height(),
            width: color.width(),
            encoding: if bgr { "bgr8" } else { "rgb8" }.to_owned(),
            is_bigendian: 0,
            step: color.width() * 3,
            data,
        }
    }

    /// A little-endian `16UC1` image of `depth` in millimetres (no reading and depths beyond
    /// 65.535 m become 0).
    ///
    /// # Errors
    /// Never for a valid depth image (the unit is fixed); kept fallible for the core conversion.
    pub fn from_depth_16uc1(header: Header, depth: &DepthImage) -> Result<Self, ImageError> {
        let raw = depth.to_u16(DEPTH_16UC1_UNIT_M)?;
        Ok(Self {
            header,
            height: depth.height(),
            width: depth.width(),
            encoding: "16UC1".to_owned(),
            is_bigendian: 0,
            step: depth.width() * 2,
            data: raw.iter().flat_map(|v| v.to_le_bytes()).collect(),
        })
    }

    /// A little-endian `32FC1` image of `depth` in metres (NaN = no reading).
    pub fn from_depth_32fc1(header: Header, depth: &DepthImage) -> Self {
        Self {
            header,
            height: depth.height(),
            width: depth.width(),
            encoding: "32FC1".to_owned(),
            is_bigendian: 0,
            step: depth.width() * 4,
            data: depth
                .as_slice()
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect(),
        }
    }

    /// The pixel rows without their padding, after checking `step` and the data length.
    fn rows(&self, bytes_per_pixel: u64) -> Result<impl Iterator<Item = &[u8]>, ImageError> {
        let min_step = u64::from(self.width) * bytes_per_pixel;
        let step = u64::from(self.step);
        let fits = step >= min_step
            && step
                .checked_mul(u64::from(self.height))
                .is_some_and(|n| n == self.data.len() as u64);
        if !fits || self.width == 0 || self.height == 0 {
            return Err(ImageError::Size {
                width: self.width,
                height: self.height,
                encoding: self.encoding.clone(),
                step: self.step,
                min_step,
                len: self.data.len(),
            });
        }
        let row_len = min_step as usize;
        Ok(self
            .data
            .chunks_exact(self.step as usize)
            .map(move |row| &row[..row_len]))
    }

    /// The colour pixels.
    ///
    /// # Errors
    /// [`ImageError::Encoding`] for an encoding other than `rgb8`/`bgr8`/`rgba8`/`bgra8`;
    /// [`ImageError::Size`]
    /// when step, size and data disagree.
    pub fn to_color(&self) -> Result<ColorImage, ImageError> {
        let (bgr, channels) = match self.encoding.as_str() {
            "rgb8" => (false, 3),
            "bgr8" => (true, 3),
            "rgba8" => (false, 4),
            "bgra8" => (true, 4),
            _ => {
                return Err(ImageError::Encoding {
                    encoding: self.encoding.clone(),
                    role: "colour",
                    supported: "rgb8, bgr8, rgba8, bgra8",
                })
            }
        };
        let mut rgb = Vec::with_capacity(self.width as usize * self.height as usize * 3);
        for row in self.rows(channels)? {
            if channels == 3 {
                rgb.extend_from_slice(row);
            } else {
                // Alpha is dropped.
                row.chunks_exact(4)
                    .for_each(|p| rgb.extend_from_slice(&p[..3]));
            }
        }
        if bgr {
            rgb.chunks_exact_mut(3).for_each(|p| p.swap(0, 2));
        }
        Ok(ColorImage::from_rgb(self.width, self.height, rgb)?)
    }

    /// The 16-bit values of a `16UC1` or `mono16` image (RealSense raw depth units), row
    /// padding dropped and `is_bigendian` honoured.
    ///
    /// # Errors
    /// [`ImageError::Encoding`] for another encoding; [`ImageError::Size`].
    pub fn to_raw_u16(&self) -> Result<Vec<u16>, ImageError> {
        if !matches!(self.encoding.as_str(), "16UC1" | "mono16") {
            return Err(ImageError::Encoding {
                encoding: self.encoding.clone(),
                role: "raw depth",
                supported: "mono16, 16UC1",
            });
        }
        let big = self.is_bigendian != 0;
        let mut raw = Vec::with_capacity(self.width as usize * self.height as usize);
        for row in self.rows(2)? {
            raw.extend(row.chunks_exact(2).map(|b| {
                let b = [b[0], b[1]];
                if big {
                    u16::from_be_bytes(b)
                } else {
                    u16::from_le_bytes(b)
                }
            }));
        }
        Ok(raw)
    }

    /// The depth in metres.
    ///
    /// # Errors
    /// [`ImageError::Encoding`] for an encoding other than `16UC1`/`32FC1`;
    /// [`ImageError::Size`] when step, size and data disagree.
    pub fn to_depth(&self) -> Result<DepthImage, ImageError> {
        let big = self.is_bigendian != 0;
        match self.encoding.as_str() {
            "16UC1" => Ok(DepthImage::from_u16(
                self.width,
                self.height,
                &self.to_raw_u16()?,
                DEPTH_16UC1_UNIT_M,
            )?),
            "32FC1" => {
                let mut depth_m = Vec::with_capacity(self.width as usize * self.height as usize);
                for row in self.rows(4)? {
                    depth_m.extend(row.chunks_exact(4).map(|b| {
                        let b = [b[0], b[1], b[2], b[3]];
                        if big {
                            f32::from_be_bytes(b)
                        } else {
                            f32::from_le_bytes(b)
                        }
                    }));
                }
                Ok(DepthImage::from_meters(self.width, self.height, depth_m)?)
            }
            _ => Err(ImageError::Encoding {
                encoding: self.encoding.clone(),
                role: "depth",
                supported: "16UC1 (millimetres), 32FC1 (metres)",
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header() -> Header {
        Header::at(5, "cam")
    }

    #[test]
    fn colour_round_trips_through_rgb8_and_bgr8() {
        let mut color = ColorImage::filled(3, 2, [10, 20, 30]);
        color.set(2, 1, [200, 100, 0]);
        for bgr in [false, true] {
            let msg = Image::from_color(header(), &color, bgr);
            let back = Image::read(&msg.to_cdr()).unwrap();
            assert_eq!(back, msg);
            assert_eq!(back.to_color().unwrap(), color);
            let ros1 = Image::read_as(&msg.to_ros1(), Serialization::Ros1).unwrap();
            assert_eq!(ros1, msg);
        }
        // rgba8 / bgra8: alpha dropped.
        let msg = Image::from_color(header(), &color, true);
        let mut bgra = msg.clone();
        bgra.encoding = "bgra8".into();
        bgra.step = 3 * 4;
        bgra.data = msg
            .data
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect();
        assert_eq!(bgra.to_color().unwrap(), color);
    }

    #[test]
    fn padded_rows_and_big_endian_depth_are_read() {
        // 2×2 16UC1, big-endian, each row padded to 6 bytes.
        let msg = Image {
            header: header(),
            height: 2,
            width: 2,
            encoding: "16UC1".into(),
            is_bigendian: 1,
            step: 6,
            data: vec![0x03, 0xE8, 0, 0, 9, 9, 0x07, 0xD0, 0x00, 0x01, 9, 9],
        };
        let d = msg.to_depth().unwrap();
        assert_eq!(d.as_slice()[0], 1.0);
        assert!(d.as_slice()[1].is_nan());
        assert_eq!(d.as_slice()[2], 2.0);
        assert_eq!(d.as_slice()[3], 0.001);
    }

    #[test]
    fn depth_32fc1_maps_nan_and_zero_to_no_depth() {
        let depth = DepthImage::from_meters(3, 1, vec![1.25, f32::NAN, 0.5]).unwrap();
        let msg = Image::from_depth_32fc1(header(), &depth);
        let mut data = msg.data.clone();
        data[4..8].copy_from_slice(&0f32.to_le_bytes());
        let zeroed = Image {
            data,
            ..msg.clone()
        };
        for m in [msg, zeroed] {
            let back = m.to_depth().unwrap();
            assert_eq!(back.as_slice()[0], 1.25);
            assert!(back.as_slice()[1].is_nan());
        }
    }

    #[test]
    fn sizes_and_encodings_are_checked() {
        let color = ColorImage::filled(4, 4, [1, 2, 3]);
        let mut msg = Image::from_color(header(), &color, false);
        msg.data.pop();
        assert!(matches!(
            msg.to_color(),
            Err(ImageError::Size { len: 47, .. })
        ));
        let mut msg = Image::from_color(header(), &color, false);
        msg.step = 8;
        assert!(matches!(msg.to_color(), Err(ImageError::Size { .. })));
        let mut msg = Image::from_color(header(), &color, false);
        msg.encoding = "yuv422".into();
        let e = msg.to_color().unwrap_err().to_string();
        assert!(e.contains("yuv422") && e.contains("rgb8"), "{e}");
        assert!(msg.to_depth().unwrap_err().to_string().contains("16UC1"));
    }
}
