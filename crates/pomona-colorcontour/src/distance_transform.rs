//! Exact Euclidean distance from every mask pixel to the nearest background pixel.
//!
//! The value at a fruit pixel is the radius of the largest disc centred there that stays in the
//! mask, so its local maxima are the centres of the mask's inscribed discs — one per fruit even
//! where fruit touch and their outlines run into each other ([`crate::ray_circles`] starts there).
//! Computed in two passes (Felzenszwalb and Huttenlocher, "Distance transforms of sampled
//! functions", 2012): the distance to the nearest background pixel of the same column, by one
//! sweep down and one up; then, along each row, the lower envelope of the parabolas
//! `(x − x')² + column distance(x')²`. The second pass runs only over each run of fruit pixels
//! and the background pixel at either end of it: a pixel beyond that background pixel is
//! farther than it, so the envelope of the run alone is exact, and the work follows the fruit,
//! not the frame. Pixels outside the image are not background, so a fruit cut by the image
//! border keeps its depth there.

/// Squared distance, in pixels², from each pixel of the row-major `width` × `height` `mask` to
/// the nearest pixel where the mask is `false` (0 on background; `f32::INFINITY` everywhere when
/// the image has no background). A mask of the wrong length gives an empty result.
pub fn squared_distance_to_background(mask: &[bool], width: usize, height: usize) -> Vec<f32> {
    if mask.len() != width * height || mask.is_empty() {
        return Vec::new();
    }
    // Distance to the nearest background pixel of the column: down, then up (row by row, so
    // that each step is one pass over two contiguous rows).
    let mut d: Vec<f32> = mask[..width]
        .iter()
        .map(|&fruit| if fruit { f32::INFINITY } else { 0.0 })
        .collect();
    d.resize(mask.len(), 0.0);
    for y in 1..height {
        let (above, rest) = d.split_at_mut(y * width);
        let above = &above[(y - 1) * width..];
        let fruit = &mask[y * width..(y + 1) * width];
        for ((v, &up), &f) in rest[..width].iter_mut().zip(above).zip(fruit) {
            *v = if f { up + 1.0 } else { 0.0 };
        }
    }
    for y in (0..height.saturating_sub(1)).rev() {
        let (upper, below) = d.split_at_mut((y + 1) * width);
        for (v, &down) in upper[y * width..].iter_mut().zip(&below[..width]) {
            *v = v.min(down + 1.0);
        }
    }
    for v in &mut d {
        *v *= *v;
    }
    // Along each row, over each fruit run and the background pixel at either end.
    let mut envelope = Envelope::with_capacity(width);
    for (row, fruit) in d.chunks_exact_mut(width).zip(mask.chunks_exact(width)) {
        let mut x = 0;
        while x < width {
            if !fruit[x] {
                x += 1;
                continue;
            }
            let start = x;
            while x < width && fruit[x] {
                x += 1;
            }
            envelope.transform(&mut row[start.saturating_sub(1)..(x + 1).min(width)]);
        }
    }
    d
}

/// Scratch space of the 1D transform: the parabolas of the lower envelope and their bounds.
struct Envelope {
    f: Vec<f32>,
    vertex: Vec<usize>,
    bound: Vec<f32>,
}

impl Envelope {
    fn with_capacity(n: usize) -> Self {
        Self {
            f: Vec::with_capacity(n),
            vertex: Vec::with_capacity(n),
            bound: Vec::with_capacity(n + 1),
        }
    }

    /// Replaces `line[q]` by `min_p (q − p)² + line[p]` (infinite values are no parabola).
    fn transform(&mut self, line: &mut [f32]) {
        self.f.clear();
        self.f.extend_from_slice(line);
        self.vertex.clear();
        self.bound.clear();
        for (q, &fq) in self.f.iter().enumerate() {
            if !fq.is_finite() {
                continue;
            }
            while let Some(&p) = self.vertex.last() {
                let s = intersection(&self.f, p, q);
                if s <= *self.bound.last().unwrap_or(&f32::NEG_INFINITY) {
                    self.vertex.pop();
                    self.bound.pop();
                } else {
                    self.vertex.push(q);
                    self.bound.push(s);
                    break;
                }
            }
            if self.vertex.is_empty() {
                self.vertex.push(q);
                self.bound.push(f32::NEG_INFINITY);
            }
        }
        if self.vertex.is_empty() {
            return;
        }
        let mut k = 0;
        for (q, out) in line.iter_mut().enumerate() {
            while k + 1 < self.vertex.len() && self.bound[k + 1] < q as f32 {
                k += 1;
            }
            let p = self.vertex[k];
            let dq = q as f32 - p as f32;
            *out = dq * dq + self.f[p];
        }
    }
}

/// Where the parabolas with vertices at `p < q` (heights `f[p]`, `f[q]`) cross.
fn intersection(f: &[f32], p: usize, q: usize) -> f32 {
    let (pf, qf) = (p as f32, q as f32);
    ((f[q] + qf * qf) - (f[p] + pf * pf)) / (2.0 * (qf - pf))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The brute-force definition.
    fn brute(mask: &[bool], w: usize, h: usize) -> Vec<f32> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                (0..w * h)
                    .filter(|&j| !mask[j])
                    .map(|j| {
                        let (u, v) = ((j % w) as f32, (j / w) as f32);
                        (x - u).powi(2) + (y - v).powi(2)
                    })
                    .fold(f32::INFINITY, f32::min)
            })
            .collect()
    }

    #[test]
    fn equals_the_brute_force_distance_on_random_masks() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for (w, h, p) in [(17, 11, 0.9), (9, 23, 0.6), (30, 30, 0.97), (1, 5, 0.5)] {
            let mask: Vec<bool> = (0..w * h).map(|_| rng.gen_bool(p)).collect();
            assert_eq!(
                squared_distance_to_background(&mask, w, h),
                brute(&mask, w, h),
                "{w}×{h}"
            );
        }
    }

    #[test]
    fn a_disc_peaks_at_its_centre_with_its_radius_and_the_border_is_not_background() {
        let (w, h) = (40, 30);
        let mask: Vec<bool> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f64, (i / w) as f64);
                (x - 20.0).hypot(y - 15.0) <= 10.0
            })
            .collect();
        let d = squared_distance_to_background(&mask, w, h);
        let peak = (0..w * h)
            .max_by(|&a, &b| d[a].total_cmp(&d[b]))
            .unwrap_or(0);
        assert_eq!((peak % w, peak / w), (20, 15));
        assert_eq!(d[peak], 101.0); // (21, 25): the nearest pixel outside the disc of radius 10
                                    // All fruit: no background anywhere, the border does not count.
        assert!(squared_distance_to_background(&[true; 12], 4, 3)
            .iter()
            .all(|v| v.is_infinite()));
        assert!(squared_distance_to_background(&[true; 3], 4, 3).is_empty());
    }
}
