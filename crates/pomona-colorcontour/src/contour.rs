//! The mask's outlines as closed, ordered, smoothed curves (seed 004 §3.2: "the resulting image is
//! smoothed (5×5 Gaussian convolution), thresholded, and the edges are detected. Pixels on the
//! edges are subsequently sorted to obtain a list of contiguous points. All edges are closed
//! curves, and each closed curve is labeled as a separate object").
//!
//! Here: a separable 5×5 binomial (Gaussian) kernel on the 0/1 mask, a threshold at one half,
//! 8-connected components, and Moore-neighbour border following of each component's outer border
//! (stopping by Jacob's criterion), giving pixel centres in order. Departures, documented: only
//! outer borders are followed (the borders of holes — leaves lying across a fruit — are concave
//! seen from the fruit, and the circle fit drops concave pieces anyway); the ordered points are
//! smoothed by a circular moving average so that pixel staircase steps do not look like
//! curvature.

use pomona_core::nalgebra::Point2;

use crate::mask_runs::Runs;

/// The 5-tap binomial kernel (σ ≈ 1 px), the 1D factor of the 5×5 Gaussian, in sixteenths.
const KERNEL: [u16; 5] = [1, 4, 6, 4, 1];

/// The 5×5 Gaussian of a 0/1 mask thresholded at one half (borders replicate the edge pixel).
///
/// On a 0/1 mask the filter is exact in integers: a row pass gives sixteenths (0–16), the
/// column pass 256ths, and "above one half" is a sum above 128.
pub fn smooth_mask(mask: &[bool], width: usize, height: usize) -> Vec<bool> {
    if width == 0 || height == 0 || mask.len() != width * height {
        return mask.to_vec();
    }
    let clamp = |i: isize, n: usize| i.clamp(0, n as isize - 1) as usize;
    let mut rows = vec![0u16; mask.len()];
    for (row, out) in mask.chunks_exact(width).zip(rows.chunks_exact_mut(width)) {
        let tap = |x: usize, k: usize| KERNEL[k] * u16::from(row[x]);
        // The two pixels at either end replicate the edge; the rest read their window directly.
        for x in (0..width.min(2)).chain(width.saturating_sub(2).max(2)..width) {
            out[x] = (0..5)
                .map(|k| tap(clamp(x as isize + k as isize - 2, width), k))
                .sum();
        }
        if width > 4 {
            for (x, o) in out.iter_mut().enumerate().take(width - 2).skip(2) {
                *o = tap(x - 2, 0) + tap(x - 1, 1) + tap(x, 2) + tap(x + 1, 3) + tap(x + 2, 4);
            }
        }
    }
    let mut out = vec![false; mask.len()];
    for (y, out_row) in out.chunks_exact_mut(width).enumerate() {
        let near: [&[u16]; 5] = std::array::from_fn(|k| {
            let yy = clamp(y as isize + k as isize - 2, height);
            &rows[yy * width..(yy + 1) * width]
        });
        for (x, o) in out_row.iter_mut().enumerate() {
            let s = near[0][x] + 4 * near[1][x] + 6 * near[2][x] + 4 * near[3][x] + near[4][x];
            *o = s > 128;
        }
    }
    out
}

/// The eight neighbour offsets, clockwise on screen (y down), starting east.
const NEIGHBOURS: [(isize, isize); 8] = [
    (1, 0),
    (1, 1),
    (0, 1),
    (-1, 1),
    (-1, 0),
    (-1, -1),
    (0, -1),
    (1, -1),
];

fn direction_of(dx: isize, dy: isize) -> usize {
    NEIGHBOURS.iter().position(|&d| d == (dx, dy)).unwrap_or(0)
}

/// One closed outline: pixel centres in order (the last joins the first), and the number of
/// pixels of the component it bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct Contour {
    /// Border pixel centres, in order around the component.
    pub points: Vec<Point2<f64>>,
    /// Pixels in the component.
    pub area_px: usize,
}

/// The index after `i` (< `n`) around a closed contour of `n` points: `(i + 1) % n` without
/// the division, which the edge fit would otherwise pay at every step of every window.
pub(crate) fn next_around(i: usize, n: usize) -> usize {
    if i + 1 >= n {
        0
    } else {
        i + 1
    }
}

impl Contour {
    /// Twice the signed area enclosed (shoelace); its sign gives the direction of travel.
    pub fn signed_area2(&self) -> f64 {
        let n = self.points.len();
        (0..n)
            .map(|i| {
                let (p, q) = (self.points[i], self.points[next_around(i, n)]);
                p.x * q.y - q.x * p.y
            })
            .sum()
    }

    /// The same outline with each point replaced by the mean of the `2 half_window + 1` points
    /// around it (circularly).
    pub fn smoothed(&self, half_window: usize) -> Self {
        let n = self.points.len();
        if half_window == 0 || n < 2 * half_window + 1 {
            return self.clone();
        }
        let k = half_window as isize;
        let points = (0..n as isize)
            .map(|i| {
                let mut s = Point2::origin().coords;
                for j in -k..=k {
                    s += self.points[(i + j).rem_euclid(n as isize) as usize].coords;
                }
                Point2::from(s / (2 * k + 1) as f64)
            })
            .collect();
        Self {
            points,
            area_px: self.area_px,
        }
    }
}

/// Outer borders of the 8-connected components of `mask` with at least `min_area_px` pixels.
pub fn trace_contours(
    mask: &[bool],
    width: usize,
    height: usize,
    min_area_px: usize,
) -> Vec<Contour> {
    if width == 0 || mask.len() != width * height {
        return Vec::new();
    }
    let at = |x: isize, y: isize| {
        x >= 0 && y >= 0 && (x as usize) < width && (y as usize) < height && {
            mask[y as usize * width + x as usize]
        }
    };
    // The components through their runs; a component's root is its first run, whose first
    // pixel is the component's first in raster order, with background (or the image edge) to
    // its west — where the border following starts.
    let runs = Runs::passing(mask, width, |m| m);
    let mut regions = runs.regions();
    let area = runs.region_areas(&mut regions);
    let mut out = Vec::new();
    for (k, run) in runs.runs.iter().enumerate() {
        if regions.find(k) != k || area[k] < min_area_px.max(1) {
            continue;
        }
        let s = (run.x0 as isize, run.y as isize);
        out.push(Contour {
            points: follow_border(s, &at, 4 * area[k] + 8),
            area_px: area[k],
        });
    }
    out
}

/// Moore-neighbour tracing from `start`, entered from the west, until the first move repeats
/// from `start` (Jacob's stopping criterion) or `max_steps`.
fn follow_border(
    start: (isize, isize),
    at: &impl Fn(isize, isize) -> bool,
    max_steps: usize,
) -> Vec<Point2<f64>> {
    let mut points = vec![Point2::new(start.0 as f64, start.1 as f64)];
    let (mut p, mut back) = (start, 4usize);
    let mut first_move = None;
    for _ in 0..max_steps {
        let found = (1..=8).map(|k| (back + k) % 8).find(|&d| {
            let (dx, dy) = NEIGHBOURS[d];
            at(p.0 + dx, p.1 + dy)
        });
        let Some(d) = found else {
            break; // a single pixel
        };
        if p == start {
            match first_move {
                None => first_move = Some(d),
                Some(f) if f == d => {
                    points.pop(); // `start` again
                    break;
                }
                Some(_) => {}
            }
        }
        let q = (p.0 + NEIGHBOURS[d].0, p.1 + NEIGHBOURS[d].1);
        // The neighbour checked just before `q` was background; search from it next time.
        let (bx, by) = NEIGHBOURS[(d + 7) % 8];
        back = direction_of(p.0 + bx - q.0, p.1 + by - q.1);
        p = q;
        points.push(Point2::new(p.0 as f64, p.1 as f64));
    }
    if points.len() > 1 && points.first() == points.last() {
        points.pop();
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn the_integer_gaussian_is_the_5x5_gaussian_thresholded_at_one_half() {
        // The filter as written down: 5×5 binomial weights over the replicated-border image,
        // in floating point, on random masks of every small size and a few larger ones.
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut next = move || rng.next_u64();
        let w1 = [1.0, 4.0, 6.0, 4.0, 1.0].map(|w: f64| w / 16.0);
        for (width, height) in (1..8)
            .flat_map(|w| (1..8).map(move |h| (w, h)))
            .chain([(31, 9)])
        {
            let density = next() % 100;
            let mask: Vec<bool> = (0..width * height)
                .map(|_| next() % 100 < density)
                .collect();
            let at = |x: isize, y: isize| {
                let (x, y) = (
                    x.clamp(0, width as isize - 1),
                    y.clamp(0, height as isize - 1),
                );
                f64::from(u8::from(mask[y as usize * width + x as usize]))
            };
            let expected: Vec<bool> = (0..width * height)
                .map(|i| {
                    let (x, y) = ((i % width) as isize, (i / width) as isize);
                    let s: f64 = (0..5)
                        .flat_map(|j| (0..5).map(move |k| (j, k)))
                        .map(|(j, k)| w1[j] * w1[k] * at(x + k as isize - 2, y + j as isize - 2))
                        .sum();
                    s > 0.5
                })
                .collect();
            assert_eq!(
                smooth_mask(&mask, width, height),
                expected,
                "{width}×{height}"
            );
        }
    }

    fn disc(w: usize, h: usize, cx: f64, cy: f64, r: f64) -> Vec<bool> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64 - cx, (i / w) as f64 - cy);
                x * x + y * y <= r * r
            })
            .collect()
    }

    #[test]
    fn components_are_found_as_a_flood_fill_finds_them() {
        // Every 8-connected component of random masks, in the raster order of its first pixel,
        // with its area, and its border starting at that pixel.
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..200 {
            let (w, h) = (
                1 + (rng.next_u64() % 25) as usize,
                1 + (rng.next_u64() % 25) as usize,
            );
            let density = rng.next_u64() % 100;
            let mask: Vec<bool> = (0..w * h).map(|_| rng.next_u64() % 100 < density).collect();
            let mut seen = vec![false; w * h];
            let mut expected = Vec::new();
            for start in 0..w * h {
                if !mask[start] || seen[start] {
                    continue;
                }
                let (mut area, mut stack) = (0, vec![start]);
                seen[start] = true;
                while let Some(i) = stack.pop() {
                    area += 1;
                    let (x, y) = ((i % w) as isize, (i / w) as isize);
                    for (dx, dy) in NEIGHBOURS {
                        let (nx, ny) = (x + dx, y + dy);
                        if nx >= 0 && ny >= 0 && (nx as usize) < w && (ny as usize) < h {
                            let j = ny as usize * w + nx as usize;
                            if mask[j] && !seen[j] {
                                seen[j] = true;
                                stack.push(j);
                            }
                        }
                    }
                }
                let first = Point2::new((start % w) as f64, (start / w) as f64);
                expected.push((area, first));
            }
            let found: Vec<(usize, Point2<f64>)> = trace_contours(&mask, w, h, 1)
                .iter()
                .map(|c| (c.area_px, c.points[0]))
                .collect();
            assert_eq!(found, expected, "{w}×{h}");
        }
        // An empty image of no width has no components (and does not panic).
        assert!(trace_contours(&[], 0, 4, 1).is_empty());
    }

    #[test]
    fn a_square_is_traced_once_around_its_border() {
        let (w, h) = (8, 7);
        let mask: Vec<bool> = (0..w * h)
            .map(|i| (2..6).contains(&(i % w)) && (1..5).contains(&(i / w)))
            .collect();
        let c = trace_contours(&mask, w, h, 1);
        assert_eq!(c.len(), 1);
        assert_eq!(c[0].area_px, 16);
        assert_eq!(c[0].points.len(), 12, "{:?}", c[0].points);
        let unique: std::collections::HashSet<_> = c[0]
            .points
            .iter()
            .map(|p| (p.x as i64, p.y as i64))
            .collect();
        assert_eq!(unique.len(), 12);
        // Consecutive points are 8-neighbours, including last → first.
        let n = c[0].points.len();
        for i in 0..n {
            let d = c[0].points[(i + 1) % n] - c[0].points[i];
            assert!(d.x.abs() <= 1.0 && d.y.abs() <= 1.0 && d.norm() > 0.0);
        }
    }

    #[test]
    fn components_are_separate_and_small_ones_dropped() {
        let (w, h) = (60, 40);
        let mut mask = disc(w, h, 15.0, 20.0, 10.0);
        for (m, d) in mask.iter_mut().zip(disc(w, h, 45.0, 20.0, 8.0)) {
            *m |= d;
        }
        mask[0] = true; // a single pixel
        let c = trace_contours(&mask, w, h, 5);
        assert_eq!(c.len(), 2);
        for (contour, r) in c.iter().zip([10.0, 8.0]) {
            // The outline of a disc is about 2πr long and encloses about πr².
            let n = contour.points.len() as f64;
            assert!(n > 4.0 * r && n < 8.0 * r, "{n} points for r {r}");
            let area = contour.signed_area2().abs() / 2.0;
            let expected = std::f64::consts::PI * r * r;
            assert!((area - expected).abs() < 0.2 * expected, "{area}");
        }
        // Smoothing keeps a disc's outline near its circle.
        let s = c[0].smoothed(2);
        for p in &s.points {
            let d = (p - Point2::new(15.0, 20.0)).norm();
            assert!((d - 10.0).abs() < 1.5, "{d}");
        }
    }

    #[test]
    fn the_gaussian_fills_pinholes_and_removes_specks() {
        let (w, h) = (30, 30);
        let mut mask = disc(w, h, 15.0, 15.0, 8.0);
        mask[15 * w + 15] = false;
        mask[2 * w + 2] = true;
        let s = smooth_mask(&mask, w, h);
        assert!(s[15 * w + 15] && !s[2 * w + 2]);
    }
}
