//! Thinning a cluster to a pixel lattice before normals and MSAC, so that the work per fruit
//! does not grow with the camera's resolution (not in seed 002).
//!
//! A fruit at a given distance covers `(fx / 365)²` times as many pixels on a camera of focal
//! length `fx` as on the Kinect v2 of seed 002: about 6 times on a 1920×1080 Azure Kinect
//! (917 px). Every pixel of a cluster gets a window normal and takes part in MSAC's inlier
//! counts and refinement, so on such frames most of the detector's time went into points that
//! add no information the Kinect v2's density did not have. With a reference focal length set,
//! a cluster keeps the pixels on every `k`-th row and column, `k = ⌊fx / reference⌋`: every
//! pixel on a Kinect v2 (365 px), a D435 (615 px) and an SR4000 (220 px), every second row and
//! column (a quarter) on the Azure Kinect. Region growing, the depth proposals' area gates and
//! the normals' windows still see every pixel; only the points handed to the shape fit (and so
//! to the descriptor) are thinned, and MSAC's point-count limits shrink by `k²` with them. The
//! lattice is fixed to the image, so a frame's result does not depend on cluster order or
//! threads.
//!
//! Off by default. Measured on the three real `ak-apples` frames (1920×1080): with the
//! built-in model, 44 of 84 tagged apples at the operating confidence against 43, and
//! detection about 40 % faster; but `pomona experiment --leave-one-out` (trained on two real
//! frames, tested on the third) found 0.885 of the apples against 0.923 with every pixel. Small
//! and half-hidden apples far away lose the points that made them a shape.

use std::borrow::Cow;

use serde::{Deserialize, Serialize};

/// The lattice clusters are thinned to.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct ClusterLattice {
    /// The focal length, px, up to which every pixel is kept (365 is seed 002's Kinect v2);
    /// `None` (the default, and model files written before it) keeps every pixel on every
    /// camera.
    pub reference_focal_px: Option<f64>,
}

impl ClusterLattice {
    /// Every pixel on every camera.
    pub fn off() -> Self {
        Self::default()
    }

    /// The lattice step, pixels, for a camera of focal length `fx_px`: `⌊fx / reference⌋`, at
    /// least 1 (and 1 when off, or for a focal length that is not a positive number).
    ///
    /// ```
    /// use pomona_shapefit::ClusterLattice;
    /// let lattice = ClusterLattice { reference_focal_px: Some(365.0) };
    /// assert_eq!(lattice.step(365.0), 1); // Kinect v2
    /// assert_eq!(lattice.step(615.0), 1); // D435
    /// assert_eq!(lattice.step(917.1), 2); // Azure Kinect, 1920×1080
    /// assert_eq!(ClusterLattice::off().step(917.1), 1);
    /// ```
    pub fn step(&self, fx_px: f64) -> usize {
        match self.reference_focal_px {
            Some(reference) if reference > 0.0 && fx_px.is_finite() && fx_px > 0.0 => {
                (fx_px / reference).floor().max(1.0) as usize
            }
            _ => 1,
        }
    }

    /// The pixels of `cluster` (row-major indices into an image `width` wide) on the lattice of
    /// step `step`, in their order; the cluster itself when `step` is 1.
    pub fn thin(step: usize, width: usize, cluster: &[usize]) -> Cow<'_, [usize]> {
        if step <= 1 || width == 0 {
            return Cow::Borrowed(cluster);
        }
        Cow::Owned(
            cluster
                .iter()
                .copied()
                .filter(|&i| (i % width) % step == 0 && (i / width) % step == 0)
                .collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thinning_keeps_every_step_th_row_and_column() {
        let width = 10;
        let cluster: Vec<usize> = (0..60).collect(); // six full rows
        let kept = ClusterLattice::thin(2, width, &cluster);
        assert_eq!(kept.len(), 15); // rows 0, 2, 4 × columns 0, 2, 4, 6, 8
        assert!(kept
            .iter()
            .all(|&i| (i % width) % 2 == 0 && (i / width) % 2 == 0));
        assert_eq!(&*ClusterLattice::thin(1, width, &cluster), &cluster[..]);
    }

    #[test]
    fn odd_focal_lengths_fall_back_to_every_pixel() {
        let lattice = ClusterLattice {
            reference_focal_px: Some(365.0),
        };
        for fx in [f64::NAN, 0.0, -900.0, f64::INFINITY] {
            assert_eq!(lattice.step(fx), 1, "{fx}");
        }
        assert_eq!(lattice.step(3.0 * 365.0), 3);
    }
}
