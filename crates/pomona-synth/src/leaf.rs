//! A leaf blade: a thin curved patch cut by the outline of its [`LeafFamily`].
//!
//! In the leaf frame x runs along the blade (petiole at `x = -a`, tip at `x = +a`), y across it
//! and z along the normal. The surface is the paraboloid `z = kx·x² + ky·y²` (droop along the
//! blade, cupping or curling across it), cut by the family's outline (the narrow domain's
//! elliptic outline is `|y| <= b·sqrt(1 - s²)·(1 - 0.3·s)` with `s = x / a`). A ray meets a
//! paraboloid in a quadratic, so intersection is exact and cheap.

use nalgebra::{Point3, Rotation3, Vector3};

use crate::{LeafFamily, Material};

/// One leaf in the scene frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Leaf {
    /// Centre of the blade, scene frame, metres.
    pub center: Point3<f64>,
    /// Rotation from the leaf frame to the scene frame.
    pub orientation: Rotation3<f64>,
    /// Half length `a` along the blade, metres.
    pub half_length_m: f64,
    /// Half width `b` across the blade, metres.
    pub half_width_m: f64,
    /// Curvature coefficient along the blade, `kx` (1/m).
    pub bend_along: f64,
    /// Curvature coefficient across the blade, `ky` (1/m).
    pub bend_across: f64,
    /// Surface appearance.
    pub material: Material,
    /// Outline of the blade.
    pub family: LeafFamily,
}

/// Hit record of a leaf: ray parameter and blade coordinates (for the midrib shading).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LeafHit {
    /// Ray parameter.
    pub t: f64,
    /// Position across the blade relative to the half width, in `[-1, 1]`.
    pub across: f64,
}

impl Leaf {
    /// Radius of a sphere about the centre that contains the blade.
    pub fn bounding_radius_m(&self) -> f64 {
        let (a, b) = (self.half_length_m, self.half_width_m);
        let sag = self.bend_along.abs() * a * a + self.bend_across.abs() * b * b;
        (a * a + b * b + sag * sag).sqrt() * 1.01
    }

    /// The eight corners, scene frame, of a leaf-frame box that contains the blade: `|x| <= a`,
    /// `|y| <= 1.05·b` (the widest outline), z between the lowest and highest sag. Its
    /// projection bounds the blade's pixels far more tightly than the bounding sphere's for
    /// narrow or tilted blades.
    pub fn box_corners(&self) -> [Point3<f64>; 8] {
        let (a, b) = (self.half_length_m, 1.05 * self.half_width_m);
        let (sx, sy) = (self.bend_along * a * a, self.bend_across * b * b);
        let z_lo = 0f64.min(sx) + 0f64.min(sy) - 1e-9;
        let z_hi = 0f64.max(sx) + 0f64.max(sy) + 1e-9;
        std::array::from_fn(|i| {
            let x = if i & 1 == 0 { -a } else { a };
            let y = if i & 2 == 0 { -b } else { b };
            let z = if i & 4 == 0 { z_lo } else { z_hi };
            self.center + self.orientation * Vector3::new(x, y, z)
        })
    }

    /// Nearest intersection with `t > 0` of `origin + t·dir` (`dir` need not be unit length).
    pub fn intersect(&self, origin: &Point3<f64>, dir: &Vector3<f64>) -> Option<LeafHit> {
        let inv = self.orientation.inverse();
        let o = inv * (origin - self.center);
        let d = inv * dir;
        let (kx, ky) = (self.bend_along, self.bend_across);
        let qa = kx * d.x * d.x + ky * d.y * d.y;
        let qb = 2.0 * (kx * o.x * d.x + ky * o.y * d.y) - d.z;
        let qc = kx * o.x * o.x + ky * o.y * o.y - o.z;
        let mut roots = [f64::NAN; 2];
        if qa.abs() < 1e-12 {
            if qb.abs() < 1e-15 {
                return None;
            }
            roots[0] = -qc / qb;
        } else {
            let disc = qb * qb - 4.0 * qa * qc;
            if disc < 0.0 {
                return None;
            }
            let s = disc.sqrt();
            // Numerically stable pair of roots.
            let q = -0.5 * (qb + qb.signum() * s);
            let (r1, r2) = if q != 0.0 {
                (q / qa, qc / q)
            } else {
                (0.0, 0.0)
            };
            roots = [r1.min(r2), r1.max(r2)];
        }
        roots.into_iter().filter(|t| *t > 1e-9).find_map(|t| {
            let p = o + d * t;
            self.across_at(p.x, p.y).map(|across| LeafHit { t, across })
        })
    }

    /// Nine points spread over the blade (centre, towards both tips, both margins and the four
    /// quarters), scene frame. The sampler uses them to keep leaves from cutting through fruit.
    pub fn probe_points(&self) -> [Point3<f64>; 9] {
        let (a, b) = (self.half_length_m, self.half_width_m);
        let st = [
            (0.0, 0.0),
            (0.9, 0.0),
            (-0.9, 0.0),
            (0.0, 0.8),
            (0.0, -0.8),
            (0.5, 0.5),
            (0.5, -0.5),
            (-0.5, 0.5),
            (-0.5, -0.5),
        ];
        st.map(|(s, w)| {
            let (x, y) = (s * a, w * b);
            let z = self.bend_along * x * x + self.bend_across * y * y;
            self.center + self.orientation * Vector3::new(x, y, z)
        })
    }

    /// Relative across-blade position if `(x, y)` lies inside the outline.
    fn across_at(&self, x: f64, y: f64) -> Option<f64> {
        self.family
            .across_at(x, y, self.half_length_m, self.half_width_m)
    }

    /// Unit normal at a scene-frame point of the blade, on the leaf frame's +z side.
    pub fn normal_at(&self, p: &Point3<f64>) -> Vector3<f64> {
        let q = self.orientation.inverse() * (p - self.center);
        let n = Vector3::new(
            -2.0 * self.bend_along * q.x,
            -2.0 * self.bend_across * q.y,
            1.0,
        );
        (self.orientation * n).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn leaf(bend: f64) -> Leaf {
        Leaf {
            center: Point3::new(0.0, 0.0, 0.5),
            // Leaf normal (+z) towards the camera.
            orientation: Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI),
            half_length_m: 0.05,
            half_width_m: 0.02,
            bend_along: bend,
            bend_across: 0.0,
            material: Material {
                albedo: [0.1, 0.4, 0.1],
                specular: 0.1,
                shininess: 10.0,
            },
            family: LeafFamily::Elliptic,
        }
    }

    #[test]
    fn flat_leaf_is_hit_at_its_plane_inside_the_outline_only() {
        let l = leaf(0.0);
        let hit = l
            .intersect(&Point3::origin(), &Vector3::new(0.0, 0.0, 1.0))
            .unwrap();
        assert!((hit.t - 0.5).abs() < 1e-12 && hit.across.abs() < 1e-12);
        // 6 cm off to the side at z = 0.5: outside the blade.
        assert!(l
            .intersect(&Point3::origin(), &Vector3::new(0.12, 0.0, 1.0))
            .is_none());
        assert!(l.normal_at(&Point3::new(0.0, 0.0, 0.5)).z < -0.99);
    }

    #[test]
    fn bent_leaf_hit_lies_on_the_paraboloid() {
        let l = leaf(6.0);
        let d = Vector3::new(0.06, 0.01, 1.0);
        let hit = l.intersect(&Point3::origin(), &d).unwrap();
        let q = l.orientation.inverse() * (Point3::origin() + d * hit.t - l.center);
        assert!((q.z - 6.0 * q.x * q.x).abs() < 1e-12);
        assert!(l.bounding_radius_m() >= (q.norm() - 1e-12));
    }

    /// Whether the ray through the leaf-frame point `(x, y)` of a flat leaf hits the blade.
    fn hits_at(family: LeafFamily, x: f64, y: f64) -> bool {
        let mut l = leaf(0.0);
        l.family = family;
        l.half_width_m = 0.05 * family.width_ratio_range().1;
        let p = l.center + l.orientation * Vector3::new(x, y, 0.0);
        l.intersect(&Point3::origin(), &(p - Point3::origin()))
            .is_some()
    }

    #[test]
    fn every_family_is_hit_on_its_blade_and_missed_in_its_notches() {
        let a = 0.05;
        // Elliptic: centre hits, beyond the tip misses.
        assert!(hits_at(LeafFamily::Elliptic, 0.0, 0.01));
        assert!(!hits_at(LeafFamily::Elliptic, 0.0, 0.03));
        // Lanceolate: widest below the middle, pointed: near the tip a narrow strip only.
        let b = 0.05 * LeafFamily::Lanceolate.width_ratio_range().1;
        assert!(hits_at(LeafFamily::Lanceolate, -0.5 * a, 0.9 * b));
        assert!(!hits_at(LeafFamily::Lanceolate, 0.8 * a, 0.3 * b));
        // Lobed: inside the tip lobe and a side lobe; the notch between them misses.
        assert!(hits_at(LeafFamily::Lobed, 0.85 * a, 0.0));
        let side = 72f64.to_radians();
        assert!(hits_at(
            LeafFamily::Lobed,
            0.8 * a * side.cos(),
            0.8 * a * side.sin()
        ));
        let notch = 36f64.to_radians();
        assert!(!hits_at(
            LeafFamily::Lobed,
            0.7 * a * notch.cos(),
            0.7 * a * notch.sin()
        ));
        assert!(!hits_at(LeafFamily::Lobed, -0.7 * a, 0.0), "petiole notch");
        // Compound: inside a lateral leaflet and on the rachis; between leaflets misses.
        let b = 0.05 * LeafFamily::Compound.width_ratio_range().1;
        assert!(hits_at(LeafFamily::Compound, -0.55 * a, 0.5 * b));
        assert!(hits_at(LeafFamily::Compound, -0.05 * a, -0.6 * b));
        assert!(hits_at(LeafFamily::Compound, -0.3 * a, 0.0));
        assert!(hits_at(LeafFamily::Compound, 0.8 * a, 0.1 * b));
        assert!(!hits_at(LeafFamily::Compound, -0.3 * a, 0.5 * b));
        assert!(!hits_at(LeafFamily::Compound, 0.3 * a, -0.6 * b));
    }
}
