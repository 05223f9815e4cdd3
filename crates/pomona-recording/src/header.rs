//! `std_msgs/Header`: the stamp and coordinate frame every sensor message starts with. The stamp
//! (`builtin_interfaces/Time`, seconds and nanoseconds) is what frames are synchronised and named
//! by.

use serde::{Deserialize, Serialize};

use crate::cdr::{CdrError, CdrReader, CdrWriter};

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

    /// Reads the header at the start of a message.
    ///
    /// # Errors
    /// [`CdrError`] for a truncated payload or a bad `frame_id`.
    pub fn read(r: &mut CdrReader<'_>) -> Result<Self, CdrError> {
        Ok(Self {
            stamp_sec: r.i32("header.stamp.sec")?,
            stamp_nanosec: r.u32("header.stamp.nanosec")?,
            frame_id: r.string("header.frame_id")?,
        })
    }

    /// Appends the header.
    pub fn write(&self, w: &mut CdrWriter) {
        w.i32(self.stamp_sec);
        w.u32(self.stamp_nanosec);
        w.string(&self.frame_id);
    }

    /// Reads how `Image` and `CameraInfo` both begin: the header, then `height` and `width`.
    ///
    /// # Errors
    /// As [`Header::read`].
    pub fn read_sized(r: &mut CdrReader<'_>) -> Result<(Self, u32, u32), CdrError> {
        Ok((Self::read(r)?, r.u32("height")?, r.u32("width")?))
    }

    /// Appends the header, `height` and `width` (see [`Header::read_sized`]).
    pub fn write_sized(&self, w: &mut CdrWriter, height: u32, width: u32) {
        self.write(w);
        w.u32(height);
        w.u32(width);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        h.write(&mut w);
        let bytes = w.into_bytes();
        assert_eq!(
            Header::read(&mut CdrReader::new(&bytes).unwrap()).unwrap(),
            h
        );
    }
}
