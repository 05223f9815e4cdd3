//! # pomona-shapefit
//!
//! The `shape-fit` detector of seed 002 (Lin et al. 2019): a naive-Bayes colour mask in HSV,
//! region growing on the masked depth image, repeated MSAC sphere/cylinder fitting per cluster,
//! the 66-D GPCD descriptor and an RBF SVM that keeps fruit and rejects leaves. It outputs a
//! fitted shape per fruit, so a robot gets the centre, the diameter and, for cylinders
//! (eggplants), the axis.
//!
//! Each stage is its own type behind [`pomona_pipeline::Stage`] (see [`stages`]); the
//! [`ShapeFitPipeline`] trains a [`pomona_learn::ModelFile`] and loads a detector from one.
//! Parameters default to the paper's values; where we depart from it, [`ShapeFitParams`] and the
//! stage docs say why.
//!
//! Training measures the size-dependent parameters on the annotated fruit instead of taking
//! them from the configuration ([`SizePrior`], `size_prior: from-truth`, the default; `fixed`
//! keeps the configured values): radius ranges, which shapes to fit, the depth limit and a
//! depth-scaled minimum cluster size; it also learns a [`RadiusCalibration`] that replaces each
//! fitted sphere's poorly observed radius and refits its centre. Truth marked incomplete
//! (`"complete": false`) does not turn every unmatched candidate into a negative: candidates
//! that could be unannotated fruit are left out of training (see `docs/learning-and-evaluation.md`).
//!
//! Two additions for scenes the models were not tuned on: **depth proposals**
//! ([`DepthProposalParams`]) offer fruit-sized depth-only clusters the colour mask missed (green
//! fruit among green leaves) to the same shape fit and classifier, and training mines **hard
//! negatives** (`hard_negative_rounds`) among the candidates a random cap left out. Opt-in,
//! pairs of depth proposals that a leaf in front cut out of one fruit are proposed as one too
//! ([`PieceJoining`]).

mod candidate;
mod cluster_lattice;
mod color_model;
mod curvature_check;
mod depth_proposals;
mod gpcd;
mod negative_selection;
mod oversized_split;
mod params;
mod piece_joining;
mod pipeline;
mod region_growing;
mod size_prior;
pub mod stages;

pub use candidate::Candidate;
pub use cluster_lattice::ClusterLattice;
pub use color_model::{ColorBayes, ColorBayesParams, ColorHistograms, ColorLut};
pub use curvature_check::CurvatureCheck;
pub use depth_proposals::DepthProposalParams;
pub use gpcd::{gpcd, GpcdParams, HueStatistics, GPCD_LEN};
pub use negative_selection::MINING_MIN_SCORE;
pub use oversized_split::OversizedSplit;
pub use params::{
    CoaxialMergeParams, LabelRule, ShapeFitParams, BUILT_IN_DOUBLE_CURVATURE_PATCH_RADII,
};
pub use piece_joining::PieceJoining;
pub use pipeline::{ShapeFitDetector, ShapeFitPipeline, ShapeFitStageParams, PIPELINE_NAME};
pub use pomona_consensus::{fit_center_fixed_radius, RadiusCalibration, MIN_CALIBRATION_SAMPLES};
/// Re-exported from pomona-core, where the one RGB → HSV conversion lives.
pub use pomona_core::rgb_to_hsv;
pub use region_growing::{grow_regions, grow_regions_over, MinFruitArea, RegionGrowingParams};
pub use size_prior::{
    SizePrior, SizePriorMode, DEPTH_MARGIN, ELONGATED_RATIO, MIN_VISIBLE_FRACTION, RADIUS_MARGIN,
};
