//! The PLY header: the `format` line, then `element` lines each followed by its `property`
//! lines, up to `end_header`. Parsing it tells how the rows that follow are laid out.

use std::collections::HashSet;

use super::{PlyEncoding, PlyError};
use crate::pcd::clip;

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

    pub(super) fn is_integer(self) -> bool {
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

impl PlyHeader {
    /// Parses the header at the start of `bytes`; returns it and the offset where the data starts
    /// (just after the `end_header` line's newline).
    ///
    /// # Errors
    /// A [`PlyError`] header variant.
    pub fn parse(bytes: &[u8]) -> Result<(Self, usize), PlyError> {
        let mut pos = 0;
        let mut line = 0;
        let mut builder = HeaderBuilder::default();
        loop {
            if pos >= bytes.len() {
                return Err(if line == 0 {
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
            line += 1;
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
            if builder.feed(text, line)? {
                return Ok((builder.finish()?, pos));
            }
        }
    }

    /// The element called `name`, if any.
    pub fn element(&self, name: &str) -> Option<&PlyElement> {
        self.elements.iter().find(|e| e.name == name)
    }
}

/// The header read so far, line by line after the first.
#[derive(Default)]
struct HeaderBuilder {
    encoding: Option<PlyEncoding>,
    elements: Vec<PlyElement>,
    /// Names in `elements`, for the duplicate check (a hostile header may have very many).
    element_names: HashSet<String>,
    /// Property names of the last element, for the same reason.
    property_names: HashSet<String>,
    comments: Vec<String>,
    obj_info: Vec<String>,
}

impl HeaderBuilder {
    /// Takes header line number `line` (after the first); `true` at `end_header`.
    fn feed(&mut self, text: &str, line: usize) -> Result<bool, PlyError> {
        let trimmed = text.trim_start();
        let mut words = trimmed.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            return Ok(false);
        };
        let args: Vec<&str> = words.collect();
        match keyword {
            "comment" => self
                .comments
                .push(trimmed[keyword.len()..].trim().to_owned()),
            "obj_info" => self
                .obj_info
                .push(trimmed[keyword.len()..].trim().to_owned()),
            "format" => self.format(&args, line)?,
            "element" => self.element(&args, line)?,
            "property" => self.property(&args, line)?,
            "end_header" => return Ok(true),
            other => {
                return Err(PlyError::UnknownHeaderLine {
                    line,
                    keyword: clip(other),
                })
            }
        }
        Ok(false)
    }

    fn format(&mut self, args: &[&str], line: usize) -> Result<(), PlyError> {
        if self.encoding.is_some() {
            return Err(PlyError::DuplicateFormat { line });
        }
        let [fmt, version] = args else {
            return Err(PlyError::MalformedHeaderLine {
                line,
                reason: "expected `format <type> 1.0`",
            });
        };
        let enc = PlyEncoding::from_keyword(fmt).ok_or_else(|| PlyError::UnknownFormat {
            line,
            format: clip(fmt),
        })?;
        if !matches!(*version, "1.0" | "1") {
            return Err(PlyError::UnsupportedVersion {
                line,
                version: clip(version),
            });
        }
        self.encoding = Some(enc);
        Ok(())
    }

    fn element(&mut self, args: &[&str], line: usize) -> Result<(), PlyError> {
        if self.encoding.is_none() {
            return Err(PlyError::MissingFormat);
        }
        let [name, count] = args else {
            return Err(PlyError::MalformedHeaderLine {
                line,
                reason: "expected `element <name> <count>`",
            });
        };
        let count = count
            .parse::<u64>()
            .map_err(|_| PlyError::MalformedHeaderLine {
                line,
                reason: "element count is not a non-negative integer",
            })?;
        if !self.element_names.insert((*name).to_owned()) {
            return Err(PlyError::DuplicateElement {
                line,
                name: clip(name),
            });
        }
        self.property_names.clear();
        self.elements.push(PlyElement {
            name: (*name).to_owned(),
            count,
            properties: Vec::new(),
        });
        Ok(())
    }

    fn property(&mut self, args: &[&str], line: usize) -> Result<(), PlyError> {
        let Some(element) = self.elements.last_mut() else {
            return Err(PlyError::PropertyOutsideElement { line });
        };
        let ty = |t: &str| {
            PlyType::from_name(t).ok_or_else(|| PlyError::InvalidType { line, ty: clip(t) })
        };
        let (name, kind) = match args {
            ["list", count, item, name] => {
                let count_ty = ty(count)?;
                if !count_ty.is_integer() {
                    return Err(PlyError::InvalidType {
                        line,
                        ty: clip(count),
                    });
                }
                let item = ty(item)?;
                let kind = PlyPropertyKind::List {
                    count: count_ty,
                    item,
                };
                (*name, kind)
            }
            [t, name] if *t != "list" => (*name, PlyPropertyKind::Scalar(ty(t)?)),
            _ => {
                return Err(PlyError::MalformedHeaderLine {
                    line,
                    reason: "expected `property <type> <name>` or `property list <count type> <item type> <name>`",
                })
            }
        };
        if !self.property_names.insert(name.to_owned()) {
            return Err(PlyError::DuplicateProperty {
                element: clip(&element.name),
                name: clip(name),
            });
        }
        element.properties.push(PlyProperty {
            name: name.to_owned(),
            kind,
        });
        Ok(())
    }

    fn finish(self) -> Result<PlyHeader, PlyError> {
        Ok(PlyHeader {
            encoding: self.encoding.ok_or(PlyError::MissingFormat)?,
            elements: self.elements,
            comments: self.comments,
            obj_info: self.obj_info,
        })
    }
}
