//! ROS 1 serialisation, the encoding of messages in ROS 1 bags.
//!
//! Fields follow each other in declaration order with no alignment and no envelope, every
//! primitive little-endian. A `string` is a `u32` byte count and the bytes (no terminator); a
//! variable array (`uint8[]`, `float64[]`) a `u32` element count and the elements; a fixed
//! array (`float64[9]`) the elements alone. `std_msgs/Header` is `uint32 seq`, `time stamp`
//! (`uint32 secs`, `uint32 nsecs`) and `string frame_id`. Like [`crate::cdr`], only what
//! `sensor_msgs/Image`, `sensor_msgs/CameraInfo` and the few RealSense messages need is here,
//! and every length is checked against the bytes left before it is used.

use crate::message_fields::{FieldReader, FieldWriter};
use crate::{CdrError, Header};

/// Reads the fields of one ROS 1 payload in order.
#[derive(Debug)]
pub struct Ros1Reader<'a> {
    bytes: &'a [u8],
    position: usize,
}

impl<'a> Ros1Reader<'a> {
    /// Starts reading `payload` at its first byte.
    pub fn new(payload: &'a [u8]) -> Self {
        Self {
            bytes: payload,
            position: 0,
        }
    }

    fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], CdrError> {
        let left = self.bytes.len() - self.position;
        if n > left {
            return Err(CdrError::Truncated {
                what,
                len: self.bytes.len(),
                needed: n - left,
            });
        }
        let slice = &self.bytes[self.position..self.position + n];
        self.position += n;
        Ok(slice)
    }

    fn array<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], CdrError> {
        let mut out = [0; N];
        out.copy_from_slice(self.take(N, what)?);
        Ok(out)
    }

    /// A `float32`.
    ///
    /// # Errors
    /// [`CdrError::Truncated`].
    pub fn f32(&mut self, what: &'static str) -> Result<f32, CdrError> {
        self.array::<4>(what).map(f32::from_le_bytes)
    }

    /// The bytes after the last field read (for optional trailing fields).
    pub fn rest(&self) -> &'a [u8] {
        &self.bytes[self.position..]
    }
}

impl<'a> FieldReader<'a> for Ros1Reader<'a> {
    fn u8(&mut self, what: &'static str) -> Result<u8, CdrError> {
        Ok(self.take(1, what)?[0])
    }
    fn u32(&mut self, what: &'static str) -> Result<u32, CdrError> {
        self.array::<4>(what).map(u32::from_le_bytes)
    }
    fn f64(&mut self, what: &'static str) -> Result<f64, CdrError> {
        self.array::<8>(what).map(f64::from_le_bytes)
    }
    fn string(&mut self, what: &'static str) -> Result<String, CdrError> {
        let len = self.u32(what)? as usize;
        let bytes = self.take(len, what)?;
        std::str::from_utf8(bytes)
            .map(str::to_owned)
            .map_err(|_| CdrError::BadString(what))
    }
    fn byte_sequence(&mut self, what: &'static str) -> Result<&'a [u8], CdrError> {
        let len = self.u32(what)? as usize;
        self.take(len, what)
    }
    fn remaining(&self) -> usize {
        self.bytes.len() - self.position
    }
    fn header(&mut self) -> Result<Header, CdrError> {
        let _seq = self.u32("header.seq")?;
        let secs = self.u32("header.stamp.secs")?;
        let nsecs = self.u32("header.stamp.nsecs")?;
        Ok(Header {
            stamp_sec: i32::try_from(secs).map_err(|_| CdrError::StampOutOfRange(secs))?,
            stamp_nanosec: nsecs,
            frame_id: self.string("header.frame_id")?,
        })
    }
}

/// Writes the fields of one ROS 1 payload in order. Headers are written with `seq` 0.
#[derive(Debug, Clone, Default)]
pub struct Ros1Writer {
    bytes: Vec<u8>,
}

impl Ros1Writer {
    /// An empty payload.
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends a `float32`.
    pub fn f32(&mut self, value: f32) {
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    /// The finished payload.
    pub fn into_bytes(self) -> Vec<u8> {
        self.bytes
    }

    fn length(&mut self, len: usize) {
        // ROS messages cannot exceed 4 GiB; saturating keeps a reader's length check failing.
        self.u32(u32::try_from(len).unwrap_or(u32::MAX));
    }
}

impl FieldWriter for Ros1Writer {
    fn u8(&mut self, value: u8) {
        self.bytes.push(value);
    }
    fn u32(&mut self, value: u32) {
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }
    fn f64(&mut self, value: f64) {
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }
    fn string(&mut self, value: &str) {
        self.length(value.len());
        self.bytes.extend_from_slice(value.as_bytes());
    }
    fn byte_sequence(&mut self, value: &[u8]) {
        self.length(value.len());
        self.bytes.extend_from_slice(value);
    }
    fn header(&mut self, header: &Header) {
        self.u32(0);
        // Negative seconds (before the epoch) cannot be stamps of a recording; ROS 1 time is
        // unsigned, so they are written as 0.
        self.u32(u32::try_from(header.stamp_sec).unwrap_or(0));
        self.u32(header.stamp_nanosec);
        self.string(&header.frame_id);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_round_trip_without_alignment() {
        let mut w = Ros1Writer::new();
        w.header(&Header::at(1_700_000_000_000_000_123, "cam"));
        w.u8(7);
        w.f64(0.25);
        w.f64_sequence(&[1.5, -2.0]);
        w.f32(3.5);
        let bytes = w.into_bytes();
        // seq, secs, nsecs, len + "cam", u8, then the f64 unaligned at byte 20.
        assert_eq!(&bytes[20..28], &0.25f64.to_le_bytes());
        let mut r = Ros1Reader::new(&bytes);
        let h = r.header().unwrap();
        assert_eq!(h.stamp_ns(), Some(1_700_000_000_000_000_123));
        assert_eq!(h.frame_id, "cam");
        assert_eq!(r.u8("a").unwrap(), 7);
        assert_eq!(r.f64("b").unwrap(), 0.25);
        assert_eq!(r.f64_sequence("c").unwrap(), vec![1.5, -2.0]);
        assert_eq!(r.f32("d").unwrap(), 3.5);
        assert!(r.rest().is_empty());
        assert!(matches!(r.u8("e"), Err(CdrError::Truncated { .. })));
    }

    #[test]
    fn oversized_lengths_and_late_stamps_are_errors() {
        let mut w = Ros1Writer::new();
        w.u32(1_000_000);
        let bytes = w.into_bytes();
        assert!(Ros1Reader::new(&bytes).byte_sequence("data").is_err());
        assert!(Ros1Reader::new(&bytes).f64_sequence("d").is_err());
        assert!(Ros1Reader::new(&bytes).string("s").is_err());
        let mut w = Ros1Writer::new();
        for v in [0, u32::MAX, 0, 0] {
            w.u32(v);
        }
        let bytes = w.into_bytes();
        assert_eq!(
            Ros1Reader::new(&bytes).header(),
            Err(CdrError::StampOutOfRange(u32::MAX))
        );
    }
}
