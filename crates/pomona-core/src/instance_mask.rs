//! A per-pixel instance label image: 0 is background, `k` is the k-th fruit of the frame's truth
//! (1-based, in the order of `FrameTruth::fruits`).
//!
//! Synthetic datasets store one beside each frame (`mask/<frame>.png`, 16-bit); colour models
//! train from it, and tests use it to check that depth pixels lie on the right fruit.

use crate::CoreError;

/// Row-major 16-bit instance ids.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InstanceMask {
    width: u32,
    height: u32,
    ids: Vec<u16>,
}

impl InstanceMask {
    /// Wraps a buffer of ids.
    ///
    /// # Errors
    /// [`CoreError::SizeMismatch`] when the buffer length disagrees with the size.
    pub fn from_ids(width: u32, height: u32, ids: Vec<u16>) -> Result<Self, CoreError> {
        let expected = width as usize * height as usize;
        if ids.len() != expected {
            return Err(CoreError::SizeMismatch {
                what: "instance mask ids",
                width,
                height,
                expected,
                actual: ids.len(),
            });
        }
        Ok(Self { width, height, ids })
    }

    /// An all-background mask.
    pub fn background(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            ids: vec![0; width as usize * height as usize],
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The id at `(u, v)`, or `None` outside the image.
    pub fn get(&self, u: u32, v: u32) -> Option<u16> {
        (u < self.width && v < self.height)
            .then(|| self.ids[v as usize * self.width as usize + u as usize])
    }

    /// Sets the id at `(u, v)`; does nothing outside the image.
    pub fn set(&mut self, u: u32, v: u32, id: u16) {
        if u < self.width && v < self.height {
            self.ids[v as usize * self.width as usize + u as usize] = id;
        }
    }

    /// All ids, row-major.
    pub fn as_slice(&self) -> &[u16] {
        &self.ids
    }

    /// Number of pixels carrying `id`.
    pub fn count(&self, id: u16) -> usize {
        self.ids.iter().filter(|&&i| i == id).count()
    }
}
