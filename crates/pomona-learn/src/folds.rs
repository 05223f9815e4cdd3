//! Stratified k-fold assignment from a seeded ChaCha generator.
//!
//! Stratification keeps the class ratio of every fold close to the whole set's, which matters with
//! 5:1 imbalance and small data (a fold without positives would make accuracy meaningless). The
//! assignment depends only on the labels and the seed, never on thread count or timing.

use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Fold index (`0..k`) of every sample: each class is shuffled with the seeded generator and dealt
/// round-robin, positives continuing where negatives stopped so fold sizes differ by at most one.
///
/// ```
/// let labels = [true, false, false, true, false, false, false, true, false, false];
/// let folds = pomona_learn::stratified_folds(&labels, 3, 7);
/// assert_eq!(folds, pomona_learn::stratified_folds(&labels, 3, 7));
/// for f in 0..3 {
///     assert!(labels.iter().zip(&folds).any(|(&l, &k)| l && k == f));
/// }
/// ```
pub fn stratified_folds(labels: &[bool], k: usize, seed: u64) -> Vec<usize> {
    let k = k.max(1);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut folds = vec![0; labels.len()];
    let mut next = 0;
    for class in [false, true] {
        let mut idx: Vec<usize> = (0..labels.len()).filter(|&i| labels[i] == class).collect();
        idx.shuffle(&mut rng);
        for i in idx {
            folds[i] = next % k;
            next += 1;
        }
    }
    folds
}
