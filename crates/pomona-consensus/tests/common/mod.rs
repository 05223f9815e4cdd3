//! Synthetic partial shapes for tests and benches: what a depth camera at the origin sees.
#![allow(dead_code, missing_docs, clippy::unwrap_used)]

use pomona_consensus::nalgebra::{Point3, Unit, Vector3};
use pomona_consensus::OrientedPoint;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// Standard normal by Box–Muller.
pub fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = rng.gen_range(f64::EPSILON..1.0);
    let u2: f64 = rng.gen_range(0.0..1.0);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

fn frame(axis: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if axis.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = axis.cross(&helper).normalize();
    (u, axis.cross(&u))
}

/// `n` points of the camera-facing cap of a sphere covering `fraction` of its area, with isotropic
/// Gaussian noise `sigma_m`; normals are the exact outward (camera-facing) ones.
pub fn sphere_cap(
    center: Point3<f64>,
    radius_m: f64,
    fraction: f64,
    n: usize,
    sigma_m: f64,
    rng: &mut ChaCha8Rng,
) -> Vec<OrientedPoint> {
    let towards_camera = -center.coords.normalize();
    let (u, v) = frame(&towards_camera);
    let min_cos = 1.0 - 2.0 * fraction;
    (0..n)
        .map(|_| {
            // Uniform on the cap: cos θ uniform in [min_cos, 1].
            let c: f64 = rng.gen_range(min_cos..1.0);
            let s = (1.0 - c * c).sqrt();
            let phi: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
            let dir = towards_camera * c + u * (s * phi.cos()) + v * (s * phi.sin());
            let noise = Vector3::new(gauss(rng), gauss(rng), gauss(rng)) * sigma_m;
            OrientedPoint::new(center + dir * radius_m + noise, dir)
        })
        .collect()
}

/// `n` points of the camera-facing half of a finite cylinder with noise; exact radial normals.
pub fn cylinder_half(
    center: Point3<f64>,
    axis: Unit<Vector3<f64>>,
    radius_m: f64,
    length_m: f64,
    n: usize,
    sigma_m: f64,
    rng: &mut ChaCha8Rng,
) -> Vec<OrientedPoint> {
    let a = axis.into_inner();
    let to_cam = -center.coords;
    // u: radial direction facing the camera; v completes the frame.
    let u = (to_cam - a * a.dot(&to_cam)).normalize();
    let v = a.cross(&u);
    (0..n)
        .map(|_| {
            let phi: f64 = rng.gen_range(-std::f64::consts::FRAC_PI_2..std::f64::consts::FRAC_PI_2);
            let s: f64 = rng.gen_range(-0.5..0.5) * length_m;
            let radial = u * phi.cos() + v * phi.sin();
            let noise = Vector3::new(gauss(rng), gauss(rng), gauss(rng)) * sigma_m;
            OrientedPoint::new(center + a * s + radial * radius_m + noise, radial)
        })
        .collect()
}

/// `n` points uniform in the axis-aligned box `center ± half_m`, without normals.
pub fn box_outliers(
    center: Point3<f64>,
    half_m: f64,
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<OrientedPoint> {
    (0..n)
        .map(|_| {
            let d = Vector3::new(
                rng.gen_range(-half_m..half_m),
                rng.gen_range(-half_m..half_m),
                rng.gen_range(-half_m..half_m),
            );
            OrientedPoint::without_normal(center + d)
        })
        .collect()
}

pub fn angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.normalize()
        .dot(&b.normalize())
        .abs()
        .clamp(0.0, 1.0)
        .acos()
        .to_degrees()
}

/// An organised `w × h` cloud of a sphere seen by a pinhole camera at the origin (focal `f_px`,
/// principal point at the image centre); pixels missing the sphere are NaN.
pub fn organised_sphere(
    w: u32,
    h: u32,
    f_px: f64,
    center: Point3<f64>,
    radius_m: f64,
) -> pomona_core::PointCloud {
    let mut pts = Vec::with_capacity((w * h) as usize);
    for v in 0..h {
        for u in 0..w {
            let d = Vector3::new(
                (u as f64 - w as f64 / 2.0) / f_px,
                (v as f64 - h as f64 / 2.0) / f_px,
                1.0,
            )
            .normalize();
            let b = d.dot(&center.coords);
            let disc = b * b - (center.coords.norm_squared() - radius_m * radius_m);
            if disc > 0.0 {
                pts.push(Point3::from(d * (b - disc.sqrt())).cast::<f32>());
            } else {
                pts.push(Point3::new(f32::NAN, f32::NAN, f32::NAN));
            }
        }
    }
    pomona_core::PointCloud::organized(w, h, pts).unwrap()
}
