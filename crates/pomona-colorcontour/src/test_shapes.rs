//! Masks drawn from shape predicates and a circle check, shared by the unit tests of the circle
//! sources ([`crate::ray_circles`], [`crate::hough_circles`]).

use pomona_core::nalgebra::Point2;

use crate::ContourCircle;

/// A row-major `w`×`h` mask, true where `inside(x, y)`.
pub(crate) fn mask_of(w: usize, h: usize, inside: impl Fn(f64, f64) -> bool) -> Vec<bool> {
    (0..w * h)
        .map(|i| inside((i % w) as f64, (i / w) as f64))
        .collect()
}

/// Whether `c` is centred within `tol` pixels of (`x`, `y`) with a radius within `tol` of `r`.
pub(crate) fn near(c: &ContourCircle, x: f64, y: f64, r: f64, tol: f64) -> bool {
    (c.center_px - Point2::new(x, y)).norm() <= tol && (c.radius_px - r).abs() <= tol
}
