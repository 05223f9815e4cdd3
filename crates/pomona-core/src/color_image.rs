//! An 8-bit RGB image, row-major, no padding.
//!
//! Kept independent of any codec crate so the data model stays at the bottom of the dependency
//! graph; `pomona-io` converts to and from PNG/JPEG.

use crate::CoreError;

/// An 8-bit RGB image stored row-major as interleaved `[r, g, b]` bytes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ColorImage {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl ColorImage {
    /// Wraps an interleaved RGB buffer of length `3 * width * height`.
    ///
    /// # Errors
    /// [`CoreError::SizeMismatch`] when the buffer length disagrees with the size.
    pub fn from_rgb(width: u32, height: u32, rgb: Vec<u8>) -> Result<Self, CoreError> {
        let expected = 3 * width as usize * height as usize;
        if rgb.len() != expected {
            return Err(CoreError::SizeMismatch {
                what: "colour image bytes",
                width,
                height,
                expected,
                actual: rgb.len(),
            });
        }
        Ok(Self { width, height, rgb })
    }

    /// An image filled with one colour.
    pub fn filled(width: u32, height: u32, color: [u8; 3]) -> Self {
        let rgb = color.repeat(width as usize * height as usize);
        Self { width, height, rgb }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The colour at column `u`, row `v`, or `None` outside the image.
    pub fn get(&self, u: u32, v: u32) -> Option<[u8; 3]> {
        if u >= self.width || v >= self.height {
            return None;
        }
        let i = 3 * (v as usize * self.width as usize + u as usize);
        Some([self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]])
    }

    /// Sets the colour at `(u, v)`; does nothing outside the image.
    pub fn set(&mut self, u: u32, v: u32, color: [u8; 3]) {
        if u < self.width && v < self.height {
            let i = 3 * (v as usize * self.width as usize + u as usize);
            self.rgb[i..i + 3].copy_from_slice(&color);
        }
    }

    /// The interleaved bytes.
    pub fn as_rgb(&self) -> &[u8] {
        &self.rgb
    }

    /// Mutable interleaved bytes.
    pub fn as_rgb_mut(&mut self) -> &mut [u8] {
        &mut self.rgb
    }

    /// Pixels as `[r, g, b]` triples in row-major order.
    pub fn pixels(&self) -> impl ExactSizeIterator<Item = [u8; 3]> + '_ {
        self.rgb.chunks_exact(3).map(|c| [c[0], c[1], c[2]])
    }

    /// Consumes the image, returning the interleaved bytes.
    pub fn into_rgb(self) -> Vec<u8> {
        self.rgb
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn get_and_set_address_row_major() {
        let mut img = ColorImage::filled(3, 2, [1, 2, 3]);
        img.set(2, 1, [9, 8, 7]);
        assert_eq!(img.get(2, 1), Some([9, 8, 7]));
        assert_eq!(&img.as_rgb()[15..18], &[9, 8, 7]);
        assert_eq!(img.get(3, 0), None);
        assert_eq!(img.pixels().len(), 6);
    }

    #[test]
    fn wrong_buffer_length_is_rejected() {
        assert!(matches!(
            ColorImage::from_rgb(2, 2, vec![0; 11]),
            Err(CoreError::SizeMismatch {
                expected: 12,
                actual: 11,
                ..
            })
        ));
    }
}
