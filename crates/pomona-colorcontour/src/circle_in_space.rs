//! A fruit circle in the image lifted to 3D with the depth inside it (seed 004 gets 3D from a
//! stereo pair, §4; with an RGB-D frame we read depth directly).
//!
//! A sphere of radius R whose centre is at depth Z images as a circle of radius ≈ f R / Z. Each
//! fruit pixel at a fraction ρ of the circle's radius from its centre sees the surface
//! R (1 − √(1 − ρ²)) behind the front point, so subtracting that gives one estimate of the front
//! point's depth per pixel; their median is the surface point on the central ray, and the centre
//! lies R further along the ray. R comes from the pixel radius at the estimated depth (two rounds).

use pomona_core::nalgebra::{Point2, Point3};
use pomona_core::{PinholeCamera, RgbdFrame};

/// A circle's 3D centre and radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereFromCircle {
    /// Fruit centre in the camera frame, metres.
    pub center_m: Point3<f64>,
    /// Fruit radius, metres.
    pub radius_m: f64,
}

fn median(values: &mut [f64]) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mid = values.len() / 2;
    let (_, m, _) = values.select_nth_unstable_by(mid, f64::total_cmp);
    Some(*m)
}

/// The sphere behind the circle `(center_px, radius_px)` from the depth of the fruit pixels
/// (`fruit[i]`) within `core_fraction` of the radius; `None` when none has depth. At most about
/// 400 pixels are read (a regular grid) so large circles cost no more than small ones.
pub fn sphere_from_depth(
    frame: &RgbdFrame,
    fruit: &[bool],
    center_px: Point2<f64>,
    radius_px: f64,
    core_fraction: f64,
) -> Option<SphereFromCircle> {
    let camera = frame.camera();
    let depth = frame.depth();
    let reach = radius_px * core_fraction;
    let step = (reach / 10.0).max(1.0);
    let mut samples: Vec<(f64, f64)> = Vec::new(); // (ρ, depth)
    let steps = (reach / step).ceil() as i64;
    for j in -steps..=steps {
        for i in -steps..=steps {
            let p = center_px + pomona_core::nalgebra::Vector2::new(i as f64, j as f64) * step;
            let rho = (p - center_px).norm() / radius_px;
            if rho > core_fraction {
                continue;
            }
            let Some((u, v)) = camera.pixel_of(&p) else {
                continue;
            };
            let k = v as usize * camera.width as usize + u as usize;
            if !fruit.get(k).copied().unwrap_or(false) {
                continue;
            }
            if let Some(z) = depth.get(u, v).filter(|z| z.is_finite() && *z > 0.0) {
                samples.push((rho, f64::from(z)));
            }
        }
    }
    let mut z_raw: Vec<f64> = samples.iter().map(|s| s.1).collect();
    let mut radius_m = radius_px * median(&mut z_raw)? / camera.mean_focal_px();
    let mut front = 0.0;
    for _ in 0..2 {
        let mut fronts: Vec<f64> = samples
            .iter()
            .map(|&(rho, z)| z - radius_m * (1.0 - (1.0 - rho * rho).max(0.0).sqrt()))
            .collect();
        front = median(&mut fronts)?;
        radius_m = radius_px * (front + radius_m) / camera.mean_focal_px();
    }
    Some(SphereFromCircle {
        center_m: along_ray(camera, center_px, front, radius_m),
        radius_m,
    })
}

/// The sphere of radius `radius_m` whose image is the circle, without depth: its centre is at
/// depth f R / r.
pub fn sphere_from_size(
    camera: &PinholeCamera,
    center_px: Point2<f64>,
    radius_px: f64,
    radius_m: f64,
) -> SphereFromCircle {
    let z = camera.mean_focal_px() * radius_m / radius_px.max(1e-9);
    SphereFromCircle {
        center_m: camera.back_project(center_px.x, center_px.y, z),
        radius_m,
    }
}

/// The point at depth `front_depth_m` on the ray through `pixel`, moved `radius_m` further along
/// the ray.
fn along_ray(
    camera: &PinholeCamera,
    pixel: Point2<f64>,
    front_depth_m: f64,
    radius_m: f64,
) -> Point3<f64> {
    let surface = camera.back_project(pixel.x, pixel.y, front_depth_m);
    let ray = surface.coords.normalize();
    surface + ray * radius_m
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_core::DepthImage;

    #[test]
    fn a_rendered_sphere_gives_back_its_centre_and_radius() {
        let (w, h) = (200u32, 160u32);
        let camera = PinholeCamera::new(w, h, 300.0, 300.0, 99.5, 79.5).unwrap();
        let (center, r) = (Point3::new(0.05, -0.02, 0.8), 0.04);
        // Ray-cast the sphere: depth of the first hit per pixel.
        let mut depth = vec![f32::NAN; (w * h) as usize];
        let mut fruit = vec![false; (w * h) as usize];
        for v in 0..h {
            for u in 0..w {
                let d = camera
                    .back_project(f64::from(u), f64::from(v), 1.0)
                    .coords
                    .normalize();
                let b = d.dot(&center.coords);
                let disc = b * b - (center.coords.norm_squared() - r * r);
                if disc >= 0.0 {
                    let t = b - disc.sqrt();
                    let k = (v * w + u) as usize;
                    depth[k] = (t * d.z) as f32;
                    fruit[k] = true;
                }
            }
        }
        let frame =
            RgbdFrame::new(camera, DepthImage::from_meters(w, h, depth).unwrap(), None).unwrap();
        let c_px = camera.project(&center).unwrap();
        let r_px = 300.0 * r / center.z;
        let s = sphere_from_depth(&frame, &fruit, c_px, r_px, 0.8).unwrap();
        assert!((s.center_m - center).norm() < 0.003, "{:?}", s.center_m);
        assert!((s.radius_m - r).abs() < 0.002, "{}", s.radius_m);
        // Without depth, the prior radius places it at f R / r.
        let p = sphere_from_size(&camera, c_px, r_px, r);
        assert!((p.center_m - center).norm() < 0.002, "{:?}", p.center_m);
        assert!(sphere_from_depth(&frame, &vec![false; fruit.len()], c_px, r_px, 0.8).is_none());
    }
}
