//! The background behind the crop row: a large plane with a procedural texture.
//!
//! The narrow domain uses [`BackdropKind::Foliage`] only: dark, out of focus foliage and soil that
//! gives every pixel a depth reading and keeps the colour histogram realistic (mostly dark green)
//! without modelling the next row. The wide domain also draws bare soil, black ground cloth
//! (dark in the infrared, so a depth camera gets no return from it), white greenhouse plastic, and
//! open sky (no surface at all: bright colour, no depth).

use nalgebra::{Point3, Unit, Vector3};

use crate::rng::mix64;
use crate::Material;

/// An infinite textured plane.
#[derive(Debug, Clone, PartialEq)]
pub struct Backdrop {
    /// A point on the plane, scene frame, metres.
    pub point: Point3<f64>,
    /// Unit normal, facing the camera.
    pub normal: Unit<Vector3<f64>>,
    /// Seed of the texture.
    pub texture_seed: u64,
    /// What the plane is made of.
    pub kind: BackdropKind,
}

/// The surface of a [`Backdrop`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BackdropKind {
    /// Dark out-of-focus foliage with patches of soil (the narrow domain's backdrop).
    Foliage,
    /// Bare brown soil with pebbles.
    Soil,
    /// Black woven ground cloth: near-black and dark in the infrared, so it returns no depth.
    Cloth,
    /// White greenhouse plastic film with folds.
    Plastic,
    /// Open sky: no surface (no depth); pixels that hit nothing get this linear radiance at
    /// the horizon, fading to `zenith` (linear RGB) towards `up`.
    Sky {
        /// Linear RGB radiance near the horizon.
        horizon: [f64; 3],
        /// Linear RGB radiance high up.
        zenith: [f64; 3],
        /// The world's up direction in the scene frame (tilted with the camera).
        up: Unit<Vector3<f64>>,
    },
}

impl Backdrop {
    /// Ray parameter `t > 0` where `origin + t·dir` meets the plane.
    pub fn intersect(&self, origin: &Point3<f64>, dir: &Vector3<f64>) -> Option<f64> {
        if matches!(self.kind, BackdropKind::Sky { .. }) {
            return None;
        }
        let denom = self.normal.dot(dir);
        if denom.abs() < 1e-12 {
            return None;
        }
        let t = self.normal.dot(&(self.point - origin)) / denom;
        (t > 1e-9).then_some(t)
    }

    /// Whether a depth camera gets a return from this surface (black cloth absorbs the
    /// infrared; the sky has no surface).
    pub fn returns_depth(&self) -> bool {
        matches!(
            self.kind,
            BackdropKind::Foliage | BackdropKind::Soil | BackdropKind::Plastic
        )
    }

    /// Radiance of a sky pixel whose (unnormalised, scene-frame) ray direction is `dir`, or
    /// `None` when the backdrop is not sky.
    pub fn sky_radiance(&self, dir: &Vector3<f64>) -> Option<[f64; 3]> {
        let BackdropKind::Sky {
            horizon,
            zenith,
            up,
        } = self.kind
        else {
            return None;
        };
        // Elevation of the ray: 0 at the horizon, 1 straight up.
        let e = (dir.normalize().dot(&up)).clamp(0.0, 1.0).sqrt();
        Some(std::array::from_fn(|c| {
            horizon[c] * (1.0 - e) + zenith[c] * e
        }))
    }

    /// The material at a point of the plane.
    pub fn material_at(&self, p: &Point3<f64>) -> Material {
        // Two in-plane coordinates (any orthonormal pair will do).
        let n = self.normal.as_ref();
        let e1 = n.cross(&Vector3::y()).normalize();
        let e2 = n.cross(&e1);
        let v = p - self.point;
        let (x, y) = (v.dot(&e1), v.dot(&e2));
        match self.kind {
            BackdropKind::Foliage => self.foliage_at(x, y),
            BackdropKind::Soil => {
                let coarse = value_noise(x / 0.08, y / 0.08, self.texture_seed);
                let fine = value_noise(x / 0.008, y / 0.008, self.texture_seed ^ 0x5A5A);
                let pebble = smooth(
                    0.72,
                    0.78,
                    value_noise(x / 0.02, y / 0.02, !self.texture_seed),
                );
                let g = 0.6 + 0.5 * coarse + 0.25 * fine;
                let dirt = [0.11 * g, 0.075 * g, 0.045 * g];
                let stone = [0.24 * g, 0.22 * g, 0.19 * g];
                Material {
                    albedo: std::array::from_fn(|c| dirt[c] * (1.0 - pebble) + stone[c] * pebble),
                    specular: 0.0,
                    shininess: 1.0,
                }
            }
            BackdropKind::Cloth => {
                // A woven texture: alternating threads 3 mm apart.
                let weave = 0.5 + 0.5 * ((x / 0.003).sin() * (y / 0.003).sin());
                let fine = value_noise(x / 0.05, y / 0.05, self.texture_seed);
                let g = 0.005 + 0.008 * weave + 0.005 * fine;
                Material {
                    albedo: [g, g, 1.1 * g],
                    specular: 0.04,
                    shininess: 6.0,
                }
            }
            BackdropKind::Plastic => {
                let fold = value_noise(x / 0.25, y / 0.05, self.texture_seed);
                let g = 0.55 + 0.3 * fold;
                Material {
                    albedo: [g, g, 0.97 * g],
                    specular: 0.15,
                    shininess: 15.0,
                }
            }
            BackdropKind::Sky { horizon, .. } => Material {
                albedo: horizon.map(|c| c.clamp(0.0, 1.0)),
                specular: 0.0,
                shininess: 1.0,
            },
        }
    }

    /// The narrow domain's texture: a blend of dark foliage and soil by value noise.
    fn foliage_at(&self, x: f64, y: f64) -> Material {
        let coarse = value_noise(x / 0.06, y / 0.06, self.texture_seed);
        let fine = value_noise(x / 0.015, y / 0.015, self.texture_seed ^ 0xA5A5);
        let soil = smooth(0.55, 0.8, coarse);
        let foliage = [0.01 + 0.015 * fine, 0.03 + 0.04 * fine, 0.006 + 0.01 * fine];
        let earth = [0.06 + 0.03 * fine, 0.04 + 0.02 * fine, 0.02 + 0.01 * fine];
        let mut albedo = [0.0; 3];
        for c in 0..3 {
            albedo[c] = foliage[c] * (1.0 - soil) + earth[c] * soil;
        }
        Material {
            albedo,
            specular: 0.0,
            shininess: 1.0,
        }
    }
}

/// Smooth step from 0 at `lo` to 1 at `hi`.
fn smooth(lo: f64, hi: f64, x: f64) -> f64 {
    let t = ((x - lo) / (hi - lo)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Bilinear value noise in `[0, 1]` over an integer lattice hashed with `seed`.
fn value_noise(x: f64, y: f64, seed: u64) -> f64 {
    let (xf, yf) = (x.floor(), y.floor());
    let (ix, iy) = (xf as i64, yf as i64);
    let (fx, fy) = (x - xf, y - yf);
    let (sx, sy) = (fx * fx * (3.0 - 2.0 * fx), fy * fy * (3.0 - 2.0 * fy));
    let h = |i: i64, j: i64| {
        let k = mix64(seed ^ mix64((i as u64).wrapping_mul(0x9E37) ^ (j as u64).rotate_left(32)));
        (k >> 11) as f64 / (1u64 << 53) as f64
    };
    let top = h(ix, iy) * (1.0 - sx) + h(ix + 1, iy) * sx;
    let bottom = h(ix, iy + 1) * (1.0 - sx) + h(ix + 1, iy + 1) * sx;
    top * (1.0 - sy) + bottom * sy
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_hit_and_texture_are_deterministic() {
        let b = Backdrop {
            point: Point3::new(0.0, 0.0, 1.5),
            normal: Unit::new_normalize(Vector3::new(0.0, 0.0, -1.0)),
            texture_seed: 5,
            kind: BackdropKind::Foliage,
        };
        let t = b
            .intersect(&Point3::origin(), &Vector3::new(0.1, 0.2, 1.0))
            .unwrap();
        assert!((t - 1.5).abs() < 1e-12);
        let p = Point3::new(0.15, 0.3, 1.5);
        assert_eq!(b.material_at(&p), b.material_at(&p));
        for c in b.material_at(&p).albedo {
            assert!((0.0..=1.0).contains(&c));
        }
        let v = value_noise(3.3, -7.1, 9);
        assert!((0.0..=1.0).contains(&v));
        let sky = Backdrop {
            kind: BackdropKind::Sky {
                horizon: [0.8, 0.85, 0.9],
                zenith: [0.3, 0.5, 0.9],
                up: -Vector3::y_axis(),
            },
            ..b.clone()
        };
        assert!(sky.intersect(&Point3::origin(), &Vector3::z()).is_none());
        assert!(!sky.returns_depth() && b.returns_depth());
        let cloth = Backdrop {
            kind: BackdropKind::Cloth,
            ..b
        };
        assert!(!cloth.returns_depth());
        assert!(cloth.material_at(&p).luminance() < 0.04);
    }
}
