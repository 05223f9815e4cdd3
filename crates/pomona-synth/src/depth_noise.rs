//! Depth sensor noise models (`--noise`), applied to the exact z-buffer after rendering.
//!
//! * `none` — exact z of the surface point (stored as `f32`).
//! * `low` — structured-light-like (Kinect v1, RealSense): Gaussian axial noise with
//!   `σ = 1.5 mm · (z / 1 m)²`.
//! * `tof` — time-of-flight-like (SwissRanger, Kinect v2): axial noise of 4 mm on bright surfaces
//!   rising to 8 mm on dark ones; flying pixels (a blend of foreground and background depth) on
//!   half the pixels at depth edges; dropouts on dark or grazing surfaces; 1 mm quantisation.
//!
//! Noise moves each point along its own pixel ray (only z changes), as real sensors do.

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

/// What the noise model needs to know about each pixel's surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SurfaceSample {
    /// Exact z, metres (`NaN` where nothing was hit).
    pub z: f64,
    /// Albedo luminance times the cosine of the incidence angle (the ToF return strength).
    pub amplitude: f64,
    /// Cosine of the angle between the surface normal and the line of sight.
    pub cos_incidence: f64,
}

impl NoiseModel {
    /// All models, in CLI order.
    pub const ALL: [NoiseModel; 3] = [NoiseModel::None, NoiseModel::Low, NoiseModel::Tof];

    /// The name used on the command line and in `synth.json`.
    pub fn name(self) -> &'static str {
        match self {
            NoiseModel::None => "none",
            NoiseModel::Low => "low",
            NoiseModel::Tof => "tof",
        }
    }

    /// Axial standard deviation at depth `z` for a surface of return amplitude `amplitude`.
    pub fn sigma_m(self, z: f64, amplitude: f64) -> f64 {
        match self {
            NoiseModel::None => 0.0,
            NoiseModel::Low => LOW_SIGMA_AT_1M * z * z,
            NoiseModel::Tof => {
                let darkness = ((0.25 - amplitude) / 0.25).clamp(0.0, 1.0);
                TOF_SIGMA_MIN + (TOF_SIGMA_MAX - TOF_SIGMA_MIN) * darkness
            }
        }
    }

    /// Turns exact per-pixel surfaces (row-major, `width` wide) into sensor depth in metres
    /// (`NaN` = no reading).
    pub(crate) fn apply(
        self,
        surfaces: &[SurfaceSample],
        width: usize,
        rng: &mut SynthRng,
    ) -> Vec<f32> {
        match self {
            NoiseModel::None => surfaces.iter().map(|s| s.z as f32).collect(),
            NoiseModel::Low => {
                let mut normal = NormalSampler::default();
                surfaces
                    .iter()
                    .map(|s| {
                        if s.z.is_finite() {
                            (s.z + self.sigma_m(s.z, s.amplitude) * normal.sample(rng)) as f32
                        } else {
                            f32::NAN
                        }
                    })
                    .collect()
            }
            NoiseModel::Tof => self.apply_tof(surfaces, width, rng),
        }
    }

    fn apply_tof(self, surfaces: &[SurfaceSample], width: usize, rng: &mut SynthRng) -> Vec<f32> {
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
            if !s.z.is_finite() {
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
            z += self.sigma_m(s.z, s.amplitude) * n;
            out.push(((z * 1000.0).round() / 1000.0) as f32);
        }
        out
    }
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
                cos_incidence: 1.0
            };
            n
        ]
    }

    #[test]
    fn none_is_exact_and_low_grows_with_depth() {
        let mut rng = frame_rng(0, 0);
        let s = flat(0.7, 100);
        assert!(NoiseModel::None
            .apply(&s, 10, &mut rng)
            .iter()
            .all(|&z| z == 0.7f32));
        assert!((NoiseModel::Low.sigma_m(2.0, 0.0) - 4.0 * LOW_SIGMA_AT_1M).abs() < 1e-15);
    }

    #[test]
    fn tof_noise_is_quantised_and_about_4mm_on_bright_surfaces() {
        let mut rng = frame_rng(0, 1);
        let s = flat(0.8, 10_000);
        let d = NoiseModel::Tof.apply(&s, 100, &mut rng);
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
        let d = NoiseModel::Tof.apply(&s, 20, &mut rng);
        let dropped_dark = d[..50].iter().filter(|z| z.is_nan()).count();
        assert!(dropped_dark > 30, "{dropped_dark}");
        let flying = d[80..120]
            .iter()
            .filter(|z| z.is_finite() && **z > 0.7 && **z < 1.1)
            .count();
        assert!(flying > 5, "{flying}");
    }
}
