//! A depth image in metres: the z coordinate (not the ray length) of each pixel's surface point.
//!
//! Sensors deliver 16-bit integers times a unit; in memory we hold `f32` metres with `NaN` for
//! "no reading", so algorithms never have to remember which sentinel or unit a sensor used.

use crate::CoreError;

/// Depth in metres (z along the optical axis), row-major; `NaN` means no reading.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthImage {
    width: u32,
    height: u32,
    depth_m: Vec<f32>,
}

impl DepthImage {
    /// Wraps a buffer of metres (`NaN` = no reading). Non-positive and infinite values are
    /// normalised to `NaN`, so "valid" always means finite and in front of the camera.
    ///
    /// # Errors
    /// [`CoreError::SizeMismatch`] when the buffer length disagrees with the size.
    pub fn from_meters(width: u32, height: u32, mut depth_m: Vec<f32>) -> Result<Self, CoreError> {
        let expected = width as usize * height as usize;
        if depth_m.len() != expected {
            return Err(CoreError::SizeMismatch {
                what: "depth image values",
                width,
                height,
                expected,
                actual: depth_m.len(),
            });
        }
        for d in &mut depth_m {
            if !(d.is_finite() && *d > 0.0) {
                *d = f32::NAN;
            }
        }
        Ok(Self {
            width,
            height,
            depth_m,
        })
    }

    /// Converts raw sensor values: `z = raw * unit_m`, and 0 means no reading.
    ///
    /// # Errors
    /// [`CoreError::InvalidDepthUnit`] for a non-finite or non-positive unit;
    /// [`CoreError::SizeMismatch`] when the buffer length disagrees with the size.
    ///
    /// ```
    /// use pomona_core::DepthImage;
    /// let d = DepthImage::from_u16(2, 1, &[0, 1500], 0.001).unwrap();
    /// assert!(d.get(0, 0).is_none());
    /// assert_eq!(d.get(1, 0), Some(1.5));
    /// ```
    pub fn from_u16(width: u32, height: u32, raw: &[u16], unit_m: f64) -> Result<Self, CoreError> {
        if !(unit_m.is_finite() && unit_m > 0.0) {
            return Err(CoreError::InvalidDepthUnit(unit_m));
        }
        let depth_m = raw
            .iter()
            .map(|&r| {
                if r == 0 {
                    f32::NAN
                } else {
                    (r as f64 * unit_m) as f32
                }
            })
            .collect();
        Self::from_meters(width, height, depth_m)
    }

    /// Converts back to raw sensor values: `round(z / unit_m)`; no reading, and depths that do
    /// not fit in 16 bits, become 0 (no reading).
    ///
    /// # Errors
    /// [`CoreError::InvalidDepthUnit`] for a non-finite or non-positive unit.
    pub fn to_u16(&self, unit_m: f64) -> Result<Vec<u16>, CoreError> {
        if !(unit_m.is_finite() && unit_m > 0.0) {
            return Err(CoreError::InvalidDepthUnit(unit_m));
        }
        Ok(self
            .depth_m
            .iter()
            .map(|&d| {
                let raw = (d as f64 / unit_m).round();
                if raw.is_finite() && raw >= 1.0 && raw <= u16::MAX as f64 {
                    raw as u16
                } else {
                    0
                }
            })
            .collect())
    }

    /// An image with no readings.
    pub fn empty(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            depth_m: vec![f32::NAN; width as usize * height as usize],
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

    /// The depth at `(u, v)` in metres, or `None` outside the image or without a reading.
    pub fn get(&self, u: u32, v: u32) -> Option<f32> {
        if u >= self.width || v >= self.height {
            return None;
        }
        let d = self.depth_m[v as usize * self.width as usize + u as usize];
        d.is_finite().then_some(d)
    }

    /// Sets the depth at `(u, v)`; non-finite or non-positive values clear the reading.
    pub fn set(&mut self, u: u32, v: u32, depth_m: f32) {
        if u < self.width && v < self.height {
            let d = if depth_m.is_finite() && depth_m > 0.0 {
                depth_m
            } else {
                f32::NAN
            };
            self.depth_m[v as usize * self.width as usize + u as usize] = d;
        }
    }

    /// All values, row-major, `NaN` where there is no reading.
    pub fn as_slice(&self) -> &[f32] {
        &self.depth_m
    }

    /// Whether any pixel has a reading (stops at the first; a colour-only frame has none).
    pub fn has_readings(&self) -> bool {
        self.depth_m.iter().any(|d| d.is_finite())
    }

    /// Number of pixels with a reading.
    pub fn valid_count(&self) -> usize {
        self.depth_m.iter().filter(|d| d.is_finite()).count()
    }

    /// Fraction of pixels with a reading, in `[0, 1]`.
    pub fn valid_fraction(&self) -> f64 {
        if self.depth_m.is_empty() {
            return 0.0;
        }
        self.valid_count() as f64 / self.depth_m.len() as f64
    }

    /// Smallest and largest valid depth in metres, or `None` if no pixel has a reading.
    pub fn range_m(&self) -> Option<(f32, f32)> {
        self.depth_m
            .iter()
            .filter(|d| d.is_finite())
            .fold(None, |acc, &d| match acc {
                None => Some((d, d)),
                Some((lo, hi)) => Some((lo.min(d), hi.max(d))),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn u16_round_trip_keeps_millimetres_and_holes() {
        let raw = [0u16, 1, 731, 65535];
        let d = DepthImage::from_u16(4, 1, &raw, 0.001).unwrap();
        assert_eq!(d.valid_count(), 3);
        assert_eq!(d.to_u16(0.001).unwrap(), raw);
        assert_eq!(d.range_m(), Some((0.001, 65.535)));
    }

    #[test]
    fn out_of_range_depth_becomes_no_reading() {
        let d = DepthImage::from_meters(3, 1, vec![70.0, -1.0, f32::INFINITY]).unwrap();
        assert_eq!(d.valid_count(), 1);
        assert!(d.has_readings());
        assert_eq!(d.to_u16(0.001).unwrap(), [0, 0, 0]);
    }

    #[test]
    fn bad_unit_is_rejected() {
        assert!(DepthImage::from_u16(1, 1, &[1], 0.0).is_err());
        assert!(DepthImage::from_u16(1, 1, &[1], f64::NAN).is_err());
    }

    #[test]
    fn empty_image_has_no_range() {
        let d = DepthImage::empty(2, 2);
        assert_eq!(d.range_m(), None);
        assert_eq!(d.valid_fraction(), 0.0);
        assert!(!d.has_readings());
    }
}
