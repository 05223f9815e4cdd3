//! Decoding PCD point data (ascii, binary, binary_compressed) into a [`PointCloud`].

use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use pomona_core::nalgebra::{Point3, Vector3};
use pomona_core::PointCloud;

use super::header::{HeaderParser, MAX_HEADER_BYTES};
use super::{clip, PcdEncoding, PcdError, PcdHeader, PcdScalar};
use crate::lzf;

/// Reads a whole PCD file held in memory.
///
/// # Errors
/// A [`PcdError`] naming what is wrong with the header or the data.
pub fn read_pcd(bytes: &[u8]) -> Result<PointCloud, PcdError> {
    let (header, offset) = PcdHeader::parse(bytes)?;
    let data = bytes.get(offset..).unwrap_or_default();
    let first_data_line = 1 + bytes[..offset.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count();
    decode(&header, data, first_data_line, bytes.len() as u64)
}

/// Reads the PCD file at `path` (entirely into memory).
///
/// # Errors
/// [`PcdError::File`] wrapping the cause.
pub fn read_pcd_file(path: impl AsRef<Path>) -> Result<PointCloud, PcdError> {
    let path = path.as_ref();
    std::fs::read(path)
        .map_err(PcdError::from)
        .and_then(|bytes| read_pcd(&bytes))
        .map_err(|e| e.with_path(path))
}

/// Reads only the header of the PCD file at `path` (at most 1 MiB of it), e.g. to describe the
/// file without decoding its points.
///
/// # Errors
/// [`PcdError::File`] wrapping the cause.
pub fn read_pcd_header_file(path: impl AsRef<Path>) -> Result<PcdHeader, PcdError> {
    let path = path.as_ref();
    let inner = || -> Result<PcdHeader, PcdError> {
        let file = std::fs::File::open(path)?;
        let mut reader = BufReader::new(file).take(MAX_HEADER_BYTES as u64);
        let mut parser = HeaderParser::default();
        let mut line = Vec::new();
        loop {
            line.clear();
            if reader.read_until(b'\n', &mut line)? == 0 {
                return Err(PcdError::MissingHeaderLine("DATA"));
            }
            let text = line.strip_suffix(b"\n").unwrap_or(&line);
            if parser.feed(text)? {
                return parser.into_header();
            }
        }
    };
    inner().map_err(|e| e.with_path(path))
}

/// Where one kept field lives in the decoded data.
#[derive(Debug, Clone, Copy)]
struct Slot {
    /// Index in `header.fields`.
    field: usize,
    scalar: PcdScalar,
    /// Byte offset of the field within a point.
    offset: usize,
}

/// Which fields map to which cloud attributes.
#[derive(Debug, Default)]
struct Plan {
    x: Option<Slot>,
    y: Option<Slot>,
    z: Option<Slot>,
    rgb: Option<Slot>,
    label: Option<Slot>,
    nx: Option<Slot>,
    ny: Option<Slot>,
    nz: Option<Slot>,
    intensity: Option<Slot>,
}

/// A kept field's role.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    X,
    Y,
    Z,
    Rgb,
    Label,
    Nx,
    Ny,
    Nz,
    Intensity,
}

fn role_of(name: &str) -> Option<Role> {
    Some(match name {
        "x" => Role::X,
        "y" => Role::Y,
        "z" => Role::Z,
        "rgb" | "rgba" => Role::Rgb,
        "label" => Role::Label,
        "normal_x" => Role::Nx,
        "normal_y" => Role::Ny,
        "normal_z" => Role::Nz,
        "intensity" => Role::Intensity,
        _ => return None,
    })
}

impl Plan {
    fn new(header: &PcdHeader) -> Result<Self, PcdError> {
        let mut plan = Plan::default();
        let mut offset = 0_usize;
        for (i, f) in header.fields.iter().enumerate() {
            let here = offset;
            // The header guarantees the point size fits in u32.
            offset += f.byte_len() as usize;
            let Some(role) = role_of(&f.name) else {
                continue;
            };
            if f.count != 1 {
                return Err(PcdError::UnsupportedField {
                    field: clip(&f.name),
                    reason: "COUNT must be 1 for this field",
                });
            }
            if role == Role::Rgb && f.scalar.size() != 4 {
                return Err(PcdError::UnsupportedField {
                    field: clip(&f.name),
                    reason: "a packed colour must be 4 bytes (SIZE 4)",
                });
            }
            let target = match role {
                Role::X => &mut plan.x,
                Role::Y => &mut plan.y,
                Role::Z => &mut plan.z,
                Role::Rgb => &mut plan.rgb,
                Role::Label => &mut plan.label,
                Role::Nx => &mut plan.nx,
                Role::Ny => &mut plan.ny,
                Role::Nz => &mut plan.nz,
                Role::Intensity => &mut plan.intensity,
            };
            if target.is_some() {
                return Err(PcdError::DuplicateField(clip(&f.name)));
            }
            *target = Some(Slot {
                field: i,
                scalar: f.scalar,
                offset: here,
            });
        }
        for (slot, name) in [(plan.x, "x"), (plan.y, "y"), (plan.z, "z")] {
            if slot.is_none() {
                return Err(PcdError::MissingField(name));
            }
        }
        let normals = [
            (plan.nx, "normal_x"),
            (plan.ny, "normal_y"),
            (plan.nz, "normal_z"),
        ];
        if normals.iter().any(|(s, _)| s.is_some()) {
            if let Some((_, name)) = normals.iter().find(|(s, _)| s.is_none()) {
                return Err(PcdError::MissingField(name));
            }
        }
        Ok(plan)
    }

    /// Every kept field with its role.
    fn slots(&self) -> impl Iterator<Item = (Slot, Role)> {
        [
            (self.x, Role::X),
            (self.y, Role::Y),
            (self.z, Role::Z),
            (self.rgb, Role::Rgb),
            (self.label, Role::Label),
            (self.nx, Role::Nx),
            (self.ny, Role::Ny),
            (self.nz, Role::Nz),
            (self.intensity, Role::Intensity),
        ]
        .into_iter()
        .filter_map(|(s, r)| s.map(|s| (s, r)))
    }

    /// Bytes the decoded columns take per point.
    fn column_bytes_per_point(&self) -> u64 {
        let size = |present: bool, bytes: usize| if present { bytes as u64 } else { 0 };
        size(true, std::mem::size_of::<Point3<f32>>())
            + size(self.rgb.is_some(), std::mem::size_of::<[u8; 3]>())
            + size(self.label.is_some(), std::mem::size_of::<u32>())
            + size(self.nx.is_some(), std::mem::size_of::<Vector3<f32>>())
            + size(self.intensity.is_some(), std::mem::size_of::<f32>())
    }

    fn role(&self, field: usize) -> Option<Role> {
        self.slots()
            .find_map(|(s, r)| (s.field == field).then_some(r))
    }
}

/// Copies up to `N` bytes into an array (the callers always pass exactly `N`).
fn le<const N: usize>(s: &[u8]) -> [u8; N] {
    let mut a = [0_u8; N];
    let n = s.len().min(N);
    a[..n].copy_from_slice(&s[..n]);
    a
}

/// A decoded scalar, widened.
#[derive(Debug, Clone, Copy)]
enum Num {
    I(i64),
    U(u64),
    F(f64),
    /// Kept apart from `F` so the exact bit pattern of an `F 4` survives (packed colours).
    F32(f32),
}

impl Num {
    fn from_le(s: &[u8], scalar: PcdScalar) -> Num {
        match scalar {
            PcdScalar::I8 => Num::I(i64::from(i8::from_le_bytes(le(s)))),
            PcdScalar::I16 => Num::I(i64::from(i16::from_le_bytes(le(s)))),
            PcdScalar::I32 => Num::I(i64::from(i32::from_le_bytes(le(s)))),
            PcdScalar::I64 => Num::I(i64::from_le_bytes(le(s))),
            PcdScalar::U8 => Num::U(u64::from(s.first().copied().unwrap_or_default())),
            PcdScalar::U16 => Num::U(u64::from(u16::from_le_bytes(le(s)))),
            PcdScalar::U32 => Num::U(u64::from(u32::from_le_bytes(le(s)))),
            PcdScalar::U64 => Num::U(u64::from_le_bytes(le(s))),
            PcdScalar::F32 => Num::F32(f32::from_le_bytes(le(s))),
            PcdScalar::F64 => Num::F(f64::from_le_bytes(le(s))),
        }
    }

    /// Parses an ascii token as a value of `scalar`, range-checked.
    fn parse(tok: &str, scalar: PcdScalar) -> Option<Num> {
        Some(match scalar {
            PcdScalar::I8 => Num::I(i64::from(tok.parse::<i8>().ok()?)),
            PcdScalar::I16 => Num::I(i64::from(tok.parse::<i16>().ok()?)),
            PcdScalar::I32 => Num::I(i64::from(tok.parse::<i32>().ok()?)),
            PcdScalar::I64 => Num::I(tok.parse::<i64>().ok()?),
            PcdScalar::U8 => Num::U(u64::from(tok.parse::<u8>().ok()?)),
            PcdScalar::U16 => Num::U(u64::from(tok.parse::<u16>().ok()?)),
            PcdScalar::U32 => Num::U(u64::from(tok.parse::<u32>().ok()?)),
            PcdScalar::U64 => Num::U(tok.parse::<u64>().ok()?),
            PcdScalar::F32 => Num::F32(tok.parse::<f32>().ok()?),
            PcdScalar::F64 => Num::F(tok.parse::<f64>().ok()?),
        })
    }

    fn to_f32(self) -> f32 {
        match self {
            Num::I(v) => v as f32,
            Num::U(v) => v as f32,
            Num::F(v) => v as f32,
            Num::F32(v) => v,
        }
    }

    /// The 32 bits of a packed colour.
    fn to_bits32(self) -> u32 {
        match self {
            // Only 4-byte fields reach here, so the integer casts keep all bits.
            Num::I(v) => v as u32,
            Num::U(v) => v as u32,
            Num::F(v) => (v as f32).to_bits(),
            Num::F32(v) => v.to_bits(),
        }
    }

    fn to_label(self) -> Option<u32> {
        match self {
            Num::I(v) => u32::try_from(v).ok(),
            Num::U(v) => u32::try_from(v).ok(),
            Num::F(v) => float_label(v),
            Num::F32(v) => float_label(f64::from(v)),
        }
    }

    fn as_f64(self) -> f64 {
        match self {
            Num::I(v) => v as f64,
            Num::U(v) => v as f64,
            Num::F(v) => v,
            Num::F32(v) => f64::from(v),
        }
    }
}

fn float_label(v: f64) -> Option<u32> {
    (v.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&v)).then_some(v as u32)
}

fn unpack_rgb(bits: u32) -> [u8; 3] {
    [(bits >> 16) as u8, (bits >> 8) as u8, bits as u8]
}

/// Columns of decoded attributes, one entry per point.
struct Columns {
    points: Vec<Point3<f32>>,
    colors: Option<Vec<[u8; 3]>>,
    labels: Option<Vec<u32>>,
    normals: Option<Vec<Vector3<f32>>>,
    intensities: Option<Vec<f32>>,
}

impl Columns {
    fn new(plan: &Plan, n: usize) -> Self {
        Columns {
            points: vec![Point3::origin(); n],
            colors: plan.rgb.map(|_| vec![[0; 3]; n]),
            labels: plan.label.map(|_| vec![0; n]),
            normals: plan.nx.map(|_| vec![Vector3::zeros(); n]),
            intensities: plan.intensity.map(|_| vec![0.0; n]),
        }
    }

    /// Stores value `v` of role `role` for point `i` (`i < n` by construction).
    fn set(&mut self, role: Role, i: usize, v: Num) -> Result<(), PcdError> {
        match role {
            Role::X | Role::Y | Role::Z => {
                if let Some(p) = self.points.get_mut(i) {
                    let c = match role {
                        Role::X => &mut p.x,
                        Role::Y => &mut p.y,
                        _ => &mut p.z,
                    };
                    *c = v.to_f32();
                }
            }
            Role::Nx | Role::Ny | Role::Nz => {
                if let Some(n) = self.normals.as_mut().and_then(|n| n.get_mut(i)) {
                    let c = match role {
                        Role::Nx => &mut n.x,
                        Role::Ny => &mut n.y,
                        _ => &mut n.z,
                    };
                    *c = v.to_f32();
                }
            }
            Role::Rgb => {
                if let Some(c) = self.colors.as_mut().and_then(|c| c.get_mut(i)) {
                    *c = unpack_rgb(v.to_bits32());
                }
            }
            Role::Label => {
                let label = v.to_label().ok_or(PcdError::LabelOutOfRange {
                    point: i as u64,
                    value: v.as_f64(),
                })?;
                if let Some(l) = self.labels.as_mut().and_then(|l| l.get_mut(i)) {
                    *l = label;
                }
            }
            Role::Intensity => {
                if let Some(x) = self.intensities.as_mut().and_then(|x| x.get_mut(i)) {
                    *x = v.to_f32();
                }
            }
        }
        Ok(())
    }

    fn into_cloud(self, header: &PcdHeader) -> Result<PointCloud, PcdError> {
        let mut cloud = if header.is_organized() {
            PointCloud::organized(header.width, header.height, self.points)?
        } else {
            PointCloud::unorganized(self.points)
        };
        if let Some(c) = self.colors {
            cloud = cloud.with_colors(c)?;
        }
        if let Some(n) = self.normals {
            cloud = cloud.with_normals(n)?;
        }
        if let Some(l) = self.labels {
            cloud = cloud.with_labels(l)?;
        }
        if let Some(x) = self.intensities {
            cloud = cloud.with_intensities(x)?;
        }
        Ok(cloud)
    }
}

fn decode(
    header: &PcdHeader,
    data: &[u8],
    first_line: usize,
    input_len: u64,
) -> Result<PointCloud, PcdError> {
    let plan = Plan::new(header)?;
    let points = header.points;
    let point_size = header.point_size();
    let available = data.len() as u64;
    let needed = match header.encoding {
        PcdEncoding::Binary => points.saturating_mul(point_size),
        // Each value takes at least one character and one separator (the last may end the file).
        PcdEncoding::Ascii => points
            .saturating_mul(
                2 * header
                    .fields
                    .iter()
                    .map(|f| u64::from(f.count))
                    .sum::<u64>(),
            )
            .saturating_sub(1),
        // Checked against the declared sizes below.
        PcdEncoding::BinaryCompressed => 8,
    };
    if needed > available {
        return Err(PcdError::Truncated {
            points,
            needed,
            available,
        });
    }
    let columns = points.saturating_mul(plan.column_bytes_per_point());
    match header.encoding {
        PcdEncoding::Binary => {
            check_budget(columns, input_len)?;
            // Fits: it is at most the input length.
            let body = &data[..needed as usize];
            decode_columns(header, &plan, body, points as usize, false)
        }
        PcdEncoding::BinaryCompressed => {
            let body = decompress_body(header, data, columns, input_len)?;
            decode_columns(header, &plan, &body, points as usize, true)
        }
        PcdEncoding::Ascii => {
            check_budget(columns, input_len)?;
            decode_ascii(header, &plan, data, first_line)
        }
    }
}

/// Fails with [`PcdError::OverBudget`] when `needed` decoded bytes exceed the budget of an
/// input of `input_len` bytes.
fn check_budget(needed: u64, input_len: u64) -> Result<(), PcdError> {
    match crate::read_budget::over_budget(needed, input_len) {
        Some(budget) => Err(PcdError::OverBudget { needed, budget }),
        None => Ok(()),
    }
}

/// Checks the size pair of a `binary_compressed` payload, then that the decompressed body plus
/// the `columns` bytes it decodes to fit the budget, and decompresses it.
fn decompress_body(
    header: &PcdHeader,
    data: &[u8],
    columns: u64,
    input_len: u64,
) -> Result<Vec<u8>, PcdError> {
    let points = header.points;
    let needed = points.saturating_mul(header.point_size());
    // The caller checked that the two size words are present.
    let available = data.len() as u64;
    let c = data.get(0..4).unwrap_or_default();
    let u = data.get(4..8).unwrap_or_default();
    let compressed = u64::from(u32::from_le_bytes(le(c)));
    let uncompressed = u64::from(u32::from_le_bytes(le(u)));
    if uncompressed != needed {
        return Err(PcdError::CompressedSizeMismatch {
            declared: uncompressed,
            expected: needed,
        });
    }
    if compressed > available.saturating_sub(8) {
        return Err(PcdError::Truncated {
            points,
            needed: compressed + 8,
            available,
        });
    }
    if uncompressed > compressed * lzf::MAX_EXPANSION_RATIO as u64 {
        return Err(PcdError::ImplausibleCompression {
            compressed,
            uncompressed,
        });
    }
    check_budget(columns.saturating_add(uncompressed), input_len)?;
    let payload = &data[8..8 + compressed as usize];
    Ok(lzf::decompress(payload, uncompressed as usize)?)
}

/// Decodes `n` points from `body`, which holds exactly `n × point size` bytes, point-major
/// (`binary`) or field-major (`binary_compressed`).
fn decode_columns(
    header: &PcdHeader,
    plan: &Plan,
    body: &[u8],
    n: usize,
    field_major: bool,
) -> Result<PointCloud, PcdError> {
    let point_size = header.point_size() as usize;
    let mut cols = Columns::new(plan, n);
    for (slot, role) in plan.slots() {
        let size = slot.scalar.size();
        let (start, stride) = if field_major {
            (slot.offset.saturating_mul(n), size)
        } else {
            (slot.offset, point_size)
        };
        let column = body.get(start..).unwrap_or_default();
        for (k, chunk) in column.chunks(stride.max(1)).take(n).enumerate() {
            cols.set(role, k, Num::from_le(chunk, slot.scalar))?;
        }
    }
    cols.into_cloud(header)
}

fn decode_ascii(
    header: &PcdHeader,
    plan: &Plan,
    data: &[u8],
    first_line: usize,
) -> Result<PointCloud, PcdError> {
    let points = header.points;
    // Bounded by the point size, which the header keeps within u32.
    let tokens_per_point: usize = header.fields.iter().map(|f| f.count as usize).sum();
    let n = points as usize;
    let mut cols = Columns::new(plan, n);
    // The role of each field (not of each token: a field's COUNT may be huge).
    let roles: Vec<Option<Role>> = (0..header.fields.len()).map(|i| plan.role(i)).collect();
    let mut found = 0_usize;
    for (line_idx, line) in data.split(|&b| b == b'\n').enumerate() {
        if found == n {
            break;
        }
        let line_no = first_line + line_idx;
        let tokens = || {
            line.split(|b| b.is_ascii_whitespace())
                .filter(|t| !t.is_empty())
        };
        let count = tokens().count();
        if count == 0 {
            continue;
        }
        if count != tokens_per_point {
            return Err(PcdError::AsciiValueCount {
                line: line_no,
                expected: tokens_per_point,
                found: count,
            });
        }
        let token_fields = header
            .fields
            .iter()
            .zip(&roles)
            .flat_map(|(f, &role)| std::iter::repeat_n((f, role), f.count as usize));
        for (tok, (field, role)) in tokens().zip(token_fields) {
            let value = parse_ascii_value(tok, field.scalar, role).ok_or_else(|| {
                PcdError::AsciiBadNumber {
                    line: line_no,
                    field: clip(&field.name),
                    token: clip(&String::from_utf8_lossy(tok)),
                    ty: field.scalar.to_string(),
                }
            })?;
            if let Some(role) = role {
                cols.set(role, found, value)?;
            }
        }
        found += 1;
    }
    if found < n {
        return Err(PcdError::AsciiTooFewPoints {
            expected: points,
            found: found as u64,
        });
    }
    cols.into_cloud(header)
}

/// Parses one ascii token of a field of type `scalar` with `role`.
fn parse_ascii_value(tok: &[u8], scalar: PcdScalar, role: Option<Role>) -> Option<Num> {
    let text = std::str::from_utf8(tok).ok()?;
    if role == Some(Role::Rgb) && scalar == PcdScalar::F32 {
        parse_packed_float(text)
    } else {
        Num::parse(text, scalar)
    }
}

/// An ascii packed colour of a float-typed `rgb`/`rgba` field: current PCL writes the 32 bits as
/// an unsigned integer, older writers as the float they form. Packed colours are never integral
/// floats other than 0 (they are denormals or NaNs), so an all-digit token is the integer form.
fn parse_packed_float(t: &str) -> Option<Num> {
    if !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit()) {
        t.parse::<u32>()
            .ok()
            .map(|bits| Num::F32(f32::from_bits(bits)))
    } else {
        t.parse::<f32>().ok().map(Num::F32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::CloudLayout;

    fn pcd(header_fields: &str, points: usize, data: &str) -> Vec<u8> {
        format!("VERSION 0.7\n{header_fields}\nWIDTH {points}\nHEIGHT 1\nPOINTS {points}\nDATA ascii\n{data}")
            .into_bytes()
    }

    #[test]
    fn ascii_skips_unknown_fields_and_converts_types() {
        let bytes = pcd(
            "FIELDS _ x y z curvature rgb label intensity\nSIZE 1 2 8 1 4 4 2 1\nTYPE U I F U F U U U\nCOUNT 2 1 1 1 1 1 1 1",
            2,
            "1 2 -3 0.5 7 0.25 16711935 9 200\n\n0 0 -32768 nan 255 1e3 65280 65535 0\n",
        );
        let c = read_pcd(&bytes).unwrap();
        assert_eq!(c.len(), 2);
        assert_eq!(c.layout(), CloudLayout::Unorganized);
        assert_eq!(c.points()[0], Point3::new(-3.0, 0.5, 7.0));
        assert_eq!(c.points()[1].x, -32768.0);
        assert!(c.points()[1].y.is_nan());
        assert_eq!(c.colors().unwrap(), &[[255, 0, 255], [0, 255, 0]]);
        assert_eq!(c.labels().unwrap(), &[9, 65535]);
        assert_eq!(c.intensities().unwrap(), &[200.0, 0.0]);
        assert!(c.normals().is_none());
    }

    #[test]
    fn ascii_float_rgb_accepts_integer_and_float_forms() {
        let bits: u32 = 0x00_11_22_33;
        let as_float = format!("{:e}", f32::from_bits(bits));
        let bytes = pcd(
            "FIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F F",
            2,
            &format!("0 0 0 {bits}\n0 0 0 {as_float}\n"),
        );
        let c = read_pcd(&bytes).unwrap();
        assert_eq!(c.colors().unwrap(), &[[0x11, 0x22, 0x33]; 2]);
    }

    #[test]
    fn ascii_errors() {
        let f = "FIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F I";
        assert!(matches!(
            read_pcd(&pcd(f, 2, "1 2 3 4\n1.5 2.5 3.5\n")).unwrap_err(),
            PcdError::AsciiValueCount {
                line: 10,
                expected: 4,
                found: 3
            }
        ));
        assert!(matches!(
            read_pcd(&pcd(f, 2, "1 2 3 4\n1 2 x3 4\n")).unwrap_err(),
            PcdError::AsciiBadNumber { line: 10, .. }
        ));
        assert!(matches!(
            read_pcd(&pcd(f, 2, "1 2 3 -4\n1 2 3 4\n")).unwrap_err(),
            PcdError::LabelOutOfRange { point: 0, .. }
        ));
        assert!(matches!(
            read_pcd(&pcd(f, 3, "1.000 2.000 3.000 4\n1.000 2.000 3.000 4\n")).unwrap_err(),
            PcdError::AsciiTooFewPoints {
                expected: 3,
                found: 2
            }
        ));
        assert!(matches!(
            read_pcd(&pcd(f, 3, "1 2 3 4\n")).unwrap_err(),
            PcdError::Truncated { points: 3, .. }
        ));
        // U 1 out of range.
        let g = "FIELDS x y z label\nSIZE 4 4 4 1\nTYPE F F F U";
        assert!(matches!(
            read_pcd(&pcd(g, 1, "1 2 3 256\n")).unwrap_err(),
            PcdError::AsciiBadNumber { .. }
        ));
    }

    #[test]
    fn field_mapping_errors() {
        let e = |fields: &str| read_pcd(&pcd(fields, 0, "")).unwrap_err();
        assert!(matches!(
            e("FIELDS x y\nSIZE 4 4\nTYPE F F"),
            PcdError::MissingField("z")
        ));
        assert!(matches!(
            e("FIELDS x y z x\nSIZE 4 4 4 4\nTYPE F F F F"),
            PcdError::DuplicateField(_)
        ));
        assert!(matches!(
            e("FIELDS x y z rgb rgba\nSIZE 4 4 4 4 4\nTYPE F F F F U"),
            PcdError::DuplicateField(_)
        ));
        assert!(matches!(
            e("FIELDS x y z rgb\nSIZE 4 4 4 8\nTYPE F F F F"),
            PcdError::UnsupportedField { .. }
        ));
        assert!(matches!(
            e("FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 2 1"),
            PcdError::UnsupportedField { .. }
        ));
        assert!(matches!(
            e("FIELDS x y z normal_x normal_z\nSIZE 4 4 4 4 4\nTYPE F F F F F"),
            PcdError::MissingField("normal_y")
        ));
    }

    #[test]
    fn binary_decodes_every_scalar_type() {
        // x as every type in turn; y, z fixed F 4.
        let cases: [(PcdScalar, Vec<u8>, f32); 10] = [
            (PcdScalar::I8, (-5_i8).to_le_bytes().to_vec(), -5.0),
            (PcdScalar::I16, (-300_i16).to_le_bytes().to_vec(), -300.0),
            (
                PcdScalar::I32,
                (-70000_i32).to_le_bytes().to_vec(),
                -70000.0,
            ),
            (
                PcdScalar::I64,
                (-(1_i64 << 40)).to_le_bytes().to_vec(),
                -(2f32.powi(40)),
            ),
            (PcdScalar::U8, vec![200], 200.0),
            (PcdScalar::U16, 60000_u16.to_le_bytes().to_vec(), 60000.0),
            (
                PcdScalar::U32,
                4_000_000_000_u32.to_le_bytes().to_vec(),
                4e9,
            ),
            (
                PcdScalar::U64,
                (1_u64 << 50).to_le_bytes().to_vec(),
                2f32.powi(50),
            ),
            (PcdScalar::F32, 1.5_f32.to_le_bytes().to_vec(), 1.5),
            (PcdScalar::F64, 0.1_f64.to_le_bytes().to_vec(), 0.1),
        ];
        for (scalar, bytes, want) in cases {
            for encoding in ["binary", "binary_compressed"] {
                let mut body = bytes.clone();
                body.extend(2.0_f32.to_le_bytes());
                body.extend(3.0_f32.to_le_bytes());
                let mut file = format!(
                    "FIELDS x y z\nSIZE {} 4 4\nTYPE {} F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA {encoding}\n",
                    scalar.size(),
                    scalar.type_char()
                )
                .into_bytes();
                if encoding == "binary" {
                    file.extend(&body);
                } else {
                    let c = lzf::compress(&body);
                    file.extend((c.len() as u32).to_le_bytes());
                    file.extend((body.len() as u32).to_le_bytes());
                    file.extend(c);
                }
                let cloud = read_pcd(&file).unwrap();
                assert_eq!(cloud.points()[0], Point3::new(want, 2.0, 3.0), "{scalar}");
            }
        }
    }

    #[test]
    fn labels_of_every_integer_type() {
        for (ty, size, bytes, want) in [
            ('U', 1, vec![7_u8], Some(7)),
            ('U', 8, (1_u64 << 33).to_le_bytes().to_vec(), None),
            ('U', 8, 12_u64.to_le_bytes().to_vec(), Some(12)),
            ('I', 2, (-1_i16).to_le_bytes().to_vec(), None),
            ('F', 4, 3.0_f32.to_le_bytes().to_vec(), Some(3)),
            ('F', 4, 3.5_f32.to_le_bytes().to_vec(), None),
        ] {
            let mut file = format!(
                "FIELDS x y z label\nSIZE 4 4 4 {size}\nTYPE F F F {ty}\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary\n"
            )
            .into_bytes();
            file.extend([0_u8; 12]);
            file.extend(bytes);
            match (read_pcd(&file), want) {
                (Ok(c), Some(w)) => assert_eq!(c.labels().unwrap(), &[w]),
                (Err(PcdError::LabelOutOfRange { .. }), None) => {}
                (r, w) => panic!("{ty}{size}: {r:?} vs {w:?}"),
            }
        }
    }
}
