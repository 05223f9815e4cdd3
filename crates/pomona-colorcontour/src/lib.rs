//! # pomona-colorcontour
//!
//! The `color-contour` detector of seed 004 (Plebe & Grasso 2001, the vision system of an
//! orange-picking robot): fruit colour in the HΣ plane (§3.1, [`hsigma`]) classified by a small
//! perceptron ([`Mlp`]) compiled into an exact lookup table ([`HSigmaLut`]); fruit circles from
//! the curvature of the mask's contours (§3.2: [`Contour`], [`arc_half_angle`] solves Eq. 8,
//! [`contour_circles`]), pruned by overlap ([`prune_overlapping`]) and by size; and, where the
//! frame has depth, each circle lifted to a 3D centre and diameter ([`sphere_from_depth`]). It
//! works on pieces of contour, so it finds oranges that leaves or neighbours hide in large part.
//!
//! Each step is a [`pomona_pipeline::Stage`] (see [`stages`]); [`ColorContourPipeline`] trains
//! a [`pomona_pipeline::ModelFile`] (the perceptron and the stage parameters in `stage_params`;
//! its SVM slot is empty: the score is contour support × colour purity) and loads a
//! [`ColorContourDetector`] from one. The built-in model is retrained by
//! `cargo run --release -p pomona-colorcontour --example train_color_contour_default`.
//!
//! Departures from the paper, each documented where it is made: the perceptron's size, scaling
//! and training schedule ([`Mlp`]); only outer borders followed, and contours smoothed
//! ([`Contour`]); concave and straight windows, the jump rule, wrap-around joining and the
//! support score ([`contour_circles`]); overlap relative to the smaller circle
//! ([`prune_overlapping`]); the size test before the overlap test, and 3D from depth instead of
//! stereo ([`stages::FruitStage`], [`sphere_from_depth`]). More, each a parameter whose
//! paper value restores the paper's step: hysteresis on the colour table ([`hysteresis_mask`]),
//! a closing of the mask ([`close_mask`]), least-squares circles of each group's contour points
//! ([`GroupCircle`], [`refine_circle`]), merging of arcs that lie on one circle
//! ([`merge_arcs`]), ranking overlapping circles by arc length ([`PruneRank`]) and taking them
//! for one fruit only when their centres are close ([`clash`]), circles voted for by every
//! outline pixel along its normal ([`hough_circles`], on by default) beside the edge fit's, for
//! outlines that leaves notch into arcs too short for its windows, and circles from rays cast
//! out of the mask's inscribed discs ([`ray_circles`], [`squared_distance_to_background`]; opt-in)
//! for fruit that touch or overlap. Not built here: stereo matching (§4).
//!
//! Tracking during the arm's approach (§3.3) is [`ApproachTracker`]: a 5×5 colour check at the
//! expected position, a four-direction edge scan and circle fit ([`scan_four_directions`],
//! [`circle_from_boundaries`]), and a rectangular spiral search with growing steps ([`spiral_points`]) when
//! the fruit is not where expected, with recovery after loss; it classifies pixels with a
//! model's colour table ([`ColorContourStageParams::color_table`]). Not in the paper: a local
//! re-detection with the detector's own stages on a window around the fruit ([`Redetect`],
//! [`ColorContourDetector::fitted_circles_in`]) where the four scans are in doubt.

mod arc_half_angle;
mod circle_in_space;
mod circle_least_squares;
mod circle_merging;
mod circle_pruning;
mod contour;
mod contour_circles;
mod depth_cut;
mod depth_spheres;
mod disc_share;
mod distance_transform;
mod edge_scan;
mod ellipse_fit;
mod hough_circles;
mod hsigma;
mod hsigma_lut;
mod local_maxima;
mod local_redetection;
mod mask_closing;
mod mask_hysteresis;
mod mask_runs;
mod mlp;
mod params;
mod patch_shift;
mod pipeline;
mod pixel_f1;
mod ray_circles;
mod spiral_search;
pub mod stages;
#[cfg(test)]
mod test_shapes;
mod tracking;
mod training_pixels;
mod window_reduce;

pub use arc_half_angle::{arc_half_angle, arc_radius};
pub use circle_in_space::{sphere_from_depth, sphere_from_size, SphereFromCircle};
pub use circle_least_squares::{fit_circle, refine_circle, rms_distance};
pub use circle_merging::merge_arcs;
pub use circle_pruning::{clash, disc_overlap_area, prune_overlapping, PruneRank};
pub use contour::{smooth_mask, trace_contours, Contour};
pub use contour_circles::{
    contour_arcs, contour_circles, ContourArc, ContourCircle, EdgeFitParams, GroupCircle,
};
pub use depth_cut::{cut_at_depth_steps, DepthCutParams};
pub use depth_spheres::{depth_sphere_circles, DepthSphereParams};
pub use distance_transform::squared_distance_to_background;
pub use edge_scan::{
    circle_from_boundaries, scan_four_directions, EdgeScanParams, ScanEnd, SCAN_DIRECTIONS,
};
pub use ellipse_fit::{fit_ellipse, Ellipse, EllipseFit};
pub use hough_circles::{hough_circles, HoughCircleParams};
pub use hsigma::{
    hsigma, hsigma_integers, hsigma_of_integers, intensity_level, intensity_of_level,
    network_inputs, INTENSITY_LEVELS,
};
pub use hsigma_lut::{quantise_probability, HSigmaLut};
pub use local_redetection::{most_consistent_circle, LocalRedetectParams, Redetect, SampledRegion};
pub use mask_closing::close_mask;
pub use mask_hysteresis::hysteresis_mask;
pub use mlp::{HSigmaSample, Mlp, MlpParams};
pub use params::{ColorContourParams, EXTRA_CIRCLE_SOURCE_KEYS};
pub use patch_shift::{PatchShiftParams, PatchTemplate};
pub use pipeline::{
    ColorContourDetector, ColorContourPipeline, ColorContourStageParams, PIPELINE_NAME,
};
pub use pixel_f1::{
    best_f1_threshold, for_each_labelled_pixel, pixel_counts, value_histograms, PixelCounts,
};
pub use ray_circles::{ray_circles, RayCircleParams};
pub use spiral_search::{spiral_points, SpiralParams};
pub use tracking::{ApproachTracker, TrackEstimate, TrackParams, TrackStatus, FRUIT_SHARE_GRID};
pub use training_pixels::{fruit_labels, taught_labels, training_pixels};
