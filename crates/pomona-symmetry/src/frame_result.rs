//! What one run of a box detector on a frame reports besides its detections: whether the
//! highlight pruning ran and how many boxes each step kept — for reports, benches and the
//! seed-000 tables.

use pomona_core::Detection;

/// Whether and how the highlight pruning ran on a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PruningState {
    /// Pruning ran; boxes were restricted to this fraction of the image.
    Applied {
        /// Fraction of pixels inside the mask.
        kept_fraction: f64,
        /// Highlight markers found.
        markers: usize,
    },
    /// Pruning is disabled in the parameters.
    Disabled,
    /// The frame has no colour image, so pruning is off (depth-only operation).
    NoColor,
}

/// Everything a detector found in a frame, for reports and benches.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameResult {
    /// Merged detections, best first.
    pub detections: Vec<Detection>,
    /// Pruning outcome.
    pub pruning: PruningState,
    /// Boxes that passed early rejection.
    pub boxes: usize,
    /// Boxes given the full reference frame, features and classifier (fewer than `boxes` when
    /// the cascade dropped some).
    pub searched: usize,
    /// Boxes scoring at least `merging.min_score`, before merging.
    pub positives: usize,
}
