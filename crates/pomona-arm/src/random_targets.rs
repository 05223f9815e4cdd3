//! Seeded random targets in the two-arm cell's working volume, for testing and measuring
//! planners on problems nobody picked by hand.

use nalgebra::Point3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::Target;

/// `n` targets drawn uniformly from x ∈ [−0.4, 1.0], y ∈ [−0.4, 0.4], z ∈ [0.4, 1.1] m in arm
/// A's hub frame (both arms' reach and some beyond it), ids `"0"`, `"1"`, …; same seed, same
/// targets.
pub fn random_targets(n: usize, seed: u64) -> Vec<Target> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|i| Target {
            id: i.to_string(),
            center_m: Point3::new(
                rng.gen_range(-0.4..1.0),
                rng.gen_range(-0.4..0.4),
                rng.gen_range(0.4..1.1),
            ),
        })
        .collect()
}
