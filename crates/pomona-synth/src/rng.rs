//! Seeding and the few distributions the generator needs.
//!
//! Every random choice comes from a ChaCha8 stream. Frame `i` of a dataset with seed `s` uses the
//! stream [`frame_rng`]`(s, i)`, which depends on nothing else, so frames can be rendered in any
//! order on any number of threads and still come out bit-identical.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The random generator used throughout the crate.
pub type SynthRng = ChaCha8Rng;

/// The generator for frame `index` of a dataset with seed `dataset_seed`: the ChaCha key comes
/// from the dataset seed, the stream number is the frame index.
pub fn frame_rng(dataset_seed: u64, index: u64) -> SynthRng {
    let mut rng = ChaCha8Rng::seed_from_u64(dataset_seed);
    rng.set_stream(index);
    rng
}

/// A seed-derived generator for an independent purpose (for example per-view sensor noise).
pub(crate) fn sub_rng(seed: u64, stream: u64) -> SynthRng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

/// Uniform sample in `[lo, hi)` (returns `lo` for an empty range).
pub(crate) fn uniform(rng: &mut SynthRng, lo: f64, hi: f64) -> f64 {
    if hi > lo {
        rng.gen_range(lo..hi)
    } else {
        lo
    }
}

/// Standard normal samples in pairs (Box–Muller yields two per logarithm and `sin_cos`); keeps
/// the spare, so it needs one logarithm and one `sin_cos` per two samples.
#[derive(Debug, Default)]
pub(crate) struct NormalSampler {
    spare: Option<f64>,
}

impl NormalSampler {
    /// The next standard normal sample.
    pub(crate) fn sample(&mut self, rng: &mut SynthRng) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let u1: f64 = 1.0 - rng.gen::<f64>();
        let u2: f64 = rng.gen::<f64>();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        self.spare = Some(r * s);
        r * c
    }
}

/// A 64-bit mixing function (SplitMix64 finaliser), used for hash-based procedural textures.
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_streams_are_reproducible_and_distinct() {
        let a: u64 = frame_rng(7, 3).gen();
        let b: u64 = frame_rng(7, 3).gen();
        let c: u64 = frame_rng(7, 4).gen();
        let d: u64 = frame_rng(8, 3).gen();
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert_ne!(a, d);
    }

    #[test]
    fn normal_samples_have_unit_spread() {
        let mut rng = frame_rng(1, 0);
        let n = 20_000;
        let mut normal = NormalSampler::default();
        let xs: Vec<f64> = (0..n).map(|_| normal.sample(&mut rng)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03, "mean {mean}");
        assert!((var - 1.0).abs() < 0.05, "variance {var}");
    }
}
