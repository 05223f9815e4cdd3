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

/// A row-major `w`×`h` mask of the union of `discs` (centre x, centre y, radius).
pub(crate) fn mask_of_discs(w: usize, h: usize, discs: &[(f64, f64, f64)]) -> Vec<bool> {
    mask_of(w, h, |x, y| {
        discs.iter().any(|&(cx, cy, r)| (x - cx).hypot(y - cy) <= r)
    })
}

/// Panics unless every disc has a circle [`near`] it within `tol`.
pub(crate) fn assert_each_disc_found(
    circles: &[ContourCircle],
    discs: &[(f64, f64, f64)],
    tol: f64,
) {
    for &(x, y, r) in discs {
        assert!(
            circles.iter().any(|c| near(c, x, y, r, tol)),
            "disc at ({x}, {y}) r {r}: {circles:?}"
        );
    }
}
