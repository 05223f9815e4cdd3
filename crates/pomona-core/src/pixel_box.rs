//! An axis-aligned box in pixel coordinates, `[xmin, ymin, xmax, ymax]` on disk.

use nalgebra::Point2;
use serde::{Deserialize, Serialize};

use crate::CoreError;

/// Axis-aligned pixel box; corners inclusive, in the same pixel-centre convention as the camera.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "[f64; 4]", into = "[f64; 4]")]
pub struct PixelBox {
    /// Left edge (column).
    pub xmin: f64,
    /// Top edge (row).
    pub ymin: f64,
    /// Right edge (column).
    pub xmax: f64,
    /// Bottom edge (row).
    pub ymax: f64,
}

impl PixelBox {
    /// A validated box.
    ///
    /// # Errors
    /// [`CoreError::InvalidBox`] when a corner is not finite or the corners are out of order.
    pub fn new(xmin: f64, ymin: f64, xmax: f64, ymax: f64) -> Result<Self, CoreError> {
        let ok =
            [xmin, ymin, xmax, ymax].iter().all(|c| c.is_finite()) && xmin <= xmax && ymin <= ymax;
        if ok {
            Ok(Self {
                xmin,
                ymin,
                xmax,
                ymax,
            })
        } else {
            Err(CoreError::InvalidBox(xmin, ymin, xmax, ymax))
        }
    }

    /// Whether a continuous pixel position lies inside (edges included).
    pub fn contains(&self, p: &Point2<f64>) -> bool {
        p.x >= self.xmin && p.x <= self.xmax && p.y >= self.ymin && p.y <= self.ymax
    }

    /// Width in pixels (`xmax - xmin`).
    pub fn width(&self) -> f64 {
        self.xmax - self.xmin
    }

    /// Height in pixels (`ymax - ymin`).
    pub fn height(&self) -> f64 {
        self.ymax - self.ymin
    }

    /// Centre of the box.
    pub fn center(&self) -> Point2<f64> {
        Point2::new(0.5 * (self.xmin + self.xmax), 0.5 * (self.ymin + self.ymax))
    }
}

impl TryFrom<[f64; 4]> for PixelBox {
    type Error = CoreError;

    fn try_from(c: [f64; 4]) -> Result<Self, CoreError> {
        Self::new(c[0], c[1], c[2], c[3])
    }
}

impl From<PixelBox> for [f64; 4] {
    fn from(b: PixelBox) -> Self {
        [b.xmin, b.ymin, b.xmax, b.ymax]
    }
}
