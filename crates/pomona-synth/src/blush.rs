//! A blush: the sun-facing side of a fruit coloured differently from the rest (a red cheek on
//! a green or yellow apple, a ripening pepper). The ground colour is the fruit's material; the
//! blush colour takes over smoothly on the side its direction points to.

use nalgebra::{Unit, Vector3};

/// A coloured cheek on one side of a fruit body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blush {
    /// Centre direction of the cheek, scene frame.
    pub towards: Unit<Vector3<f64>>,
    /// Albedo of the cheek (linear RGB).
    pub albedo: [f64; 3],
    /// Cosine (of the angle from `towards`) at which the cheek has faded out; in `[-1, 1)`.
    pub fade_cos: f64,
}

impl Blush {
    /// Weight in `[0, 1]` of the blush colour at unit direction `from_center` (fruit centre to
    /// the surface point).
    pub fn weight(&self, from_center: &Vector3<f64>) -> f64 {
        let c = from_center.dot(&self.towards);
        let t = ((c - self.fade_cos) / (1.0 - self.fade_cos).max(1e-6)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    }

    /// `ground` albedo blended towards the blush at `from_center`.
    pub fn albedo_at(&self, ground: &[f64; 3], from_center: &Vector3<f64>) -> [f64; 3] {
        let w = self.weight(from_center);
        std::array::from_fn(|c| ground[c] * (1.0 - w) + self.albedo[c] * w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blush_covers_its_side_only() {
        let b = Blush {
            towards: Vector3::x_axis(),
            albedo: [0.5, 0.0, 0.0],
            fade_cos: 0.0,
        };
        assert_eq!(
            b.albedo_at(&[0.0, 0.4, 0.0], &Vector3::x()),
            [0.5, 0.0, 0.0]
        );
        assert_eq!(
            b.albedo_at(&[0.0, 0.4, 0.0], &-Vector3::x()),
            [0.0, 0.4, 0.0]
        );
    }
}
