//! Which negative candidates the classifier is trained on.
//!
//! A training frame gives hundreds of negative candidates (leaves, stems, ground; more since the
//! depth proposals) for every few fruit. Training on all of them only slows the grid search, so
//! a seeded random choice keeps at most `max_negatives_per_positive` per positive (seed 002
//! trains with about 5:1). A random choice mostly keeps easy negatives; the leaves that look
//! like fruit are rare among them. **Hard-negative mining** (not in seed 002; bootstrapping, as
//! the symmetry pipeline does) then adds, per round, the negatives left out that the current
//! classifier scores highest — at least [`MINING_MIN_SCORE`], inside its margin — at most
//! `hard_negatives_per_positive` per positive, and retrains.

use rand::seq::SliceRandom;
use rand::SeedableRng;

/// A left-out negative is mined only when the classifier scores it at least this (the edge of
/// the SVM's margin on the negative side): those further out cannot move the boundary.
pub const MINING_MIN_SCORE: f64 = -1.0;

/// Indices (sorted) of every positive and at most `ratio` negatives per positive (at least
/// one positive's worth), the negatives chosen by a shuffle seeded with `seed`.
pub(crate) fn cap_negatives(labels: &[bool], ratio: f64, seed: u64) -> Vec<usize> {
    let positives = labels.iter().filter(|&&l| l).count();
    let mut negatives: Vec<usize> = (0..labels.len()).filter(|&i| !labels[i]).collect();
    let cap = (ratio * positives.max(1) as f64).ceil() as usize;
    if negatives.len() > cap {
        negatives.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
        negatives.truncate(cap);
    }
    let mut kept: Vec<usize> = (0..labels.len()).filter(|&i| labels[i]).collect();
    kept.extend(negatives);
    kept.sort_unstable();
    kept
}

/// The negatives not yet `chosen` with the highest `scores`, at least [`MINING_MIN_SCORE`], at
/// most `limit`, highest first (ties by index).
pub(crate) fn hardest_negatives(
    labels: &[bool],
    chosen: &[usize],
    scores: &[f64],
    limit: usize,
) -> Vec<usize> {
    let mut taken = vec![false; labels.len()];
    for &i in chosen {
        taken[i] = true;
    }
    let mut hard: Vec<usize> = (0..labels.len())
        .filter(|&i| !labels[i] && !taken[i] && scores[i] >= MINING_MIN_SCORE)
        .collect();
    hard.sort_by(|&a, &b| scores[b].total_cmp(&scores[a]).then(a.cmp(&b)));
    hard.truncate(limit);
    hard
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cap_keeps_every_positive_and_is_seeded() {
        let labels: Vec<bool> = (0..100).map(|i| i % 10 == 0).collect();
        let kept = cap_negatives(&labels, 2.0, 7);
        assert_eq!(kept.len(), 10 + 20);
        assert!(labels
            .iter()
            .enumerate()
            .all(|(i, &l)| !l || kept.contains(&i)));
        assert_eq!(kept, cap_negatives(&labels, 2.0, 7));
        assert_ne!(kept, cap_negatives(&labels, 2.0, 8));
        assert_eq!(cap_negatives(&labels, 20.0, 7).len(), 100);
    }

    #[test]
    fn mining_takes_the_highest_scoring_negatives_left_out() {
        let labels = [true, false, false, false, false, false];
        let scores = [3.0, 0.5, 2.0, -0.5, -1.5, 1.0];
        // 2 is already chosen; 4 is beyond the margin; the positive is never mined.
        assert_eq!(
            hardest_negatives(&labels, &[0, 2], &scores, 10),
            vec![5, 1, 3]
        );
        assert_eq!(hardest_negatives(&labels, &[0, 2], &scores, 2), vec![5, 1]);
        assert!(hardest_negatives(&labels, &[0, 1, 2, 3, 5], &scores, 10).is_empty());
    }
}
