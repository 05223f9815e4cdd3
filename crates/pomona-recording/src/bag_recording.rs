//! A ROS 1 bag read as a recording: which connections hold the colour, depth and camera-info
//! messages (the requested topics, the RealSense ROS 1 driver's by default, or the RealSense SDK
//! layout), their messages with decoded headers, and a RealSense bag's depth calibration.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use pomona_core::nalgebra::Isometry3;
use pomona_core::{DepthImage, PinholeCamera};

use crate::bag::Bag;
use crate::depth_registration::register_depth;
use crate::realsense::{
    decode_float32, decode_transform, RealSenseCalibration, RealSenseLayout, DEFAULT_DEPTH_UNIT_M,
};
use crate::recording::{stamp, OpenedMessages, RecordingFormat, Stamped, TopicMessages};
use crate::ros1::Ros1Reader;
use crate::{
    CameraInfo, CdrError, Image, ImageError, RecordingError, RecordingTopics, Serialization,
    TopicRequest, TopicSummary,
};

const ROS1_IMAGE_TYPE: &str = "sensor_msgs/Image";
const ROS1_CAMERA_INFO_TYPE: &str = "sensor_msgs/CameraInfo";

/// What a kept message is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Color,
    Depth,
    Info,
    DepthInfo,
    ColorTf(u32),
    DepthTf(u32),
    DepthUnits,
}

/// Reads the bag's messages of the requested topics (or the format's defaults).
///
/// # Errors
/// [`RecordingError::Bag`] for a corrupt container; [`RecordingError::WrongSchema`] for a
/// requested topic of another type; [`RecordingError::Cdr`] / [`RecordingError::BadStamp`] for
/// a header that cannot be read; [`RecordingError::RealSense`] / [`RecordingError::CameraInfo`]
/// for a RealSense bag without usable calibration.
pub(crate) fn read(
    path: &Path,
    bytes: &[u8],
    request: &TopicRequest,
) -> Result<OpenedMessages, RecordingError> {
    let bag_error = |source| RecordingError::Bag {
        path: path.to_owned(),
        source,
    };
    let bag = Bag::open(bytes).map_err(bag_error)?;
    let connections = bag.connections();
    let has_topic = |t: &str| connections.values().any(|c| c.topic == t);
    let ros1 = RecordingTopics::ros1();
    let layout = if request.is_empty() && !has_topic(&ros1.color) {
        RealSenseLayout::find(connections.values().map(|c| c.topic.as_str()))
    } else {
        None
    };
    let (format, topics) = match &layout {
        Some(layout) => (RecordingFormat::RealSenseBag, layout.topics()),
        None => (RecordingFormat::Ros1Bag, request.resolve(ros1)),
    };
    let mut roles: BTreeMap<u32, Role> = BTreeMap::new();
    for c in connections.values() {
        let role = if c.topic == topics.color {
            Some(Role::Color)
        } else if c.topic == topics.depth {
            Some(Role::Depth)
        } else if c.topic == topics.camera_info {
            Some(Role::Info)
        } else if let Some(layout) = &layout {
            if c.topic == layout.depth.info_topic() {
                Some(Role::DepthInfo)
            } else if c.topic == layout.depth.depth_units_topic() {
                Some(Role::DepthUnits)
            } else if let Some(r) = layout.color.tf_reference(&c.topic) {
                Some(Role::ColorTf(r))
            } else {
                layout.depth.tf_reference(&c.topic).map(Role::DepthTf)
            }
        } else {
            None
        };
        let Some(role) = role else { continue };
        let expected = match role {
            Role::Color | Role::Depth => Some(ROS1_IMAGE_TYPE),
            Role::Info | Role::DepthInfo => Some(ROS1_CAMERA_INFO_TYPE),
            _ => None,
        };
        if let Some(expected) = expected.filter(|e| *e != c.message_type) {
            return Err(RecordingError::WrongSchema {
                path: path.to_owned(),
                topic: c.topic.clone(),
                schema: c.message_type.clone(),
                encoding: "ros1".to_owned(),
                expected,
                expected_encoding: Serialization::Ros1,
            });
        }
        roles.insert(c.id, role);
    }
    let read = bag
        .read_messages(|id| roles.contains_key(&id))
        .map_err(bag_error)?;

    let mut summary: BTreeMap<&str, (&str, u64)> = BTreeMap::new();
    for (id, n) in &read.counts {
        if let Some(c) = connections.get(id) {
            let entry = summary
                .entry(c.topic.as_str())
                .or_insert((c.message_type.as_str(), 0));
            entry.1 += n;
        }
    }
    let mut messages = TopicMessages {
        color: Vec::new(),
        depth: Vec::new(),
        info: Vec::new(),
        topics: summary
            .into_iter()
            .map(|(topic, (schema, messages))| TopicSummary {
                topic: topic.to_owned(),
                schema: schema.to_owned(),
                messages,
            })
            .collect(),
    };
    let mut extras = Extras::default();
    for message in read.kept {
        let (Some(&role), Some(connection)) = (
            roles.get(&message.connection),
            connections.get(&message.connection),
        ) else {
            continue;
        };
        let topic = connection.topic.as_str();
        let cdr_error = |source| RecordingError::Cdr {
            path: path.to_owned(),
            topic: topic.to_owned(),
            log_time_ns: message.time_ns,
            source,
        };
        match role {
            Role::Color | Role::Depth => {
                let (header, _) =
                    Image::read_encoding(&message.data, Serialization::Ros1).map_err(cdr_error)?;
                let stamped = Stamped {
                    stamp_ns: stamp(path, topic, &header)?,
                    frame_id: header.frame_id,
                    payload: message.data,
                };
                if role == Role::Color {
                    messages.color.push(stamped);
                } else {
                    messages.depth.push(stamped);
                }
            }
            Role::Info | Role::DepthInfo => {
                let info =
                    CameraInfo::read_as(&message.data, Serialization::Ros1).map_err(cdr_error)?;
                if role == Role::Info {
                    messages
                        .info
                        .push((stamp(path, topic, &info.header)?, info));
                } else if extras.depth_info.is_none() {
                    extras.depth_info = Some((topic.to_owned(), info));
                }
            }
            Role::ColorTf(r) => {
                let tf = decode_transform(&message.data).map_err(cdr_error)?;
                extras.color_tf.entry(r).or_insert(tf);
            }
            Role::DepthTf(r) => {
                let tf = decode_transform(&message.data).map_err(cdr_error)?;
                extras.depth_tf.entry(r).or_insert(tf);
            }
            Role::DepthUnits => {
                if extras.depth_unit_m.is_none() {
                    extras.depth_unit_m = Some(decode_float32(&message.data).map_err(cdr_error)?);
                }
            }
        }
    }
    let realsense = match &layout {
        Some(layout) => Some(extras.calibration(path, layout)?),
        None => None,
    };
    Ok(OpenedMessages {
        messages,
        format,
        topics,
        realsense,
    })
}

/// The RealSense messages beside the three topics.
#[derive(Default)]
struct Extras {
    depth_info: Option<(String, CameraInfo)>,
    color_tf: BTreeMap<u32, Isometry3<f64>>,
    depth_tf: BTreeMap<u32, Isometry3<f64>>,
    depth_unit_m: Option<f32>,
}

impl Extras {
    fn calibration(
        self,
        path: &Path,
        layout: &RealSenseLayout,
    ) -> Result<RealSenseCalibration, RecordingError> {
        let fail = |what: String| RecordingError::RealSense {
            path: path.to_owned(),
            what,
        };
        let Some((topic, info)) = self.depth_info else {
            return Err(fail(format!(
                "no depth camera info on `{}`",
                layout.depth.info_topic()
            )));
        };
        let depth_camera = info
            .to_camera()
            .map_err(|source| RecordingError::CameraInfo {
                path: path.to_owned(),
                topic,
                stamp_ns: info.header.stamp_ns().unwrap_or(0),
                source: Box::new(source),
            })?;
        // Extrinsics of colour and depth relative to the same reference group; depth without
        // its own is the reference (the identity).
        let references: BTreeSet<u32> = self.color_tf.keys().copied().collect();
        let Some((color_from_ref, depth_from_ref)) = references.iter().find_map(|r| {
            let color = self.color_tf.get(r)?;
            Some((
                *color,
                self.depth_tf
                    .get(r)
                    .copied()
                    .unwrap_or_else(Isometry3::identity),
            ))
        }) else {
            return Err(fail(format!(
                "no depth→colour extrinsics: no `{}` transform",
                layout.color.tf_topic(0)
            )));
        };
        let depth_unit_m = match self.depth_unit_m {
            None => DEFAULT_DEPTH_UNIT_M,
            Some(u) if u.is_finite() && u > 0.0 => f64::from(u),
            Some(u) => {
                return Err(fail(format!(
                    "depth units `{}` = {u} is not a positive number of metres",
                    layout.depth.depth_units_topic()
                )))
            }
        };
        Ok(RealSenseCalibration {
            depth_camera,
            color_from_depth: color_from_ref * depth_from_ref.inverse(),
            depth_unit_m,
        })
    }
}

/// Why a RealSense depth message could not be registered.
#[derive(Debug)]
pub(crate) enum RawDepthError {
    /// The payload is not a ROS 1 image.
    Cdr(CdrError),
    /// Its pixels are not raw 16-bit depth of the depth camera's size.
    Image(ImageError),
}

/// A RealSense depth message (`mono16` / `16UC1` raw units) registered to `color_camera`.
pub(crate) fn registered_depth(
    payload: &[u8],
    calibration: &RealSenseCalibration,
    color_camera: &PinholeCamera,
) -> Result<DepthImage, RawDepthError> {
    let mut r = Ros1Reader::new(payload);
    let image = Image::decode(&mut r).map_err(RawDepthError::Cdr)?;
    // librealsense ≥ 2.50 appends `float32 depth_units` after the pixels.
    let unit_m = match r.rest() {
        [a, b, c, d] => {
            let u = f32::from_le_bytes([*a, *b, *c, *d]);
            if u.is_finite() && u > 0.0 {
                f64::from(u)
            } else {
                calibration.depth_unit_m
            }
        }
        _ => calibration.depth_unit_m,
    };
    let raw = image.to_raw_u16().map_err(RawDepthError::Image)?;
    let d = &calibration.depth_camera;
    if (image.width, image.height) != (d.width, d.height) {
        return Err(RawDepthError::Image(ImageError::CameraSize {
            width: image.width,
            height: image.height,
            camera_width: d.width,
            camera_height: d.height,
        }));
    }
    let depth_m = register_depth(&raw, unit_m, d, color_camera, &calibration.color_from_depth);
    DepthImage::from_meters(color_camera.width, color_camera.height, depth_m)
        .map_err(|e| RawDepthError::Image(ImageError::Core(e)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Header;

    #[test]
    fn an_images_own_depth_units_win_over_the_option() {
        let camera = PinholeCamera::new(3, 1, 2.0, 2.0, 1.0, 0.0).unwrap();
        let calibration = RealSenseCalibration {
            depth_camera: camera,
            color_from_depth: Isometry3::identity(),
            depth_unit_m: 0.001,
        };
        let image = Image {
            header: Header::at(5, "0"),
            height: 1,
            width: 3,
            encoding: "mono16".into(),
            is_bigendian: 0,
            step: 6,
            data: [1000u16, 0, 2500]
                .iter()
                .flat_map(|v| v.to_le_bytes())
                .collect(),
        };
        let plain = image.to_ros1();
        let depth = registered_depth(&plain, &calibration, &camera).unwrap();
        assert_eq!(depth.as_slice()[0], 1.0);
        assert!(depth.as_slice()[1].is_nan());
        assert_eq!(depth.as_slice()[2], 2.5);
        let mut with_units = plain.clone();
        with_units.extend_from_slice(&0.0001f32.to_le_bytes());
        let depth = registered_depth(&with_units, &calibration, &camera).unwrap();
        assert!((depth.as_slice()[0] - 0.1).abs() < 1e-6);
        // A depth image of another size than its camera is an error, not garbage.
        let small = PinholeCamera::new(2, 1, 2.0, 2.0, 1.0, 0.0).unwrap();
        let wrong = RealSenseCalibration {
            depth_camera: small,
            ..calibration
        };
        assert!(matches!(
            registered_depth(&plain, &wrong, &camera),
            Err(RawDepthError::Image(ImageError::CameraSize { .. }))
        ));
    }
}
