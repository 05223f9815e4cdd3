//! The implicit surface of a fruit body, in the body's own frame.
//!
//! One family covers every kind: a solid of revolution about the body z axis (the symmetry axis,
//! pointing to the stem end) whose meridian is a superellipse, optionally tapered along the axis
//! and modulated by `n` lobes around it:
//!
//! ```text
//! t = z / h                                   (-1 at the blossom end, +1 at the stem end)
//! R(t, φ) = R0 · (1 - |t|^p)^(1/p) · (1 + taper·t) · (1 + a·cos(nφ))
//! F(x, y, z) = sqrt(x² + y²) - R(t, φ)        (negative inside)
//! ```
//!
//! `p = 2` gives an ellipsoid (oranges, apples, guava, eggplant); `p = 3` or `4` with 3–4 lobes
//! gives the blocky, lobed bell pepper. The lobes are symmetric under reflection through every plane
//! that contains the axis and a lobe crest, so the truth `axis` lies in the symmetry planes.
//! `F` is not a distance, but near the surface it changes at about 1 m per metre moved radially,
//! which is all the ray marcher and the tests need.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Shape parameters of one fruit body (metres, in the body frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FruitShape {
    /// Base equatorial radius `R0`, metres.
    pub radius_m: f64,
    /// Half the length along the symmetry axis, `h`, metres.
    pub half_length_m: f64,
    /// Superellipse exponent `p` of the meridian (2 = ellipse; larger = blockier).
    pub profile_exponent: f64,
    /// Linear radius change along the axis: `> 0` wider at the stem end, `< 0` narrower.
    pub taper: f64,
    /// Number of lobes around the axis (0 for none).
    pub lobes: u32,
    /// Relative lobe amplitude `a`.
    pub lobe_depth: f64,
}

impl FruitShape {
    /// A sphere of the given radius.
    pub fn sphere(radius_m: f64) -> Self {
        Self {
            radius_m,
            half_length_m: radius_m,
            profile_exponent: 2.0,
            taper: 0.0,
            lobes: 0,
            lobe_depth: 0.0,
        }
    }

    /// The same proportions scaled across the axis so the largest width is `width_m`
    /// (the length along the axis is kept).
    pub fn with_width(mut self, width_m: f64) -> Self {
        let (_, d) = self.extents();
        if d > 0.0 {
            self.radius_m *= width_m / d;
        }
        self
    }

    /// The implicit function `F` at a body-frame point: negative inside, zero on the surface.
    pub fn implicit(&self, p: &Vector3<f64>) -> f64 {
        let h = self.half_length_m;
        let rho = (p.x * p.x + p.y * p.y).sqrt();
        let t = p.z / h;
        let at = t.abs();
        if at >= 1.0 {
            return rho + (at - 1.0) * h;
        }
        let mut r = self.radius_m * self.meridian(at) * (1.0 + self.taper * t);
        if self.lobes > 0 && rho > 1e-12 {
            r *= 1.0 + self.lobe_depth * cos_n_phi(p.x / rho, self.lobes);
        }
        rho - r
    }

    /// The surface radius at axial position `t ∈ [-1, 1]` and azimuth `φ`.
    pub fn surface_radius(&self, t: f64, phi: f64) -> f64 {
        if t.abs() >= 1.0 {
            return 0.0;
        }
        let lobe = if self.lobes > 0 {
            1.0 + self.lobe_depth * (self.lobes as f64 * phi).cos()
        } else {
            1.0
        };
        self.radius_m * self.meridian(t.abs()) * (1.0 + self.taper * t) * lobe
    }

    /// `(1 - |t|^p)^(1/p)`; the exponents the catalogue uses (2, 3, 4) avoid `powf`, which
    /// would otherwise dominate rendering time.
    fn meridian(&self, at: f64) -> f64 {
        let p = self.profile_exponent;
        if p == 2.0 {
            (1.0 - at * at).sqrt()
        } else if p == 3.0 {
            (1.0 - at * at * at).max(0.0).cbrt()
        } else if p == 4.0 {
            let a2 = at * at;
            (1.0 - a2 * a2).max(0.0).sqrt().sqrt()
        } else {
            (1.0 - at.powf(p)).max(0.0).powf(1.0 / p)
        }
    }

    /// `(max radius, largest diameter)` found by sampling the surface densely: the diameter is the
    /// largest width through the axis, `max over t, φ of R(t, φ) + R(t, φ + π)`.
    pub fn extents(&self) -> (f64, f64) {
        let mut max_r: f64 = 0.0;
        let mut max_d: f64 = 0.0;
        // Lobe crests and valleys lie at multiples of π/n; 120 azimuths hit them for n <= 6.
        for i in 0..=200 {
            let t = -1.0 + 2.0 * i as f64 / 200.0;
            for j in 0..120 {
                let phi = std::f64::consts::PI * j as f64 / 120.0;
                let a = self.surface_radius(t, phi);
                let b = self.surface_radius(t, phi + std::f64::consts::PI);
                max_r = max_r.max(a).max(b);
                max_d = max_d.max(a + b);
            }
        }
        (max_r, max_d)
    }
}

/// `cos(nφ)` from `cos φ` by the Chebyshev recurrence `T(k+1) = 2c·T(k) - T(k-1)` (no trig).
fn cos_n_phi(c: f64, n: u32) -> f64 {
    let (mut prev, mut cur) = (1.0, c);
    for _ in 1..n {
        let next = 2.0 * c * cur - prev;
        prev = cur;
        cur = next;
    }
    if n == 0 {
        1.0
    } else {
        cur
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chebyshev_matches_trig() {
        for n in 0..6 {
            for k in 0..20 {
                let phi = k as f64 * 0.3;
                assert!((cos_n_phi(phi.cos(), n) - (n as f64 * phi).cos()).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn sphere_implicit_is_radial_distance() {
        let s = FruitShape::sphere(0.04);
        assert!(s.implicit(&Vector3::new(0.04, 0.0, 0.0)).abs() < 1e-12);
        assert!(s.implicit(&Vector3::zeros()) < 0.0);
        assert!(s.implicit(&Vector3::new(0.0, 0.0, 0.05)) > 0.0);
        let (r, d) = s.extents();
        assert!((r - 0.04).abs() < 1e-9 && (d - 0.08).abs() < 1e-9);
    }

    #[test]
    fn fast_meridians_match_the_general_formula() {
        for p in [2.0, 3.0, 4.0] {
            let fast = FruitShape {
                profile_exponent: p,
                ..FruitShape::sphere(1.0)
            };
            for i in 0..=100 {
                let at = i as f64 / 100.0;
                let general = (1.0 - at.powf(p)).max(0.0).powf(1.0 / p);
                assert!((fast.meridian(at) - general).abs() < 1e-12, "p {p} t {at}");
            }
        }
    }

    #[test]
    fn lobes_make_the_pepper_wider_at_crests() {
        let s = FruitShape {
            radius_m: 0.04,
            half_length_m: 0.05,
            profile_exponent: 3.0,
            taper: 0.1,
            lobes: 4,
            lobe_depth: 0.1,
        };
        assert!(s.surface_radius(0.0, 0.0) > s.surface_radius(0.0, std::f64::consts::FRAC_PI_4));
        // A point on the crest surface has F = 0.
        let r = s.surface_radius(0.2, 0.0);
        assert!(s.implicit(&Vector3::new(r, 0.0, 0.2 * 0.05)).abs() < 1e-12);
    }
}
