//! PCD, the Point Cloud Library's point-cloud file format (versions 0.7 and 0.6).
//!
//! A PCD file is a short text header followed by the point data:
//!
//! ```text
//! # .PCD v0.7 - Point Cloud Data file format
//! VERSION 0.7
//! FIELDS x y z rgb label
//! SIZE 4 4 4 4 4
//! TYPE F F F F U
//! COUNT 1 1 1 1 1
//! WIDTH 640
//! HEIGHT 480
//! VIEWPOINT 0 0 0 1 0 0 0
//! POINTS 307200
//! DATA binary_compressed
//! ```
//!
//! Each *field* is `COUNT` scalars of `SIZE` bytes and `TYPE` `I` (signed), `U` (unsigned) or `F`
//! (IEEE float). `HEIGHT > 1` means an organised (image-shaped) cloud. The data is one of
//!
//! * `ascii`: one point per line, whitespace-separated values in field order;
//! * `binary`: the points back to back (point-major), little endian;
//! * `binary_compressed`: `u32` compressed size, `u32` uncompressed size (little endian), then an
//!   [LZF](crate::lzf) stream that decompresses to the values *field-major*: every point's first
//!   field, then every point's second field, and so on.
//!
//! # What maps to a [`PointCloud`]
//! `x y z` (required) become positions; `rgb`/`rgba` (4 bytes holding `0xAARRGGBB`, whether typed
//! as a float or an integer) become colours; `label`, `normal_x normal_y normal_z` and `intensity`
//! become the matching attributes. Any other field (`curvature`, `_` padding, descriptors with
//! `COUNT > 1`, …) is skipped using its `SIZE`, `TYPE` and `COUNT`. Values of any type are
//! converted (positions, normals and intensities to `f32`; labels must be integers that fit a
//! `u32`). Invalid (`NaN`) points are kept, so organised clouds keep their grid.
//!
//! # Robustness
//! The reader never panics and never allocates more than a small multiple of the input size: the
//! declared point count is checked against the bytes actually present *before* anything is
//! allocated, and a `binary_compressed` payload must declare an uncompressed size equal to
//! `POINTS × point size` and achievable by LZF ([`crate::lzf::MAX_EXPANSION_RATIO`]). Every
//! failure is a [`PcdError`] variant naming what is wrong.
//!
//! Deviations from PCL, deliberately stricter: unknown header keywords are an error (PCL ignores
//! them), as are recognised fields with `COUNT != 1`, a second `x`/`rgb`/… field, and normals with
//! only some of their three components. `VERSION` is optional and not interpreted.
//!
//! # What the writer produces
//! See [`write_pcd`]: `x y z` as `F 4`; then, when the cloud has them, `rgb`, `normal_x normal_y
//! normal_z` (`F 4`), `intensity` (`F 4`) and `label` (`U 4`); `WIDTH`/`HEIGHT` from the layout;
//! `VIEWPOINT 0 0 0 1 0 0 0`.

mod header;
mod read;
mod write;

use std::path::PathBuf;

use pomona_core::CoreError;

pub use header::{PcdField, PcdHeader, PcdScalar};
pub use read::{read_pcd, read_pcd_file, read_pcd_header_file};
pub use write::{write_pcd, write_pcd_file};

#[cfg(doc)]
use pomona_core::PointCloud;

use crate::lzf::LzfError;

/// How the point data of a PCD file is stored (its `DATA` line).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PcdEncoding {
    /// Text, one point per line.
    Ascii,
    /// Raw little-endian points, point-major.
    Binary,
    /// LZF-compressed little-endian values, field-major.
    BinaryCompressed,
}

impl PcdEncoding {
    /// The word used on the `DATA` line.
    pub fn keyword(self) -> &'static str {
        match self {
            PcdEncoding::Ascii => "ascii",
            PcdEncoding::Binary => "binary",
            PcdEncoding::BinaryCompressed => "binary_compressed",
        }
    }

    /// Parses a `DATA` word (case-insensitive).
    pub fn from_keyword(word: &str) -> Option<Self> {
        [
            PcdEncoding::Ascii,
            PcdEncoding::Binary,
            PcdEncoding::BinaryCompressed,
        ]
        .into_iter()
        .find(|e| e.keyword().eq_ignore_ascii_case(word))
    }
}

impl std::fmt::Display for PcdEncoding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.keyword())
    }
}

/// Why a PCD file could not be read or written.
///
/// Wrapped causes ([`PcdError::File`], [`PcdError::Io`], [`PcdError::Lzf`]) are reported through
/// [`std::error::Error::source`], not repeated in the message; print the chain (e.g. anyhow's
/// `{:#}`) to see them. Header line numbers are 1-based and count every line of the file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PcdError {
    /// An error while reading or writing a particular file.
    #[error("PCD file {}", path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        #[source]
        source: Box<PcdError>,
    },
    /// The underlying reader or writer failed.
    #[error("I/O error")]
    Io(#[from] std::io::Error),
    /// A header line is not UTF-8 text (often: this is not a PCD file).
    #[error("header line {line} is not text; not a PCD file?")]
    HeaderNotText {
        /// The line.
        line: usize,
    },
    /// A header line starts with a word that is not a PCD keyword.
    #[error("header line {line}: unknown keyword {keyword:?}; not a PCD file?")]
    UnknownHeaderLine {
        /// The line.
        line: usize,
        /// Its first word (truncated to 40 characters).
        keyword: String,
    },
    /// A required header line is absent.
    #[error("header has no {0} line")]
    MissingHeaderLine(&'static str),
    /// A header keyword appears twice.
    #[error("header line {line}: second {keyword} line")]
    DuplicateHeaderLine {
        /// The keyword.
        keyword: &'static str,
        /// The line of the second occurrence.
        line: usize,
    },
    /// A header value cannot be parsed or is out of range.
    #[error("header line {line}: invalid {keyword} value {value:?}: {reason}")]
    InvalidHeaderValue {
        /// The keyword.
        keyword: &'static str,
        /// The line.
        line: usize,
        /// The offending text (truncated to 40 characters).
        value: String,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// The `DATA` line names an unknown storage type.
    #[error("header line {line}: unknown DATA type {value:?} (expected ascii, binary or binary_compressed)")]
    UnknownDataType {
        /// The line.
        line: usize,
        /// The word found (truncated to 40 characters).
        value: String,
    },
    /// `SIZE`, `TYPE` or `COUNT` does not have one entry per field.
    #[error("FIELDS lists {fields} fields but {keyword} has {found} entries")]
    FieldCountMismatch {
        /// `SIZE`, `TYPE` or `COUNT`.
        keyword: &'static str,
        /// Number of fields.
        fields: usize,
        /// Number of entries on the other line.
        found: usize,
    },
    /// A field's `TYPE`/`SIZE` pair is not one PCL allows (`I`/`U` of 1, 2, 4, 8 bytes; `F` of 4, 8).
    #[error("field {field:?} has unsupported TYPE {ty} with SIZE {size}")]
    InvalidFieldType {
        /// The field.
        field: String,
        /// Its `TYPE` letter.
        ty: char,
        /// Its `SIZE`.
        size: u64,
    },
    /// `WIDTH × HEIGHT` differs from `POINTS`.
    #[error("WIDTH {width} × HEIGHT {height} = {product} but POINTS is {points}")]
    PointCountMismatch {
        /// Declared width.
        width: u32,
        /// Declared height.
        height: u32,
        /// Their product.
        product: u64,
        /// Declared number of points.
        points: u64,
    },
    /// A field the reader needs (`x`, `y` or `z`; a normal component when another is present).
    #[error("no {0:?} field")]
    MissingField(&'static str),
    /// A field that maps to a cloud attribute appears twice (`rgb` and `rgba` count as one).
    #[error("field {0:?} appears more than once")]
    DuplicateField(String),
    /// A recognised field has a shape the reader cannot map.
    #[error("field {field:?}: {reason}")]
    UnsupportedField {
        /// The field.
        field: String,
        /// Why.
        reason: &'static str,
    },
    /// The file declares more point data than it contains (checked before allocating).
    #[error(
        "data is truncated: {points} points need {needed} bytes but only {available} are present"
    )]
    Truncated {
        /// Declared number of points.
        points: u64,
        /// Bytes the declared points need (saturating).
        needed: u64,
        /// Bytes present after the header.
        available: u64,
    },
    /// A `binary_compressed` uncompressed size that does not match `POINTS × point size`.
    #[error(
        "binary_compressed: uncompressed size {declared} but POINTS × point size is {expected}"
    )]
    CompressedSizeMismatch {
        /// The size in the file.
        declared: u64,
        /// `POINTS × point size`.
        expected: u64,
    },
    /// A `binary_compressed` size pair that LZF cannot produce.
    #[error(
        "binary_compressed: {uncompressed} bytes cannot come from {compressed} bytes of LZF data"
    )]
    ImplausibleCompression {
        /// Declared compressed size.
        compressed: u64,
        /// Declared uncompressed size.
        uncompressed: u64,
    },
    /// The LZF payload is corrupt.
    #[error("binary_compressed payload is corrupt")]
    Lzf(#[from] LzfError),
    /// `ascii` data has fewer point lines than `POINTS`.
    #[error("ascii data has {found} point lines but POINTS is {expected}")]
    AsciiTooFewPoints {
        /// Declared number of points.
        expected: u64,
        /// Point lines found.
        found: u64,
    },
    /// An `ascii` point line with the wrong number of values.
    #[error("line {line}: {found} values but the fields need {expected}")]
    AsciiValueCount {
        /// The line.
        line: usize,
        /// Values per point implied by the header.
        expected: usize,
        /// Values on the line.
        found: usize,
    },
    /// An `ascii` value that is not a number of its field's type.
    #[error("line {line}: {token:?} is not a valid {ty} value for field {field:?}")]
    AsciiBadNumber {
        /// The line.
        line: usize,
        /// The field.
        field: String,
        /// The offending text (truncated to 40 characters).
        token: String,
        /// The field's type, e.g. `U 1`.
        ty: String,
    },
    /// A label value that is not a non-negative integer fitting in `u32`.
    #[error("point {point}: label {value} is not an integer in 0..=4294967295")]
    LabelOutOfRange {
        /// The point's index.
        point: u64,
        /// The value read.
        value: f64,
    },
    /// Decoding would allocate more than the reader's budget for a file of this size (see
    /// [`crate::read_budget`]): the header declares far more data than the file can hold.
    #[error(
        "decoding needs {needed} bytes, over the budget of {budget} bytes for a file this size"
    )]
    OverBudget {
        /// Bytes the decoded data would take.
        needed: u64,
        /// The budget ([`crate::read_budget::decode_budget_bytes`] of the input size).
        budget: u64,
    },
    /// The cloud is too large to be described by a PCD header (`WIDTH` and compressed sizes are
    /// 32-bit).
    #[error("cloud too large for PCD: {0}")]
    TooLarge(&'static str),
    /// The decoded attributes could not form a cloud (an internal inconsistency).
    #[error("decoded data does not form a cloud: {0}")]
    Cloud(#[from] CoreError),
}

impl PcdError {
    /// Attaches a path, unless the error already carries one.
    pub fn with_path(self, path: impl Into<PathBuf>) -> Self {
        match self {
            e @ PcdError::File { .. } => e,
            e => PcdError::File {
                path: path.into(),
                source: Box::new(e),
            },
        }
    }

    /// The error without the path wrapper, for matching on the cause.
    pub fn root(&self) -> &PcdError {
        match self {
            PcdError::File { source, .. } => source.root(),
            e => e,
        }
    }
}

/// Shortens user-controlled text quoted in an error message.
pub(crate) fn clip(s: &str) -> String {
    const MAX: usize = 40;
    match s.char_indices().nth(MAX) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_owned(),
    }
}
