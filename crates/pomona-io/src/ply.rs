//! PLY (the Stanford polygon file format), read and written as a point cloud.
//!
//! A PLY file is a text header declaring *elements* (rows of typed *properties*), then the rows:
//!
//! ```text
//! ply
//! format binary_little_endian 1.0
//! comment anything
//! element vertex 3
//! property float x
//! property float y
//! property float z
//! property uchar red
//! property uchar green
//! property uchar blue
//! element face 1
//! property list uchar int vertex_indices
//! end_header
//! ```
//!
//! Formats `ascii 1.0`, `binary_little_endian 1.0` and `binary_big_endian 1.0` are read and
//! written. Scalar types are `char uchar short ushort int uint float double` and their
//! `int8 … float64` aliases; a *list* property stores a count followed by that many items.
//!
//! # What maps to a [`PointCloud`]
//! From the `vertex` element (property names case-insensitive): `x y z` (required, any type);
//! `red green blue` (also `r g b`, `diffuse_red diffuse_green diffuse_blue`): `uchar` as is,
//! `ushort` scaled down by 256, floats taken as 0–1 and scaled to 0–255, other integers clamped;
//! `nx ny nz` (or `normal_x …`); `intensity` (or `scalar_intensity`, `scalar`); `label`. `alpha`
//! and every other vertex property are skipped by type; every other element (faces, edges, …) is
//! parsed and skipped, list properties included. PLY has no grid, so clouds read unorganised.
//!
//! # Robustness
//! The reader never panics. Before allocating, the vertex count is checked against the bytes left
//! (every vertex needs at least its scalar bytes, or one character and a separator per value in
//! ascii) and the decoded columns against the read budget ([`crate::read_budget`]), so allocation
//! is bounded by the file size; truncated rows, bad numbers and negative list counts are
//! [`PlyError`] variants naming the element and row.
//!
//! # Where things are
//! [`header`] parses the header; `rows` reads values in each encoding; `vertices` maps vertex
//! properties to cloud columns; [`read`] walks the elements; [`write`] writes a cloud.
//!
//! # What the writer produces
//! See [`write_ply`]: one `vertex` element, no faces.

mod header;
mod read;
mod rows;
mod vertices;
mod write;

use std::path::PathBuf;

use pomona_core::CoreError;

pub use header::{PlyElement, PlyHeader, PlyProperty, PlyPropertyKind, PlyType};
pub use read::{read_ply, read_ply_file};
pub use write::{write_ply, write_ply_file};

/// How the rows of a PLY file are stored (its `format` line).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlyEncoding {
    /// Text, whitespace-separated values.
    Ascii,
    /// Binary, little endian.
    BinaryLittleEndian,
    /// Binary, big endian.
    BinaryBigEndian,
}

impl PlyEncoding {
    /// The word used on the `format` line.
    pub fn keyword(self) -> &'static str {
        match self {
            PlyEncoding::Ascii => "ascii",
            PlyEncoding::BinaryLittleEndian => "binary_little_endian",
            PlyEncoding::BinaryBigEndian => "binary_big_endian",
        }
    }

    pub(crate) fn from_keyword(word: &str) -> Option<Self> {
        [
            PlyEncoding::Ascii,
            PlyEncoding::BinaryLittleEndian,
            PlyEncoding::BinaryBigEndian,
        ]
        .into_iter()
        .find(|e| e.keyword() == word)
    }
}

impl std::fmt::Display for PlyEncoding {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.keyword())
    }
}

/// Why a PLY file could not be read or written.
///
/// Wrapped causes ([`PlyError::File`], [`PlyError::Io`]) are reported through
/// [`std::error::Error::source`], not repeated in the message. Header line numbers are 1-based.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlyError {
    /// An error while reading or writing a particular file.
    #[error("PLY file {}", path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        #[source]
        source: Box<PlyError>,
    },
    /// The underlying reader or writer failed.
    #[error("I/O error")]
    Io(#[from] std::io::Error),
    /// The file does not start with the line `ply`.
    #[error("not a PLY file (the first line is not \"ply\")")]
    NotPly,
    /// A header line is not UTF-8 text.
    #[error("header line {line} is not text")]
    HeaderNotText {
        /// The line.
        line: usize,
    },
    /// The header never reaches `end_header`.
    #[error("header has no end_header line")]
    MissingEndHeader,
    /// No `format` line before the first element or the end of the header.
    #[error("header has no format line")]
    MissingFormat,
    /// A second `format` line.
    #[error("header line {line}: second format line")]
    DuplicateFormat {
        /// The line.
        line: usize,
    },
    /// A `format` other than ascii / binary_little_endian / binary_big_endian.
    #[error("header line {line}: unknown format {format:?}")]
    UnknownFormat {
        /// The line.
        line: usize,
        /// The word found (truncated to 40 characters).
        format: String,
    },
    /// A format version other than 1.0.
    #[error("header line {line}: unsupported PLY version {version:?} (only 1.0)")]
    UnsupportedVersion {
        /// The line.
        line: usize,
        /// The version found (truncated to 40 characters).
        version: String,
    },
    /// A header line with an unknown keyword.
    #[error("header line {line}: unknown keyword {keyword:?}")]
    UnknownHeaderLine {
        /// The line.
        line: usize,
        /// Its first word (truncated to 40 characters).
        keyword: String,
    },
    /// A known header line with the wrong shape.
    #[error("header line {line}: {reason}")]
    MalformedHeaderLine {
        /// The line.
        line: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// An unknown scalar type name (or a float list count).
    #[error("header line {line}: invalid type {ty:?}")]
    InvalidType {
        /// The line.
        line: usize,
        /// The type text (truncated to 40 characters).
        ty: String,
    },
    /// A `property` line before any `element` line.
    #[error("header line {line}: property outside any element")]
    PropertyOutsideElement {
        /// The line.
        line: usize,
    },
    /// Two elements with the same name.
    #[error("header line {line}: second element {name:?}")]
    DuplicateElement {
        /// The line.
        line: usize,
        /// The element name (truncated to 40 characters).
        name: String,
    },
    /// Two properties of one element with the same name, or two that map to the same
    /// attribute (e.g. `red` and `diffuse_red`).
    #[error("element {element:?} has property {name:?} twice")]
    DuplicateProperty {
        /// The element.
        element: String,
        /// The property (truncated to 40 characters).
        name: String,
    },
    /// There is no `vertex` element.
    #[error("no vertex element")]
    MissingVertexElement,
    /// A vertex property the reader needs (`x`, `y`, `z`; the rest of a colour or normal).
    #[error("vertex element has no {0:?} property")]
    MissingProperty(&'static str),
    /// A recognised vertex property has a shape the reader cannot map.
    #[error("vertex property {name:?}: {reason}")]
    UnsupportedProperty {
        /// The property.
        name: String,
        /// Why.
        reason: &'static str,
    },
    /// The declared vertices cannot fit in the data that follows (checked before allocating).
    #[error("data is truncated: {vertices} vertices need at least {needed} bytes but {available} remain")]
    Truncated {
        /// Declared vertex count.
        vertices: u64,
        /// Minimum bytes they need (saturating).
        needed: u64,
        /// Bytes left when the vertex element starts.
        available: u64,
    },
    /// The data ends inside an element's rows.
    #[error("data ends in row {row} of element {element:?} (of {count})")]
    UnexpectedEof {
        /// The element.
        element: String,
        /// The row being read.
        row: u64,
        /// The element's declared row count.
        count: u64,
    },
    /// An ascii value that is not a number of its property's type.
    #[error("line {line}: {token:?} is not a valid {ty} for {element}.{property}")]
    AsciiBadNumber {
        /// The line of the data.
        line: usize,
        /// The element.
        element: String,
        /// The property.
        property: String,
        /// The offending text (truncated to 40 characters).
        token: String,
        /// The expected type name.
        ty: &'static str,
    },
    /// A negative list count.
    #[error("element {element:?} row {row}: negative list count {count} for {property}")]
    InvalidListCount {
        /// The element.
        element: String,
        /// The row.
        row: u64,
        /// The property.
        property: String,
        /// The count read.
        count: i64,
    },
    /// Decoding would allocate more than the reader's budget for a file of this size (see
    /// [`crate::read_budget`]).
    #[error(
        "decoding needs {needed} bytes, over the budget of {budget} bytes for a file this size"
    )]
    OverBudget {
        /// Bytes the decoded vertices would take.
        needed: u64,
        /// The budget ([`crate::read_budget::decode_budget_bytes`] of the input size).
        budget: u64,
    },
    /// A label that is not a non-negative integer fitting in `u32`.
    #[error("vertex {vertex}: label {value} is not an integer in 0..=4294967295")]
    LabelOutOfRange {
        /// The vertex index.
        vertex: u64,
        /// The value read.
        value: f64,
    },
    /// The decoded attributes could not form a cloud (an internal inconsistency).
    #[error("decoded data does not form a cloud: {0}")]
    Cloud(#[from] CoreError),
}

impl PlyError {
    /// Attaches a path, unless the error already carries one.
    pub fn with_path(self, path: impl Into<PathBuf>) -> Self {
        match self {
            e @ PlyError::File { .. } => e,
            e => PlyError::File {
                path: path.into(),
                source: Box::new(e),
            },
        }
    }

    /// The error without the path wrapper, for matching on the cause.
    pub fn root(&self) -> &PlyError {
        match self {
            PlyError::File { source, .. } => source.root(),
            e => e,
        }
    }
}
