//! Errors raised when a value cannot form a valid core type.

/// Why a core value was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CoreError {
    /// A camera parameter is not finite or not positive.
    #[error("camera parameter `{name}` must be finite and positive, got {value}")]
    InvalidCameraParameter {
        /// Parameter name as it appears in `camera.json`.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The lens distortion cannot be undone over the whole image: the radial map folds back (or
    /// the inversion does not converge) before the farthest image corner.
    #[error(
        "camera distortion k1 = {k1}, k2 = {k2} cannot be inverted over the image (it folds back \
         or does not converge by the normalised radius {radius:.3} of the farthest corner); \
         a real lens's coefficients keep it invertible there"
    )]
    DistortionNotInvertible {
        /// Second-order coefficient.
        k1: f64,
        /// Fourth-order coefficient.
        k2: f64,
        /// Normalised (distorted) radius of the image corner where it fails.
        radius: f64,
    },
    /// A buffer's length does not match the declared image or cloud size.
    #[error("{what}: expected {expected} elements for {width}x{height}, got {actual}")]
    SizeMismatch {
        /// Which buffer.
        what: &'static str,
        /// Declared width.
        width: u32,
        /// Declared height.
        height: u32,
        /// Elements implied by the declared size.
        expected: usize,
        /// Elements actually supplied.
        actual: usize,
    },
    /// Two images (or an image and the camera) that must have the same size do not.
    #[error("{what}: {a_w}x{a_h} does not match {b_w}x{b_h}")]
    DimensionsDisagree {
        /// Which pair.
        what: &'static str,
        /// First width.
        a_w: u32,
        /// First height.
        a_h: u32,
        /// Second width.
        b_w: u32,
        /// Second height.
        b_h: u32,
    },
    /// A depth unit that is not finite and positive.
    #[error("depth unit must be finite and positive, got {0}")]
    InvalidDepthUnit(f64),
    /// A vector that must be normalised has zero or non-finite length.
    #[error("{0} must be a finite non-zero vector")]
    DegenerateVector(&'static str),
    /// A bounding box whose corners are out of order or not finite.
    #[error("bounding box [{0}, {1}, {2}, {3}] must be finite with xmin <= xmax and ymin <= ymax")]
    InvalidBox(f64, f64, f64, f64),
    /// A voxel side that is not finite and positive, or too small for the cloud.
    #[error("voxel size {voxel_m} m {reason}")]
    InvalidVoxelSize {
        /// The offending side, metres.
        voxel_m: f64,
        /// What is wrong with it.
        reason: &'static str,
    },
}
