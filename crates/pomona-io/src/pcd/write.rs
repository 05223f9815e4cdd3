//! Encoding a [`PointCloud`] as a PCD file.

use std::io::{BufWriter, Write};
use std::path::Path;

use pomona_core::{CloudLayout, PointCloud};

use super::{PcdEncoding, PcdError};
use crate::atomic_write::write_atomically;
use crate::cloud_file::push_f32;
use crate::lzf;

/// One written field; every one is 4 bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Out {
    X,
    Y,
    Z,
    Rgb,
    Nx,
    Ny,
    Nz,
    Intensity,
    Label,
}

impl Out {
    fn name(self) -> &'static str {
        match self {
            Out::X => "x",
            Out::Y => "y",
            Out::Z => "z",
            Out::Rgb => "rgb",
            Out::Nx => "normal_x",
            Out::Ny => "normal_y",
            Out::Nz => "normal_z",
            Out::Intensity => "intensity",
            Out::Label => "label",
        }
    }
}

/// The bits written for a colour: opaque alpha, like PCL's `PointXYZRGB`.
fn pack_rgb([r, g, b]: [u8; 3]) -> u32 {
    0xFF00_0000 | (u32::from(r) << 16) | (u32::from(g) << 8) | u32::from(b)
}

struct Source<'a> {
    cloud: &'a PointCloud,
}

impl Source<'_> {
    /// The field's 32 bits for point `i` (`i < len`; attributes are present when listed).
    fn bits(&self, field: Out, i: usize) -> u32 {
        let c = self.cloud;
        let f = |v: Option<f32>| v.unwrap_or(f32::NAN).to_bits();
        match field {
            Out::X => f(c.points().get(i).map(|p| p.x)),
            Out::Y => f(c.points().get(i).map(|p| p.y)),
            Out::Z => f(c.points().get(i).map(|p| p.z)),
            Out::Nx => f(c.normals().and_then(|n| n.get(i)).map(|n| n.x)),
            Out::Ny => f(c.normals().and_then(|n| n.get(i)).map(|n| n.y)),
            Out::Nz => f(c.normals().and_then(|n| n.get(i)).map(|n| n.z)),
            Out::Intensity => f(c.intensities().and_then(|v| v.get(i)).copied()),
            Out::Rgb => c
                .colors()
                .and_then(|v| v.get(i))
                .map_or(0, |&rgb| pack_rgb(rgb)),
            Out::Label => c.labels().and_then(|v| v.get(i)).copied().unwrap_or(0),
        }
    }
}

/// Writes `cloud` as a PCD v0.7 file with the given data encoding.
///
/// Fields, all `SIZE 4`: `x y z` (`F`); `rgb` when the cloud has colours, packed `0xFFRRGGBB`
/// (opaque, as PCL's `PointXYZRGB`) and typed `F` in the binary encodings as PCL's point types
/// declare it, but `U` in `ascii`, where a float would have to be printed as text that is a NaN
/// or a denormal and many readers lose those (current PCL writes `U` for the same reason);
/// `normal_x normal_y normal_z` (`F`) when it has normals; `intensity` (`F`); `label` (`U`).
/// An organised cloud gets its `WIDTH`/`HEIGHT` (one with `HEIGHT 1` reads back unorganised, as
/// in PCL); an unorganised one `WIDTH` = number of points and `HEIGHT 1`. `VIEWPOINT` is the
/// identity. Invalid points are written as they are (`NaN`, `nan` in ascii). Ascii floats are
/// printed in the shortest form that reads back to the same `f32`.
///
/// The output is buffered internally.
///
/// # Errors
/// [`PcdError::Io`] from the writer; [`PcdError::TooLarge`] when an unorganised cloud has more
/// than `u32::MAX` points or a `binary_compressed` payload exceeds 4 GiB.
pub fn write_pcd(
    cloud: &PointCloud,
    out: impl Write,
    encoding: PcdEncoding,
) -> Result<(), PcdError> {
    let mut fields = vec![Out::X, Out::Y, Out::Z];
    if cloud.colors().is_some() {
        fields.push(Out::Rgb);
    }
    if cloud.normals().is_some() {
        fields.extend([Out::Nx, Out::Ny, Out::Nz]);
    }
    if cloud.intensities().is_some() {
        fields.push(Out::Intensity);
    }
    if cloud.labels().is_some() {
        fields.push(Out::Label);
    }
    let n = cloud.len();
    let (width, height) = match cloud.layout() {
        CloudLayout::Organized { width, height } => (width, height),
        CloudLayout::Unorganized => (
            u32::try_from(n)
                .map_err(|_| PcdError::TooLarge("more than 2^32-1 unorganised points"))?,
            1,
        ),
    };
    let type_of = |f: Out| match f {
        Out::Label => 'U',
        Out::Rgb if encoding == PcdEncoding::Ascii => 'U',
        _ => 'F',
    };
    let join =
        |g: &dyn Fn(Out) -> String| fields.iter().map(|&f| g(f)).collect::<Vec<_>>().join(" ");
    let header = format!(
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {}\nSIZE {}\nTYPE {}\nCOUNT {}\nWIDTH {width}\nHEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {}\n",
        join(&|f| f.name().to_owned()),
        join(&|_| "4".to_owned()),
        join(&|f| type_of(f).to_string()),
        join(&|_| "1".to_owned()),
        encoding.keyword(),
    );
    let mut w = BufWriter::with_capacity(1 << 16, out);
    w.write_all(header.as_bytes())?;
    let src = Source { cloud };
    match encoding {
        PcdEncoding::Ascii => {
            let mut line = String::with_capacity(16 * fields.len());
            for i in 0..n {
                line.clear();
                for (k, &f) in fields.iter().enumerate() {
                    if k > 0 {
                        line.push(' ');
                    }
                    let bits = src.bits(f, i);
                    match f {
                        Out::Rgb | Out::Label => line.push_str(&bits.to_string()),
                        _ => push_f32(&mut line, f32::from_bits(bits)),
                    }
                }
                line.push('\n');
                w.write_all(line.as_bytes())?;
            }
        }
        PcdEncoding::Binary => {
            let mut row = Vec::with_capacity(4 * fields.len());
            for i in 0..n {
                row.clear();
                for &f in &fields {
                    row.extend_from_slice(&src.bits(f, i).to_le_bytes());
                }
                w.write_all(&row)?;
            }
        }
        PcdEncoding::BinaryCompressed => {
            let total = n
                .checked_mul(4 * fields.len())
                .filter(|&t| u32::try_from(t).is_ok())
                .ok_or(PcdError::TooLarge("binary_compressed data over 4 GiB"))?;
            let mut soa = Vec::with_capacity(total);
            for &f in &fields {
                for i in 0..n {
                    soa.extend_from_slice(&src.bits(f, i).to_le_bytes());
                }
            }
            let compressed = lzf::compress(&soa);
            let clen = u32::try_from(compressed.len())
                .map_err(|_| PcdError::TooLarge("binary_compressed data over 4 GiB"))?;
            w.write_all(&clen.to_le_bytes())?;
            // `total` was checked to fit above.
            w.write_all(&(total as u32).to_le_bytes())?;
            w.write_all(&compressed)?;
        }
    }
    w.flush()?;
    Ok(())
}

/// Writes `cloud` to the PCD file at `path` (see [`write_pcd`]), replacing it atomically: the
/// data goes to a temporary file in the same directory that is renamed over `path` only once
/// complete, so an error never leaves a partial file at `path`.
///
/// # Errors
/// [`PcdError::File`] wrapping the cause.
pub fn write_pcd_file(
    path: impl AsRef<Path>,
    cloud: &PointCloud,
    encoding: PcdEncoding,
) -> Result<(), PcdError> {
    let path = path.as_ref();
    write_atomically(
        path,
        |w| write_pcd(cloud, w, encoding),
        |_, e| PcdError::from(e),
    )
    .map_err(|e| e.with_path(path))
}
