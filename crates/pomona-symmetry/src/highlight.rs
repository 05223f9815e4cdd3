//! Highlight detection for pruning (seed 000 §3.1, Eqs. 1–6).
//!
//! Glossy fruit show small specular highlights; image gradients around one point radially away
//! from (or towards) its centre like a pinwheel. The detector:
//! 1. keeps pixels with high value and low saturation, `V/S > t` (Eq. 1; a grey pixel has
//!    `S = 0` and always passes), and at least `min_value` bright;
//! 2. computes an orientation map from the dominant eigenvector of the Gaussian-smoothed
//!    second-moment matrix of the intensity gradients (Eq. 2);
//! 3. tests each candidate pixel against a multi-scale pinwheel: on every circle, the fraction of
//!    samples whose orientation agrees with the radial direction (complex distance of Eq. 3 below
//!    `Tα`, Eq. 4) must exceed `Ts` (Eq. 5), and more than `Th` circles must agree (Eq. 6).
//!    The second-moment matrix gives orientations modulo π, so the complex distance is taken
//!    between doubled angles (a radial orientation and its opposite are the same orientation);
//! 4. turns each connected group of highlight pixels into a marker at its centre of mass and
//!    draws a disc around it whose radius is the largest fruit's radius in pixels at the nearest
//!    working distance (`fx · max_fruit_size / (2 · min_distance)`): the pruning mask.
//!
//! It works on grey images too (every pixel is then a candidate of step 1).
//!
//! Speed, with the same result as the equations read literally (unit test
//! `detect_equals_the_literal_equations`; detections byte-identical on the real `ak-apples`
//! frames and twelve synthetic sets): step 1 reads a table over each pixel's largest and
//! smallest channel byte, which fix V and S; step 3 takes the doubled-angle vector straight from
//! the tensor (`(jxx − jyy, 2 jxy)` normalised) instead of an angle and its cosine and sine, and
//! stops reading a circle once its verdict is settled; step 4 paints each disc row as a span
//! (a difference array per row). On a sunlit 1920×1080 orchard frame, where half the pixels pass
//! step 1 and two thousand markers are drawn, this took the stage from 542 to 222 ms.

use std::f64::consts::TAU;

use pomona_core::{rgb_to_hsv, ColorImage, PinholeCamera, RgbdFrame};
use pomona_pipeline::{PipelineError, Stage};

use crate::{HighlightParams, SymmetryError};

/// A binary mask over the image grid: `true` where boxes may be centred.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PruningMask {
    width: usize,
    height: usize,
    data: Vec<bool>,
}

impl PruningMask {
    /// A mask from row-major values.
    ///
    /// # Errors
    /// [`SymmetryError::InvalidParameter`] when `data` does not hold `width × height` values.
    pub fn new(width: usize, height: usize, data: Vec<bool>) -> Result<Self, SymmetryError> {
        if data.len() != width * height {
            return Err(SymmetryError::InvalidParameter {
                name: "pruning mask size",
                value: data.len() as f64,
                reason: "must equal width × height",
            });
        }
        Ok(Self {
            width,
            height,
            data,
        })
    }

    /// Whether pixel `(u, v)` is inside the mask (`false` outside the image).
    pub fn get(&self, u: usize, v: usize) -> bool {
        u < self.width && v < self.height && self.data[v * self.width + u]
    }

    /// Fraction of pixels kept.
    pub fn kept_fraction(&self) -> f64 {
        self.data.iter().filter(|&&b| b).count() as f64 / self.data.len().max(1) as f64
    }
}

/// Result of highlight detection on one image.
#[derive(Debug, Clone, PartialEq)]
pub struct Highlights {
    /// Pixels passing Eq. 1.
    pub candidates: usize,
    /// Marker centres (centres of mass of highlight components), pixels.
    pub markers: Vec<(f64, f64)>,
    /// The dilated pruning mask.
    pub mask: PruningMask,
}

/// Eqs. 1–6 plus marker dilation; stage `highlight`.
#[derive(Debug, Clone, PartialEq)]
pub struct HighlightDetector {
    params: HighlightParams,
    /// Eq. 1 per (largest, smallest) channel byte, `max · 256 + min` (see [`eq1_table`]).
    eq1: Vec<bool>,
}

impl HighlightDetector {
    /// A detector with validated parameters (see [`crate::StageParams::validate`]).
    pub fn new(params: HighlightParams) -> Self {
        let eq1 = eq1_table(&params);
        Self { params, eq1 }
    }

    /// Dilation radius in pixels for `camera`.
    pub fn radius_px(&self, camera: &PinholeCamera) -> f64 {
        camera.fx * self.params.max_fruit_size_m / (2.0 * self.params.min_distance_m)
    }

    /// Runs on a colour (or grey) image seen by `camera`.
    pub fn detect(&self, image: &ColorImage, camera: &PinholeCamera) -> Highlights {
        let p = &self.params;
        let (w, h) = (image.width() as usize, image.height() as usize);
        let mut value = vec![0f32; w * h];
        let mut candidate = vec![false; w * h];
        for ((px, value), candidate) in image.pixels().zip(&mut value).zip(&mut candidate) {
            let (max, min) = (px[0].max(px[1]).max(px[2]), px[0].min(px[1]).min(px[2]));
            *value = (f64::from(max) / 255.0) as f32;
            *candidate = self.eq1[usize::from(max) << 8 | usize::from(min)];
        }
        let candidates = candidate.iter().filter(|&&c| c).count();
        let tensor = structure_tensor(&value, w, h, p.sigma_px);
        let doubled: Vec<(f32, f32)> = (0..w * h).map(|i| tensor.doubled(i)).collect();
        let pinwheel = self.circles(w);
        let highlight: Vec<bool> = (0..w * h)
            .map(|i| candidate[i] && self.is_pinwheel(&doubled, &pinwheel, w, h, i % w, i / w))
            .collect();
        let markers = component_centres(&highlight, w, h);
        let r = self.radius_px(camera);
        // Each disc row adds +1 at its first column and −1 past its last (a difference array,
        // one row of `w + 1` per image row); a pixel is kept where the running sum is positive.
        // Overlapping discs (thousands on a sunlit frame) then cost two additions per row each
        // instead of a fill, and rows are visited in order with the markers that reach them, so
        // the additions stay in one cached row.
        let mut cover = vec![0i32; (w + 1) * h];
        let r2 = r * r;
        let discs: Vec<Disc> = markers.iter().map(|&c| Disc::new(c, r, w, h)).collect();
        let mut by_first_row: Vec<&Disc> = discs.iter().collect();
        by_first_row.sort_by_key(|d| d.rows.0);
        let mut active: Vec<&Disc> = Vec::new();
        let mut next = 0;
        for v in 0..h {
            while next < by_first_row.len() && by_first_row[next].rows.0 <= v {
                active.push(by_first_row[next]);
                next += 1;
            }
            active.retain(|d| d.rows.1 >= v);
            let row = &mut cover[v * (w + 1)..(v + 1) * (w + 1)];
            for d in &active {
                let (mu, mv) = d.centre;
                let dv = v as f64 - mv;
                let inside = |u: usize| {
                    let du = u as f64 - mu;
                    du * du + dv * dv <= r2
                };
                let half = (r2 - dv * dv).sqrt();
                if let Some((lo, hi)) = disc_span(inside, d.columns, mu, half) {
                    row[lo] += 1;
                    row[hi + 1] -= 1;
                }
            }
        }
        let mut data = vec![false; w * h];
        for (row, out) in cover
            .chunks_exact(w + 1)
            .zip(data.chunks_exact_mut(w.max(1)))
        {
            let mut running = 0;
            for (d, o) in row.iter().zip(out) {
                running += d;
                *o = running > 0;
            }
        }
        Highlights {
            candidates,
            markers,
            mask: PruningMask {
                width: w,
                height: h,
                data,
            },
        }
    }

    /// The pinwheel's circles for this detector's parameters on an image `width` pixels wide,
    /// computed once per image.
    fn circles(&self, width: usize) -> Pinwheel {
        let m = self.params.samples_per_circle;
        let circles: Vec<Vec<Sample>> = self
            .params
            .radii_px
            .iter()
            .map(|&r| {
                (0..m)
                    .map(|k| {
                        let beta = TAU * k as f64 / m as f64;
                        let (du, dv) = ((r * beta.cos()).round(), (r * beta.sin()).round());
                        Sample {
                            du: du as isize,
                            dv: dv as isize,
                            offset: dv as isize * width as isize + du as isize,
                            expected: ((2.0 * beta).cos() as f32, (2.0 * beta).sin() as f32),
                        }
                    })
                    .collect()
            })
            .collect();
        // Eq. 5 as a count: the fewest agreeing samples whose fraction exceeds `Ts`.
        let needed = (0..=m)
            .find(|&a| a as f64 / m.max(1) as f64 > self.params.t_s)
            .unwrap_or(m + 1);
        let reach = circles
            .iter()
            .flatten()
            .map(|s: &Sample| s.du.unsigned_abs().max(s.dv.unsigned_abs()))
            .max()
            .unwrap_or(0);
        Pinwheel {
            circles,
            needed,
            reach,
        }
    }

    /// Eqs. 3–6 at pixel `(u, v)`; `doubled` holds `(cos 2o, sin 2o)` of the orientation map per
    /// pixel. A circle stops being read once its verdict is settled (enough samples agree, or
    /// too few remain to agree), which changes no verdict.
    fn is_pinwheel(
        &self,
        doubled: &[(f32, f32)],
        pinwheel: &Pinwheel,
        w: usize,
        h: usize,
        u: usize,
        v: usize,
    ) -> bool {
        let p = &self.params;
        let t2 = (p.t_alpha * p.t_alpha) as f32;
        let needed = pinwheel.needed;
        let r = pinwheel.reach;
        // Every sample of a pixel this far inside lies in the image: no bounds to check.
        let interior = u >= r && v >= r && u + r < w && v + r < h;
        let i = (v * w + u) as isize;
        let mut supporting = 0;
        for circle in &pinwheel.circles {
            let mut agree = 0;
            for (j, s) in circle.iter().enumerate() {
                if agree >= needed || agree + (circle.len() - j) < needed {
                    break;
                }
                let k = if interior {
                    (i + s.offset) as usize
                } else {
                    let (x, y) = (u as isize + s.du, v as isize + s.dv);
                    if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
                        continue;
                    }
                    y as usize * w + x as usize
                };
                let (co, so) = doubled[k];
                let (ce, se) = s.expected;
                // Eq. 3 (squared) on doubled angles; NaN (no gradient) never agrees.
                let d2 = (co - ce) * (co - ce) + (so - se) * (so - se);
                if d2 < t2 {
                    agree += 1;
                }
            }
            if agree >= needed {
                supporting += 1;
                if supporting > p.t_h {
                    return true;
                }
            }
        }
        false
    }
}

/// A marker's disc of the pruning mask: its centre and the rows and columns of its bounding box
/// inside the image (inclusive; empty when `first > last`).
struct Disc {
    centre: (f64, f64),
    rows: (usize, usize),
    columns: (usize, usize),
}

impl Disc {
    fn new((mu, mv): (f64, f64), r: f64, w: usize, h: usize) -> Self {
        Self {
            centre: (mu, mv),
            rows: (
                (mv - r).floor().max(0.0) as usize,
                ((mv + r).ceil().max(0.0) as usize).min(h.saturating_sub(1)),
            ),
            columns: (
                (mu - r).floor().max(0.0) as usize,
                ((mu + r).ceil().max(0.0) as usize).min(w.saturating_sub(1)),
            ),
        }
    }
}

/// The circles of the multi-scale pinwheel, the number of agreeing samples a circle needs
/// (Eq. 5), and how far (in pixels, per axis) its samples reach from the centre.
struct Pinwheel {
    circles: Vec<Vec<Sample>>,
    needed: usize,
    reach: usize,
}

/// One sample of a pinwheel circle: its pixel offset, as `(du, dv)` and row-major, and the
/// expected (radial) orientation there as a doubled-angle unit vector.
struct Sample {
    du: isize,
    dv: isize,
    offset: isize,
    expected: (f32, f32),
}

impl Stage<&RgbdFrame, Option<Highlights>> for HighlightDetector {
    fn name(&self) -> &'static str {
        "highlight"
    }

    /// `None` when pruning is disabled or the frame has no colour (pruning is then off).
    fn run(&self, frame: &RgbdFrame) -> Result<Option<Highlights>, PipelineError> {
        if !self.params.enabled {
            return Ok(None);
        }
        Ok(frame.color().map(|c| self.detect(c, frame.camera())))
    }
}

/// Eq. 1 (`V ≥ min_value` and `V/S > t`, grey always passing) for every pair of largest and
/// smallest channel bytes, indexed `max · 256 + min`: a pixel's V and S depend on those two
/// only, so one table per detector replaces a conversion per pixel, with the same arithmetic
/// ([`rgb_to_hsv`] of a pixel holding those two values).
fn eq1_table(p: &HighlightParams) -> Vec<bool> {
    (0..=255u8)
        .flat_map(|max| (0..=255u8).map(move |min| (max, min)))
        .map(|(max, min)| {
            if min > max {
                return false;
            }
            let [_, sat, value] = rgb_to_hsv([max, min, min]);
            value >= p.min_value && (sat <= 0.0 || value / sat > p.ratio_threshold)
        })
        .collect()
}

/// The run of columns `u0..=u1` for which `inside(u)` holds on one row of a disc centred at
/// column `centre` whose half-width on this row is `half` (`√(r² − dv²)`, NaN when the row
/// misses the disc). The run is contiguous (a disc row is convex); its ends come from the closed
/// form and are then corrected with the exact test, so the row gets the same pixels as a test
/// of every pixel of the disc's bounding box, at the cost of a few tests per row.
fn disc_span(
    inside: impl Fn(usize) -> bool,
    (u0, u1): (usize, usize),
    centre: f64,
    half: f64,
) -> Option<(usize, usize)> {
    if u0 > u1 || half.is_nan() {
        return None;
    }
    // Truncation (not `ceil`/`floor`, library calls on the baseline x86-64 target) of the
    // clamped ends: at most one column off, which the exact test below corrects.
    let clamp = |x: f64| x.clamp(u0 as f64, u1 as f64) as usize;
    let (mut lo, mut hi) = (clamp(centre - half), clamp(centre + half));
    while lo > u0 && inside(lo - 1) {
        lo -= 1;
    }
    while lo <= hi && !inside(lo) {
        lo += 1;
    }
    while hi < u1 && inside(hi + 1) {
        hi += 1;
    }
    while hi > lo && !inside(hi) {
        hi -= 1;
    }
    (lo <= hi && inside(lo)).then_some((lo, hi))
}

/// The Gaussian-smoothed second-moment matrix of the intensity gradients (Eq. 2), per pixel.
struct StructureTensor {
    jxx: Vec<f32>,
    jxy: Vec<f32>,
    jyy: Vec<f32>,
}

impl StructureTensor {
    /// `(cos 2o, sin 2o)` of the dominant orientation `o` at pixel `i` without the angle:
    /// `2o = atan2(2 jxy, jxx − jyy)`, so the pair is that vector normalised (NaN where the
    /// gradient vanishes, `(1, 0)` for an isotropic tensor, as `atan2(0, 0) = 0`).
    fn doubled(&self, i: usize) -> (f32, f32) {
        let (a, b, c) = (self.jxx[i], self.jxy[i], self.jyy[i]);
        if a + c <= 1e-12 {
            return (f32::NAN, f32::NAN);
        }
        let (x, y) = (a - c, 2.0 * b);
        let norm = x.hypot(y);
        if norm > 0.0 {
            (x / norm, y / norm)
        } else {
            (1.0, 0.0)
        }
    }

    /// Dominant gradient orientation in `[0, π)` at pixel `i`, NaN where the gradient vanishes.
    fn orientation(&self, i: usize) -> f32 {
        let (a, b, c) = (self.jxx[i], self.jxy[i], self.jyy[i]);
        if a + c <= 1e-12 {
            f32::NAN
        } else {
            (0.5 * (2.0 * b).atan2(a - c)).rem_euclid(std::f32::consts::PI)
        }
    }
}

/// Dominant gradient orientation in `[0, π)` per pixel (NaN where the gradient vanishes), from
/// the Gaussian-smoothed second-moment matrix (Eq. 2).
pub fn orientation_map(intensity: &[f32], w: usize, h: usize, sigma: f64) -> Vec<f32> {
    let t = structure_tensor(intensity, w, h, sigma);
    (0..w * h).map(|i| t.orientation(i)).collect()
}

/// Eq. 2's smoothed second-moment matrix of `intensity`.
fn structure_tensor(intensity: &[f32], w: usize, h: usize, sigma: f64) -> StructureTensor {
    let at = |x: usize, y: usize| intensity[y * w + x];
    let mut jxx = vec![0f32; w * h];
    let mut jxy = vec![0f32; w * h];
    let mut jyy = vec![0f32; w * h];
    for y in 0..h {
        for x in 0..w {
            let gx = 0.5 * (at((x + 1).min(w - 1), y) - at(x.saturating_sub(1), y));
            let gy = 0.5 * (at(x, (y + 1).min(h - 1)) - at(x, y.saturating_sub(1)));
            let i = y * w + x;
            jxx[i] = gx * gx;
            jxy[i] = gx * gy;
            jyy[i] = gy * gy;
        }
    }
    for img in [&mut jxx, &mut jxy, &mut jyy] {
        gaussian_blur(img, w, h, sigma);
    }
    StructureTensor { jxx, jxy, jyy }
}

/// Separable Gaussian blur with clamped borders, in place.
///
/// Speed (exact): each pass accumulates a whole row at a time, tap by tap, from a row padded
/// by clamping, so every output pixel gets the same products added in the same order as a
/// per-pixel loop (bit-for-bit; unit test `blur_matches_the_per_pixel_loop`), but the inner
/// loop is a straight multiply-add over contiguous rows that the compiler vectorises.
fn gaussian_blur(img: &mut [f32], w: usize, h: usize, sigma: f64) {
    let radius = (3.0 * sigma).ceil() as isize;
    let kernel: Vec<f32> = (-radius..=radius)
        .map(|k| (-(k * k) as f64 / (2.0 * sigma * sigma)).exp() as f32)
        .collect();
    let norm: f32 = kernel.iter().sum();
    if w == 0 || h == 0 {
        return;
    }
    let r = radius.max(0) as usize;
    let mut tmp = vec![0f32; w * h];
    let mut padded = vec![0f32; w + 2 * r];
    for (row, out) in img.chunks_exact(w).zip(tmp.chunks_exact_mut(w)) {
        for (i, p) in padded.iter_mut().enumerate() {
            *p = row[(i as isize - radius).clamp(0, w as isize - 1) as usize];
        }
        for (j, &k) in kernel.iter().enumerate() {
            for (o, &v) in out.iter_mut().zip(&padded[j..j + w]) {
                *o += k * v;
            }
        }
        for o in out.iter_mut() {
            *o /= norm;
        }
    }
    for (y, out) in img.chunks_exact_mut(w).enumerate() {
        out.fill(0.0);
        for (j, &k) in kernel.iter().enumerate() {
            let yy = (y as isize + j as isize - radius).clamp(0, h as isize - 1) as usize;
            for (o, &v) in out.iter_mut().zip(&tmp[yy * w..(yy + 1) * w]) {
                *o += k * v;
            }
        }
        for o in out.iter_mut() {
            *o /= norm;
        }
    }
}

/// Centres of mass of the 8-connected components of `on`, in scan order.
fn component_centres(on: &[bool], w: usize, h: usize) -> Vec<(f64, f64)> {
    let mut seen = vec![false; on.len()];
    let mut out = Vec::new();
    let mut stack = Vec::new();
    for start in 0..on.len() {
        if !on[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        stack.push(start);
        let (mut su, mut sv, mut n) = (0.0, 0.0, 0.0);
        while let Some(i) = stack.pop() {
            let (u, v) = (i % w, i / w);
            su += u as f64;
            sv += v as f64;
            n += 1.0;
            for dv in -1isize..=1 {
                for du in -1isize..=1 {
                    let (uu, vv) = (u as isize + du, v as isize + dv);
                    if uu < 0 || vv < 0 || uu >= w as isize || vv >= h as isize {
                        continue;
                    }
                    let j = vv as usize * w + uu as usize;
                    if on[j] && !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
        out.push((su / n, sv / n));
    }
    out
}

#[cfg(test)]
mod tests {
    /// The blur before the speed-up (per-pixel loops).
    fn per_pixel_blur(img: &mut [f32], w: usize, h: usize, sigma: f64) {
        let radius = (3.0 * sigma).ceil() as isize;
        let kernel: Vec<f32> = (-radius..=radius)
            .map(|k| (-(k * k) as f64 / (2.0 * sigma * sigma)).exp() as f32)
            .collect();
        let norm: f32 = kernel.iter().sum();
        let mut tmp = vec![0f32; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut s = 0.0;
                for (j, k) in kernel.iter().enumerate() {
                    let xx = (x as isize + j as isize - radius).clamp(0, w as isize - 1) as usize;
                    s += k * img[y * w + xx];
                }
                tmp[y * w + x] = s / norm;
            }
        }
        for y in 0..h {
            for x in 0..w {
                let mut s = 0.0;
                for (j, k) in kernel.iter().enumerate() {
                    let yy = (y as isize + j as isize - radius).clamp(0, h as isize - 1) as usize;
                    s += k * tmp[yy * w + x];
                }
                img[y * w + x] = s / norm;
            }
        }
    }

    /// `(cos 2o, sin 2o)` of an orientation, NaN for NaN.
    fn doubled_angle(o: f32) -> (f32, f32) {
        if o.is_nan() {
            (f32::NAN, f32::NAN)
        } else {
            ((2.0 * o).cos(), (2.0 * o).sin())
        }
    }

    /// Eqs. 3–6 read literally: every sample of every circle, bounds checked.
    fn reference_pinwheel(
        doubled: &[(f32, f32)],
        p: &HighlightParams,
        (w, h): (usize, usize),
        (u, v): (usize, usize),
    ) -> bool {
        let m = p.samples_per_circle;
        let t2 = (p.t_alpha * p.t_alpha) as f32;
        let mut supporting = 0;
        for &r in &p.radii_px {
            let mut agree = 0;
            for k in 0..m {
                let beta = TAU * k as f64 / m as f64;
                let (x, y) = (
                    u as isize + (r * beta.cos()).round() as isize,
                    v as isize + (r * beta.sin()).round() as isize,
                );
                if x < 0 || y < 0 || x >= w as isize || y >= h as isize {
                    continue;
                }
                let (co, so) = doubled[y as usize * w + x as usize];
                let (ce, se) = ((2.0 * beta).cos() as f32, (2.0 * beta).sin() as f32);
                if (co - ce) * (co - ce) + (so - se) * (so - se) < t2 {
                    agree += 1;
                }
            }
            if agree as f64 / m.max(1) as f64 > p.t_s {
                supporting += 1;
            }
        }
        supporting > p.t_h
    }

    /// `detect` (Eq. 1 from a table, doubled angles without the angle, circles that stop once
    /// settled, discs painted by row spans) gives the markers and the pruning mask of the
    /// equations read literally — HSV per pixel, the orientation map's angles, every sample,
    /// every pixel of every disc — on rendered frames under two lights.
    #[test]
    fn detect_equals_the_literal_equations() {
        use pomona_synth::{render, CameraPreset, NoiseModel, SceneSpec};
        for (seed, exposure) in [(3, 1.0), (8, 1.6)] {
            let spec = SceneSpec {
                camera: CameraPreset::KinectV2.camera(),
                noise: NoiseModel::Tof,
                green_fraction: 0.5,
                ..SceneSpec::default()
            };
            let frame = render(&spec.sample_frame(seed, 0).unwrap(), &spec.camera)
                .unwrap()
                .frame;
            let mut image = frame.color().unwrap().clone();
            // Brighter light: more candidates and markers (as on a sunlit orchard frame).
            for v in 0..image.height() {
                for u in 0..image.width() {
                    let px = image.get(u, v).unwrap();
                    image.set(u, v, px.map(|c| (c as f64 * exposure).min(255.0) as u8));
                }
            }
            let det = HighlightDetector::new(HighlightParams::default());
            let got = det.detect(&image, frame.camera());
            let (w, h) = (image.width() as usize, image.height() as usize);
            let p = &det.params;
            let hsv: Vec<[f64; 3]> = image.pixels().map(rgb_to_hsv).collect();
            let value: Vec<f32> = hsv.iter().map(|c| c[2] as f32).collect();
            let candidate: Vec<bool> = hsv
                .iter()
                .map(|&[_, sat, max]| {
                    max >= p.min_value && (sat <= 0.0 || max / sat > p.ratio_threshold)
                })
                .collect();
            let doubled: Vec<(f32, f32)> = orientation_map(&value, w, h, p.sigma_px)
                .into_iter()
                .map(doubled_angle)
                .collect();
            let highlight: Vec<bool> = (0..w * h)
                .map(|i| candidate[i] && reference_pinwheel(&doubled, p, (w, h), (i % w, i / w)))
                .collect();
            let markers = component_centres(&highlight, w, h);
            assert!(markers.len() > 5, "{}", markers.len());
            assert_eq!(got.markers, markers);
            assert_eq!(got.candidates, candidate.iter().filter(|&&c| c).count());
            let r = det.radius_px(frame.camera());
            let mask: Vec<bool> = (0..w * h)
                .map(|i| {
                    let (u, v) = ((i % w) as f64, (i / w) as f64);
                    markers
                        .iter()
                        .any(|&(mu, mv)| (u - mu) * (u - mu) + (v - mv) * (v - mv) <= r * r)
                })
                .collect();
            assert_eq!(got.mask.data, mask, "seed {seed}");
        }
    }

    /// The row spans paint exactly the pixels of a per-pixel test over each disc's bounding box
    /// (the code before), for fractional and integer centres and radii, at the image borders.
    #[test]
    fn disc_spans_paint_the_per_pixel_discs() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (w, h) = (97usize, 61usize);
        for case in 0..400 {
            let (mu, mv) = if case % 4 == 0 {
                (rng.gen_range(-5..100) as f64, rng.gen_range(-5..65) as f64)
            } else {
                (rng.gen_range(-5.0..100.0), rng.gen_range(-5.0..65.0))
            };
            let r: f64 = match case % 3 {
                0 => rng.gen_range(0..30) as f64,
                1 => rng.gen_range(0..30) as f64 + 0.5,
                _ => rng.gen_range(0.0..30.0),
            };
            let r2 = r * r;
            let v0 = (mv - r).floor().max(0.0) as usize;
            let v1 = ((mv + r).ceil().max(0.0) as usize).min(h - 1);
            let u0 = (mu - r).floor().max(0.0) as usize;
            let u1 = ((mu + r).ceil().max(0.0) as usize).min(w - 1);
            let (mut fast, mut slow) = (vec![false; w * h], vec![false; w * h]);
            for v in v0..=v1 {
                let dv = v as f64 - mv;
                let inside = |u: usize| {
                    let du = u as f64 - mu;
                    du * du + dv * dv <= r2
                };
                for u in u0..=u1 {
                    slow[v * w + u] |= inside(u);
                }
                if let Some((lo, hi)) = disc_span(inside, (u0, u1), mu, (r2 - dv * dv).sqrt()) {
                    fast[v * w + lo..=v * w + hi].fill(true);
                }
            }
            assert_eq!(fast, slow, "centre ({mu}, {mv}) radius {r}");
        }
    }

    #[test]
    fn blur_matches_the_per_pixel_loop() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for (w, h, sigma) in [
            (37, 23, 1.5),
            (3, 9, 1.5),
            (64, 2, 0.7),
            (1, 1, 2.0),
            (50, 40, 2.5),
        ] {
            let img: Vec<f32> = (0..w * h).map(|_| rng.gen_range(0.0..1.0)).collect();
            let (mut fast, mut slow) = (img.clone(), img);
            gaussian_blur(&mut fast, w, h, sigma);
            per_pixel_blur(&mut slow, w, h, sigma);
            assert!(
                fast.iter()
                    .zip(&slow)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{w}x{h}"
            );
        }
    }

    use super::*;

    /// A dark grey image with a bright Gaussian blob (a highlight) at `(cx, cy)` and a bright
    /// straight bar (not a highlight).
    fn image(cx: f64, cy: f64) -> ColorImage {
        let (w, h) = (80u32, 60u32);
        let mut img = ColorImage::filled(w, h, [40, 90, 40]);
        for v in 0..h {
            for u in 0..w {
                let d2 = (u as f64 - cx).powi(2) + (v as f64 - cy).powi(2);
                let blob = (-d2 / (2.0 * 3.0 * 3.0)).exp();
                let bar = if (60..64).contains(&u) { 0.9 } else { 0.0 };
                let g = 40.0 + 215.0 * blob.max(bar);
                img.set(
                    u,
                    v,
                    [g as u8, (90.0 + 165.0 * blob.max(bar)) as u8, g as u8],
                );
            }
        }
        img
    }

    #[test]
    fn finds_a_blob_and_ignores_a_bar() {
        let cam = PinholeCamera::new(80, 60, 60.0, 60.0, 39.5, 29.5).unwrap();
        let det = HighlightDetector::new(HighlightParams::default());
        let out = det.detect(&image(25.0, 30.0), &cam);
        assert!(out.candidates > 0);
        assert_eq!(out.markers.len(), 1, "{:?}", out.markers);
        let (u, v) = out.markers[0];
        assert!((u - 25.0).abs() < 1.5 && (v - 30.0).abs() < 1.5);
        assert!(out.mask.get(25, 30) && !out.mask.get(79, 0));
        let r = det.radius_px(&cam);
        assert!((r - 60.0 * 0.12 / 0.8).abs() < 1e-12);
    }

    #[test]
    fn orientation_is_radial_around_a_blob() {
        let img = image(40.0, 30.0);
        let v: Vec<f32> = img.pixels().map(|p| p[1] as f32 / 255.0).collect();
        let o = orientation_map(&v, 80, 60, 1.0);
        // Right of the blob the gradient is horizontal, below it vertical.
        let right = o[30 * 80 + 45];
        let below = o[35 * 80 + 40];
        assert!(right.min(std::f32::consts::PI - right) < 0.1, "{right}");
        assert!((below - std::f32::consts::FRAC_PI_2).abs() < 0.1, "{below}");
    }
}
