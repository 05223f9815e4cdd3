//! A stem: a finite open cylinder between two points. Used for the plants' main stalks and for
//! the short peduncles that carry the fruit.

use nalgebra::{Point3, Vector3};

use crate::Material;

/// A straight cylindrical stem in the scene frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Stem {
    /// One end of the axis, scene frame, metres.
    pub start: Point3<f64>,
    /// The other end.
    pub end: Point3<f64>,
    /// Radius, metres.
    pub radius_m: f64,
    /// Surface appearance.
    pub material: Material,
}

impl Stem {
    /// Nearest intersection with `t > 0` of `origin + t·dir` with the cylinder's side.
    pub fn intersect(&self, origin: &Point3<f64>, dir: &Vector3<f64>) -> Option<f64> {
        let axis = self.end - self.start;
        let len = axis.norm();
        if len <= 0.0 {
            return None;
        }
        let a = axis / len;
        let oc = origin - self.start;
        let d_perp = dir - a * dir.dot(&a);
        let o_perp = oc - a * oc.dot(&a);
        let qa = d_perp.dot(&d_perp);
        if qa < 1e-18 {
            return None;
        }
        let qb = o_perp.dot(&d_perp);
        let qc = o_perp.dot(&o_perp) - self.radius_m * self.radius_m;
        let disc = qb * qb - qa * qc;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        [(-qb - s) / qa, (-qb + s) / qa]
            .into_iter()
            .filter(|t| *t > 1e-9)
            .find(|t| {
                let h = (oc + dir * *t).dot(&a);
                (0.0..=len).contains(&h)
            })
    }

    /// Outward unit normal at a scene-frame point on the side.
    pub fn normal_at(&self, p: &Point3<f64>) -> Vector3<f64> {
        let a = (self.end - self.start).normalize();
        let v = p - self.start;
        let radial = v - a * v.dot(&a);
        let n = radial.norm();
        if n > 0.0 {
            radial / n
        } else {
            a
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertical_stem_is_hit_on_its_front_side() {
        let s = Stem {
            start: Point3::new(0.0, -1.0, 1.0),
            end: Point3::new(0.0, 1.0, 1.0),
            radius_m: 0.01,
            material: Material {
                albedo: [0.3, 0.4, 0.1],
                specular: 0.0,
                shininess: 1.0,
            },
        };
        let t = s
            .intersect(&Point3::origin(), &Vector3::new(0.0, 0.0, 1.0))
            .unwrap();
        assert!((t - 0.99).abs() < 1e-12);
        let n = s.normal_at(&Point3::new(0.0, 0.0, 0.99));
        assert!((n - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-12);
        assert!(s
            .intersect(&Point3::origin(), &Vector3::new(0.0, 2.0, 1.0))
            .is_none());
        assert!(s
            .intersect(&Point3::origin(), &Vector3::new(0.02, 0.0, 1.0))
            .is_none());
    }
}
