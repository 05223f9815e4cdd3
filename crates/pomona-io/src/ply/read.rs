//! Reading a PLY file into a point cloud: every element is walked (so faces and other elements
//! after the vertices are validated and skipped), the `vertex` rows become the cloud.

use std::path::Path;

use pomona_core::PointCloud;

use super::rows::{decode_scalar, Ascii, Binary, Fail, Num, RowSource};
use super::vertices::{min_row_bytes, VertexPlan, Vertices};
use super::{PlyElement, PlyEncoding, PlyError, PlyHeader, PlyPropertyKind, PlyType};
use crate::pcd::clip;

/// Walks every element of the data; returns the vertices (`None` when the file has no vertex
/// rows to read). `input_len` is the whole file's length, for the read budget.
fn read_rows(
    src: &mut dyn RowSource,
    header: &PlyHeader,
    input_len: u64,
) -> Result<Option<Vertices>, PlyError> {
    let mut vertices = None;
    for element in &header.elements {
        if element.properties.is_empty() {
            // Rows of nothing take no space.
            continue;
        }
        if element.name == "vertex" {
            let plan = checked_vertex_plan(src, header, element, input_len)?;
            vertices = Some(read_vertices(src, element, &plan)?);
        } else {
            read_element(src, element, None)?;
        }
    }
    Ok(vertices)
}

/// The vertex plan, once the vertex count is known to fit the bytes left and its columns the
/// read budget.
fn checked_vertex_plan(
    src: &dyn RowSource,
    header: &PlyHeader,
    element: &PlyElement,
    input_len: u64,
) -> Result<VertexPlan, PlyError> {
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
    let columns = element
        .count
        .saturating_mul(Vertices::bytes_per_vertex(&plan));
    if let Some(budget) = crate::read_budget::over_budget(columns, input_len) {
        return Err(PlyError::OverBudget {
            needed: columns,
            budget,
        });
    }
    Ok(plan)
}

/// The scalar type of each property (`None` for a list).
fn scalar_types(element: &PlyElement) -> Vec<Option<PlyType>> {
    element
        .properties
        .iter()
        .map(|p| match p.kind {
            PlyPropertyKind::Scalar(t) => Some(t),
            PlyPropertyKind::List { .. } => None,
        })
        .collect()
}

/// Reads the vertex rows (their count is bounded by the input: see [`checked_vertex_plan`]).
fn read_vertices(
    src: &mut dyn RowSource,
    element: &PlyElement,
    plan: &VertexPlan,
) -> Result<Vertices, PlyError> {
    let n = element.count as usize;
    let types = scalar_types(element);
    let color_types = plan.rgb.map(|i| {
        i.and_then(|i| types.get(i).copied().flatten())
            .unwrap_or(PlyType::UInt8)
    });
    let mut out = Vertices::with_capacity(plan, n);
    // Fast path: binary vertices of scalars only have a fixed size and are decoded in place.
    if types.iter().all(Option::is_some) {
        let mut offsets = Vec::with_capacity(types.len());
        let mut row_size = 0;
        for t in types.iter().flatten() {
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
            return Ok(out);
        }
    }
    read_element(src, element, Some((plan, &color_types, &mut out)))?;
    Ok(out)
}

/// Reads the rows of `element` one value at a time; for the vertex element, `vertices` says
/// where its values go.
fn read_element(
    src: &mut dyn RowSource,
    element: &PlyElement,
    mut vertices: Option<(&VertexPlan, &[PlyType; 3], &mut Vertices)>,
) -> Result<(), PlyError> {
    let mut row_values: Vec<Num> = Vec::new();
    for row in 0..element.count {
        row_values.clear();
        for p in &element.properties {
            let ctx = |f: Fail, ty: PlyType| match f {
                Fail::Eof => PlyError::UnexpectedEof {
                    element: clip(&element.name),
                    row,
                    count: element.count,
                },
                Fail::Bad { line, token } => PlyError::AsciiBadNumber {
                    line,
                    element: clip(&element.name),
                    property: clip(&p.name),
                    token,
                    ty: ty.name(),
                },
            };
            let value = match p.kind {
                PlyPropertyKind::Scalar(t) => src.value(t).map_err(|f| ctx(f, t))?,
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
                    Num::I(0)
                }
            };
            if vertices.is_some() {
                row_values.push(value);
            }
        }
        if let Some((plan, color_types, v)) = &mut vertices {
            let get = |i: Option<usize>| i.and_then(|i| row_values.get(i)).copied();
            v.push(plan, color_types, row, get)?;
        }
    }
    Ok(())
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
            bytes.len() as u64,
        )?,
        enc => read_rows(
            &mut Binary {
                data,
                pos: 0,
                big_endian: enc == PlyEncoding::BinaryBigEndian,
            },
            &header,
            bytes.len() as u64,
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

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::nalgebra::Point3;

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
