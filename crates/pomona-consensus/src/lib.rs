//! # pomona-consensus
//!
//! Robust geometric fitting for the `shape-fit` detector (seed 002, "MSAC-based shape
//! detection"): generic sample-consensus traits, MSAC and RANSAC loops, sphere and cylinder
//! estimators with fruit-size priors, a plane estimator, repeated extraction of several shapes
//! from one cluster (Algorithm 1), and the PCA normals the cylinder estimator needs.
//!
//! The design follows rust-cv's `sample-consensus` and kornia-rs's RANSAC: algorithms are
//! separate from data. A [`Model`] measures residuals, an [`Estimator`] builds models from minimal
//! samples, a [`Sampler`] draws those samples, and a [`Consensus`] loop ([`Msac`], [`Ransac`])
//! ties them together without knowing any geometry.
//!
//! ## Conventions
//! * `f64` metres throughout; residuals are point-to-surface distances in metres, and the paper's
//!   millimetre thresholds are converted (T = 25 mm → `0.025`).
//! * Every parameter set is a plain struct with the paper's defaults and a `check()` that
//!   validates it into the runnable type.
//! * Every random draw comes from a seeded ChaCha stream: same seed, same result, on any thread
//!   count.
//! * Bad *points* (non-finite, or without a needed normal) are skipped, never an error.
//!
//! ## Example
//! ```
//! use pomona_consensus::{nalgebra::{Point3, Vector3}, OrientedPoint, ShapeExtractionParams};
//!
//! // A 40 mm fruit 0.8 m in front of the camera: the camera-facing hemisphere.
//! let centre = Point3::new(0.02, -0.01, 0.8);
//! let points: Vec<OrientedPoint> = (0..400)
//!     .map(|i| {
//!         let z = -(i as f64 + 0.5) / 400.0; // towards the camera
//!         let phi = i as f64 * 2.399_963; // golden angle spiral
//!         let s = (1.0 - z * z).sqrt();
//!         let n = Vector3::new(s * phi.cos(), s * phi.sin(), z);
//!         OrientedPoint::new(centre + n * 0.04, n)
//!     })
//!     .collect();
//!
//! let extractor = ShapeExtractionParams { seed: 7, ..Default::default() }.check()?;
//! let shapes = extractor.extract(&points)?;
//! assert_eq!(shapes.len(), 1);
//! assert!((shapes[0].model.center() - centre).norm() < 1e-6);
//! assert!((shapes[0].model.radius_m() - 0.04).abs() < 1e-6);
//! # Ok::<(), pomona_consensus::ConsensusError>(())
//! ```

mod consensus;
mod cylinder;
mod damped_step;
mod error;
mod estimator;
mod extraction;
mod kd_tree;
mod msac;
pub mod normals;
mod oriented_point;
mod plane;
mod radial_prior;
mod radius_calibration;
mod ransac;
mod sampler;
mod sphere;

pub use consensus::{Consensus, Fit};
pub use cylinder::{Cylinder, CylinderEstimator, CylinderEstimatorParams};
pub use error::ConsensusError;
pub use estimator::{Estimator, Model};
pub use extraction::{
    extract_repeated, Extracted, RepeatLimits, Shape, ShapeChoice, ShapeExtractionParams,
    ShapeExtractor,
};
pub use kd_tree::KdTree;
pub use msac::{Acceptance, CostFunction, Msac, MsacParams};
pub use normals::{KnnNormalParams, KnnNormals, WindowNormalParams, WindowNormals};
pub use oriented_point::{OrientedPoint, Positioned};
pub use plane::{Plane, PlaneEstimator};
pub use radius_calibration::{fit_center_fixed_radius, RadiusCalibration, MIN_CALIBRATION_SAMPLES};
pub use ransac::{Ransac, RansacParams};
pub use sampler::{Sampler, UniformSampler};
pub use sphere::{Sphere, SphereEstimator, SphereEstimatorParams};

/// Re-exported so callers name the same nalgebra version.
pub use nalgebra;
