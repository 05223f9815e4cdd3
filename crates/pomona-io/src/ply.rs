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
//! ascii), so allocation is bounded by the file size; truncated rows, bad numbers and negative
//! list counts are [`PlyError`] variants naming the element and row.
//!
//! # What the writer produces
//! See [`write_ply`]: one `vertex` element, no faces.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use pomona_core::nalgebra::{Point3, Vector3};
use pomona_core::{CloudLayout, CoreError, PointCloud};

use crate::atomic_write::write_atomically;
use crate::cloud_file::push_f32;
use crate::pcd::clip;

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

    fn from_keyword(word: &str) -> Option<Self> {
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

/// A PLY scalar type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlyType {
    /// `char` / `int8`.
    Int8,
    /// `uchar` / `uint8`.
    UInt8,
    /// `short` / `int16`.
    Int16,
    /// `ushort` / `uint16`.
    UInt16,
    /// `int` / `int32`.
    Int32,
    /// `uint` / `uint32`.
    UInt32,
    /// `float` / `float32`.
    Float32,
    /// `double` / `float64`.
    Float64,
}

impl PlyType {
    /// Parses a type name (classic or sized form).
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => PlyType::Int8,
            "uchar" | "uint8" => PlyType::UInt8,
            "short" | "int16" => PlyType::Int16,
            "ushort" | "uint16" => PlyType::UInt16,
            "int" | "int32" => PlyType::Int32,
            "uint" | "uint32" => PlyType::UInt32,
            "float" | "float32" => PlyType::Float32,
            "double" | "float64" => PlyType::Float64,
            _ => return None,
        })
    }

    /// The classic type name, as written.
    pub fn name(self) -> &'static str {
        match self {
            PlyType::Int8 => "char",
            PlyType::UInt8 => "uchar",
            PlyType::Int16 => "short",
            PlyType::UInt16 => "ushort",
            PlyType::Int32 => "int",
            PlyType::UInt32 => "uint",
            PlyType::Float32 => "float",
            PlyType::Float64 => "double",
        }
    }

    /// Size in bytes in the binary formats.
    pub fn size(self) -> usize {
        match self {
            PlyType::Int8 | PlyType::UInt8 => 1,
            PlyType::Int16 | PlyType::UInt16 => 2,
            PlyType::Int32 | PlyType::UInt32 | PlyType::Float32 => 4,
            PlyType::Float64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, PlyType::Float32 | PlyType::Float64)
    }
}

/// The shape of a property.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlyPropertyKind {
    /// One value.
    Scalar(PlyType),
    /// A count (of an integer type) followed by that many items.
    List {
        /// Type of the count.
        count: PlyType,
        /// Type of each item.
        item: PlyType,
    },
}

/// One `property` line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlyProperty {
    /// Property name as written.
    pub name: String,
    /// Scalar or list, with types.
    pub kind: PlyPropertyKind,
}

/// One `element` line with its properties.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlyElement {
    /// Element name, e.g. `vertex`, `face`.
    pub name: String,
    /// Number of rows.
    pub count: u64,
    /// Properties of each row, in order.
    pub properties: Vec<PlyProperty>,
}

/// A parsed PLY header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlyHeader {
    /// The `format` line.
    pub encoding: PlyEncoding,
    /// Elements in file order.
    pub elements: Vec<PlyElement>,
    /// Text of the `comment` lines.
    pub comments: Vec<String>,
    /// Text of the `obj_info` lines.
    pub obj_info: Vec<String>,
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

// ---------------------------------------------------------------------------------------------
// Header

impl PlyHeader {
    /// Parses the header at the start of `bytes`; returns it and the offset where the data starts
    /// (just after the `end_header` line's newline).
    ///
    /// # Errors
    /// A [`PlyError`] header variant.
    pub fn parse(bytes: &[u8]) -> Result<(Self, usize), PlyError> {
        let mut pos = 0;
        let mut line_no = 0;
        let mut encoding = None;
        let mut elements: Vec<PlyElement> = Vec::new();
        let mut comments = Vec::new();
        let mut obj_info = Vec::new();
        loop {
            if pos >= bytes.len() {
                return Err(if line_no == 0 {
                    PlyError::NotPly
                } else {
                    PlyError::MissingEndHeader
                });
            }
            let rest = &bytes[pos..];
            let (raw, next) = match rest.iter().position(|&b| b == b'\n') {
                Some(i) => (&rest[..i], pos + i + 1),
                None => (rest, bytes.len()),
            };
            pos = next;
            line_no += 1;
            let line = line_no;
            let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
            let Ok(text) = std::str::from_utf8(raw) else {
                return Err(if line == 1 {
                    PlyError::NotPly
                } else {
                    PlyError::HeaderNotText { line }
                });
            };
            if line == 1 {
                if text.trim_end() != "ply" {
                    return Err(PlyError::NotPly);
                }
                continue;
            }
            let trimmed = text.trim_start();
            let mut words = trimmed.split_ascii_whitespace();
            let Some(keyword) = words.next() else {
                continue;
            };
            let args: Vec<&str> = words.collect();
            match keyword {
                "comment" | "obj_info" => {
                    let body = trimmed[keyword.len()..].trim().to_owned();
                    if keyword == "comment" {
                        comments.push(body);
                    } else {
                        obj_info.push(body);
                    }
                }
                "format" => {
                    if encoding.is_some() {
                        return Err(PlyError::DuplicateFormat { line });
                    }
                    let [fmt, version] = args.as_slice() else {
                        return Err(PlyError::MalformedHeaderLine {
                            line,
                            reason: "expected `format <type> 1.0`",
                        });
                    };
                    let enc =
                        PlyEncoding::from_keyword(fmt).ok_or_else(|| PlyError::UnknownFormat {
                            line,
                            format: clip(fmt),
                        })?;
                    if !matches!(*version, "1.0" | "1") {
                        return Err(PlyError::UnsupportedVersion {
                            line,
                            version: clip(version),
                        });
                    }
                    encoding = Some(enc);
                }
                "element" => {
                    if encoding.is_none() {
                        return Err(PlyError::MissingFormat);
                    }
                    let [name, count] = args.as_slice() else {
                        return Err(PlyError::MalformedHeaderLine {
                            line,
                            reason: "expected `element <name> <count>`",
                        });
                    };
                    let count =
                        count
                            .parse::<u64>()
                            .map_err(|_| PlyError::MalformedHeaderLine {
                                line,
                                reason: "element count is not a non-negative integer",
                            })?;
                    if elements.iter().any(|e| e.name == *name) {
                        return Err(PlyError::DuplicateElement {
                            line,
                            name: clip(name),
                        });
                    }
                    elements.push(PlyElement {
                        name: (*name).to_owned(),
                        count,
                        properties: Vec::new(),
                    });
                }
                "property" => {
                    let Some(element) = elements.last_mut() else {
                        return Err(PlyError::PropertyOutsideElement { line });
                    };
                    let ty = |t: &str| {
                        PlyType::from_name(t)
                            .ok_or_else(|| PlyError::InvalidType { line, ty: clip(t) })
                    };
                    let (name, kind) = match args.as_slice() {
                        ["list", count, item, name] => {
                            let count_ty = ty(count)?;
                            if !count_ty.is_integer() {
                                return Err(PlyError::InvalidType {
                                    line,
                                    ty: clip(count),
                                });
                            }
                            (
                                *name,
                                PlyPropertyKind::List {
                                    count: count_ty,
                                    item: ty(item)?,
                                },
                            )
                        }
                        [t, name] if *t != "list" => (*name, PlyPropertyKind::Scalar(ty(t)?)),
                        _ => {
                            return Err(PlyError::MalformedHeaderLine {
                                line,
                                reason: "expected `property <type> <name>` or `property list <count type> <item type> <name>`",
                            })
                        }
                    };
                    if element.properties.iter().any(|p| p.name == name) {
                        return Err(PlyError::DuplicateProperty {
                            element: clip(&element.name),
                            name: clip(name),
                        });
                    }
                    element.properties.push(PlyProperty {
                        name: name.to_owned(),
                        kind,
                    });
                }
                "end_header" => {
                    let encoding = encoding.ok_or(PlyError::MissingFormat)?;
                    return Ok((
                        PlyHeader {
                            encoding,
                            elements,
                            comments,
                            obj_info,
                        },
                        pos,
                    ));
                }
                other => {
                    return Err(PlyError::UnknownHeaderLine {
                        line,
                        keyword: clip(other),
                    })
                }
            }
        }
    }

    /// The element called `name`, if any.
    pub fn element(&self, name: &str) -> Option<&PlyElement> {
        self.elements.iter().find(|e| e.name == name)
    }
}

// ---------------------------------------------------------------------------------------------
// Reading

/// A decoded value.
#[derive(Debug, Clone, Copy)]
enum Num {
    I(i64),
    F32(f32),
    F64(f64),
}

impl Num {
    fn to_f32(self) -> f32 {
        match self {
            Num::I(v) => v as f32,
            Num::F32(v) => v,
            Num::F64(v) => v as f32,
        }
    }

    fn as_f64(self) -> f64 {
        match self {
            Num::I(v) => v as f64,
            Num::F32(v) => f64::from(v),
            Num::F64(v) => v,
        }
    }

    fn to_channel(self, ty: PlyType) -> u8 {
        match (self, ty) {
            (Num::I(v), PlyType::UInt16) => (v >> 8).clamp(0, 255) as u8,
            (Num::I(v), _) => v.clamp(0, 255) as u8,
            (v, _) => {
                let f = v.as_f64();
                if f.is_nan() {
                    0
                } else {
                    (f.clamp(0.0, 1.0) * 255.0).round() as u8
                }
            }
        }
    }

    fn to_label(self) -> Option<u32> {
        match self {
            Num::I(v) => u32::try_from(v).ok(),
            v => {
                let f = v.as_f64();
                (f.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&f)).then_some(f as u32)
            }
        }
    }
}

/// Why a value could not be read (context is added by the caller).
enum Fail {
    Eof,
    Bad { line: usize, token: String },
}

/// Row data in one of the three encodings.
trait RowSource {
    fn value(&mut self, ty: PlyType) -> Result<Num, Fail>;
    /// Skips `n` items of type `ty`.
    fn skip(&mut self, n: u64, ty: PlyType) -> Result<(), Fail>;
    fn remaining(&self) -> usize;
    /// Binary sources: the next `len` bytes at once, with the byte order (`true`: big endian).
    fn block(&mut self, _len: usize) -> Option<(&[u8], bool)> {
        None
    }
}

struct Binary<'a> {
    data: &'a [u8],
    pos: usize,
    big_endian: bool,
}

/// Decodes one binary value; `s` holds exactly `ty.size()` bytes (shorter is zero-padded).
fn decode_scalar(s: &[u8], ty: PlyType, big_endian: bool) -> Num {
    fn arr<const N: usize>(s: &[u8], big_endian: bool) -> [u8; N] {
        let mut a = [0_u8; N];
        let n = s.len().min(N);
        a[..n].copy_from_slice(&s[..n]);
        if big_endian {
            a.reverse();
        }
        a
    }
    let b = big_endian;
    match ty {
        PlyType::Int8 => Num::I(i64::from(i8::from_le_bytes(arr(s, b)))),
        PlyType::UInt8 => Num::I(i64::from(u8::from_le_bytes(arr(s, b)))),
        PlyType::Int16 => Num::I(i64::from(i16::from_le_bytes(arr(s, b)))),
        PlyType::UInt16 => Num::I(i64::from(u16::from_le_bytes(arr(s, b)))),
        PlyType::Int32 => Num::I(i64::from(i32::from_le_bytes(arr(s, b)))),
        PlyType::UInt32 => Num::I(i64::from(u32::from_le_bytes(arr(s, b)))),
        PlyType::Float32 => Num::F32(f32::from_le_bytes(arr(s, b))),
        PlyType::Float64 => Num::F64(f64::from_le_bytes(arr(s, b))),
    }
}

impl RowSource for Binary<'_> {
    fn value(&mut self, ty: PlyType) -> Result<Num, Fail> {
        let s = self
            .data
            .get(self.pos..self.pos + ty.size())
            .ok_or(Fail::Eof)?;
        self.pos += ty.size();
        Ok(decode_scalar(s, ty, self.big_endian))
    }

    fn block(&mut self, len: usize) -> Option<(&[u8], bool)> {
        let s = self.data.get(self.pos..self.pos.checked_add(len)?)?;
        self.pos += len;
        Some((s, self.big_endian))
    }

    fn skip(&mut self, n: u64, ty: PlyType) -> Result<(), Fail> {
        let bytes = n.checked_mul(ty.size() as u64).ok_or(Fail::Eof)?;
        if bytes > self.remaining() as u64 {
            return Err(Fail::Eof);
        }
        self.pos += bytes as usize;
        Ok(())
    }

    fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }
}

struct Ascii<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Ascii<'a> {
    fn token(&mut self) -> Option<(&'a [u8], usize)> {
        let data = self.data;
        while let Some(&b) = data.get(self.pos) {
            if !b.is_ascii_whitespace() {
                break;
            }
            if b == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
        let start = self.pos;
        while data.get(self.pos).is_some_and(|b| !b.is_ascii_whitespace()) {
            self.pos += 1;
        }
        (self.pos > start).then(|| (&data[start..self.pos], self.line))
    }
}

fn parse_ascii(tok: &str, ty: PlyType) -> Option<Num> {
    Some(match ty {
        PlyType::Int8 => Num::I(i64::from(tok.parse::<i8>().ok()?)),
        PlyType::UInt8 => Num::I(i64::from(tok.parse::<u8>().ok()?)),
        PlyType::Int16 => Num::I(i64::from(tok.parse::<i16>().ok()?)),
        PlyType::UInt16 => Num::I(i64::from(tok.parse::<u16>().ok()?)),
        PlyType::Int32 => Num::I(i64::from(tok.parse::<i32>().ok()?)),
        PlyType::UInt32 => Num::I(i64::from(tok.parse::<u32>().ok()?)),
        PlyType::Float32 => Num::F32(tok.parse::<f32>().ok()?),
        PlyType::Float64 => Num::F64(tok.parse::<f64>().ok()?),
    })
}

impl RowSource for Ascii<'_> {
    fn value(&mut self, ty: PlyType) -> Result<Num, Fail> {
        let (tok, line) = self.token().ok_or(Fail::Eof)?;
        std::str::from_utf8(tok)
            .ok()
            .and_then(|t| parse_ascii(t, ty))
            .ok_or_else(|| Fail::Bad {
                line,
                token: clip(&String::from_utf8_lossy(tok)),
            })
    }

    fn skip(&mut self, n: u64, ty: PlyType) -> Result<(), Fail> {
        // Each iteration consumes a token or stops, so this is bounded by the input.
        for _ in 0..n {
            self.value(ty)?;
        }
        Ok(())
    }

    fn remaining(&self) -> usize {
        self.data.len().saturating_sub(self.pos)
    }
}

/// Vertex property indices that map to cloud attributes.
#[derive(Debug, Default)]
struct VertexPlan {
    xyz: [Option<usize>; 3],
    rgb: [Option<usize>; 3],
    normal: [Option<usize>; 3],
    intensity: Option<usize>,
    label: Option<usize>,
}

impl VertexPlan {
    fn new(vertex: &PlyElement) -> Result<Self, PlyError> {
        let mut plan = VertexPlan::default();
        for (i, p) in vertex.properties.iter().enumerate() {
            let lower = p.name.to_ascii_lowercase();
            let slot = match lower.as_str() {
                "x" => &mut plan.xyz[0],
                "y" => &mut plan.xyz[1],
                "z" => &mut plan.xyz[2],
                "red" | "r" | "diffuse_red" => &mut plan.rgb[0],
                "green" | "g" | "diffuse_green" => &mut plan.rgb[1],
                "blue" | "b" | "diffuse_blue" => &mut plan.rgb[2],
                "nx" | "normal_x" => &mut plan.normal[0],
                "ny" | "normal_y" => &mut plan.normal[1],
                "nz" | "normal_z" => &mut plan.normal[2],
                "intensity" | "scalar_intensity" | "scalar" => &mut plan.intensity,
                "label" => &mut plan.label,
                _ => continue,
            };
            if matches!(p.kind, PlyPropertyKind::List { .. }) {
                return Err(PlyError::UnsupportedProperty {
                    name: clip(&p.name),
                    reason: "must be a scalar, not a list",
                });
            }
            if slot.replace(i).is_some() {
                return Err(PlyError::DuplicateProperty {
                    element: clip(&vertex.name),
                    name: clip(&p.name),
                });
            }
        }
        for (slot, name) in plan.xyz.iter().zip(["x", "y", "z"]) {
            if slot.is_none() {
                return Err(PlyError::MissingProperty(name));
            }
        }
        for (group, names) in [
            (&plan.rgb, ["red", "green", "blue"]),
            (&plan.normal, ["nx", "ny", "nz"]),
        ] {
            if group.iter().any(Option::is_some) {
                if let Some((_, name)) = group.iter().zip(names).find(|(s, _)| s.is_none()) {
                    return Err(PlyError::MissingProperty(name));
                }
            }
        }
        Ok(plan)
    }
}

/// Minimum bytes one row of `element` occupies in `encoding`.
fn min_row_bytes(element: &PlyElement, encoding: PlyEncoding) -> u64 {
    match encoding {
        PlyEncoding::Ascii => 2 * element.properties.len() as u64,
        _ => element
            .properties
            .iter()
            .map(|p| match p.kind {
                PlyPropertyKind::Scalar(t) => t.size() as u64,
                PlyPropertyKind::List { count, .. } => count.size() as u64,
            })
            .sum(),
    }
}

struct Vertices {
    points: Vec<Point3<f32>>,
    colors: Option<Vec<[u8; 3]>>,
    normals: Option<Vec<Vector3<f32>>>,
    intensities: Option<Vec<f32>>,
    labels: Option<Vec<u32>>,
}

impl Vertices {
    fn with_capacity(plan: &VertexPlan, n: usize) -> Self {
        Vertices {
            points: Vec::with_capacity(n),
            colors: plan.rgb[0].map(|_| Vec::with_capacity(n)),
            normals: plan.normal[0].map(|_| Vec::with_capacity(n)),
            intensities: plan.intensity.map(|_| Vec::with_capacity(n)),
            labels: plan.label.map(|_| Vec::with_capacity(n)),
        }
    }

    /// Appends vertex `row`, whose property `i` is `get(Some(i))`.
    fn push(
        &mut self,
        plan: &VertexPlan,
        color_types: &[PlyType; 3],
        row: u64,
        get: impl Fn(Option<usize>) -> Option<Num>,
    ) -> Result<(), PlyError> {
        let f = |i: Option<usize>| get(i).map_or(f32::NAN, Num::to_f32);
        self.points
            .push(Point3::new(f(plan.xyz[0]), f(plan.xyz[1]), f(plan.xyz[2])));
        if let Some(colors) = &mut self.colors {
            let ch = |k: usize| get(plan.rgb[k]).map_or(0, |v| v.to_channel(color_types[k]));
            colors.push([ch(0), ch(1), ch(2)]);
        }
        if let Some(normals) = &mut self.normals {
            normals.push(Vector3::new(
                f(plan.normal[0]),
                f(plan.normal[1]),
                f(plan.normal[2]),
            ));
        }
        if let Some(intensities) = &mut self.intensities {
            intensities.push(f(plan.intensity));
        }
        if let Some(labels) = &mut self.labels {
            let value = get(plan.label).unwrap_or(Num::I(0));
            labels.push(value.to_label().ok_or(PlyError::LabelOutOfRange {
                vertex: row,
                value: value.as_f64(),
            })?);
        }
        Ok(())
    }
}

fn read_rows(src: &mut dyn RowSource, header: &PlyHeader) -> Result<Option<Vertices>, PlyError> {
    let mut vertices = None;
    let mut row_values: Vec<Num> = Vec::new();
    for element in &header.elements {
        let eof = |row| PlyError::UnexpectedEof {
            element: clip(&element.name),
            row,
            count: element.count,
        };
        if element.properties.is_empty() {
            // Rows of nothing take no space.
            continue;
        }
        let is_vertex = element.name == "vertex";
        let plan = if is_vertex {
            let plan = VertexPlan::new(element)?;
            let available = src.remaining() as u64;
            let needed = element
                .count
                .saturating_mul(min_row_bytes(element, header.encoding))
                .saturating_sub(u64::from(header.encoding == PlyEncoding::Ascii));
            if needed > available {
                return Err(PlyError::Truncated {
                    vertices: element.count,
                    needed,
                    available,
                });
            }
            Some(plan)
        } else {
            None
        };
        // Bounded by the input length: checked just above.
        let n = if is_vertex { element.count as usize } else { 0 };
        let scalar_types: Vec<Option<PlyType>> = element
            .properties
            .iter()
            .map(|p| match p.kind {
                PlyPropertyKind::Scalar(t) => Some(t),
                PlyPropertyKind::List { .. } => None,
            })
            .collect();
        let color_types = plan.as_ref().map_or([PlyType::UInt8; 3], |plan| {
            plan.rgb.map(|i| {
                i.and_then(|i| scalar_types.get(i).copied().flatten())
                    .unwrap_or(PlyType::UInt8)
            })
        });
        let mut v = plan.as_ref().map(|plan| Vertices::with_capacity(plan, n));
        // Fast path: binary vertices of scalars only have a fixed size and are decoded in place.
        if let (Some(plan), Some(out)) = (&plan, &mut v) {
            if scalar_types.iter().all(Option::is_some) {
                let mut offsets = Vec::with_capacity(scalar_types.len());
                let mut row_size = 0;
                for t in scalar_types.iter().flatten() {
                    offsets.push((row_size, *t));
                    row_size += t.size();
                }
                if let Some((block, big)) = src.block(n.saturating_mul(row_size)) {
                    for (row, bytes) in block.chunks_exact(row_size.max(1)).enumerate() {
                        let get = |i: Option<usize>| {
                            let (off, t) = *offsets.get(i?)?;
                            Some(decode_scalar(bytes.get(off..)?, t, big))
                        };
                        out.push(plan, &color_types, row as u64, get)?;
                    }
                    vertices = v.take();
                    continue;
                }
            }
        }
        for row in 0..element.count {
            row_values.clear();
            for p in &element.properties {
                let ctx = |f: Fail, ty: PlyType| match f {
                    Fail::Eof => eof(row),
                    Fail::Bad { line, token } => PlyError::AsciiBadNumber {
                        line,
                        element: clip(&element.name),
                        property: clip(&p.name),
                        token,
                        ty: ty.name(),
                    },
                };
                match p.kind {
                    PlyPropertyKind::Scalar(t) => {
                        let value = src.value(t).map_err(|f| ctx(f, t))?;
                        if is_vertex {
                            row_values.push(value);
                        }
                    }
                    PlyPropertyKind::List { count, item } => {
                        let c = match src.value(count).map_err(|f| ctx(f, count))? {
                            Num::I(c) => c,
                            // Count types are integers (checked in the header).
                            other => other.as_f64() as i64,
                        };
                        let c = u64::try_from(c).map_err(|_| PlyError::InvalidListCount {
                            element: clip(&element.name),
                            row,
                            property: clip(&p.name),
                            count: c,
                        })?;
                        src.skip(c, item).map_err(|f| ctx(f, item))?;
                        if is_vertex {
                            row_values.push(Num::I(0));
                        }
                    }
                }
            }
            if let (Some(plan), Some(v)) = (&plan, &mut v) {
                let get = |i: Option<usize>| i.and_then(|i| row_values.get(i)).copied();
                v.push(plan, &color_types, row, get)?;
            }
        }
        if v.is_some() {
            vertices = v;
        }
    }
    Ok(vertices)
}

/// Reads a whole PLY file held in memory as an unorganised cloud.
///
/// # Errors
/// A [`PlyError`] naming what is wrong with the header or the data.
pub fn read_ply(bytes: &[u8]) -> Result<PointCloud, PlyError> {
    let (header, offset) = PlyHeader::parse(bytes)?;
    let vertex = header
        .element("vertex")
        .ok_or(PlyError::MissingVertexElement)?;
    if vertex.properties.is_empty() {
        return Err(PlyError::MissingProperty("x"));
    }
    let data = bytes.get(offset..).unwrap_or_default();
    let header_lines = 1 + bytes[..offset.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count();
    let vertices = match header.encoding {
        PlyEncoding::Ascii => read_rows(
            &mut Ascii {
                data,
                pos: 0,
                line: header_lines,
            },
            &header,
        )?,
        enc => read_rows(
            &mut Binary {
                data,
                pos: 0,
                big_endian: enc == PlyEncoding::BinaryBigEndian,
            },
            &header,
        )?,
    };
    let v = vertices.ok_or(PlyError::MissingVertexElement)?;
    let mut cloud = PointCloud::unorganized(v.points);
    if let Some(c) = v.colors {
        cloud = cloud.with_colors(c)?;
    }
    if let Some(n) = v.normals {
        cloud = cloud.with_normals(n)?;
    }
    if let Some(x) = v.intensities {
        cloud = cloud.with_intensities(x)?;
    }
    if let Some(l) = v.labels {
        cloud = cloud.with_labels(l)?;
    }
    Ok(cloud)
}

/// Reads the PLY file at `path` (entirely into memory) as an unorganised cloud.
///
/// # Errors
/// [`PlyError::File`] wrapping the cause.
pub fn read_ply_file(path: impl AsRef<Path>) -> Result<PointCloud, PlyError> {
    let path = path.as_ref();
    std::fs::read(path)
        .map_err(PlyError::from)
        .and_then(|bytes| read_ply(&bytes))
        .map_err(|e| e.with_path(path))
}

// ---------------------------------------------------------------------------------------------
// Writing

/// Writes `cloud` as a PLY 1.0 file with one `vertex` element and no faces.
///
/// Vertex properties: `float x y z`; `uchar red green blue` when the cloud has colours; `float nx
/// ny nz` with normals; `float intensity` with intensities; `uint label` with labels.
///
/// Invalid (`NaN`) points are **kept**, as `NaN` floats (`nan` in ascii): PLY floats allow them,
/// and keeping them preserves the point count and the row-major order of an organised cloud's
/// grid, so attributes indexed by pixel still line up. Consumers that choke on `NaN` should be
/// given [`PointCloud::without_invalid`]. The grid dimensions themselves are not stored (PLY has
/// no place for them beyond a comment, which this writer adds for humans); the cloud reads back
/// unorganised.
///
/// The output is buffered internally.
///
/// # Errors
/// [`PlyError::Io`] from the writer.
pub fn write_ply(
    cloud: &PointCloud,
    out: impl Write,
    encoding: PlyEncoding,
) -> Result<(), PlyError> {
    let n = cloud.len();
    let mut header = format!(
        "ply\nformat {} 1.0\ncomment written by pomona-io\n",
        encoding.keyword()
    );
    if let CloudLayout::Organized { width, height } = cloud.layout() {
        header.push_str(&format!(
            "comment organised {width}x{height} cloud, rows in order\n"
        ));
    }
    header.push_str(&format!(
        "element vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
    ));
    let colors = cloud.colors();
    let normals = cloud.normals();
    let intensities = cloud.intensities();
    let labels = cloud.labels();
    if colors.is_some() {
        header.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    if normals.is_some() {
        header.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    if intensities.is_some() {
        header.push_str("property float intensity\n");
    }
    if labels.is_some() {
        header.push_str("property uint label\n");
    }
    header.push_str("end_header\n");
    let mut w = BufWriter::with_capacity(1 << 16, out);
    w.write_all(header.as_bytes())?;
    let big = encoding == PlyEncoding::BinaryBigEndian;
    let f32b = |v: f32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let mut line = String::new();
    let mut row = Vec::new();
    for (i, p) in cloud.points().iter().enumerate() {
        let color = colors.and_then(|c| c.get(i));
        let normal = normals.and_then(|c| c.get(i));
        let intensity = intensities.and_then(|c| c.get(i));
        let label = labels.and_then(|c| c.get(i));
        if encoding == PlyEncoding::Ascii {
            line.clear();
            let floats = |line: &mut String, vs: &[f32]| {
                for &v in vs {
                    if !line.is_empty() {
                        line.push(' ');
                    }
                    push_f32(line, v);
                }
            };
            floats(&mut line, &[p.x, p.y, p.z]);
            if let Some(c) = color {
                line.push_str(&format!(" {} {} {}", c[0], c[1], c[2]));
            }
            if let Some(nv) = normal {
                floats(&mut line, &[nv.x, nv.y, nv.z]);
            }
            if let Some(&x) = intensity {
                floats(&mut line, &[x]);
            }
            if let Some(l) = label {
                line.push_str(&format!(" {l}"));
            }
            line.push('\n');
            w.write_all(line.as_bytes())?;
        } else {
            row.clear();
            for v in [p.x, p.y, p.z] {
                row.extend_from_slice(&f32b(v));
            }
            if let Some(c) = color {
                row.extend_from_slice(c);
            }
            if let Some(nv) = normal {
                for v in [nv.x, nv.y, nv.z] {
                    row.extend_from_slice(&f32b(v));
                }
            }
            if let Some(&x) = intensity {
                row.extend_from_slice(&f32b(x));
            }
            if let Some(&l) = label {
                row.extend_from_slice(&if big {
                    l.to_be_bytes()
                } else {
                    l.to_le_bytes()
                });
            }
            w.write_all(&row)?;
        }
    }
    w.flush()?;
    Ok(())
}

/// Writes `cloud` to the PLY file at `path` (see [`write_ply`]), replacing it atomically (see
/// [`crate::cloud_file`]).
///
/// # Errors
/// [`PlyError::File`] wrapping the cause.
pub fn write_ply_file(
    path: impl AsRef<Path>,
    cloud: &PointCloud,
    encoding: PlyEncoding,
) -> Result<(), PlyError> {
    let path = path.as_ref();
    write_atomically(
        path,
        |w| write_ply(cloud, w, encoding),
        |_, e| PlyError::from(e),
    )
    .map_err(|e| e.with_path(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_ascii_with_faces_and_odd_types() {
        let text = "ply\r\nformat ascii 1.0\r\ncomment hello\r\nobj_info made by hand\r\n\
            element vertex 3\r\nproperty double x\r\nproperty double y\r\nproperty double z\r\n\
            property float alpha\r\nproperty uchar diffuse_red\r\nproperty uchar diffuse_green\r\n\
            property uchar diffuse_blue\r\nproperty list uchar int extra\r\n\
            property ushort label\r\nelement face 1\r\nproperty list uchar int vertex_indices\r\n\
            end_header\r\n\
            0 0 0 1 255 0 0 2 7 8 5\r\n1 0 0 1 0 255 0 0 6\r\n0 1 nan 1 0 0 255 1 -3 65535\r\n\
            3 0 1 2\r\n";
        let (h, _) = PlyHeader::parse(text.as_bytes()).unwrap();
        assert_eq!(h.comments, ["hello"]);
        assert_eq!(h.obj_info, ["made by hand"]);
        assert_eq!(h.element("face").unwrap().count, 1);
        let c = read_ply(text.as_bytes()).unwrap();
        assert_eq!(c.len(), 3);
        assert_eq!(c.points()[1], Point3::new(1.0, 0.0, 0.0));
        assert!(c.points()[2].z.is_nan());
        assert_eq!(
            c.colors().unwrap(),
            &[[255, 0, 0], [0, 255, 0], [0, 0, 255]]
        );
        assert_eq!(c.labels().unwrap(), &[5, 6, 65535]);
        assert!(c.normals().is_none());
    }

    #[test]
    fn reads_big_endian_and_float_colours() {
        let mut bytes = b"ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nproperty float red\nproperty float green\nproperty ushort blue\nproperty int scalar\nend_header\n".to_vec();
        for v in [1.0_f32, 2.0, 3.0, 1.0, 0.5] {
            bytes.extend(v.to_be_bytes());
        }
        bytes.extend(0x8000_u16.to_be_bytes());
        bytes.extend((-7_i32).to_be_bytes());
        let c = read_ply(&bytes).unwrap();
        assert_eq!(c.points()[0], Point3::new(1.0, 2.0, 3.0));
        assert_eq!(c.colors().unwrap(), &[[255, 128, 128]]);
        assert_eq!(c.intensities().unwrap(), &[-7.0]);
    }

    #[test]
    fn reads_binary_vertices_with_a_list_property() {
        // Vertices with a list are not fixed-size, so they take the row-by-row path.
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty list uchar ushort idx\nproperty double x\nproperty double y\nproperty double z\nproperty uint label\nend_header\n".to_vec();
        for (k, items) in [(0_u8, &[][..]), (2, &[5_u16, 6][..])] {
            bytes.push(k);
            for it in items {
                bytes.extend(it.to_le_bytes());
            }
            for v in [f64::from(k), -1.5, 1e300] {
                bytes.extend(v.to_le_bytes());
            }
            bytes.extend((u32::from(k) + 40).to_le_bytes());
        }
        let c = read_ply(&bytes).unwrap();
        assert_eq!(c.len(), 2);
        assert_eq!(c.points()[1].x, 2.0);
        assert_eq!(c.points()[1].y, -1.5);
        assert_eq!(c.points()[1].z, f32::INFINITY);
        assert_eq!(c.labels().unwrap(), &[40, 42]);
        // One byte short: the last row is cut.
        assert!(matches!(
            read_ply(&bytes[..bytes.len() - 1]),
            Err(PlyError::UnexpectedEof { row: 1, .. })
        ));
    }

    fn err(text: &str) -> PlyError {
        read_ply(text.as_bytes()).unwrap_err()
    }

    #[test]
    fn header_errors_are_typed() {
        assert!(matches!(err(""), PlyError::NotPly));
        assert!(matches!(err("PCD\n"), PlyError::NotPly));
        assert!(matches!(
            err("ply\nformat ascii 1.0\n"),
            PlyError::MissingEndHeader
        ));
        assert!(matches!(
            err("ply\nelement vertex 1\nend_header\n"),
            PlyError::MissingFormat
        ));
        assert!(matches!(
            err("ply\nformat ascii 1.0\nformat ascii 1.0\n"),
            PlyError::DuplicateFormat { line: 3 }
        ));
        assert!(matches!(
            err("ply\nformat binary_middle_endian 1.0\n"),
            PlyError::UnknownFormat { line: 2, .. }
        ));
        assert!(matches!(
            err("ply\nformat ascii 2.0\n"),
            PlyError::UnsupportedVersion { .. }
        ));
        assert!(matches!(
            err("ply\nformat ascii 1.0\nproperty float x\n"),
            PlyError::PropertyOutsideElement { line: 3 }
        ));
        assert!(matches!(
            err("ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\n"),
            PlyError::InvalidType { line: 4, .. }
        ));
        assert!(matches!(
            err("ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int x\n"),
            PlyError::InvalidType { .. }
        ));
        assert!(matches!(
            err("ply\nformat ascii 1.0\nelement vertex -1\n"),
            PlyError::MalformedHeaderLine { line: 3, .. }
        ));
        assert!(matches!(
            err("ply\nformat ascii 1.0\nelement vertex 1\nelement vertex 2\n"),
            PlyError::DuplicateElement { line: 4, .. }
        ));
        assert!(matches!(
            err("ply\nformat ascii 1.0\nbanana\n"),
            PlyError::UnknownHeaderLine { line: 3, .. }
        ));
        assert!(matches!(
            err("ply\nformat ascii 1.0\nelement face 0\nend_header\n"),
            PlyError::MissingVertexElement
        ));
        assert!(matches!(
            err("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n"),
            PlyError::MissingProperty("z")
        ));
        assert!(matches!(
            err("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar diffuse_red\nend_header\n"),
            PlyError::DuplicateProperty { .. }
        ));
        assert!(matches!(
            err("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nend_header\n"),
            PlyError::MissingProperty("green")
        ));
    }

    #[test]
    fn data_errors_are_typed() {
        let head = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list char int v\nend_header\n";
        assert!(matches!(
            err(&format!("{head}1 2 3\n4 5 6\n-1\n")),
            PlyError::InvalidListCount { count: -1, .. }
        ));
        assert!(matches!(
            err(&format!("{head}1 2 3\n4 5 six\n")),
            PlyError::AsciiBadNumber { line: 11, .. }
        ));
        assert!(matches!(
            err(&format!("{head}1 2 3\n4 5 6\n3 1 2\n")),
            PlyError::UnexpectedEof { row: 0, .. }
        ));
        assert!(matches!(
            err(&format!("{head}1 2 3\n")),
            PlyError::Truncated { vertices: 2, .. }
        ));
    }
}
