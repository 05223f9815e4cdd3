//! Voxel-grid downsampling: one point per occupied cube of a fixed side, the mean of the points
//! that fall in it.
//!
//! A depth camera samples near surfaces far more densely than distant ones; averaging per voxel
//! evens the density and cuts the point count before costly stages (the same operation as PCL's
//! `VoxelGrid` and Open3D's `voxel_down_sample`, which `scripts/open3d_blocks.sh` times it
//! against). Voxels are aligned to the smallest corner of the valid points' bounding box. The
//! output is unorganised, ordered by voxel (z, then y, then x index), so it is deterministic.
//! Positions and colours are averaged; other attributes (normals, labels, intensities) are
//! dropped, since a mean of them is not meaningful in general. Invalid points are skipped.

use nalgebra::Point3;

use crate::{CoreError, PointCloud};

/// Bits per axis of the packed voxel key.
const AXIS_BITS: u32 = 21;

/// The cloud downsampled to the mean point (and mean colour) of each occupied voxel of side
/// `voxel_m` metres.
///
/// # Errors
/// [`CoreError::InvalidVoxelSize`] when `voxel_m` is not finite and positive, or so small for the
/// cloud's extent that an axis would need more than 2²¹ voxels.
pub fn voxel_downsample(cloud: &PointCloud, voxel_m: f64) -> Result<PointCloud, CoreError> {
    if !(voxel_m.is_finite() && voxel_m > 0.0) {
        return Err(CoreError::InvalidVoxelSize {
            voxel_m,
            reason: "must be finite and positive",
        });
    }
    let points = cloud.points();
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for p in points.iter().filter(|p| p.iter().all(|c| c.is_finite())) {
        for d in 0..3 {
            min[d] = min[d].min(p[d] as f64);
            max[d] = max[d].max(p[d] as f64);
        }
    }
    let limit = (1u64 << AXIS_BITS) as f64;
    if (0..3).any(|d| (max[d] - min[d]) / voxel_m >= limit) {
        return Err(CoreError::InvalidVoxelSize {
            voxel_m,
            reason: "too small for the cloud's extent (more than 2^21 voxels along an axis)",
        });
    }
    let inv = 1.0 / voxel_m;
    let mut keyed: Vec<(u64, u32)> = points
        .iter()
        .enumerate()
        .filter(|(_, p)| p.iter().all(|c| c.is_finite()))
        .map(|(i, p)| {
            let cell = |d: usize| ((p[d] as f64 - min[d]) * inv) as u64;
            (
                cell(0) | cell(1) << AXIS_BITS | cell(2) << (2 * AXIS_BITS),
                i as u32,
            )
        })
        .collect();
    keyed.sort_unstable();
    let colors = cloud.colors();
    let mut out_points = Vec::new();
    let mut out_colors = colors.map(|_| Vec::new());
    for run in keyed.chunk_by(|a, b| a.0 == b.0) {
        let n = run.len() as f64;
        let mut sum = [0.0f64; 3];
        let mut rgb = [0.0f64; 3];
        for &(_, i) in run {
            let p = &points[i as usize];
            for d in 0..3 {
                sum[d] += p[d] as f64;
            }
            if let Some(c) = colors {
                for d in 0..3 {
                    rgb[d] += c[i as usize][d] as f64;
                }
            }
        }
        out_points.push(Point3::new(
            (sum[0] / n) as f32,
            (sum[1] / n) as f32,
            (sum[2] / n) as f32,
        ));
        if let Some(c) = out_colors.as_mut() {
            c.push(rgb.map(|v| (v / n).round() as u8));
        }
    }
    let out = PointCloud::unorganized(out_points);
    match out_colors {
        Some(c) => out.with_colors(c),
        None => Ok(out),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_in_one_voxel_average_and_others_stay_apart() {
        let nan = Point3::new(f32::NAN, f32::NAN, f32::NAN);
        let cloud = PointCloud::organized(
            3,
            2,
            vec![
                Point3::new(0.0, 0.0, 1.0),
                Point3::new(0.004, 0.002, 1.006),
                nan,
                Point3::new(0.05, 0.0, 1.0),
                Point3::new(0.0, 0.0, 1.02),
                Point3::new(0.002, 0.004, 1.0),
            ],
        )
        .unwrap()
        .with_colors(vec![
            [10, 0, 0],
            [20, 0, 0],
            [0, 0, 0],
            [0, 200, 0],
            [0, 0, 9],
            [30, 0, 0],
        ])
        .unwrap();
        let down = voxel_downsample(&cloud, 0.01).unwrap();
        assert_eq!(down.grid(), None);
        assert_eq!(down.len(), 3);
        // Ordered by (z, y, x) voxel: the corner voxel, the one 50 mm along x, the one 20 mm up z.
        let p = down.points();
        assert!(
            (p[0] - Point3::new(0.002, 0.002, 1.002)).norm() < 1e-6,
            "{p:?}"
        );
        assert_eq!(p[1], Point3::new(0.05, 0.0, 1.0));
        assert_eq!(p[2], Point3::new(0.0, 0.0, 1.02));
        assert_eq!(
            down.colors().unwrap(),
            &[[20, 0, 0], [0, 200, 0], [0, 0, 9]]
        );
    }

    #[test]
    fn bad_voxel_sizes_are_errors_and_empty_clouds_stay_empty() {
        let cloud =
            PointCloud::unorganized(vec![Point3::new(0.0, 0.0, 1.0), Point3::new(5.0, 0.0, 1.0)]);
        for bad in [0.0, -0.01, f64::NAN, f64::INFINITY, 1e-9] {
            assert!(voxel_downsample(&cloud, bad).is_err(), "{bad}");
        }
        let empty = voxel_downsample(&PointCloud::unorganized(vec![]), 0.01).unwrap();
        assert!(empty.is_empty() && empty.colors().is_none());
    }
}
