//! The share of a circle's disc whose pixels pass a test, sampled on a square grid: the colour
//! purity that scores a detected circle ([`crate::stages`]) and the fruit share that a tracked
//! circle must reach ([`crate::TrackParams::min_fruit_share`]). Sampled rather than counted
//! pixel by pixel, so that the cost does not grow with the circle.

use pomona_core::nalgebra::Point2;

/// Share of the grid points `center + (i, j) · step`, `|i|, |j| ≤ half_steps`, lying in the disc
/// of `radius` around `center` and inside the `width` × `height` image (each point taken at its
/// nearest pixel), whose pixel `(x, y)` `passes`; 0 when no grid point lies in both.
pub(crate) fn disc_share(
    center: Point2<f64>,
    radius: f64,
    (step, half_steps): (f64, i64),
    (width, height): (usize, usize),
    passes: impl Fn(usize, usize) -> bool,
) -> f64 {
    // A grid point's pixel column depends on its column of the grid only, and its row on its
    // row: round each once (`None` outside the image).
    let pixel = |centre: f64, k: i64, size: usize| {
        let v = (centre + k as f64 * step).round();
        (v >= 0.0 && v < size as f64).then_some(v as usize)
    };
    let columns: Vec<Option<usize>> = (-half_steps..=half_steps)
        .map(|i| pixel(center.x, i, width))
        .collect();
    let (mut inside, mut hits) = (0usize, 0usize);
    for j in -half_steps..=half_steps {
        let Some(y) = pixel(center.y, j, height) else {
            continue;
        };
        let dy = j as f64 * step;
        for (i, x) in (-half_steps..=half_steps).zip(&columns) {
            let dx = i as f64 * step;
            let Some(x) = *x else { continue };
            if dx * dx + dy * dy > radius * radius {
                continue;
            }
            inside += 1;
            hits += usize::from(passes(x, y));
        }
    }
    if inside == 0 {
        0.0
    } else {
        hits as f64 / inside as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_the_part_of_the_disc_in_the_image_only() {
        // A disc of radius 10 on a 100 × 100 image whose left half passes.
        let left = |x: usize, _: usize| x < 50;
        let share = |c: Point2<f64>| disc_share(c, 10.0, (1.0, 10), (100, 100), left);
        assert_eq!(share(Point2::new(20.0, 50.0)), 1.0);
        assert_eq!(share(Point2::new(80.0, 50.0)), 0.0);
        // Centred on the boundary column 49.5: the 10 columns x ≤ 49 of 21 pass; by symmetry
        // of the disc about x = 50, a little under half.
        let half = share(Point2::new(50.0, 50.0));
        assert!(half > 0.4 && half < 0.5, "{half}");
        // Centred on the image corner: only the quarter inside counts, and all of it passes.
        assert_eq!(share(Point2::new(0.0, 0.0)), 1.0);
        // Wholly outside: nothing to count.
        assert_eq!(share(Point2::new(-30.0, 50.0)), 0.0);
    }
}
