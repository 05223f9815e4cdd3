//! The two traits that separate *what* is fitted from *how* it is fitted robustly.
//!
//! Following the shape of rust-cv's `sample-consensus` crate (and kornia-rs's RANSAC), a
//! [`Model`] only knows its residual for a datum, and an [`Estimator`] only knows how to build
//! models from a minimal sample. The consensus loops ([`crate::Msac`], [`crate::Ransac`]) know
//! neither geometry nor data layout, so a new shape is one estimator away.

/// A fitted model that can measure how far a datum is from it.
pub trait Model<D> {
    /// Non-negative residual of `datum` (for the shapes here: point-to-surface distance, metres).
    ///
    /// `NaN` or infinity means "certainly an outlier"; consensus loops truncate it to the cost
    /// threshold.
    fn distance(&self, datum: &D) -> f64;
}

/// Builds models of one kind from minimal samples of data of type `D`.
pub trait Estimator<D> {
    /// The model this estimator produces.
    type Model: Model<D> + Clone;

    /// Number of data in a minimal sample (4 for a sphere, 2 oriented points for a cylinder).
    fn min_samples(&self) -> usize;

    /// A model through the data of a minimal sample (`sample.len() == min_samples()`), or `None`
    /// when the sample is degenerate or the model fails [`Estimator::is_model_valid`].
    fn estimate(&self, sample: &[&D]) -> Option<Self::Model>;

    /// Whether a datum can take part at all (finite position, a normal where one is needed).
    /// Consensus loops skip invalid data instead of failing.
    fn is_datum_valid(&self, datum: &D) -> bool;

    /// Model validity hook, for example fruit-size priors on the radius. Models failing it are
    /// discarded before their cost is evaluated.
    fn is_model_valid(&self, _model: &Self::Model) -> bool {
        true
    }

    /// Residual used by the consensus cost. Defaults to [`Model::distance`]; estimators may add
    /// checks the bare geometry does not know about (e.g. a maximum normal deviation).
    fn residual(&self, model: &Self::Model, datum: &D) -> f64 {
        model.distance(datum)
    }

    /// Optional least-squares refinement on the inliers (indices into `data`). `None` means
    /// "no refinement available or it failed"; the caller keeps the unrefined model.
    fn refine(&self, _model: &Self::Model, _data: &[D], _inliers: &[usize]) -> Option<Self::Model> {
        None
    }

    /// Last touch on the chosen model given its final inliers (for example a cylinder's extent
    /// along its axis). Defaults to the model unchanged.
    fn finish(&self, model: Self::Model, _data: &[D], _inliers: &[usize]) -> Self::Model {
        model
    }
}
