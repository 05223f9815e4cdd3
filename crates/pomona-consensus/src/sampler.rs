//! Drawing the minimal index sets a consensus loop fits models to.
//!
//! Samplers are separate from the loops so a guided sampler (PROSAC, NAPSAC) can replace the
//! uniform one without touching MSAC. Every sampler is seeded, so a fit is reproducible: the same
//! seed and data give the same sequence of samples, on any machine and any thread count.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Draws sets of distinct indices.
pub trait Sampler {
    /// Replaces `out` by `k` distinct indices drawn from `0..n`. Callers guarantee `k <= n`.
    fn sample(&mut self, n: usize, k: usize, out: &mut Vec<usize>);
}

/// Uniform sampling without replacement, driven by a seeded ChaCha8 generator.
#[derive(Debug, Clone)]
pub struct UniformSampler {
    rng: ChaCha8Rng,
}

impl UniformSampler {
    /// A sampler whose draws depend only on `seed`.
    pub fn new(seed: u64) -> Self {
        Self {
            rng: ChaCha8Rng::seed_from_u64(seed),
        }
    }
}

impl Sampler for UniformSampler {
    fn sample(&mut self, n: usize, k: usize, out: &mut Vec<usize>) {
        out.clear();
        if k > n {
            return;
        }
        // Minimal samples are tiny (2–4), so rejection of repeats is cheaper than a shuffle.
        if k * 2 <= n {
            while out.len() < k {
                let i = self.rng.gen_range(0..n);
                if !out.contains(&i) {
                    out.push(i);
                }
            }
        } else {
            // Dense case: partial Fisher–Yates over the whole range.
            let mut all: Vec<usize> = (0..n).collect();
            for j in 0..k {
                let pick = self.rng.gen_range(j..n);
                all.swap(j, pick);
            }
            out.extend_from_slice(&all[..k]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_are_distinct_in_range_and_reproducible() {
        let mut a = UniformSampler::new(7);
        let mut b = UniformSampler::new(7);
        let (mut sa, mut sb) = (Vec::new(), Vec::new());
        for n in [4usize, 5, 10, 1000] {
            for _ in 0..50 {
                a.sample(n, 4, &mut sa);
                b.sample(n, 4, &mut sb);
                assert_eq!(sa, sb);
                assert_eq!(sa.len(), 4);
                assert!(sa.iter().all(|&i| i < n));
                let mut s = sa.clone();
                s.sort_unstable();
                s.dedup();
                assert_eq!(s.len(), 4);
            }
        }
    }
}
