//! Depth sensor noise models (`--noise`), applied to the exact z-buffer after rendering.
//!
//! * `none` — exact z of the surface point (stored as `f32`).
//! * `low` — structured-light-like (Kinect v1, RealSense): Gaussian axial noise with
//!   `σ = 1.5 mm · (z / 1 m)²`.
//! * `tof` — time-of-flight-like (SwissRanger, Kinect v2): axial noise of 4 mm on bright surfaces
//!   rising to 8 mm on dark ones; flying pixels (a blend of foreground and background depth) on
//!   half the pixels at depth edges; dropouts on dark or grazing surfaces; 1 mm quantisation.
//! * `tof-multipath` — `tof` plus multipath interference (the wide domain's default for the
//!   Kinect v2, SR4000 and Azure Kinect): light reaching a pixel's surface by way of other,
//!   brighter surfaces makes the path look longer, so a pixel dimmer than its neighbourhood is
//!   pushed back by up to [`TOF_MULTIPATH_MAX_M`] (in proportion to how much brighter the
//!   surrounding [`TOF_MULTIPATH_RADIUS_PX`] window is).
//! * `stereo` — active stereo like the RealSense D435 (the wide domain's default for it): depth is
//!   computed on the left imager and matched in the right one, [`STEREO_BASELINE_M`] to the
//!   right; background pixels the right imager cannot see (just left of every foreground edge,
//!   a band as wide as the disparity difference) have no depth, as do surfaces nearer than
//!   [`STEREO_MIN_Z_M`]; error is a disparity error of [`STEREO_SUBPIXEL_SIGMA_PX`], i.e.
//!   `σ_z = z² · σ_d / (fx · B)`; 1 mm quantisation.
//!
//! Every model reports no depth where nothing was hit (sky) or where the surface returns nothing
//! in the infrared (black ground cloth). Noise moves each point along its own pixel ray (only z
//! changes), as real sensors do.

use serde::{Deserialize, Serialize};

use crate::rng::{uniform, NormalSampler, SynthRng};
use rand::Rng;

/// Depth noise model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NoiseModel {
    /// Exact depth.
    None,
    /// Structured-light-like: axial σ growing with z².
    Low,
    /// Time-of-flight-like: 4–8 mm noise, flying pixels, dropouts, 1 mm steps.
    Tof,
    /// `tof` plus multipath interference (Kinect v2, SR4000, Azure Kinect in the wide domain).
    TofMultipath,
    /// Active stereo (D435): occlusion holes beside foreground edges, σ growing with z².
    Stereo,
}

/// `low` model: σ at 1 m, metres (σ scales with z²).
pub const LOW_SIGMA_AT_1M: f64 = 0.0015;
/// `tof` model: axial σ on bright surfaces, metres.
pub const TOF_SIGMA_MIN: f64 = 0.004;
/// `tof` model: axial σ on the darkest surfaces, metres.
pub const TOF_SIGMA_MAX: f64 = 0.008;
/// `tof` model: a jump larger than this to a 4-neighbour makes a pixel a depth edge, metres.
pub const TOF_EDGE_JUMP: f64 = 0.03;
/// `tof` model: returned-signal amplitude (albedo luminance × cos incidence) below which the
/// sensor usually reports nothing.
pub const TOF_DARK_AMPLITUDE: f64 = 0.03;
/// `tof` model: cos of the incidence angle below which the sensor usually reports nothing.
pub const TOF_GRAZING_COS: f64 = 0.12;
/// `tof-multipath` model: largest extra path (depth bias) from multipath, metres.
pub const TOF_MULTIPATH_MAX_M: f64 = 0.02;
/// `tof-multipath` model: half size of the square window whose mean return strength sets the
/// multipath bias, pixels.
pub const TOF_MULTIPATH_RADIUS_PX: usize = 5;
/// `stereo` model: baseline between the two imagers, metres (D435: 50 mm).
pub const STEREO_BASELINE_M: f64 = 0.05;
/// `stereo` model: standard deviation of the disparity, pixels.
pub const STEREO_SUBPIXEL_SIGMA_PX: f64 = 0.08;
/// `stereo` model: nearest depth the matcher reports, metres.
pub const STEREO_MIN_Z_M: f64 = 0.2;

/// What the noise model needs to know about each pixel's surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SurfaceSample {
    /// Exact z, metres (`NaN` where nothing was hit).
    pub z: f64,
    /// Albedo luminance times the cosine of the incidence angle (the ToF return strength).
    pub amplitude: f64,
    /// Cosine of the angle between the surface normal and the line of sight.
    pub cos_incidence: f64,
    /// The surface returns nothing to a depth sensor (black cloth in the infrared).
    pub no_return: bool,
}

impl NoiseModel {
    /// All models, in CLI order.
    pub const ALL: [NoiseModel; 5] = [
        NoiseModel::None,
        NoiseModel::Low,
        NoiseModel::Tof,
        NoiseModel::TofMultipath,
        NoiseModel::Stereo,
    ];

    /// The name used on the command line and in `synth.json`.
    pub fn name(self) -> &'static str {
        match self {
            NoiseModel::None => "none",
            NoiseModel::Low => "low",
            NoiseModel::Tof => "tof",
            NoiseModel::TofMultipath => "tof-multipath",
            NoiseModel::Stereo => "stereo",
        }
    }

    /// The model a camera of this kind shows: time-of-flight with multipath for the Kinect v2,
    /// SR4000 and Azure Kinect, active stereo for the D435 (the wide domain's default).
    pub fn for_camera(camera: crate::CameraPreset) -> Self {
        match camera {
            crate::CameraPreset::D435 => NoiseModel::Stereo,
            crate::CameraPreset::KinectV2
            | crate::CameraPreset::Sr4000
            | crate::CameraPreset::AzureKinect => NoiseModel::TofMultipath,
        }
    }

    /// Axial standard deviation at depth `z` for a surface of return amplitude `amplitude`
    /// (`stereo`: for a camera with `fx` = 615 px, the D435's).
    pub fn sigma_m(self, z: f64, amplitude: f64) -> f64 {
        match self {
            NoiseModel::None => 0.0,
            NoiseModel::Low => LOW_SIGMA_AT_1M * z * z,
            NoiseModel::Stereo => stereo_sigma_m(z, 615.0),
            NoiseModel::Tof | NoiseModel::TofMultipath => {
                let darkness = ((0.25 - amplitude) / 0.25).clamp(0.0, 1.0);
                TOF_SIGMA_MIN + (TOF_SIGMA_MAX - TOF_SIGMA_MIN) * darkness
            }
        }
    }

    /// Turns exact per-pixel surfaces (row-major, `width` wide, camera focal length `fx`
    /// pixels) into sensor depth in metres (`NaN` = no reading).
    pub(crate) fn apply(
        self,
        surfaces: &[SurfaceSample],
        width: usize,
        fx: f64,
        rng: &mut SynthRng,
    ) -> Vec<f32> {
        match self {
            NoiseModel::None => surfaces
                .iter()
                .map(|s| if s.no_return { f32::NAN } else { s.z as f32 })
                .collect(),
            NoiseModel::Low => {
                let mut normal = NormalSampler::default();
                surfaces
                    .iter()
                    .map(|s| {
                        if s.z.is_finite() && !s.no_return {
                            (s.z + self.sigma_m(s.z, s.amplitude) * normal.sample(rng)) as f32
                        } else {
                            f32::NAN
                        }
                    })
                    .collect()
            }
            NoiseModel::Tof => self.apply_tof(surfaces, width, rng, None),
            NoiseModel::TofMultipath => {
                let bias = multipath_bias_m(surfaces, width);
                self.apply_tof(surfaces, width, rng, Some(&bias))
            }
            NoiseModel::Stereo => apply_stereo(surfaces, width, fx, rng),
        }
    }

    fn apply_tof(
        self,
        surfaces: &[SurfaceSample],
        width: usize,
        rng: &mut SynthRng,
        bias_m: Option<&[f64]>,
    ) -> Vec<f32> {
        let height = surfaces.len().checked_div(width).unwrap_or(0);
        let mut out = Vec::with_capacity(surfaces.len());
        let mut normal = NormalSampler::default();
        for (i, s) in surfaces.iter().enumerate() {
            // Draw the same number of variates for every pixel, so a change in one pixel's
            // branch never shifts the noise of the others.
            let (r_drop, r_fly, r_blend, n) = (
                rng.gen::<f64>(),
                rng.gen::<f64>(),
                uniform(rng, 0.15, 0.85),
                normal.sample(rng),
            );
            if !s.z.is_finite() || s.no_return {
                out.push(f32::NAN);
                continue;
            }
            let dark = s.amplitude < TOF_DARK_AMPLITUDE;
            let grazing = s.cos_incidence < TOF_GRAZING_COS;
            let p_drop = if dark || grazing { 0.85 } else { 0.002 };
            if r_drop < p_drop {
                out.push(f32::NAN);
                continue;
            }
            let mut z = s.z;
            if r_fly < 0.5 {
                if let Some(other) = largest_jump_neighbour(surfaces, width, height, i) {
                    z += r_blend * (other - z);
                }
            }
            if let Some(bias) = bias_m {
                z += bias[i];
            }
            z += self.sigma_m(s.z, s.amplitude) * n;
            out.push(((z * 1000.0).round() / 1000.0) as f32);
        }
        out
    }
}

/// `stereo` model: axial σ at depth `z` for a camera with focal length `fx` pixels.
fn stereo_sigma_m(z: f64, fx: f64) -> f64 {
    z * z * STEREO_SUBPIXEL_SIGMA_PX / (fx * STEREO_BASELINE_M)
}

/// Per-pixel multipath bias of the `tof-multipath` model: [`TOF_MULTIPATH_MAX_M`] times how much
/// brighter the surrounding window is than the pixel, `(mean - own) / (mean + own)` clamped
/// to `[0, 1]`. Box means come from a summed-area table, so the cost is per pixel, not per
/// window.
fn multipath_bias_m(surfaces: &[SurfaceSample], width: usize) -> Vec<f64> {
    let height = surfaces.len().checked_div(width).unwrap_or(0);
    let amp = |s: &SurfaceSample| {
        if s.z.is_finite() && !s.no_return {
            s.amplitude
        } else {
            0.0
        }
    };
    // Summed-area table with a zero row and column in front.
    let stride = width + 1;
    let mut sat = vec![0.0f64; stride * (height + 1)];
    for v in 0..height {
        let mut row = 0.0;
        for u in 0..width {
            row += amp(&surfaces[v * width + u]);
            sat[(v + 1) * stride + u + 1] = sat[v * stride + u + 1] + row;
        }
    }
    let r = TOF_MULTIPATH_RADIUS_PX;
    surfaces
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let (u, v) = (i % width, i / width);
            let (u0, u1) = (u.saturating_sub(r), (u + r + 1).min(width));
            let (v0, v1) = (v.saturating_sub(r), (v + r + 1).min(height));
            let sum = sat[v1 * stride + u1] - sat[v0 * stride + u1] - sat[v1 * stride + u0]
                + sat[v0 * stride + u0];
            let mean = sum / ((u1 - u0) * (v1 - v0)) as f64;
            let own = amp(s);
            if mean + own <= 0.0 {
                return 0.0;
            }
            TOF_MULTIPATH_MAX_M * ((mean - own) / (mean + own)).clamp(0.0, 1.0)
        })
        .collect()
}

/// The `stereo` model (see the module docs).
fn apply_stereo(surfaces: &[SurfaceSample], width: usize, fx: f64, rng: &mut SynthRng) -> Vec<f32> {
    let height = surfaces.len().checked_div(width).unwrap_or(0);
    let mut normal = NormalSampler::default();
    let mut out = vec![f32::NAN; surfaces.len()];
    for v in 0..height {
        let row = &surfaces[v * width..(v + 1) * width];
        // A pixel at column u with disparity d appears at u - d in the right image; it is
        // hidden there when a pixel to its right lands at or left of that column. Scan from
        // the right keeping the leftmost landing column.
        let mut leftmost = f64::INFINITY;
        let mut hidden = vec![false; width];
        for u in (0..width).rev() {
            let s = &row[u];
            let d = if s.z.is_finite() && s.z > 0.0 {
                fx * STEREO_BASELINE_M / s.z
            } else {
                0.0
            };
            let lands = u as f64 - d;
            hidden[u] = lands >= leftmost + 0.5;
            leftmost = leftmost.min(lands);
        }
        for u in 0..width {
            let s = &row[u];
            // Same number of variates per pixel whatever the branch.
            let n = normal.sample(rng);
            if hidden[u] || !s.z.is_finite() || s.no_return || s.z < STEREO_MIN_Z_M {
                continue;
            }
            let z = s.z + stereo_sigma_m(s.z, fx) * n;
            out[v * width + u] = ((z * 1000.0).round() / 1000.0) as f32;
        }
    }
    out
}

/// The 4-neighbour depth farthest from pixel `i`'s, if the jump exceeds [`TOF_EDGE_JUMP`].
fn largest_jump_neighbour(
    surfaces: &[SurfaceSample],
    width: usize,
    height: usize,
    i: usize,
) -> Option<f64> {
    let (u, v) = (i % width, i / width);
    let z = surfaces[i].z;
    let mut best: Option<f64> = None;
    let mut best_jump = TOF_EDGE_JUMP;
    let mut consider = |j: usize| {
        let zj = surfaces[j].z;
        if zj.is_finite() && (zj - z).abs() > best_jump {
            best_jump = (zj - z).abs();
            best = Some(zj);
        }
    };
    if u > 0 {
        consider(i - 1);
    }
    if u + 1 < width {
        consider(i + 1);
    }
    if v > 0 {
        consider(i - width);
    }
    if v + 1 < height {
        consider(i + width);
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::frame_rng;

    fn flat(z: f64, n: usize) -> Vec<SurfaceSample> {
        vec![
            SurfaceSample {
                z,
                amplitude: 0.3,
                cos_incidence: 1.0,
                no_return: false,
            };
            n
        ]
    }

    #[test]
    fn none_is_exact_and_low_grows_with_depth() {
        let mut rng = frame_rng(0, 0);
        let s = flat(0.7, 100);
        assert!(NoiseModel::None
            .apply(&s, 10, 365.0, &mut rng)
            .iter()
            .all(|&z| z == 0.7f32));
        assert!((NoiseModel::Low.sigma_m(2.0, 0.0) - 4.0 * LOW_SIGMA_AT_1M).abs() < 1e-15);
    }

    #[test]
    fn tof_noise_is_quantised_and_about_4mm_on_bright_surfaces() {
        let mut rng = frame_rng(0, 1);
        let s = flat(0.8, 10_000);
        let d = NoiseModel::Tof.apply(&s, 100, 365.0, &mut rng);
        let valid: Vec<f64> = d
            .iter()
            .filter(|z| z.is_finite())
            .map(|&z| z as f64)
            .collect();
        assert!(valid.len() > 9_900);
        for z in &valid {
            assert!(((z * 1000.0) - (z * 1000.0).round()).abs() < 1e-3);
        }
        let mean = valid.iter().sum::<f64>() / valid.len() as f64;
        let sd =
            (valid.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / valid.len() as f64).sqrt();
        assert!((sd - 0.004).abs() < 0.0005, "sd {sd}");
    }

    #[test]
    fn tof_drops_dark_surfaces_and_flies_at_edges() {
        let mut rng = frame_rng(0, 2);
        let mut s = flat(0.6, 200);
        for p in s.iter_mut().skip(100) {
            p.z = 1.2;
        }
        for p in s.iter_mut().take(50) {
            p.amplitude = 0.01;
        }
        // 20 × 10 image: rows 0–4 at 0.6 m (rows 0–2.5 dark), rows 5–9 at 1.2 m.
        let d = NoiseModel::Tof.apply(&s, 20, 365.0, &mut rng);
        let dropped_dark = d[..50].iter().filter(|z| z.is_nan()).count();
        assert!(dropped_dark > 30, "{dropped_dark}");
        let flying = d[80..120]
            .iter()
            .filter(|z| z.is_finite() && **z > 0.7 && **z < 1.1)
            .count();
        assert!(flying > 5, "{flying}");
    }

    #[test]
    fn stereo_hides_background_left_of_a_foreground_edge() {
        let mut rng = frame_rng(0, 3);
        // One row of 100 pixels: background at 2 m, a foreground block at 0.5 m on 60..80.
        let mut s = flat(2.0, 100);
        for p in s.iter_mut().skip(60).take(20) {
            p.z = 0.5;
        }
        let d = apply_stereo(&s, 100, 615.0, &mut rng);
        // Disparity difference 615·0.05·(1/0.5 − 1/2) ≈ 46 px: columns ~14..59 are hidden.
        let holes: Vec<usize> = (0..100).filter(|&u| d[u].is_nan()).collect();
        assert!(holes.len() > 40 && holes.len() < 50, "{holes:?}");
        assert!(holes.iter().all(|&u| (10..60).contains(&u)), "{holes:?}");
        // Right of the block and on it there is depth; error grows with z².
        assert!(d[65].is_finite() && d[90].is_finite());
        assert!(stereo_sigma_m(2.0, 615.0) > 15.0 * stereo_sigma_m(0.5, 615.0));
    }

    #[test]
    fn multipath_pushes_dim_pixels_among_bright_ones_back() {
        let mut s = flat(1.0, 400);
        s[210].amplitude = 0.02;
        let bias = multipath_bias_m(&s, 20);
        assert!(bias[210] > 0.5 * TOF_MULTIPATH_MAX_M, "{}", bias[210]);
        assert!(bias[0] < 1e-9);
        let mut rng = frame_rng(0, 4);
        let mut cloth = flat(1.0, 4);
        cloth[1].no_return = true;
        for model in NoiseModel::ALL {
            assert!(
                model.apply(&cloth, 2, 615.0, &mut rng)[1].is_nan(),
                "{model:?}"
            );
        }
    }
}
