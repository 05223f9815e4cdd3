//! A registered RGB-D frame: depth, optional colour on the same pixel grid, and the camera.
//!
//! The constructor is the one place that checks the three agree in size, so no detector has to.

use nalgebra::Point3;

use crate::{ColorImage, CoreError, DepthImage, PinholeCamera, PointCloud};

/// Depth and (optionally) colour registered to the same pinhole camera.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbdFrame {
    camera: PinholeCamera,
    depth: DepthImage,
    color: Option<ColorImage>,
}

impl RgbdFrame {
    /// Builds a frame after checking that every image has the camera's size.
    ///
    /// # Errors
    /// [`CoreError::DimensionsDisagree`] when depth or colour differ in size from the camera;
    /// [`CoreError::InvalidCameraParameter`] for an invalid camera.
    pub fn new(
        camera: PinholeCamera,
        depth: DepthImage,
        color: Option<ColorImage>,
    ) -> Result<Self, CoreError> {
        camera.validate()?;
        let agree = |what, w: u32, h: u32| {
            if (w, h) == (camera.width, camera.height) {
                Ok(())
            } else {
                Err(CoreError::DimensionsDisagree {
                    what,
                    a_w: w,
                    a_h: h,
                    b_w: camera.width,
                    b_h: camera.height,
                })
            }
        };
        agree("depth image vs camera", depth.width(), depth.height())?;
        if let Some(c) = &color {
            agree("colour image vs camera", c.width(), c.height())?;
        }
        Ok(Self {
            camera,
            depth,
            color,
        })
    }

    /// The camera both images were taken with.
    pub fn camera(&self) -> &PinholeCamera {
        &self.camera
    }

    /// Depth in metres.
    pub fn depth(&self) -> &DepthImage {
        &self.depth
    }

    /// Colour, when the dataset has it.
    pub fn color(&self) -> Option<&ColorImage> {
        self.color.as_ref()
    }

    /// Back-projects every pixel to an organised cloud in the camera frame (`NaN` where there is
    /// no depth), coloured when the frame has colour.
    pub fn to_cloud(&self) -> PointCloud {
        let colors = self.color.as_ref().map(|c| c.pixels().collect());
        PointCloud::from_checked_parts(self.camera.width, self.camera.height, self.points(), colors)
    }

    /// [`RgbdFrame::to_cloud`] without the colour: the detectors read colour from the frame, and
    /// at 1920×1080 the copy is 6 MB of fresh memory per frame.
    pub fn to_cloud_without_color(&self) -> PointCloud {
        PointCloud::from_checked_parts(self.camera.width, self.camera.height, self.points(), None)
    }

    /// The back-projected points in row-major pixel order, a row at a time. Without lens
    /// distortion `u − cx` is computed once per column: the same arithmetic as
    /// [`PinholeCamera::back_project`] (so the same bits), without a division by the width per
    /// pixel.
    fn points(&self) -> Vec<Point3<f32>> {
        let cam = &self.camera;
        let w = cam.width as usize;
        let depth = self.depth.as_slice();
        let du: Vec<f64> = (0..w).map(|u| u as f64 - cam.cx).collect();
        let mut points = Vec::with_capacity(depth.len());
        for (v, row) in depth.chunks_exact(w.max(1)).enumerate() {
            let dv = v as f64 - cam.cy;
            points.extend(row.iter().zip(&du).enumerate().map(|(u, (&z, &du))| {
                if !z.is_finite() {
                    return Point3::new(f32::NAN, f32::NAN, f32::NAN);
                }
                let z64 = z as f64;
                let (x, y) = match cam.distortion {
                    None => (du * z64 / cam.fx, dv * z64 / cam.fy),
                    Some(_) => {
                        let p = cam.back_project(u as f64, v as f64, z64);
                        (p.x, p.y)
                    }
                };
                Point3::new(x as f32, y as f32, z)
            }));
        }
        points
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cloud_matches_hand_back_projection() {
        let cam = PinholeCamera::new(3, 2, 100.0, 200.0, 1.0, 0.5).unwrap();
        let depth = DepthImage::from_u16(3, 2, &[1000, 0, 2000, 500, 500, 500], 0.001).unwrap();
        let color = ColorImage::filled(3, 2, [10, 20, 30]);
        let frame = RgbdFrame::new(cam, depth, Some(color)).unwrap();
        let cloud = frame.to_cloud();
        assert_eq!(cloud.grid(), Some((3, 2)));
        assert_eq!(cloud.valid_count(), 5);
        // pixel (0,0), z = 1: x = (0 - 1) * 1 / 100 = -0.01, y = (0 - 0.5) * 1 / 200 = -0.0025
        let p = cloud.at(0, 0).unwrap();
        assert!((p.x + 0.01).abs() < 1e-7 && (p.y + 0.0025).abs() < 1e-7 && p.z == 1.0);
        // pixel (2,0), z = 2: x = 1 * 2 / 100 = 0.02
        assert!((cloud.at(2, 0).unwrap().x - 0.02).abs() < 1e-7);
        assert!(!cloud.is_valid(1));
        assert_eq!(cloud.colors().unwrap()[4], [10, 20, 30]);
    }

    #[test]
    fn row_wise_points_are_the_back_projection_bit_for_bit() {
        let cam = PinholeCamera::new(7, 5, 917.123, 916.965, 3.2178, 2.7894).unwrap();
        let raw: Vec<u16> = (0..35u16)
            .map(|i| if i % 6 == 0 { 0 } else { 400 + 37 * i })
            .collect();
        let depth = DepthImage::from_u16(7, 5, &raw, 0.001).unwrap();
        let color = ColorImage::filled(7, 5, [1, 2, 3]);
        let frame = RgbdFrame::new(cam, depth, Some(color)).unwrap();
        let (coloured, plain) = (frame.to_cloud(), frame.to_cloud_without_color());
        assert!(plain.colors().is_none() && coloured.colors().is_some());
        for (i, (&z, (p, q))) in frame
            .depth()
            .as_slice()
            .iter()
            .zip(coloured.points().iter().zip(plain.points()))
            .enumerate()
        {
            if z.is_finite() {
                let e = cam.back_project((i % 7) as f64, (i / 7) as f64, z as f64);
                let expected = [e.x as f32, e.y as f32, z];
                assert_eq!(
                    [p.x, p.y, p.z].map(f32::to_bits),
                    expected.map(f32::to_bits),
                    "pixel {i}"
                );
            } else {
                assert!(p.iter().all(|c| c.is_nan()), "pixel {i}");
            }
            assert_eq!(p.map(f32::to_bits), q.map(f32::to_bits), "pixel {i}");
        }
    }

    #[test]
    fn size_disagreement_is_rejected() {
        let cam = PinholeCamera::new(3, 2, 100.0, 100.0, 1.0, 1.0).unwrap();
        let depth = DepthImage::empty(3, 2);
        assert!(RgbdFrame::new(cam, DepthImage::empty(2, 3), None).is_err());
        assert!(RgbdFrame::new(cam, depth, Some(ColorImage::filled(3, 3, [0; 3]))).is_err());
    }
}
