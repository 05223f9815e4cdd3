//! The PCD header: the text lines before the point data that say which fields each point has,
//! how they are stored and how many points follow.

use pomona_core::CloudLayout;

use super::{clip, PcdEncoding, PcdError};

/// The scalar type of a PCD field: its `TYPE` letter and `SIZE` in bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PcdScalar {
    /// `I 1`.
    I8,
    /// `I 2`.
    I16,
    /// `I 4`.
    I32,
    /// `I 8`.
    I64,
    /// `U 1`.
    U8,
    /// `U 2`.
    U16,
    /// `U 4`.
    U32,
    /// `U 8`.
    U64,
    /// `F 4`.
    F32,
    /// `F 8`.
    F64,
}

impl PcdScalar {
    /// The scalar for a `TYPE` letter and `SIZE`, if PCL allows the pair.
    pub fn from_type_size(ty: char, size: u64) -> Option<Self> {
        Some(match (ty, size) {
            ('I', 1) => PcdScalar::I8,
            ('I', 2) => PcdScalar::I16,
            ('I', 4) => PcdScalar::I32,
            ('I', 8) => PcdScalar::I64,
            ('U', 1) => PcdScalar::U8,
            ('U', 2) => PcdScalar::U16,
            ('U', 4) => PcdScalar::U32,
            ('U', 8) => PcdScalar::U64,
            ('F', 4) => PcdScalar::F32,
            ('F', 8) => PcdScalar::F64,
            _ => return None,
        })
    }

    /// Size in bytes (the `SIZE` entry).
    pub fn size(self) -> usize {
        match self {
            PcdScalar::I8 | PcdScalar::U8 => 1,
            PcdScalar::I16 | PcdScalar::U16 => 2,
            PcdScalar::I32 | PcdScalar::U32 | PcdScalar::F32 => 4,
            PcdScalar::I64 | PcdScalar::U64 | PcdScalar::F64 => 8,
        }
    }

    /// The `TYPE` letter.
    pub fn type_char(self) -> char {
        match self {
            PcdScalar::I8 | PcdScalar::I16 | PcdScalar::I32 | PcdScalar::I64 => 'I',
            PcdScalar::U8 | PcdScalar::U16 | PcdScalar::U32 | PcdScalar::U64 => 'U',
            PcdScalar::F32 | PcdScalar::F64 => 'F',
        }
    }
}

impl std::fmt::Display for PcdScalar {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}", self.type_char(), self.size())
    }
}

/// One entry of `FIELDS` with its `SIZE`, `TYPE` and `COUNT`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PcdField {
    /// Field name, e.g. `x`, `rgb`, `normal_x`, `_`.
    pub name: String,
    /// Scalar type of each element.
    pub scalar: PcdScalar,
    /// Number of elements (at least 1).
    pub count: u32,
}

impl PcdField {
    /// Bytes the field occupies in one point.
    pub fn byte_len(&self) -> u64 {
        self.scalar.size() as u64 * u64::from(self.count)
    }
}

/// A parsed and validated PCD header.
///
/// Validation guarantees: at least one field, every field of a PCL type with `COUNT >= 1`, a point
/// size that fits in `u32`, and `WIDTH × HEIGHT == POINTS`. It does not check that the fields can
/// form a [`pomona_core::PointCloud`] (that needs `x`, `y`, `z`); the reader does.
#[derive(Debug, Clone, PartialEq)]
pub struct PcdHeader {
    /// The `VERSION` text, if the line is present (not interpreted).
    pub version: Option<String>,
    /// The fields of each point, in storage order.
    pub fields: Vec<PcdField>,
    /// `WIDTH`: points per row (all points when `height <= 1`).
    pub width: u32,
    /// `HEIGHT`: rows; greater than 1 for organised clouds.
    pub height: u32,
    /// `VIEWPOINT`: translation `tx ty tz` then rotation quaternion `qw qx qy qz`; the identity
    /// `0 0 0 1 0 0 0` when the line is absent (PCD 0.6).
    pub viewpoint: [f64; 7],
    /// `POINTS`: number of points.
    pub points: u64,
    /// `DATA`: how the points are stored.
    pub encoding: PcdEncoding,
}

/// Header keywords in the order PCL writes them.
const KEYWORDS: [&str; 10] = [
    "VERSION",
    "FIELDS",
    "SIZE",
    "TYPE",
    "COUNT",
    "WIDTH",
    "HEIGHT",
    "VIEWPOINT",
    "POINTS",
    "DATA",
];

/// Longest header the file-header reader accepts before giving up (a real one is < 1 KiB).
pub(crate) const MAX_HEADER_BYTES: usize = 1 << 20;

#[derive(Default)]
struct Raw {
    version: Option<String>,
    fields: Option<Vec<String>>,
    sizes: Option<(usize, Vec<u64>)>,
    types: Option<(usize, Vec<char>)>,
    counts: Option<(usize, Vec<u32>)>,
    width: Option<u32>,
    height: Option<u32>,
    viewpoint: Option<[f64; 7]>,
    points: Option<u64>,
}

/// Incremental header parser: feed lines until it reports the `DATA` line.
#[derive(Default)]
pub(crate) struct HeaderParser {
    raw: Raw,
    line: usize,
    seen: [bool; KEYWORDS.len()],
    done: Option<PcdHeader>,
}

fn parse_list<T: std::str::FromStr>(
    keyword: &'static str,
    line: usize,
    values: &[&str],
    reason: &'static str,
) -> Result<Vec<T>, PcdError> {
    values
        .iter()
        .map(|v| {
            v.parse().map_err(|_| PcdError::InvalidHeaderValue {
                keyword,
                line,
                value: clip(v),
                reason,
            })
        })
        .collect()
}

fn parse_one<T: std::str::FromStr>(
    keyword: &'static str,
    line: usize,
    values: &[&str],
    reason: &'static str,
) -> Result<T, PcdError> {
    match values {
        [v] => v.parse().map_err(|_| PcdError::InvalidHeaderValue {
            keyword,
            line,
            value: clip(v),
            reason,
        }),
        _ => Err(PcdError::InvalidHeaderValue {
            keyword,
            line,
            value: clip(&values.join(" ")),
            reason: "expected exactly one value",
        }),
    }
}

impl HeaderParser {
    /// Feeds one line (without its `\n`). Returns `true` once the `DATA` line has been read.
    pub(crate) fn feed(&mut self, bytes: &[u8]) -> Result<bool, PcdError> {
        self.line += 1;
        let line = self.line;
        let bytes = bytes.strip_suffix(b"\r").unwrap_or(bytes);
        let text = std::str::from_utf8(bytes).map_err(|_| PcdError::HeaderNotText { line })?;
        let text = text.trim();
        if text.is_empty() || text.starts_with('#') {
            return Ok(false);
        }
        let mut words = text.split_ascii_whitespace();
        let first = words.next().unwrap_or_default();
        let values: Vec<&str> = words.collect();
        let Some(k) = KEYWORDS.iter().position(|k| *k == first) else {
            return Err(PcdError::UnknownHeaderLine {
                line,
                keyword: clip(first),
            });
        };
        let keyword = KEYWORDS[k];
        if std::mem::replace(&mut self.seen[k], true) {
            return Err(PcdError::DuplicateHeaderLine { keyword, line });
        }
        let raw = &mut self.raw;
        match keyword {
            "VERSION" => raw.version = Some(values.join(" ")),
            "FIELDS" => {
                if values.is_empty() {
                    return Err(PcdError::InvalidHeaderValue {
                        keyword,
                        line,
                        value: String::new(),
                        reason: "no fields",
                    });
                }
                raw.fields = Some(values.iter().map(|s| (*s).to_owned()).collect());
            }
            "SIZE" => {
                let v = parse_list(keyword, line, &values, "not a byte size")?;
                raw.sizes = Some((line, v));
            }
            "TYPE" => raw.types = Some((line, parse_types(line, &values)?)),
            "COUNT" => raw.counts = Some((line, parse_counts(line, &values)?)),
            "WIDTH" => {
                raw.width = Some(parse_one(keyword, line, &values, "not a 32-bit count")?);
            }
            "HEIGHT" => {
                raw.height = Some(parse_one(keyword, line, &values, "not a 32-bit count")?);
            }
            "POINTS" => {
                raw.points = Some(parse_one(keyword, line, &values, "not a 64-bit count")?);
            }
            "VIEWPOINT" => raw.viewpoint = Some(parse_viewpoint(line, &values)?),
            _ => {
                // DATA
                self.done = Some(self.finish(parse_encoding(line, &values)?)?);
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// The header, once [`feed`](Self::feed) has returned `true`.
    pub(crate) fn into_header(self) -> Result<PcdHeader, PcdError> {
        self.done.ok_or(PcdError::MissingHeaderLine("DATA"))
    }

    fn finish(&mut self, encoding: PcdEncoding) -> Result<PcdHeader, PcdError> {
        let raw = std::mem::take(&mut self.raw);
        let names = raw.fields.ok_or(PcdError::MissingHeaderLine("FIELDS"))?;
        let (size_line, sizes) = raw.sizes.ok_or(PcdError::MissingHeaderLine("SIZE"))?;
        let (_, types) = raw.types.ok_or(PcdError::MissingHeaderLine("TYPE"))?;
        let (count_line, counts) = raw.counts.unwrap_or_else(|| (0, vec![1; names.len()]));
        let width = raw.width.ok_or(PcdError::MissingHeaderLine("WIDTH"))?;
        let height = raw.height.ok_or(PcdError::MissingHeaderLine("HEIGHT"))?;
        let points = raw.points.ok_or(PcdError::MissingHeaderLine("POINTS"))?;
        for (keyword, found) in [
            ("SIZE", sizes.len()),
            ("TYPE", types.len()),
            ("COUNT", counts.len()),
        ] {
            if found != names.len() {
                return Err(PcdError::FieldCountMismatch {
                    keyword,
                    fields: names.len(),
                    found,
                });
            }
        }
        let mut fields = Vec::with_capacity(names.len());
        let mut point_size = 0_u64;
        for (((name, size), ty), count) in names.into_iter().zip(sizes).zip(types).zip(counts) {
            let scalar =
                PcdScalar::from_type_size(ty, size).ok_or_else(|| PcdError::InvalidFieldType {
                    field: clip(&name),
                    ty,
                    size,
                })?;
            let field = PcdField {
                name,
                scalar,
                count,
            };
            point_size += field.byte_len();
            if point_size > u64::from(u32::MAX) {
                return Err(PcdError::InvalidHeaderValue {
                    keyword: if count > 1 { "COUNT" } else { "SIZE" },
                    line: if count > 1 { count_line } else { size_line },
                    value: count.to_string(),
                    reason: "a point would exceed 4 GiB",
                });
            }
            fields.push(field);
        }
        let product = u64::from(width) * u64::from(height);
        if product != points {
            return Err(PcdError::PointCountMismatch {
                width,
                height,
                product,
                points,
            });
        }
        Ok(PcdHeader {
            version: raw.version,
            fields,
            width,
            height,
            viewpoint: raw.viewpoint.unwrap_or([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]),
            points,
            encoding,
        })
    }
}

impl PcdHeader {
    /// Parses the header at the start of `bytes`; returns it and the offset where the point data
    /// starts (just after the `DATA` line's newline).
    ///
    /// # Errors
    /// A [`PcdError`] header variant when a line is missing, repeated, unknown or malformed, or
    /// when the declared sizes disagree.
    pub fn parse(bytes: &[u8]) -> Result<(Self, usize), PcdError> {
        let mut parser = HeaderParser::default();
        let mut pos = 0;
        while pos < bytes.len() {
            let rest = &bytes[pos..];
            let (line, next) = match rest.iter().position(|&b| b == b'\n') {
                Some(i) => (&rest[..i], pos + i + 1),
                None => (rest, bytes.len()),
            };
            pos = next;
            if parser.feed(line)? {
                return Ok((parser.into_header()?, pos));
            }
        }
        Err(PcdError::MissingHeaderLine("DATA"))
    }

    /// Bytes per point (sum of `SIZE × COUNT`).
    pub fn point_size(&self) -> u64 {
        self.fields.iter().map(PcdField::byte_len).sum()
    }

    /// Whether the cloud is organised (`HEIGHT > 1`, as PCL decides).
    pub fn is_organized(&self) -> bool {
        self.height > 1
    }

    /// The layout the cloud will have when read.
    pub fn layout(&self) -> CloudLayout {
        if self.is_organized() {
            CloudLayout::Organized {
                width: self.width,
                height: self.height,
            }
        } else {
            CloudLayout::Unorganized
        }
    }

    /// The field called `name`, if any.
    pub fn field(&self, name: &str) -> Option<&PcdField> {
        self.fields.iter().find(|f| f.name == name)
    }
}

/// The `TYPE` line: one of `I`, `U`, `F` per field.
fn parse_types(line: usize, values: &[&str]) -> Result<Vec<char>, PcdError> {
    values
        .iter()
        .map(|s| {
            let mut c = s.chars();
            match (c.next(), c.next()) {
                (Some(t @ ('I' | 'U' | 'F')), None) => Ok(t),
                _ => Err(PcdError::InvalidHeaderValue {
                    keyword: "TYPE",
                    line,
                    value: clip(s),
                    reason: "TYPE must be I, U or F",
                }),
            }
        })
        .collect()
}

/// The `COUNT` line: a positive element count per field.
fn parse_counts(line: usize, values: &[&str]) -> Result<Vec<u32>, PcdError> {
    let v: Vec<u32> = parse_list("COUNT", line, values, "not a count")?;
    if let Some(z) = v.iter().position(|&c| c == 0) {
        return Err(PcdError::InvalidHeaderValue {
            keyword: "COUNT",
            line,
            value: clip(values[z]),
            reason: "COUNT must be at least 1",
        });
    }
    Ok(v)
}

/// The `VIEWPOINT` line: seven finite numbers, translation then quaternion.
fn parse_viewpoint(line: usize, values: &[&str]) -> Result<[f64; 7], PcdError> {
    let invalid = |reason| PcdError::InvalidHeaderValue {
        keyword: "VIEWPOINT",
        line,
        value: clip(&values.join(" ")),
        reason,
    };
    let v: Vec<f64> = parse_list("VIEWPOINT", line, values, "not a number")?;
    let vp: [f64; 7] = v
        .try_into()
        .map_err(|_| invalid("expected 7 numbers: tx ty tz qw qx qy qz"))?;
    if vp.iter().any(|x| !x.is_finite()) {
        return Err(invalid("not finite"));
    }
    Ok(vp)
}

/// The `DATA` line: exactly one known encoding word.
fn parse_encoding(line: usize, values: &[&str]) -> Result<PcdEncoding, PcdError> {
    let unknown = |value: &str| PcdError::UnknownDataType {
        line,
        value: clip(value),
    };
    match values {
        [word] => PcdEncoding::from_keyword(word).ok_or_else(|| unknown(word)),
        _ => Err(unknown(&values.join(" "))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb _\nSIZE 4 4 4 4 1\nTYPE F F F F U\nCOUNT 1 1 1 1 3\nWIDTH 2\nHEIGHT 3\nVIEWPOINT 1 2 3 1 0 0 0\nPOINTS 6\nDATA binary\nrest";

    #[test]
    fn parses_a_full_header() {
        let (h, off) = PcdHeader::parse(GOOD.as_bytes()).unwrap();
        assert_eq!(&GOOD[off..], "rest");
        assert_eq!(h.version.as_deref(), Some("0.7"));
        assert_eq!(h.fields.len(), 5);
        assert_eq!(h.fields[4].count, 3);
        assert_eq!(h.point_size(), 19);
        assert_eq!(h.viewpoint, [1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0]);
        assert_eq!(h.encoding, PcdEncoding::Binary);
        assert!(h.is_organized());
        assert_eq!(h.field("rgb").unwrap().scalar, PcdScalar::F32);
    }

    #[test]
    fn v06_header_without_viewpoint_and_count_defaults() {
        let text = "VERSION .6\r\nFIELDS x y z\r\nSIZE 8 8 8\r\nTYPE F F F\r\nWIDTH 4\r\nHEIGHT 1\r\nPOINTS 4\r\nDATA ascii\r\n";
        let (h, off) = PcdHeader::parse(text.as_bytes()).unwrap();
        assert_eq!(off, text.len());
        assert_eq!(h.viewpoint[3], 1.0);
        assert!(h.fields.iter().all(|f| f.count == 1));
        assert_eq!(h.layout(), CloudLayout::Unorganized);
    }

    fn err(text: &str) -> PcdError {
        PcdHeader::parse(text.as_bytes()).unwrap_err()
    }

    #[test]
    fn header_errors_are_typed() {
        let base = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\n";
        assert!(matches!(err(base), PcdError::MissingHeaderLine("DATA")));
        assert!(matches!(
            err(&format!("{base}DATA zip\n")),
            PcdError::UnknownDataType { line: 7, .. }
        ));
        assert!(matches!(
            err(&format!("WIDTH 1\n{base}DATA ascii\n")),
            PcdError::DuplicateHeaderLine {
                keyword: "WIDTH",
                line: 5
            }
        ));
        assert!(matches!(
            err("FIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n"),
            PcdError::FieldCountMismatch {
                keyword: "SIZE",
                fields: 3,
                found: 2
            }
        ));
        assert!(matches!(
            err("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n"),
            PcdError::FieldCountMismatch { keyword: "COUNT", .. }
        ));
        assert!(matches!(
            err("FIELDS x y z\nSIZE 4 4 2\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n"),
            PcdError::InvalidFieldType {
                ty: 'F',
                size: 2,
                ..
            }
        ));
        assert!(matches!(
            err("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n"),
            PcdError::PointCountMismatch {
                product: 4,
                points: 3,
                ..
            }
        ));
        assert!(matches!(
            err("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 4000000000000\nHEIGHT 1\nPOINTS 1\nDATA ascii\n"),
            PcdError::InvalidHeaderValue { keyword: "WIDTH", line: 4, .. }
        ));
        assert!(matches!(
            err("FIELDS x y z\nSIZE 4 4 4\nTYPE F F X\n"),
            PcdError::InvalidHeaderValue {
                keyword: "TYPE",
                ..
            }
        ));
        assert!(matches!(
            err("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 0 1\n"),
            PcdError::InvalidHeaderValue {
                keyword: "COUNT",
                ..
            }
        ));
        assert!(matches!(
            err("VIEWPOINT 0 0 0 1 0 0\n"),
            PcdError::InvalidHeaderValue {
                keyword: "VIEWPOINT",
                ..
            }
        ));
        assert!(matches!(
            err("SIZE 4 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n"),
            PcdError::MissingHeaderLine("FIELDS")
        ));
        assert!(matches!(
            err("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nHEIGHT 1\nPOINTS 1\nDATA ascii\n"),
            PcdError::MissingHeaderLine("WIDTH")
        ));
        assert!(matches!(
            err("ply\nformat ascii 1.0\n"),
            PcdError::UnknownHeaderLine { line: 1, .. }
        ));
        assert!(matches!(
            PcdHeader::parse(b"\xff\xfe\x00garbage\n").unwrap_err(),
            PcdError::HeaderNotText { line: 1 }
        ));
        assert!(matches!(err(""), PcdError::MissingHeaderLine("DATA")));
    }

    #[test]
    fn oversized_points_are_rejected() {
        let text = format!(
            "FIELDS x y z d\nSIZE 4 4 4 8\nTYPE F F F F\nCOUNT 1 1 1 {}\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary\n",
            u32::MAX
        );
        assert!(matches!(
            err(&text),
            PcdError::InvalidHeaderValue {
                keyword: "COUNT",
                line: 4,
                ..
            }
        ));
    }
}
