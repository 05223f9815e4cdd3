//! Depth registration: a depth image taken by one camera, redrawn as the depth seen from
//! another (the colour camera), as the RealSense SDK's `align` does.
//!
//! Each depth pixel with a reading is back-projected at its depth through the depth camera,
//! moved into the colour camera's frame by the depth→colour extrinsics and projected through the
//! colour camera. A depth pixel covers a small square of surface, so its two opposite corners
//! `(u ± ½, v ± ½)` are carried along too: the pixel fills every colour pixel whose centre lies
//! in the projected footprint (the nearest colour pixel when the footprint holds no centre), and
//! where several depth pixels land on one colour pixel the nearest depth wins (a z-buffer, so
//! foreground occludes background). Colour pixels no footprint reaches — the background beside
//! a foreground edge that the depth camera could not see, or outside its view — are holes (NaN,
//! "no depth"): nothing is interpolated across them.

use pomona_core::nalgebra::{Isometry3, Point2, Point3};
use pomona_core::PinholeCamera;

/// The depth image of `depth_camera` (`raw` row-major, `raw × unit_m` metres, 0 = no reading)
/// seen from `color_camera`, which sits at `color_from_depth` relative to it: metres per colour
/// pixel, NaN where no depth lands.
///
/// `raw` must hold `depth_camera.width × depth_camera.height` values (the caller checks).
pub fn register_depth(
    raw: &[u16],
    unit_m: f64,
    depth_camera: &PinholeCamera,
    color_camera: &PinholeCamera,
    color_from_depth: &Isometry3<f64>,
) -> Vec<f32> {
    let (cw, ch) = (color_camera.width as i64, color_camera.height as i64);
    let mut out = vec![f32::INFINITY; (cw * ch) as usize];
    let width = depth_camera.width as usize;
    for (i, &value) in raw.iter().enumerate() {
        if value == 0 {
            continue;
        }
        let (u, v) = ((i % width) as f64, (i / width) as f64);
        let z = f64::from(value) * unit_m;
        let to_color = |du: f64, dv: f64| -> Option<(Point3<f64>, Point2<f64>)> {
            let p = color_from_depth * depth_camera.back_project(u + du, v + dv, z);
            color_camera.project(&p).map(|q| (p, q))
        };
        let (Some((centre, _)), Some((_, q0)), Some((_, q1))) =
            (to_color(0.0, 0.0), to_color(-0.5, -0.5), to_color(0.5, 0.5))
        else {
            continue;
        };
        let depth_m = centre.z as f32;
        let Some((x0, x1)) = covered(q0.x, q1.x, cw) else {
            continue;
        };
        let Some((y0, y1)) = covered(q0.y, q1.y, ch) else {
            continue;
        };
        for y in y0..=y1 {
            let row = (y * cw) as usize;
            for x in x0..=x1 {
                let cell = &mut out[row + x as usize];
                if depth_m < *cell {
                    *cell = depth_m;
                }
            }
        }
    }
    out.iter_mut()
        .filter(|d| d.is_infinite())
        .for_each(|d| *d = f32::NAN);
    out
}

/// The pixels (inclusive, clipped to `0..size`) whose centres lie in `[min(a, b), max(a, b))`,
/// or the one nearest the footprint's middle when none does; `None` when outside the image.
fn covered(a: f64, b: f64, size: i64) -> Option<(i64, i64)> {
    let (lo, hi) = (a.min(b), a.max(b));
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    let (mut first, mut last) = (lo.ceil() as i64, hi.ceil() as i64 - 1);
    if last < first {
        let nearest = (0.5 * (lo + hi)).round() as i64;
        (first, last) = (nearest, nearest);
    }
    let (first, last) = (first.max(0), last.min(size - 1));
    (first <= last).then_some((first, last))
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::nalgebra::{Translation3, UnitQuaternion};

    fn camera() -> PinholeCamera {
        PinholeCamera::new(40, 30, 30.0, 30.0, 19.5, 14.5).unwrap()
    }

    #[test]
    fn identity_extrinsics_give_the_depth_back() {
        let raw: Vec<u16> = (0..1200).map(|i| 800 + (i % 7) as u16).collect();
        let mut raw_holes = raw.clone();
        raw_holes[5] = 0;
        let out = register_depth(
            &raw_holes,
            0.001,
            &camera(),
            &camera(),
            &Isometry3::identity(),
        );
        for (i, (&r, &d)) in raw_holes.iter().zip(&out).enumerate() {
            if r == 0 {
                assert!(d.is_nan(), "pixel {i} has no reading");
            } else {
                assert!((d - f32::from(r) * 0.001).abs() < 1e-6, "pixel {i}: {d}");
            }
        }
    }

    #[test]
    fn a_baseline_shifts_a_plane_by_f_b_over_z() {
        // A fronto-parallel plane at 1 m; the colour camera 40 mm to the depth camera's right
        // (x): points move 30 px · 0.04 m / 1 m = 1.2 px left in the colour image, so colour
        // pixel x takes depth pixel x + 1.
        let raw = vec![1000u16; 1200];
        let color_from_depth = Isometry3::from_parts(
            Translation3::new(-0.04, 0.0, 0.0),
            UnitQuaternion::identity(),
        );
        let out = register_depth(&raw, 0.001, &camera(), &camera(), &color_from_depth);
        // The rightmost column is beyond the depth camera's view (holes), the rest is 1 m.
        for y in 0..30 {
            for x in 0..39 {
                assert_eq!(out[y * 40 + x], 1.0, "({x}, {y})");
            }
            assert!(out[y * 40 + 39].is_nan());
        }
    }

    #[test]
    fn the_nearest_depth_wins() {
        // Left half at 0.5 m in front of a 2 m background, colour camera 0.1 m to the left: the
        // foreground's footprint shifts farther than the background's, overlapping it.
        let mut raw = vec![2000u16; 1200];
        for y in 0..30 {
            for x in 0..20 {
                raw[y * 40 + x] = 500;
            }
        }
        let color_from_depth =
            Isometry3::from_parts(Translation3::new(0.1, 0.0, 0.0), UnitQuaternion::identity());
        let out = register_depth(&raw, 0.001, &camera(), &camera(), &color_from_depth);
        // Foreground moves 6 px right, background 1.5 px: columns 20..26 are foreground.
        let row = &out[15 * 40..16 * 40];
        assert_eq!(row[24], 0.5, "{row:?}");
        assert_eq!(row[30], 2.0, "{row:?}");
        assert!(
            row[0].is_nan() && row[5].is_nan(),
            "left edge unseen: {row:?}"
        );
    }
}
