//! CDR (OMG Common Data Representation, XCDR1), the encoding of ROS 2 messages in MCAP files
//! (message encoding `cdr`).
//!
//! A payload starts with a 4-byte encapsulation header — `00 00` big-endian or `00 01`
//! little-endian CDR, then two option bytes — followed by the fields in declaration order, each
//! primitive aligned to its own size counted from the end of the header. Strings are a `u32`
//! length including the terminating NUL, the bytes, and the NUL; sequences are a `u32` count and
//! the elements; fixed arrays are the elements alone. Only what `sensor_msgs/Image` and
//! `sensor_msgs/CameraInfo` need is here: a compact reader and writer instead of a general serde
//! format, so every length is checked against the bytes left before anything is allocated.

use crate::message_fields::{FieldReader, FieldWriter};
use crate::Header;

/// Encapsulation identifier of little-endian plain CDR.
const CDR_LE: [u8; 2] = [0x00, 0x01];
/// Encapsulation identifier of big-endian plain CDR.
const CDR_BE: [u8; 2] = [0x00, 0x00];
/// Length of the encapsulation header.
const HEADER_LEN: usize = 4;

/// Why a CDR payload could not be decoded (wrapped with the file, topic and schema by the
/// caller).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CdrError {
    /// The payload ended before a field.
    #[error("payload ends at byte {len} while reading {what} (needs {needed} more bytes)")]
    Truncated {
        /// The field being read.
        what: &'static str,
        /// Payload length.
        len: usize,
        /// Bytes still needed.
        needed: usize,
    },
    /// The encapsulation header names a representation other than plain CDR.
    #[error("encapsulation {0:02x?} is not plain CDR (00 00 or 00 01)")]
    Encapsulation([u8; 2]),
    /// A string is not NUL-terminated UTF-8 (CDR) or not UTF-8 (ROS 1).
    #[error("string field {0} is not NUL-terminated UTF-8")]
    BadString(&'static str),
    /// A ROS 1 stamp whose seconds do not fit the 32-bit signed seconds Pomona keeps (after
    /// 2038).
    #[error("header stamp of {0} s is past 2038 (not representable)")]
    StampOutOfRange(u32),
    /// A `geometry_msgs/Transform` whose rotation is not a quaternion (zero or not finite) or
    /// whose translation is not finite.
    #[error("transform rotation {0:?} (x, y, z, w) is not a rotation")]
    BadQuaternion([f64; 4]),
}

/// Reads the fields of one CDR payload in order.
#[derive(Debug)]
pub struct CdrReader<'a> {
    bytes: &'a [u8],
    position: usize,
    little_endian: bool,
}

impl<'a> CdrReader<'a> {
    /// Starts reading `payload` after checking its encapsulation header.
    ///
    /// # Errors
    /// [`CdrError::Truncated`] for a payload shorter than the header;
    /// [`CdrError::Encapsulation`] for anything but plain CDR.
    pub fn new(payload: &'a [u8]) -> Result<Self, CdrError> {
        let Some(header) = payload.get(..HEADER_LEN) else {
            return Err(CdrError::Truncated {
                what: "encapsulation header",
                len: payload.len(),
                needed: HEADER_LEN - payload.len(),
            });
        };
        let id = [header[0], header[1]];
        let little_endian = match id {
            CDR_LE => true,
            CDR_BE => false,
            other => return Err(CdrError::Encapsulation(other)),
        };
        Ok(Self {
            bytes: &payload[HEADER_LEN..],
            position: 0,
            little_endian,
        })
    }

    fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], CdrError> {
        let end = self
            .position
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(CdrError::Truncated {
                what,
                len: self.bytes.len() + HEADER_LEN,
                needed: n - (self.bytes.len() - self.position.min(self.bytes.len())),
            });
        };
        let slice = &self.bytes[self.position..end];
        self.position = end;
        Ok(slice)
    }

    fn align(&mut self, to: usize) {
        let rem = self.position % to;
        if rem != 0 {
            // Past the end is caught by the read that follows.
            self.position += to - rem;
        }
    }

    fn array<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], CdrError> {
        self.align(N);
        let mut out = [0; N];
        out.copy_from_slice(self.take(N, what)?);
        if self.little_endian != cfg!(target_endian = "little") {
            out.reverse();
        }
        Ok(out)
    }

    /// A `uint8` (or `bool`, `char`).
    ///
    /// # Errors
    /// [`CdrError::Truncated`].
    pub fn u8(&mut self, what: &'static str) -> Result<u8, CdrError> {
        Ok(self.take(1, what)?[0])
    }

    /// A `uint32`.
    ///
    /// # Errors
    /// [`CdrError::Truncated`].
    pub fn u32(&mut self, what: &'static str) -> Result<u32, CdrError> {
        self.array::<4>(what).map(u32::from_ne_bytes)
    }

    /// An `int32`.
    ///
    /// # Errors
    /// [`CdrError::Truncated`].
    pub fn i32(&mut self, what: &'static str) -> Result<i32, CdrError> {
        self.array::<4>(what).map(i32::from_ne_bytes)
    }

    /// A `float64`.
    ///
    /// # Errors
    /// [`CdrError::Truncated`].
    pub fn f64(&mut self, what: &'static str) -> Result<f64, CdrError> {
        self.array::<8>(what).map(f64::from_ne_bytes)
    }

    /// A `string`.
    ///
    /// # Errors
    /// [`CdrError::Truncated`] (the length is checked before the bytes are copied);
    /// [`CdrError::BadString`] when it is not NUL-terminated UTF-8.
    pub fn string(&mut self, what: &'static str) -> Result<String, CdrError> {
        let len = self.u32(what)? as usize;
        if len == 0 {
            // Some writers encode the empty string without its NUL.
            return Ok(String::new());
        }
        let bytes = self.take(len, what)?;
        match bytes.split_last() {
            Some((0, text)) => std::str::from_utf8(text)
                .map(str::to_owned)
                .map_err(|_| CdrError::BadString(what)),
            _ => Err(CdrError::BadString(what)),
        }
    }

    /// A `uint8[]` sequence, borrowed from the payload.
    ///
    /// # Errors
    /// [`CdrError::Truncated`] when the count exceeds the bytes left.
    pub fn byte_sequence(&mut self, what: &'static str) -> Result<&'a [u8], CdrError> {
        let len = self.u32(what)? as usize;
        self.take(len, what)
    }
}

impl<'a> FieldReader<'a> for CdrReader<'a> {
    fn u8(&mut self, what: &'static str) -> Result<u8, CdrError> {
        CdrReader::u8(self, what)
    }
    fn u32(&mut self, what: &'static str) -> Result<u32, CdrError> {
        CdrReader::u32(self, what)
    }
    fn f64(&mut self, what: &'static str) -> Result<f64, CdrError> {
        CdrReader::f64(self, what)
    }
    fn string(&mut self, what: &'static str) -> Result<String, CdrError> {
        CdrReader::string(self, what)
    }
    fn byte_sequence(&mut self, what: &'static str) -> Result<&'a [u8], CdrError> {
        CdrReader::byte_sequence(self, what)
    }
    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.position)
    }
    /// `builtin_interfaces/Time stamp` (`int32 sec`, `uint32 nanosec`), `string frame_id`.
    fn header(&mut self) -> Result<Header, CdrError> {
        Ok(Header {
            stamp_sec: self.i32("header.stamp.sec")?,
            stamp_nanosec: CdrReader::u32(self, "header.stamp.nanosec")?,
            frame_id: CdrReader::string(self, "header.frame_id")?,
        })
    }
}

/// Writes the fields of one little-endian CDR payload in order.
#[derive(Debug, Clone)]
pub struct CdrWriter {
    bytes: Vec<u8>,
}

impl Default for CdrWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl CdrWriter {
    /// An empty payload: the little-endian encapsulation header alone.
    pub fn new() -> Self {
        Self {
            bytes: vec![CDR_LE[0], CDR_LE[1], 0, 0],
        }
    }

    fn align(&mut self, to: usize) {
        while (self.bytes.len() - HEADER_LEN) % to != 0 {
            self.bytes.push(0);
        }
    }

    /// Appends a `uint8`.
    pub fn u8(&mut self, value: u8) {
        self.bytes.push(value);
    }

    /// Appends a `uint32`.
    pub fn u32(&mut self, value: u32) {
        self.align(4);
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    /// Appends an `int32`.
    pub fn i32(&mut self, value: i32) {
        self.align(4);
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    /// Appends a `float64`.
    pub fn f64(&mut self, value: f64) {
        self.align(8);
        self.bytes.extend_from_slice(&value.to_le_bytes());
    }

    /// Appends a `string` (length with NUL, bytes, NUL).
    pub fn string(&mut self, value: &str) {
        self.length(value.len() + 1);
        self.bytes.extend_from_slice(value.as_bytes());
        self.bytes.push(0);
    }

    /// Appends a `uint8[]` sequence.
    pub fn byte_sequence(&mut self, value: &[u8]) {
        self.length(value.len());
        self.bytes.extend_from_slice(value);
    }

    fn length(&mut self, len: usize) {
        // ROS messages cannot exceed 4 GiB; saturating keeps a reader's length check failing
        // rather than wrapping.
        self.u32(u32::try_from(len).unwrap_or(u32::MAX));
    }

    /// The finished payload.
    pub fn into_bytes(self) -> Vec<u8> {
        self.bytes
    }
}

impl FieldWriter for CdrWriter {
    fn u8(&mut self, value: u8) {
        CdrWriter::u8(self, value);
    }
    fn u32(&mut self, value: u32) {
        CdrWriter::u32(self, value);
    }
    fn f64(&mut self, value: f64) {
        CdrWriter::f64(self, value);
    }
    fn string(&mut self, value: &str) {
        CdrWriter::string(self, value);
    }
    fn byte_sequence(&mut self, value: &[u8]) {
        CdrWriter::byte_sequence(self, value);
    }
    fn header(&mut self, header: &Header) {
        self.i32(header.stamp_sec);
        CdrWriter::u32(self, header.stamp_nanosec);
        CdrWriter::string(self, &header.frame_id);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::message_fields::{FieldReader, FieldWriter};

    #[test]
    fn fields_round_trip_with_alignment() {
        let mut w = CdrWriter::new();
        w.i32(-7);
        w.string("cam");
        w.u8(1);
        w.f64(0.25);
        w.byte_sequence(&[1, 2, 3]);
        w.f64_sequence(&[1.5, -2.0]);
        w.f64_array(&[3.0; 3]);
        let bytes = w.into_bytes();
        // i32 (4) + string (4 + 4) + u8 (1) + padding (3): the f64 starts 16 bytes after the
        // 4-byte header.
        assert_eq!(&bytes[20..28], &0.25f64.to_le_bytes());
        let mut r = CdrReader::new(&bytes).unwrap();
        assert_eq!(r.i32("a").unwrap(), -7);
        assert_eq!(r.string("b").unwrap(), "cam");
        assert_eq!(r.u8("c").unwrap(), 1);
        assert_eq!(r.f64("d").unwrap(), 0.25);
        assert_eq!(r.byte_sequence("e").unwrap(), &[1, 2, 3]);
        assert_eq!(r.f64_sequence("f").unwrap(), vec![1.5, -2.0]);
        assert_eq!(r.f64_array::<3>("g").unwrap(), [3.0; 3]);
        assert!(matches!(r.u8("h"), Err(CdrError::Truncated { .. })));
    }

    #[test]
    fn big_endian_payloads_are_read() {
        let mut bytes = vec![0, 0, 0, 0];
        bytes.extend_from_slice(&640u32.to_be_bytes());
        bytes.extend_from_slice(&[0; 4]);
        bytes.extend_from_slice(&1.5f64.to_be_bytes());
        let mut r = CdrReader::new(&bytes).unwrap();
        assert_eq!(r.u32("w").unwrap(), 640);
        assert_eq!(r.f64("x").unwrap(), 1.5);
    }

    #[test]
    fn oversized_lengths_and_other_encapsulations_are_errors() {
        let mut w = CdrWriter::new();
        w.u32(1_000_000);
        let bytes = w.into_bytes();
        assert!(matches!(
            CdrReader::new(&bytes).unwrap().byte_sequence("data"),
            Err(CdrError::Truncated { what: "data", .. })
        ));
        assert!(matches!(
            CdrReader::new(&bytes).unwrap().f64_sequence("d"),
            Err(CdrError::Truncated { what: "d", .. })
        ));
        assert_eq!(
            CdrReader::new(&[0, 3, 0, 0]).unwrap_err(),
            CdrError::Encapsulation([0, 3])
        );
        assert!(CdrReader::new(&[0, 1]).is_err());
    }
}
