//! `std_msgs/Header`: the stamp and coordinate frame every sensor message starts with. The stamp
//! (`builtin_interfaces/Time`, seconds and nanoseconds) is what frames are synchronised and named
//! by. How it is encoded depends on the format (`FieldReader::header`): ROS 1 adds a `seq`
//! and has unsigned seconds.

use serde::{Deserialize, Serialize};

/// `std_msgs/msg/Header`.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Header {
    /// Acquisition time, seconds part.
    pub stamp_sec: i32,
    /// Acquisition time, nanoseconds part (`< 1e9`).
    pub stamp_nanosec: u32,
    /// The coordinate frame the data is in (e.g. `camera_color_optical_frame`).
    pub frame_id: String,
}

impl Header {
    /// A header stamped `stamp_ns` nanoseconds since the epoch (saturating at `i32::MAX` s).
    pub fn at(stamp_ns: u64, frame_id: &str) -> Self {
        Self {
            stamp_sec: i32::try_from(stamp_ns / 1_000_000_000).unwrap_or(i32::MAX),
            stamp_nanosec: (stamp_ns % 1_000_000_000) as u32,
            frame_id: frame_id.to_owned(),
        }
    }

    /// The stamp in nanoseconds since the epoch; `None` for stamps before it (negative seconds)
    /// or with nanoseconds out of range.
    pub fn stamp_ns(&self) -> Option<u64> {
        let sec = u64::try_from(self.stamp_sec).ok()?;
        (self.stamp_nanosec < 1_000_000_000)
            .then(|| sec * 1_000_000_000 + u64::from(self.stamp_nanosec))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cdr::{CdrReader, CdrWriter};
    use crate::message_fields::{FieldReader, FieldWriter};

    #[test]
    fn stamps_convert_both_ways() {
        let h = Header::at(1_700_000_000_123_456_789, "cam");
        assert_eq!((h.stamp_sec, h.stamp_nanosec), (1_700_000_000, 123_456_789));
        assert_eq!(h.stamp_ns(), Some(1_700_000_000_123_456_789));
        let before_epoch = Header {
            stamp_sec: -1,
            ..h.clone()
        };
        assert_eq!(before_epoch.stamp_ns(), None);
        let mut w = CdrWriter::new();
        FieldWriter::header(&mut w, &h);
        let bytes = w.into_bytes();
        assert_eq!(CdrReader::new(&bytes).unwrap().header().unwrap(), h);
    }
}
