//! Decoding and encoding the dataset's images (PNG, JPEG) into core types.
//!
//! Decoding checks the header (size, sample type) *before* allocating pixel memory, so a
//! corrupt or hostile file cannot make us allocate more than the camera's image size, nor more
//! than the read budget of a file of its size ([`crate::read_budget`]: a few kilobytes of
//! deflate cannot declare gigabytes of pixels).

use std::path::Path;

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::error::{LimitError, LimitErrorKind};
use image::{ColorType, DynamicImage, ImageDecoder, ImageEncoder, ImageError, ImageReader, Limits};
use pomona_core::{ColorImage, DepthImage, InstanceMask};

use crate::atomic_write::write_atomically;
use crate::read_budget::{decode_budget_bytes, over_budget};
use crate::DatasetError;

/// Opens an image and checks that its size is `expected` (width, height), returning the decoder.
/// Opens the image at `path`, checks its size against `expected`, and checks that decoding it
/// (the decoder's pixels plus `out_bytes_per_pixel` for the caller's own copy) fits the read
/// budget of a file of its size (see [`crate::read_budget`]); the decoder is limited to the same
/// budget for its own buffers.
fn open_checked(
    path: &Path,
    expected: (u32, u32),
    out_bytes_per_pixel: u64,
) -> Result<impl ImageDecoder, DatasetError> {
    let image_err = |source| DatasetError::Image {
        path: path.to_owned(),
        source,
    };
    let file_len = std::fs::metadata(path)
        .map_err(|e| DatasetError::io(path, e))?
        .len();
    let mut reader = ImageReader::open(path)
        .map_err(|e| DatasetError::io(path, e))?
        .with_guessed_format()
        .map_err(|e| DatasetError::io(path, e))?;
    let mut limits = Limits::default();
    limits.max_alloc = Some(decode_budget_bytes(file_len));
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(image_err)?;
    let (width, height) = decoder.dimensions();
    if (width, height) != expected {
        return Err(DatasetError::SizeMismatch {
            path: path.to_owned(),
            width,
            height,
            expected_width: expected.0,
            expected_height: expected.1,
        });
    }
    let pixels = u64::from(width) * u64::from(height);
    let needed = decoder
        .total_bytes()
        .saturating_add(pixels.saturating_mul(out_bytes_per_pixel));
    if over_budget(needed, file_len).is_some() {
        return Err(image_err(ImageError::Limits(LimitError::from_kind(
            LimitErrorKind::InsufficientMemory,
        ))));
    }
    Ok(decoder)
}

/// Decodes a 16-bit single-channel image; `out_bytes_per_pixel` as in [`open_checked`].
fn read_u16_plane(
    path: &Path,
    expected: (u32, u32),
    out_bytes_per_pixel: u64,
) -> Result<Vec<u16>, DatasetError> {
    let decoder = open_checked(path, expected, out_bytes_per_pixel)?;
    let color = decoder.color_type();
    if color != ColorType::L16 {
        return Err(DatasetError::DepthNotSixteenBit {
            path: path.to_owned(),
            found: format!("{color:?}"),
        });
    }
    let image = DynamicImage::from_decoder(decoder).map_err(|source| DatasetError::Image {
        path: path.to_owned(),
        source,
    })?;
    Ok(image.into_luma16().into_raw())
}

/// Reads a 16-bit depth PNG of the expected size, converting raw values with `unit_m`.
///
/// # Errors
/// [`DatasetError::SizeMismatch`], [`DatasetError::DepthNotSixteenBit`], [`DatasetError::Image`]
/// for a corrupt or truncated file, [`DatasetError::Io`] when it cannot be opened.
pub fn read_depth_png(
    path: &Path,
    expected: (u32, u32),
    unit_m: f64,
) -> Result<DepthImage, DatasetError> {
    // The depth image keeps an f32 per pixel.
    let raw = read_u16_plane(path, expected, 4)?;
    DepthImage::from_u16(expected.0, expected.1, &raw, unit_m).map_err(|source| {
        DatasetError::Core {
            path: path.to_owned(),
            source,
        }
    })
}

/// Reads a 16-bit instance mask PNG of the expected size.
///
/// # Errors
/// As [`read_depth_png`].
pub fn read_mask_png(path: &Path, expected: (u32, u32)) -> Result<InstanceMask, DatasetError> {
    // The mask keeps the decoded ids.
    let ids = read_u16_plane(path, expected, 0)?;
    InstanceMask::from_ids(expected.0, expected.1, ids).map_err(|source| DatasetError::Core {
        path: path.to_owned(),
        source,
    })
}

/// Reads a colour image (PNG or JPEG, any 8- or 16-bit layout; converted to 8-bit RGB).
///
/// # Errors
/// [`DatasetError::SizeMismatch`], [`DatasetError::Image`], [`DatasetError::Io`].
pub fn read_color_image(path: &Path, expected: (u32, u32)) -> Result<ColorImage, DatasetError> {
    // Converting to 8-bit RGB may copy the decoded pixels.
    let decoder = open_checked(path, expected, 3)?;
    let image = DynamicImage::from_decoder(decoder).map_err(|source| DatasetError::Image {
        path: path.to_owned(),
        source,
    })?;
    ColorImage::from_rgb(expected.0, expected.1, image.into_rgb8().into_raw()).map_err(|source| {
        DatasetError::Core {
            path: path.to_owned(),
            source,
        }
    })
}

fn write_png(
    path: &Path,
    bytes: &[u8],
    width: u32,
    height: u32,
    color: ColorType,
) -> Result<(), DatasetError> {
    write_atomically(
        path,
        |w| {
            PngEncoder::new_with_quality(w, CompressionType::Fast, FilterType::Adaptive)
                .write_image(bytes, width, height, color.into())
                .map_err(|source| DatasetError::Image {
                    path: path.to_owned(),
                    source,
                })
        },
        |p: &Path, e| DatasetError::io(p, e),
    )
}

fn u16_bytes(values: &[u16]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_ne_bytes()).collect()
}

/// Writes an 8-bit RGB PNG.
///
/// # Errors
/// [`DatasetError::Io`] or [`DatasetError::Image`]; the destination is untouched on failure.
pub fn write_color_png(path: &Path, image: &ColorImage) -> Result<(), DatasetError> {
    write_png(
        path,
        image.as_rgb(),
        image.width(),
        image.height(),
        ColorType::Rgb8,
    )
}

/// Writes a 16-bit depth PNG with `value = round(z / unit_m)`, 0 where there is no reading.
///
/// # Errors
/// [`DatasetError::Core`] for an invalid unit, otherwise as [`write_color_png`].
pub fn write_depth_png(path: &Path, depth: &DepthImage, unit_m: f64) -> Result<(), DatasetError> {
    let raw = depth.to_u16(unit_m).map_err(|source| DatasetError::Core {
        path: path.to_owned(),
        source,
    })?;
    write_png(
        path,
        &u16_bytes(&raw),
        depth.width(),
        depth.height(),
        ColorType::L16,
    )
}

/// Writes a 16-bit instance mask PNG.
///
/// # Errors
/// As [`write_color_png`].
pub fn write_mask_png(path: &Path, mask: &InstanceMask) -> Result<(), DatasetError> {
    write_png(
        path,
        &u16_bytes(mask.as_slice()),
        mask.width(),
        mask.height(),
        ColorType::L16,
    )
}
