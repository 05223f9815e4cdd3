//! Writing a point cloud as a PLY file with one `vertex` element.

use std::io::{BufWriter, Write};
use std::path::Path;

use pomona_core::{CloudLayout, PointCloud};

use super::{PlyEncoding, PlyError};
use crate::atomic_write::write_atomically;
use crate::cloud_file::push_f32;

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
    let mut w = BufWriter::with_capacity(1 << 16, out);
    w.write_all(header_text(cloud, encoding).as_bytes())?;
    let mut line = String::new();
    let mut row = Vec::new();
    for i in 0..cloud.len() {
        if encoding == PlyEncoding::Ascii {
            line.clear();
            ascii_row(cloud, i, &mut line);
            w.write_all(line.as_bytes())?;
        } else {
            row.clear();
            binary_row(cloud, i, encoding == PlyEncoding::BinaryBigEndian, &mut row);
            w.write_all(&row)?;
        }
    }
    w.flush()?;
    Ok(())
}

/// The header of `cloud` written in `encoding`: the properties of the attributes it has.
fn header_text(cloud: &PointCloud, encoding: PlyEncoding) -> String {
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
        "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n",
        cloud.len()
    ));
    if cloud.colors().is_some() {
        header.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    if cloud.normals().is_some() {
        header.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    if cloud.intensities().is_some() {
        header.push_str("property float intensity\n");
    }
    if cloud.labels().is_some() {
        header.push_str("property uint label\n");
    }
    header.push_str("end_header\n");
    header
}

/// Appends point `i` of `cloud` as an ascii line (with its newline) to `line`.
fn ascii_row(cloud: &PointCloud, i: usize, line: &mut String) {
    let floats = |line: &mut String, vs: &[f32]| {
        for &v in vs {
            if !line.is_empty() {
                line.push(' ');
            }
            push_f32(line, v);
        }
    };
    let p = cloud.points()[i];
    floats(line, &[p.x, p.y, p.z]);
    if let Some(c) = cloud.colors().and_then(|c| c.get(i)) {
        line.push_str(&format!(" {} {} {}", c[0], c[1], c[2]));
    }
    if let Some(nv) = cloud.normals().and_then(|c| c.get(i)) {
        floats(line, &[nv.x, nv.y, nv.z]);
    }
    if let Some(&x) = cloud.intensities().and_then(|c| c.get(i)) {
        floats(line, &[x]);
    }
    if let Some(l) = cloud.labels().and_then(|c| c.get(i)) {
        line.push_str(&format!(" {l}"));
    }
    line.push('\n');
}

/// Appends point `i` of `cloud` as a binary row in the given byte order to `row`.
fn binary_row(cloud: &PointCloud, i: usize, big_endian: bool, row: &mut Vec<u8>) {
    let f32b = |v: f32| {
        if big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let p = cloud.points()[i];
    for v in [p.x, p.y, p.z] {
        row.extend_from_slice(&f32b(v));
    }
    if let Some(c) = cloud.colors().and_then(|c| c.get(i)) {
        row.extend_from_slice(c);
    }
    if let Some(nv) = cloud.normals().and_then(|c| c.get(i)) {
        for v in [nv.x, nv.y, nv.z] {
            row.extend_from_slice(&f32b(v));
        }
    }
    if let Some(&x) = cloud.intensities().and_then(|c| c.get(i)) {
        row.extend_from_slice(&f32b(x));
    }
    if let Some(&l) = cloud.labels().and_then(|c| c.get(i)) {
        row.extend_from_slice(&if big_endian {
            l.to_be_bytes()
        } else {
            l.to_le_bytes()
        });
    }
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
