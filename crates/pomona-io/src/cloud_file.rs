//! Point-cloud files of either format (PCD or PLY), chosen by file extension, and the atomic
//! write that every cloud writer in this crate uses.
//!
//! [`read_cloud`] and [`write_cloud`] dispatch on the extension (case-insensitive): `.pcd` →
//! [`CloudFormat::Pcd`], `.ply` → [`CloudFormat::Ply`]. When writing without an explicit format
//! the defaults are PCD `binary` — fast to read and write, readable by every PCL version and
//! tool, and a frame's cloud is rewritten often while `binary_compressed` saves a little disk at
//! an LZF pass per write (pass [`PcdEncoding::BinaryCompressed`] explicitly for archives) — and
//! PLY `binary_little_endian`, the form almost every PLY consumer reads fastest.
//!
//! Writes never leave a partial file at the destination: data goes to a temporary file in the
//! same directory (`.NAME.PID.N.tmp`), which is flushed, synced and then renamed over the
//! destination; on any error the temporary file is removed and the destination is untouched.
//! (A replaced file gets default permissions, not those of the file it replaces.)

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

use pomona_core::PointCloud;

use crate::pcd::{read_pcd_file, write_pcd_file, PcdEncoding, PcdError};
use crate::ply::{read_ply_file, write_ply_file, PlyEncoding, PlyError};

/// A point-cloud file format and encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CloudFormat {
    /// PCL's PCD with the given `DATA` encoding.
    Pcd(PcdEncoding),
    /// PLY with the given `format` line.
    Ply(PlyEncoding),
}

impl CloudFormat {
    /// The default PCD format: `binary` (see the module docs for why).
    pub const DEFAULT_PCD: CloudFormat = CloudFormat::Pcd(PcdEncoding::Binary);
    /// The default PLY format: `binary_little_endian`.
    pub const DEFAULT_PLY: CloudFormat = CloudFormat::Ply(PlyEncoding::BinaryLittleEndian);

    /// The default format for a path's extension (`.pcd` or `.ply`, any case).
    ///
    /// # Errors
    /// [`CloudFileError::UnknownExtension`] for anything else.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Self, CloudFileError> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .and_then(OsStr::to_str)
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("pcd") => Ok(Self::DEFAULT_PCD),
            Some("ply") => Ok(Self::DEFAULT_PLY),
            _ => Err(CloudFileError::UnknownExtension {
                path: path.to_path_buf(),
            }),
        }
    }

    /// The file extension for this format, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            CloudFormat::Pcd(_) => "pcd",
            CloudFormat::Ply(_) => "ply",
        }
    }

    /// A short name, as accepted by [`str::parse`]: `pcd-ascii`, `pcd-binary`,
    /// `pcd-binary-compressed`, `ply-ascii`, `ply-binary-le`, `ply-binary-be`.
    pub fn name(self) -> &'static str {
        match self {
            CloudFormat::Pcd(PcdEncoding::Ascii) => "pcd-ascii",
            CloudFormat::Pcd(PcdEncoding::Binary) => "pcd-binary",
            CloudFormat::Pcd(PcdEncoding::BinaryCompressed) => "pcd-binary-compressed",
            CloudFormat::Ply(PlyEncoding::Ascii) => "ply-ascii",
            CloudFormat::Ply(PlyEncoding::BinaryLittleEndian) => "ply-binary-le",
            CloudFormat::Ply(PlyEncoding::BinaryBigEndian) => "ply-binary-be",
        }
    }

    /// Every format, for listing in help text.
    pub const ALL: [CloudFormat; 6] = [
        CloudFormat::Pcd(PcdEncoding::Ascii),
        CloudFormat::Pcd(PcdEncoding::Binary),
        CloudFormat::Pcd(PcdEncoding::BinaryCompressed),
        CloudFormat::Ply(PlyEncoding::Ascii),
        CloudFormat::Ply(PlyEncoding::BinaryLittleEndian),
        CloudFormat::Ply(PlyEncoding::BinaryBigEndian),
    ];
}

impl std::fmt::Display for CloudFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for CloudFormat {
    type Err = CloudFileError;

    /// Parses a [`CloudFormat::name`] (case-insensitive, `_` accepted for `-`); plain `pcd` and
    /// `ply` give the defaults.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let norm = s.trim().to_ascii_lowercase().replace('_', "-");
        match norm.as_str() {
            "pcd" => return Ok(Self::DEFAULT_PCD),
            "ply" => return Ok(Self::DEFAULT_PLY),
            "ply-binary" | "ply-binary-little-endian" => {
                return Ok(CloudFormat::Ply(PlyEncoding::BinaryLittleEndian))
            }
            "ply-binary-big-endian" => return Ok(CloudFormat::Ply(PlyEncoding::BinaryBigEndian)),
            _ => {}
        }
        Self::ALL
            .into_iter()
            .find(|f| f.name() == norm)
            .ok_or_else(|| CloudFileError::UnknownFormatName(s.to_owned()))
    }
}

/// Why a cloud file could not be read or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CloudFileError {
    /// The path's extension is neither `.pcd` nor `.ply`.
    #[error("{}: unknown point-cloud file extension (expected .pcd or .ply)", path.display())]
    UnknownExtension {
        /// The path.
        path: PathBuf,
    },
    /// A format name that [`CloudFormat`]'s `FromStr` does not know.
    #[error(
        "unknown point-cloud format {0:?} (expected one of pcd, ply, pcd-ascii, pcd-binary, \
         pcd-binary-compressed, ply-ascii, ply-binary-le, ply-binary-be)"
    )]
    UnknownFormatName(String),
    /// Reading or writing the PCD file failed (the error names the path).
    #[error(transparent)]
    Pcd(#[from] PcdError),
    /// Reading or writing the PLY file failed (the error names the path).
    #[error(transparent)]
    Ply(#[from] PlyError),
}

/// Reads a point cloud, choosing the format from the extension of `path`.
///
/// # Errors
/// [`CloudFileError::UnknownExtension`], or the format's error (which names the path).
pub fn read_cloud(path: impl AsRef<Path>) -> Result<PointCloud, CloudFileError> {
    let path = path.as_ref();
    Ok(match CloudFormat::from_path(path)? {
        CloudFormat::Pcd(_) => read_pcd_file(path)?,
        CloudFormat::Ply(_) => read_ply_file(path)?,
    })
}

/// Writes a point cloud atomically (see the module docs), in `format` or, when `None`, the
/// default format for the extension of `path`.
///
/// # Errors
/// [`CloudFileError::UnknownExtension`] when no format is given and the extension is unknown,
/// or the format's error (which names the path).
pub fn write_cloud(
    path: impl AsRef<Path>,
    cloud: &PointCloud,
    format: Option<CloudFormat>,
) -> Result<(), CloudFileError> {
    let path = path.as_ref();
    let format = match format {
        Some(f) => f,
        None => CloudFormat::from_path(path)?,
    };
    match format {
        CloudFormat::Pcd(enc) => write_pcd_file(path, cloud, enc)?,
        CloudFormat::Ply(enc) => write_ply_file(path, cloud, enc)?,
    }
    Ok(())
}

/// Appends `v` in the shortest text that parses back to the same `f32` (`nan`, `inf`, `-inf` for
/// non-finite values; exponent notation for very small or large magnitudes).
pub(crate) fn push_f32(s: &mut String, v: f32) {
    use std::fmt::Write as _;
    if v.is_nan() {
        s.push_str("nan");
    } else if v.is_infinite() {
        s.push_str(if v > 0.0 { "inf" } else { "-inf" });
    } else {
        let a = v.abs();
        // Writing to a String cannot fail.
        let _ = if a == 0.0 || (1e-5..1e9).contains(&a) {
            write!(s, "{v}")
        } else {
            write!(s, "{v:e}")
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_from_extension_and_name() {
        assert_eq!(
            CloudFormat::from_path("a/b.PCD").unwrap(),
            CloudFormat::Pcd(PcdEncoding::Binary)
        );
        assert_eq!(
            CloudFormat::from_path("b.ply").unwrap(),
            CloudFormat::Ply(PlyEncoding::BinaryLittleEndian)
        );
        assert!(matches!(
            CloudFormat::from_path("b.xyz"),
            Err(CloudFileError::UnknownExtension { .. })
        ));
        assert!(matches!(
            CloudFormat::from_path("noext"),
            Err(CloudFileError::UnknownExtension { .. })
        ));
        for f in CloudFormat::ALL {
            assert_eq!(f.name().parse::<CloudFormat>().unwrap(), f);
        }
        assert_eq!(
            "PCD_BINARY_COMPRESSED".parse::<CloudFormat>().unwrap(),
            CloudFormat::Pcd(PcdEncoding::BinaryCompressed)
        );
        assert!(matches!(
            "las".parse::<CloudFormat>(),
            Err(CloudFileError::UnknownFormatName(_))
        ));
    }

    #[test]
    fn float_text_round_trips() {
        let values = [
            0.0_f32,
            -0.0,
            1.0,
            -0.38191,
            1e-30,
            3.4e38,
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            f32::from_bits(0x00ab_cdef),
            123_456_790.0,
            1e9,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        for v in values {
            let mut s = String::new();
            push_f32(&mut s, v);
            let back: f32 = s.parse().unwrap();
            assert_eq!(back.to_bits(), v.to_bits(), "{s}");
        }
        let mut s = String::new();
        push_f32(&mut s, f32::NAN);
        assert_eq!(s, "nan");
    }
}
