//! The stages of the detector, each behind [`pomona_pipeline::Stage`] so it can be timed,
//! benchmarked or replaced alone: seed 002's colour mask → region growing → back-projection →
//! MSAC shapes → GPCD → SVM, and our depth proposals with their screen, which feed more clusters
//! to the same MSAC stage, and the free-space and curvature checks of the shapes.

use pomona_consensus::nalgebra::Point3;
use pomona_consensus::{OrientedPoint, RepeatLimits, ShapeExtractionParams, WindowNormals};
use pomona_core::{ColorImage, PointCloud, RgbdFrame};
use pomona_learn::BatchedClassifier;
use pomona_pipeline::{run_stage, FreeSpaceCheck, PipelineError, Stage, StageTimings};
use rayon::prelude::*;

use crate::candidate::cores_within_larger_radius;
use crate::{
    gpcd, grow_regions, grow_regions_over, Candidate, ClusterLattice, ColorLut, CurvatureCheck,
    DepthProposalParams, GpcdParams, PieceJoining, RegionGrowingParams, ShapeFitParams,
};

/// Colour posterior ≥ threshold and depth within range (Eq. 2, then the masked depth image).
/// Without a colour model (depth-only data) only the depth range is applied.
#[derive(Debug, Clone)]
pub struct ColorMaskStage {
    /// The compiled posterior, `None` for depth-only models.
    pub lut: Option<ColorLut>,
    /// Posterior threshold (paper: 0.1).
    pub threshold: f32,
    /// Far limit, metres.
    pub max_depth_m: f32,
}

impl ColorMaskStage {
    /// The depth range alone: every pixel with depth up to `max_depth_m`, no colour model.
    pub fn depth_range(max_depth_m: f64) -> Self {
        Self {
            lut: None,
            threshold: 0.0,
            max_depth_m: max_depth_m as f32,
        }
    }
}

impl Stage<&RgbdFrame, Vec<bool>> for ColorMaskStage {
    fn name(&self) -> &'static str {
        "colour-mask"
    }

    fn run(&self, frame: &RgbdFrame) -> Result<Vec<bool>, PipelineError> {
        let depth = frame.depth().as_slice();
        let in_range = |d: f32| d.is_finite() && d <= self.max_depth_m;
        match (&self.lut, frame.color()) {
            (Some(lut), Some(color)) => Ok(depth
                .iter()
                .zip(color.pixels())
                .map(|(&d, rgb)| in_range(d) && lut.posterior(rgb) >= self.threshold)
                .collect()),
            (Some(_), None) => Err(PipelineError::MissingColor {
                pipeline: crate::PIPELINE_NAME,
            }),
            (None, _) => Ok(depth.iter().map(|&d| in_range(d)).collect()),
        }
    }
}

/// Region growing on the masked depth image.
pub struct RegionGrowingStage {
    /// Step and size limits.
    pub params: RegionGrowingParams,
}

impl<'a> Stage<(&'a RgbdFrame, &'a [bool]), Vec<Vec<usize>>> for RegionGrowingStage {
    fn name(&self) -> &'static str {
        "region-growing"
    }

    fn run(
        &self,
        (frame, keep): (&'a RgbdFrame, &'a [bool]),
    ) -> Result<Vec<Vec<usize>>, PipelineError> {
        let cam = frame.camera();
        Ok(grow_regions(
            cam.width as usize,
            cam.height as usize,
            cam.fx,
            frame.depth().as_slice(),
            keep,
            &self.params,
        ))
    }
}

/// Pairs of clusters that may be pieces of one fruit, as one cluster each (not in the paper; see
/// [`PieceJoining`]); the caller adds them to the clusters it joined.
#[derive(Debug, Clone, Copy)]
pub struct PieceJoiningStage {
    /// The joining rule.
    pub joining: PieceJoining,
    /// Radius of the largest fruit any shape may fit, metres.
    pub max_radius_m: f64,
}

impl<'a> Stage<(&'a RgbdFrame, &'a [Vec<usize>]), Vec<Vec<usize>>> for PieceJoiningStage {
    fn name(&self) -> &'static str {
        "piece-joining"
    }

    fn run(
        &self,
        (frame, clusters): (&'a RgbdFrame, &'a [Vec<usize>]),
    ) -> Result<Vec<Vec<usize>>, PipelineError> {
        let cam = frame.camera();
        Ok(self.joining.joined(
            clusters,
            cam.width as usize,
            frame.depth().as_slice(),
            cam.fx,
            self.max_radius_m,
        ))
    }
}

/// Depth-only clusters for fruit the colour mask misses (not in the paper; see
/// [`DepthProposalParams`]): region growing on every pixel in depth range, keeping the clusters
/// the proposal tests pass. Its input is the colour mask, to leave what it covers to the colour
/// path.
pub struct DepthProposalStage {
    /// The proposal tests.
    pub params: DepthProposalParams,
    /// The depth range alone (a mask stage without a colour model).
    pub in_range: ColorMaskStage,
    /// Region growing, as for the colour mask's clusters.
    pub regions: RegionGrowingStage,
    /// Smallest and largest radius any shape may fit, metres: the sizes of the smallest and the
    /// largest fruit.
    pub radius_range_m: (f64, f64),
    /// Pairs of clusters that may be pieces of one fruit, proposed as one too (when on).
    pub joining: Option<PieceJoiningStage>,
}

impl DepthProposalStage {
    /// The depth proposals of a model with parameters `p`: its proposal tests, depth limit and
    /// region growing, and the radius range of its sphere and cylinder estimators together.
    pub fn of_params(p: &ShapeFitParams) -> Self {
        let (sphere, cylinder) = (
            p.shapes.sphere.radius_range_m,
            p.shapes.cylinder.radius_range_m,
        );
        let radius_range_m = (sphere.0.min(cylinder.0), sphere.1.max(cylinder.1));
        Self {
            params: p.depth_proposals,
            in_range: ColorMaskStage::depth_range(p.max_depth_m),
            // Never split here: see `OversizedSplit` ("Where it runs").
            regions: RegionGrowingStage {
                params: RegionGrowingParams {
                    split_oversized: None,
                    ..p.regions
                },
            },
            radius_range_m,
            joining: p
                .depth_proposals
                .join_pieces
                .map(|joining| PieceJoiningStage {
                    joining,
                    max_radius_m: radius_range_m.1,
                }),
        }
    }
}

/// A frame's depth proposals (pixel indices per cluster).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct DepthProposals {
    /// The depth clusters proposed.
    pub clusters: Vec<Vec<usize>>,
    /// Clusters grown again from the pixels outside the colour mask of depth clusters the
    /// colour path covers (`regrow_covered`), proposed under the same tests: a shape fitted to
    /// one counts only when no colour-path shape lies on the same fruit
    /// ([`drop_pieces_of_colour_fruit`]).
    pub regrown: Vec<Vec<usize>>,
}

impl<'a> Stage<(&'a RgbdFrame, &'a [bool]), DepthProposals> for DepthProposalStage {
    fn name(&self) -> &'static str {
        "depth-proposals"
    }

    fn run(
        &self,
        (frame, color_mask): (&'a RgbdFrame, &'a [bool]),
    ) -> Result<DepthProposals, PipelineError> {
        let in_range = self.in_range.run(frame)?;
        let clusters = self.regions.run((frame, in_range.as_slice()))?;
        let (cam, depth) = (frame.camera(), frame.depth().as_slice());
        let (fx, width, height) = (cam.fx, cam.width as usize, cam.height as usize);
        let fruit_sized = |c: &Vec<usize>| {
            !c.is_empty() && self.params.fruit_sized(c, depth, fx, self.radius_range_m)
        };
        // Pieces are joined from every cluster, covered or not, and face the full test.
        let pieces = match &self.joining {
            Some(joining) => joining.run((frame, clusters.as_slice()))?,
            None => Vec::new(),
        };
        let (mut proposed, mut regrown) = (Vec::new(), Vec::new());
        for cluster in clusters {
            if !self.params.covered(&cluster, color_mask) {
                if fruit_sized(&cluster) {
                    proposed.push(cluster);
                }
            } else if self.params.regrow_covered {
                // Its pixels outside the mask, grown on their own: pixels of two depth
                // clusters are never joined by growing (they would be one cluster), and none
                // of them is in the mask, so only the size test is left.
                let rest: Vec<usize> = cluster
                    .into_iter()
                    .filter(|&i| !color_mask.get(i).copied().unwrap_or(true))
                    .collect();
                regrown.extend(
                    grow_regions_over(width, height, fx, depth, &rest, &self.regions.params)
                        .into_iter()
                        .filter(fruit_sized),
                );
            }
        }
        proposed.extend(pieces.into_iter().filter(|c| {
            self.params
                .proposes(c, color_mask, depth, fx, self.radius_range_m)
        }));
        Ok(DepthProposals {
            clusters: proposed,
            regrown,
        })
    }
}

/// The classifier's first look at each depth proposal, before the shape fit pays for it (not in
/// the paper; see [`DepthProposalParams::screen_min_score`]): the GPCD of at most
/// `gpcd.max_points` evenly strided pixels of the whole cluster, with their normals, scored by
/// the detector's own SVM. Clusters scoring below `min_score` are dropped.
pub struct ProposalScreenStage {
    /// Normal estimation, as in the shape stage (scaled to each frame's focal length).
    pub normals: WindowNormals,
    /// The descriptor, with the screen's (smaller) point budget.
    pub gpcd: GpcdParams,
    /// Whether the model uses colour.
    pub use_color: bool,
    /// The detector's classifier.
    pub svm: BatchedClassifier,
    /// Lowest score kept.
    pub min_score: f64,
}

impl ProposalScreenStage {
    /// The classifier's score of each of `clusters` (pixel indices of `frame`), in order: what
    /// the screen compares with `min_score`.
    ///
    /// # Errors
    /// Those of the descriptor and the classifier.
    pub fn scores(
        &self,
        frame: &RgbdFrame,
        cloud: &PointCloud,
        clusters: &[Vec<usize>],
    ) -> Result<Vec<f64>, PipelineError> {
        let color = if self.use_color { frame.color() } else { None };
        let normals = self.normals.for_focal(frame.camera().fx);
        let features: Result<Vec<Vec<f64>>, PipelineError> = clusters
            .par_iter()
            .map(|cluster| {
                let pixels = self.gpcd.sample(cluster);
                let colors = pixel_colors(color, &pixels);
                sampled_gpcd(cloud, &normals, &pixels, &colors, &self.gpcd)
            })
            .collect();
        let features = features?;
        let rows: Vec<&[f64]> = features.iter().map(Vec::as_slice).collect();
        Ok(self.svm.decision_values(&rows)?)
    }

    /// The `clusters` whose `scores` (from [`Self::scores`], in order) reach `min_score`.
    pub fn passing(&self, clusters: &[Vec<usize>], scores: &[f64]) -> Vec<Vec<usize>> {
        clusters
            .iter()
            .zip(scores)
            .filter(|(_, &s)| s >= self.min_score)
            .map(|(c, _)| c.clone())
            .collect()
    }
}

impl<'a> Stage<(&'a RgbdFrame, &'a PointCloud, &'a [Vec<usize>]), Vec<Vec<usize>>>
    for ProposalScreenStage
{
    fn name(&self) -> &'static str {
        "proposal-screen"
    }

    fn run(
        &self,
        (frame, cloud, clusters): (&'a RgbdFrame, &'a PointCloud, &'a [Vec<usize>]),
    ) -> Result<Vec<Vec<usize>>, PipelineError> {
        let scores = self.scores(frame, cloud, clusters)?;
        Ok(self.passing(clusters, &scores))
    }
}

/// Drops from `regrown` (shapes fitted to [`DepthProposals::regrown`]) every shape that lies on
/// a fruit of a shape in `colour` (the colour path's): one core within the other's radius (see
/// `cores_within_larger_radius`, the merging's rule too), a piece of that fruit rather than a
/// fruit beside it. Unlike the merging, the colour shape wins whatever the scores say.
pub fn drop_pieces_of_colour_fruit(colour: &[Candidate], regrown: &mut Vec<Candidate>) {
    regrown.retain(|c| {
        !colour
            .iter()
            .any(|k| cores_within_larger_radius(&k.shape, &c.shape))
    });
}

/// Back-projection of the frame to an organised point cloud (Eq. 3), once per frame for every
/// stage that needs points.
pub struct BackProjectionStage;

impl<'a> Stage<&'a RgbdFrame, PointCloud> for BackProjectionStage {
    fn name(&self) -> &'static str {
        "back-projection"
    }

    fn run(&self, frame: &'a RgbdFrame) -> Result<PointCloud, PipelineError> {
        Ok(frame.to_cloud_without_color())
    }
}

/// PCA normals (only when the estimators read them, [`ShapeExtractionParams::uses_normals`])
/// and repeated MSAC per cluster (Algorithm 1). Clusters
/// run in parallel; each uses its own seed derived from the base seed and its index, so the
/// result does not depend on the number of threads.
pub struct ShapeStage {
    /// Normal estimation, scaled to each frame's focal length
    /// ([`WindowNormals::for_focal`]).
    pub normals: WindowNormals,
    /// MSAC, estimators, limits and base seed.
    pub shapes: ShapeExtractionParams,
    /// The pixel lattice clusters are thinned to first.
    pub lattice: ClusterLattice,
}

fn err(e: pomona_consensus::ConsensusError) -> PipelineError {
    PipelineError::InvalidParameter {
        name: "shapes".into(),
        reason: e.to_string(),
    }
}

impl ShapeStage {
    fn cluster_candidates(
        &self,
        normals: &WindowNormals,
        cloud: &PointCloud,
        k: usize,
        cluster: &[usize],
        step: usize,
    ) -> Result<Vec<Candidate>, PipelineError> {
        let positions = positions(cloud, cluster);
        let normals = if self.shapes.uses_normals() {
            Some(normals.estimate_at(cloud, cluster).map_err(err)?)
        } else {
            None
        };
        let oriented: Vec<OrientedPoint> = match &normals {
            Some(normals) => OrientedPoint::zip(&positions, normals),
            None => positions
                .iter()
                .map(|&p| OrientedPoint::without_normal(p))
                .collect(),
        };
        // Point counts on a thinned cluster stand for `step²` pixels each.
        let limits = self.shapes.limits;
        let area = step * step;
        let params = ShapeExtractionParams {
            seed: self.shapes.seed ^ (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
            limits: RepeatLimits {
                min_points: limits.min_points.div_ceil(area),
                min_inliers: limits.min_inliers.div_ceil(area),
                ..limits
            },
            ..self.shapes
        };
        let extracted = params
            .check()
            .map_err(err)?
            .extract(&oriented)
            .map_err(err)?;
        Ok(extracted
            .into_iter()
            .map(|e| Candidate {
                shape: e.model,
                pixels: e.inliers.iter().map(|&i| cluster[i]).collect(),
                points: e.inliers.iter().map(|&i| positions[i]).collect(),
                normals: normals
                    .as_ref()
                    .map(|n| e.inliers.iter().map(|&i| n[i]).collect()),
            })
            .collect())
    }
}

impl<'a> Stage<(&'a RgbdFrame, &'a PointCloud, &'a [Vec<usize>]), Vec<Candidate>> for ShapeStage {
    fn name(&self) -> &'static str {
        "msac-shapes"
    }

    fn run(
        &self,
        (frame, cloud, clusters): (&'a RgbdFrame, &'a PointCloud, &'a [Vec<usize>]),
    ) -> Result<Vec<Candidate>, PipelineError> {
        let normals = self.normals.for_focal(frame.camera().fx);
        let step = self.lattice.step(frame.camera().fx);
        let width = frame.camera().width as usize;
        let per_cluster: Result<Vec<Vec<Candidate>>, PipelineError> = clusters
            .par_iter()
            .enumerate()
            .map(|(k, c)| {
                let thinned = ClusterLattice::thin(step, width, c);
                self.cluster_candidates(&normals, cloud, k, &thinned, step)
            })
            .collect();
        Ok(per_cluster?.into_iter().flatten().collect())
    }
}

/// The colours of row-major `pixels` of `image` (none without an image).
pub(crate) fn pixel_colors(image: Option<&ColorImage>, pixels: &[usize]) -> Vec<[u8; 3]> {
    let Some(img) = image else {
        return Vec::new();
    };
    let w = img.width() as usize;
    pixels
        .iter()
        .filter_map(|&i| img.get((i % w) as u32, (i / w) as u32))
        .collect()
}

/// Drops the candidates the camera sees through: a shape whose centre has the seen depth behind
/// it ([`FreeSpaceCheck`]; not in the paper). A loaded detector runs it on the shapes before the
/// descriptor; training does not, so a model learns from every shape as seed 002's does (with
/// the check in training too, 16-frame models moved by ±0.07 AP either way on the cross-domain
/// matrix, docs/results.md, "Free-space check").
pub struct FreeSpaceStage {
    /// The check and its limits.
    pub check: FreeSpaceCheck,
}

impl<'a> Stage<(&'a RgbdFrame, Vec<Candidate>), Vec<Candidate>> for FreeSpaceStage {
    fn name(&self) -> &'static str {
        "free-space"
    }

    fn run(
        &self,
        (frame, mut candidates): (&'a RgbdFrame, Vec<Candidate>),
    ) -> Result<Vec<Candidate>, PipelineError> {
        self.check.retain_admitted(frame, &mut candidates, |c| {
            (c.shape.center(), c.shape.radius_m())
        });
        Ok(candidates)
    }
}

/// Drops the candidates a plane explains about as well as their shape ([`CurvatureCheck`]). A
/// loaded detector runs it on the shapes before the descriptor, after the free-space check.
pub struct CurvatureStage {
    /// The check and its limit.
    pub check: CurvatureCheck,
}

impl Stage<Vec<Candidate>, Vec<Candidate>> for CurvatureStage {
    fn name(&self) -> &'static str {
        "curvature"
    }

    fn run(&self, mut candidates: Vec<Candidate>) -> Result<Vec<Candidate>, PipelineError> {
        candidates.retain(|c| self.check.admits(&c.shape, &c.points));
        Ok(candidates)
    }
}

/// Where the cluster a shape was fitted to came from, which decides the free-space check the
/// shape faces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShapeSource {
    /// The colour mask's clusters: the model's `free_space`.
    ColourMask,
    /// The depth proposals: `depth_proposals.free_space`, else the model's.
    DepthProposal,
}

/// The checks a loaded detector runs on the shapes before the descriptor, in its order: the
/// free space, then the curvature. One place for which checks a model's parameters switch on,
/// so that what inspects the detector's candidates (the `trace_lost_fruit` example) runs exactly
/// the detector's checks. Training runs none ([`ShapeChecks::default`]).
#[derive(Default)]
pub struct ShapeChecks {
    /// The free-space check, when switched on.
    pub free_space: Option<FreeSpaceStage>,
    /// The free-space check of the depth proposals' shapes, when switched on
    /// (`depth_proposals.free_space`, else the one above).
    pub proposal_free_space: Option<FreeSpaceStage>,
    /// The curvature check, when the model has one.
    pub curvature: Option<CurvatureStage>,
}

impl ShapeChecks {
    /// The checks `params` switch on.
    ///
    /// # Errors
    /// [`PipelineError::InvalidParameter`] naming a setting that cannot run
    /// ([`ShapeFitParams::problem`], the checks' own included).
    pub fn of_params(params: &ShapeFitParams) -> Result<Self, PipelineError> {
        usable(params.problem())?;
        let stage = |check: FreeSpaceCheck| check.enabled.then_some(FreeSpaceStage { check });
        Ok(Self {
            free_space: stage(params.free_space),
            proposal_free_space: stage(
                params
                    .depth_proposals
                    .free_space
                    .unwrap_or(params.free_space),
            ),
            curvature: params.curvature.map(|check| CurvatureStage { check }),
        })
    }

    /// `shapes` fitted to clusters from `source` less those the checks refuse: the
    /// free-space check of that source, then the curvature check.
    ///
    /// # Errors
    /// Those of the stages (none at present).
    pub fn admitted(
        &self,
        source: ShapeSource,
        frame: &RgbdFrame,
        shapes: Vec<Candidate>,
        t: &mut StageTimings,
    ) -> Result<Vec<Candidate>, PipelineError> {
        let free_space = match source {
            ShapeSource::ColourMask => &self.free_space,
            ShapeSource::DepthProposal => &self.proposal_free_space,
        };
        let shapes = match free_space {
            Some(check) => run_stage(check, (frame, shapes), t)?,
            None => shapes,
        };
        match &self.curvature {
            Some(check) => run_stage(check, shapes, t),
            None => Ok(shapes),
        }
    }
}

/// [`ShapeFitParams::problem`] — `(name under params., what is wrong)` — as an error naming
/// the setting.
pub(crate) fn usable(problem: Option<(String, String)>) -> Result<(), PipelineError> {
    match problem {
        Some((name, reason)) => Err(PipelineError::InvalidParameter {
            name: format!("params.{name}"),
            reason,
        }),
        None => Ok(()),
    }
}

/// The positions of row-major `pixels` of the organised `cloud`, widened to `f64`.
fn positions(cloud: &PointCloud, pixels: &[usize]) -> Vec<Point3<f64>> {
    pixels
        .iter()
        .map(|&i| cloud.points()[i].cast::<f64>())
        .collect()
}

/// The GPCD of the already sampled `pixels` ([`GpcdParams::sample`]) of `cloud`, with window
/// normals estimated at those pixels only, and the colour moments of `colors`. Equal to
/// [`gpcd`] of all the pixels with all their normals: the descriptor pairs only the sample.
fn sampled_gpcd(
    cloud: &PointCloud,
    normals: &WindowNormals,
    pixels: &[usize],
    colors: &[[u8; 3]],
    params: &GpcdParams,
) -> Result<Vec<f64>, PipelineError> {
    let normals = normals.estimate_at(cloud, pixels).map_err(err)?;
    Ok(gpcd(&positions(cloud, pixels), &normals, colors, params).to_vec())
}

/// The GPCD of every candidate (colour terms zero when `use_color` is off). A candidate that
/// comes without normals gets window normals at the points the descriptor samples.
pub struct DescriptorStage {
    /// Descriptor parameters.
    pub params: GpcdParams,
    /// Whether the model uses colour.
    pub use_color: bool,
    /// Normal estimation, as in the shape stage (scaled to each frame's focal length).
    pub normals: WindowNormals,
}

impl<'a> Stage<(&'a RgbdFrame, &'a PointCloud, &'a [Candidate]), Vec<Vec<f64>>>
    for DescriptorStage
{
    fn name(&self) -> &'static str {
        "gpcd"
    }

    fn run(
        &self,
        (frame, cloud, candidates): (&'a RgbdFrame, &'a PointCloud, &'a [Candidate]),
    ) -> Result<Vec<Vec<f64>>, PipelineError> {
        let color = if self.use_color { frame.color() } else { None };
        let normals = self.normals.for_focal(frame.camera().fx);
        candidates
            .par_iter()
            .map(|c| {
                let colors = pixel_colors(color, &c.pixels);
                match &c.normals {
                    Some(n) => Ok(gpcd(&c.points, n, &colors, &self.params).to_vec()),
                    None => {
                        let pixels = self.params.sample(&c.pixels);
                        sampled_gpcd(cloud, &normals, &pixels, &colors, &self.params)
                    }
                }
            })
            .collect()
    }
}

/// SVM decision values of the descriptors.
pub struct ClassifierStage {
    /// The trained classifier (scaler included).
    pub svm: BatchedClassifier,
}

impl<'a> Stage<&'a [Vec<f64>], Vec<f64>> for ClassifierStage {
    fn name(&self) -> &'static str {
        "svm"
    }

    fn run(&self, features: &'a [Vec<f64>]) -> Result<Vec<f64>, PipelineError> {
        let rows: Vec<&[f64]> = features.iter().map(Vec::as_slice).collect();
        Ok(self.svm.decision_values(&rows)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_consensus::WindowNormalParams;
    use pomona_core::{DepthImage, PinholeCamera};
    use pomona_learn::SvmClassifier;

    #[test]
    fn a_fruit_the_colour_mask_missed_is_regrown_from_the_cluster_of_one_it_found() {
        // Two fruit touching at 1 m before a background out of range (3 m): a 12 px disc the
        // colour mask holds and a 9 px disc beside it that it misses. Region growing on depth
        // joins them; the colour mask covers most of the union, so it is left to the colour
        // path and the missed fruit is only found grown again from the uncovered pixels.
        let (w, h) = (80_usize, 40_usize);
        let cam = PinholeCamera::new(w as u32, h as u32, 200.0, 200.0, 39.5, 19.5).unwrap();
        let in_disc = |i: usize, (cx, cy, r): (f64, f64, f64)| {
            let (u, v) = ((i % w) as f64 - cx, (i / w) as f64 - cy);
            u * u + v * v <= r * r
        };
        let (found, missed) = ((26.0, 20.0, 12.0), (46.0, 20.0, 9.0));
        let raw: Vec<u16> = (0..w * h)
            .map(|i| {
                if in_disc(i, found) || in_disc(i, missed) {
                    1000
                } else {
                    3000
                }
            })
            .collect();
        let frame = RgbdFrame::new(
            cam,
            DepthImage::from_u16(w as u32, h as u32, &raw, 0.001).unwrap(),
            None,
        )
        .unwrap();
        let color_mask: Vec<bool> = (0..w * h).map(|i| in_disc(i, found)).collect();
        let stage = |regrow_covered| DepthProposalStage {
            params: DepthProposalParams {
                regrow_covered,
                ..DepthProposalParams::default()
            },
            in_range: ColorMaskStage::depth_range(2.0),
            regions: RegionGrowingStage {
                params: RegionGrowingParams::default(),
            },
            radius_range_m: (0.015, 0.08),
            joining: None,
        };
        let missed_pixels: Vec<usize> = (0..w * h)
            .filter(|&i| in_disc(i, missed) && !color_mask[i])
            .collect();
        let on = stage(true).run((&frame, color_mask.as_slice())).unwrap();
        assert!(on.clusters.is_empty(), "the union is the colour path's");
        assert_eq!(on.regrown.len(), 1);
        let mut regrown = on.regrown[0].clone();
        regrown.sort_unstable();
        assert_eq!(regrown, missed_pixels);
        let off = stage(false).run((&frame, color_mask.as_slice())).unwrap();
        assert_eq!(off, DepthProposals::default());
    }

    #[test]
    fn the_depth_proposals_never_split_oversized_clusters() {
        // A model that splits: its colour path does, its proposals over every pixel in range
        // grow with the same step but leave the canopy whole (see `OversizedSplit`).
        let mut p = ShapeFitParams::default();
        p.regions.split_oversized = Some(crate::OversizedSplit::for_radius(0.06));
        let proposals = DepthProposalStage::of_params(&p);
        assert_eq!(proposals.regions.params.split_oversized, None);
        assert_eq!(
            proposals.regions.params,
            RegionGrowingParams {
                split_oversized: None,
                ..p.regions
            }
        );
        assert!(p.regions.split_oversized.is_some());
    }

    #[test]
    fn regrown_shapes_on_a_colour_path_fruit_are_dropped() {
        let ball = |x: f64, r: f64| Candidate {
            shape: pomona_consensus::Shape::Sphere(pomona_consensus::Sphere {
                center: Point3::new(x, 0.0, 1.0),
                radius_m: r,
            }),
            pixels: Vec::new(),
            points: Vec::new(),
            normals: None,
        };
        let colour = [ball(0.0, 0.035)];
        // A piece of the colour path's fruit (20 mm from its centre) and a fruit touching it.
        let mut regrown = vec![ball(0.02, 0.025), ball(0.065, 0.03)];
        drop_pieces_of_colour_fruit(&colour, &mut regrown);
        assert_eq!(regrown, vec![ball(0.065, 0.03)]);
    }

    #[test]
    fn the_free_space_stage_drops_shapes_the_camera_sees_through() {
        // A wall at 1 m fills the view: a 40 mm ball claimed at 0.8 m would hide it.
        let cam = PinholeCamera::new(40, 40, 100.0, 100.0, 19.5, 19.5).unwrap();
        let depth = DepthImage::from_u16(40, 40, &[1000; 1600], 0.001).unwrap();
        let frame = RgbdFrame::new(cam, depth, None).unwrap();
        let ball = |z: f64| Candidate {
            shape: pomona_consensus::Shape::Sphere(pomona_consensus::Sphere {
                center: Point3::new(0.0, 0.0, z),
                radius_m: 0.04,
            }),
            pixels: Vec::new(),
            points: Vec::new(),
            normals: None,
        };
        let stage = |check| FreeSpaceStage { check };
        let kept = stage(FreeSpaceCheck::default())
            .run((&frame, vec![ball(0.8), ball(1.03)]))
            .unwrap();
        assert_eq!(kept, vec![ball(1.03)]);
        let all = stage(FreeSpaceCheck::off())
            .run((&frame, vec![ball(0.8), ball(1.03)]))
            .unwrap();
        assert_eq!(all.len(), 2);
    }

    #[test]
    fn depth_proposals_face_the_stricter_free_space_check() {
        // A 40 mm ball at 1 m (8 px image radius) whose disc reads its near side (0.97 m)
        // except on a ring 0.4–0.7 of the radius out, where gaps show a wall at 1.5 m: the
        // middle is opaque and the median leads, so the colour path's check admits it; a
        // proposal, whose readings behind the centre may be a tenth of the disc, is refused.
        let cam = PinholeCamera::new(80, 80, 200.0, 200.0, 39.5, 39.5).unwrap();
        let raw: Vec<u16> = (0..6400)
            .map(|i| {
                let (u, v) = ((i % 80) as f64 - 39.5, (i / 80) as f64 - 39.5);
                let rho = (u * u + v * v).sqrt() / 8.0;
                if (0.4..0.7).contains(&rho) {
                    1500
                } else if rho < 1.0 {
                    970
                } else {
                    1500
                }
            })
            .collect();
        let frame = RgbdFrame::new(
            cam,
            DepthImage::from_u16(80, 80, &raw, 0.001).unwrap(),
            None,
        )
        .unwrap();
        let ball = Candidate {
            shape: pomona_consensus::Shape::Sphere(pomona_consensus::Sphere {
                center: Point3::new(0.0, 0.0, 1.0),
                radius_m: 0.04,
            }),
            pixels: Vec::new(),
            points: Vec::new(),
            normals: None,
        };
        // The checks `params` switch on, less the curvature check (the ball has no points).
        let checks = |params: &ShapeFitParams| ShapeChecks {
            curvature: None,
            ..ShapeChecks::of_params(params).unwrap()
        };
        let admitted = |checks: &ShapeChecks, source| {
            checks
                .admitted(
                    source,
                    &frame,
                    vec![ball.clone()],
                    &mut StageTimings::default(),
                )
                .unwrap()
        };
        let fresh = checks(&ShapeFitParams::default());
        assert_eq!(
            admitted(&fresh, ShapeSource::ColourMask),
            vec![ball.clone()]
        );
        assert!(admitted(&fresh, ShapeSource::DepthProposal).is_empty());
        // Without a check of their own (older model files) proposals face the model's.
        let mut params = ShapeFitParams::default();
        params.depth_proposals.free_space = None;
        let older = checks(&params);
        assert_eq!(admitted(&older, ShapeSource::DepthProposal), vec![ball]);
    }

    #[test]
    fn the_screen_keeps_the_clusters_its_classifier_scores_high_enough() {
        // A 40×40 tilted plane at about 1 m, cut into two clusters.
        let cam = PinholeCamera::new(40, 40, 100.0, 100.0, 20.0, 20.0).unwrap();
        let raw: Vec<u16> = (0..1600).map(|i| 1000 + (i % 40) as u16).collect();
        let depth = DepthImage::from_u16(40, 40, &raw, 0.001).unwrap();
        let frame = RgbdFrame::new(cam, depth, None).unwrap();
        let clusters = vec![(0..800).collect::<Vec<usize>>(), (800..1600).collect()];
        let screen = |score: f64| ProposalScreenStage {
            normals: WindowNormalParams::default().check().unwrap(),
            gpcd: GpcdParams {
                max_points: 64,
                ..GpcdParams::default()
            },
            use_color: false,
            svm: BatchedClassifier::new(SvmClassifier::constant(crate::GPCD_LEN, score)).unwrap(),
            min_score: -1.0,
        };
        let cloud = frame.to_cloud();
        let run = |score: f64| screen(score).run((&frame, &cloud, &clusters)).unwrap();
        assert_eq!(run(-0.5), clusters);
        assert_eq!(run(-1.0).len(), 2);
        assert!(run(-1.5).is_empty());
    }
}
