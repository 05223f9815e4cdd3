//! The fields of a ROS message, read and written independently of the wire format.
//!
//! ROS 2 recordings carry messages in CDR ([`crate::cdr`]), ROS 1 bags in ROS 1 serialisation
//! ([`crate::ros1`]). Both lay out `sensor_msgs/Image` and `sensor_msgs/CameraInfo` as the same
//! fields in the same order and differ only in how a field is encoded (alignment, string
//! terminator, the header's `seq`). [`FieldReader`] and [`FieldWriter`] are that difference, so
//! each message is decoded and encoded by one function for both formats.

use crate::{CdrError, Header};

/// Reads the fields of one message payload in order.
pub trait FieldReader<'a> {
    /// A `uint8` (or `bool`).
    ///
    /// # Errors
    /// [`CdrError::Truncated`].
    fn u8(&mut self, what: &'static str) -> Result<u8, CdrError>;
    /// A `uint32`.
    ///
    /// # Errors
    /// [`CdrError::Truncated`].
    fn u32(&mut self, what: &'static str) -> Result<u32, CdrError>;
    /// A `float64`.
    ///
    /// # Errors
    /// [`CdrError::Truncated`].
    fn f64(&mut self, what: &'static str) -> Result<f64, CdrError>;
    /// A `string`.
    ///
    /// # Errors
    /// [`CdrError::Truncated`] (checked before copying); [`CdrError::BadString`].
    fn string(&mut self, what: &'static str) -> Result<String, CdrError>;
    /// A `uint8[]`, borrowed from the payload.
    ///
    /// # Errors
    /// [`CdrError::Truncated`] when the count exceeds the bytes left.
    fn byte_sequence(&mut self, what: &'static str) -> Result<&'a [u8], CdrError>;
    /// Bytes not yet read (an upper bound on what a length may claim).
    fn remaining(&self) -> usize;
    /// The `std_msgs/Header` at the start of a message.
    ///
    /// # Errors
    /// [`CdrError`] for a truncated header, a bad `frame_id` or an unrepresentable stamp.
    fn header(&mut self) -> Result<Header, CdrError>;

    /// A `float64[]`, its count checked against the bytes left before allocating.
    ///
    /// # Errors
    /// [`CdrError::Truncated`].
    fn f64_sequence(&mut self, what: &'static str) -> Result<Vec<f64>, CdrError> {
        let len = self.u32(what)? as usize;
        let left = self.remaining();
        if len.saturating_mul(8) > left {
            return Err(CdrError::Truncated {
                what,
                len: left,
                needed: len.saturating_mul(8) - left,
            });
        }
        (0..len).map(|_| self.f64(what)).collect()
    }

    /// A `float64[N]` fixed array.
    ///
    /// # Errors
    /// [`CdrError::Truncated`].
    fn f64_array<const N: usize>(&mut self, what: &'static str) -> Result<[f64; N], CdrError> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f64(what)?;
        }
        Ok(out)
    }

    /// The header, then `height` and `width`: how `Image` and `CameraInfo` both begin.
    ///
    /// # Errors
    /// As [`FieldReader::header`].
    fn sized_header(&mut self) -> Result<(Header, u32, u32), CdrError> {
        Ok((self.header()?, self.u32("height")?, self.u32("width")?))
    }
}

/// Writes the fields of one message payload in order.
pub trait FieldWriter {
    /// Appends a `uint8`.
    fn u8(&mut self, value: u8);
    /// Appends a `uint32`.
    fn u32(&mut self, value: u32);
    /// Appends a `float64`.
    fn f64(&mut self, value: f64);
    /// Appends a `string`.
    fn string(&mut self, value: &str);
    /// Appends a `uint8[]`.
    fn byte_sequence(&mut self, value: &[u8]);
    /// Appends a `std_msgs/Header`.
    fn header(&mut self, header: &Header);

    /// Appends a `float64[]`.
    fn f64_sequence(&mut self, values: &[f64]) {
        // ROS messages cannot exceed 4 GiB; saturating keeps a reader's check failing.
        self.u32(u32::try_from(values.len()).unwrap_or(u32::MAX));
        values.iter().for_each(|&v| self.f64(v));
    }

    /// Appends a `float64[N]` fixed array.
    fn f64_array(&mut self, values: &[f64]) {
        values.iter().for_each(|&v| self.f64(v));
    }

    /// Appends the header, `height` and `width` (see [`FieldReader::sized_header`]).
    fn sized_header(&mut self, header: &Header, height: u32, width: u32) {
        self.header(header);
        self.u32(height);
        self.u32(width);
    }
}
