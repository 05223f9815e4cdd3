//! The `color-contour` pipeline: training (the colour perceptron on fruit and background pixels)
//! and the detector that chains the stages.

use pomona_core::{ColorImage, Detection, ImageCircle, PinholeCamera, RgbdFrame};
use pomona_learn::{ModelFile, SvmClassifier};
use pomona_pipeline::{
    may_have_untagged_fruit, params_from_json, params_to_json, run_stage, untagged_fruit_circles,
    Detector, FrameSource, Pipeline, PipelineError, StageTimings, TrainOptions,
};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::stages::{
    ColorClassStage, ContourStage, DepthCutStage, DepthSphereStage, EdgeFitStage, FruitStage,
    HoughCircleStage, MaskCleaningStage, RayCircleStage,
};
use crate::{
    best_f1_threshold, quantise_probability, taught_labels, training_pixels, value_histograms,
    ColorContourParams, ContourCircle, DepthCutParams, DepthSphereParams, HSigmaLut,
    HoughCircleParams, Mlp, RayCircleParams, SampledRegion,
};

/// Name of the pipeline on the command line and in model files.
pub const PIPELINE_NAME: &str = "color-contour";

/// What the model file's `stage_params` holds for this pipeline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColorContourStageParams {
    /// Stage parameters used in training.
    pub params: ColorContourParams,
    /// The trained colour perceptron.
    pub mlp: Mlp,
}

impl ColorContourStageParams {
    /// The stage parameters of a `color-contour` model file.
    ///
    /// # Errors
    /// [`PipelineError::StageParams`] when the file's `stage_params` are not this pipeline's.
    pub fn from_model(model: &ModelFile) -> Result<Self, PipelineError> {
        serde_json::from_value(model.stage_params.clone())
            .map_err(|e| PipelineError::StageParams(e.to_string()))
    }

    /// The perceptron compiled into its lookup table, and the table value from which a pixel
    /// is fruit (what the detector's colour stage and the tracker use).
    ///
    /// # Errors
    /// [`PipelineError::StageParams`] for an unusable perceptron;
    /// [`PipelineError::InvalidParameter`] for a colour threshold outside [0, 1].
    pub fn color_table(&self) -> Result<(HSigmaLut, u8), PipelineError> {
        if !self.mlp.is_valid() {
            return Err(PipelineError::StageParams(
                "the colour perceptron's weights are inconsistent or not finite".into(),
            ));
        }
        if !(0.0..=1.0).contains(&self.params.color_threshold) {
            return Err(PipelineError::InvalidParameter {
                name: "color_threshold".into(),
                reason: "must lie in [0, 1]".into(),
            });
        }
        Ok((
            HSigmaLut::compile(&self.mlp),
            quantise_probability(self.params.color_threshold),
        ))
    }
}

/// The colour-contour method (seed 004). `params` are used for training; a loaded model carries
/// its own.
#[derive(Debug, Clone, Default)]
pub struct ColorContourPipeline {
    /// Stage parameters for training.
    pub params: ColorContourParams,
}

impl ColorContourPipeline {
    /// One training: the colour perceptron on pixels of every frame ([`training_pixels`]) and,
    /// with `learn_color_threshold`, its threshold, both from the labels [`taught_labels`]
    /// gives with frame `i`'s background pixels inside `left_out[i]` left out (none for frames
    /// past the end of `left_out`). Also says, per frame, whether its labels may leave fruit
    /// untagged ([`may_have_untagged_fruit`]).
    fn train_once(
        &self,
        frames: &dyn FrameSource,
        options: &TrainOptions,
        left_out: &[Vec<ImageCircle>],
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<(ModelFile, Vec<bool>), PipelineError> {
        let n = frames.len();
        let done = std::sync::atomic::AtomicUsize::new(0);
        let per_class = self.params.pixels_per_class_per_frame;
        let discs = |i: usize| left_out.get(i).map_or(&[][..], Vec::as_slice);
        let per_frame: Result<Vec<(Vec<_>, bool)>, PipelineError> = (0..n)
            .into_par_iter()
            .map(|i| {
                let lf = frames.load(i)?;
                if lf.frame.color().is_none() {
                    return Err(PipelineError::MissingColor {
                        pipeline: PIPELINE_NAME,
                    });
                }
                let seed = options.seed ^ (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
                let labels = taught_labels(&lf, discs(i)).unwrap_or_default();
                let samples = training_pixels(&lf, &labels, per_class, seed);
                let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                progress(k, n);
                Ok((samples, may_have_untagged_fruit(&lf)))
            })
            .collect();
        let (per_frame, untagged): (Vec<_>, Vec<bool>) = per_frame?.into_iter().unzip();
        let samples: Vec<_> = per_frame.into_iter().flatten().collect();
        let mlp = Mlp::train(&samples, &self.params.mlp, options.seed).ok_or_else(|| {
            PipelineError::NotEnoughTrainingData {
                pipeline: PIPELINE_NAME,
                reason: format!(
                    "the colour perceptron needs fruit and background pixels ({} frames gave {} \
                     samples, {} of fruit)",
                    n,
                    samples.len(),
                    samples.iter().filter(|s| s.1).count()
                ),
            }
        })?;
        let mut params = self.params.clone();
        if params.learn_color_threshold {
            let lut = HSigmaLut::compile(&mlp);
            let per_frame: Result<Vec<[[u64; 256]; 2]>, PipelineError> = (0..n)
                .into_par_iter()
                .map(|i| {
                    let lf = frames.load(i)?;
                    let labels = taught_labels(&lf, discs(i)).unwrap_or_default();
                    Ok(value_histograms(&lf, &labels, &lut))
                })
                .collect();
            let mut total = [[0u64; 256]; 2];
            for h in per_frame? {
                for (t, f) in total.iter_mut().zip(h) {
                    for (a, b) in t.iter_mut().zip(f) {
                        *a += b;
                    }
                }
            }
            if let Some(t) = best_f1_threshold(&total) {
                params.color_threshold = f64::from(t) / 255.0;
            }
        }
        let stage = ColorContourStageParams { params, mlp };
        let model = ModelFile::new(PIPELINE_NAME, params_to_json(&stage), &no_svm());
        Ok((model, untagged))
    }
}

/// The model file's classifier slot: this method has no SVM (its score is support × colour
/// purity), so the file carries an empty one that is never evaluated.
fn no_svm() -> SvmClassifier {
    SvmClassifier::constant(1, 0.0)
}

impl Pipeline for ColorContourPipeline {
    fn name(&self) -> &'static str {
        PIPELINE_NAME
    }

    fn needs_color(&self) -> bool {
        true
    }

    /// Circles come from colour alone; without depth a detection is placed by the prior fruit
    /// radius (`prior_radius_m`) and has no diameter.
    fn needs_depth(&self) -> bool {
        false
    }

    fn train_params(&self) -> serde_json::Value {
        params_to_json(&self.params)
    }

    fn with_train_params(
        &self,
        params: serde_json::Value,
    ) -> Result<Box<dyn Pipeline>, PipelineError> {
        Ok(Box::new(Self {
            params: params_from_json(params)?,
        }))
    }

    fn default_model(&self) -> Option<&'static str> {
        Some(include_str!("../models/default.json")).filter(|s| !s.trim().is_empty())
    }

    fn train(
        &self,
        frames: &dyn FrameSource,
        options: &TrainOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<ModelFile, PipelineError> {
        let scale = self.params.untagged_fruit_disc_scale;
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(PipelineError::InvalidParameter {
                name: "untagged_fruit_disc_scale".into(),
                reason: "must be 0 (off) or positive".into(),
            });
        }
        let n = frames.len();
        let (first, untagged) = self.train_once(frames, options, &[], progress)?;
        if scale == 0.0 || !untagged.contains(&true) {
            return Ok(first);
        }
        // What the first model finds away from the tagged fruit is left out of the second
        // training (training_pixels.rs).
        let detector = ColorContourDetector::new(&ColorContourStageParams::from_model(&first)?)?;
        let left_out = (0..n)
            .into_par_iter()
            .map(|i| {
                if !untagged[i] {
                    return Ok(Vec::new());
                }
                let lf = frames.load(i)?;
                let found = detector.detect(&lf.frame, &mut StageTimings::default())?;
                Ok(untagged_fruit_circles(&lf, &found, scale))
            })
            .collect::<Result<Vec<Vec<ImageCircle>>, PipelineError>>()?;
        if left_out.iter().all(Vec::is_empty) {
            return Ok(first); // nothing to leave out: the second training would repeat the first
        }
        // The second pass continues the progress: frames n + 1 to 2n.
        let (second, _) =
            self.train_once(frames, options, &left_out, &|k, _| progress(n + k, 2 * n))?;
        Ok(second)
    }

    fn complete_stage_params(
        &self,
        stage_params: &serde_json::Value,
    ) -> Result<serde_json::Value, PipelineError> {
        pomona_pipeline::complete_with_defaults::<ColorContourStageParams>(stage_params)
    }

    fn load(&self, model: &ModelFile) -> Result<Box<dyn Detector>, PipelineError> {
        let stage = ColorContourStageParams::from_model(model)?;
        Ok(Box::new(ColorContourDetector::new(&stage)?))
    }
}

/// A trained colour-contour detector.
#[derive(Debug, Clone)]
pub struct ColorContourDetector {
    color: ColorClassStage,
    smoothing_half_window: usize,
    min_component_px: usize,
    mask_closing_px: usize,
    depth_cut: Option<DepthCutParams>,
    depth_spheres: Option<DepthSphereParams>,
    radius_range_m: (f64, f64),
    edge_fit: EdgeFitStage,
    ray_circles: Option<RayCircleParams>,
    hough_circles: Option<HoughCircleParams>,
    fruit: FruitStage,
}

impl ColorContourDetector {
    /// Builds the stages from a model's stage parameters (compiles the lookup table).
    ///
    /// # Errors
    /// [`PipelineError::StageParams`] for an unusable perceptron;
    /// [`PipelineError::InvalidParameter`] for out-of-range parameters.
    pub fn new(stage: &ColorContourStageParams) -> Result<Self, PipelineError> {
        let (lut, threshold) = stage.color_table()?;
        Self::from_table(lut, threshold, &stage.params)
    }

    /// Builds the stages from a compiled colour table (fruit from table value `threshold`) and
    /// the stage parameters `p` (their `color_threshold` only scales the hysteresis threshold,
    /// `color_grow_fraction` × `color_threshold`).
    ///
    /// # Errors
    /// [`PipelineError::InvalidParameter`] for out-of-range parameters.
    pub fn from_table(
        lut: HSigmaLut,
        threshold: u8,
        p: &ColorContourParams,
    ) -> Result<Self, PipelineError> {
        let invalid = |name: &str, reason: &str| PipelineError::InvalidParameter {
            name: name.into(),
            reason: reason.into(),
        };
        if !(0.0..=1.0).contains(&p.color_grow_fraction) {
            return Err(invalid("color_grow_fraction", "must lie in [0, 1]"));
        }
        if let Some((name, reason)) = p.edge_fit.problem() {
            return Err(invalid(name, reason));
        }
        if p.edge_fit.merge_max_rms.is_nan() || p.edge_fit.merge_max_rms < 0.0 {
            return Err(invalid(
                "edge_fit.merge_max_rms",
                "must be 0 (off) or positive",
            ));
        }
        let (lo, hi) = p.radius_range_m;
        if !(lo > 0.0 && lo <= hi) {
            return Err(invalid("radius_range_m", "needs 0 < min ≤ max"));
        }
        if !(p.radius_tolerance.is_finite() && p.radius_tolerance >= 0.0) {
            return Err(invalid("radius_tolerance", "must be 0 (off) or positive"));
        }
        let (near, far) = p.working_distance_m;
        if !(near > 0.0 && near <= far) {
            return Err(invalid("working_distance_m", "needs 0 < near ≤ far"));
        }
        if !(p.prune_center_reach.is_finite() && p.prune_center_reach >= 0.0) {
            return Err(invalid("prune_center_reach", "must be 0 (off) or positive"));
        }
        if p.prior_radius_m.is_nan() || p.prior_radius_m <= 0.0 {
            return Err(invalid("prior_radius_m", "must be positive"));
        }
        if let Some((name, reason)) = p.ray_circles.as_ref().and_then(|r| r.problem()) {
            return Err(invalid(name, reason));
        }
        if let Some((name, reason)) = p.hough_circles.as_ref().and_then(|h| h.problem()) {
            return Err(invalid(name, reason));
        }
        if let Some((name, reason)) = p.depth_cut.as_ref().and_then(|c| c.problem()) {
            return Err(invalid(name, reason));
        }
        if let Some((name, reason)) = p.depth_spheres.as_ref().and_then(|c| c.problem()) {
            return Err(invalid(name, reason));
        }
        if !(p.depth_refit_tolerance_m.is_finite() && p.depth_refit_tolerance_m >= 0.0) {
            return Err(invalid(
                "depth_refit_tolerance_m",
                "must be 0 (off) or positive",
            ));
        }
        Ok(Self {
            color: ColorClassStage::from_params(lut, threshold, p),
            smoothing_half_window: p.edge_fit.smoothing_half_window,
            min_component_px: p.min_component_px,
            mask_closing_px: p.mask_closing_px,
            depth_cut: p.depth_cut,
            depth_spheres: p.depth_spheres,
            radius_range_m: p.accepted_radius_range_m(),
            edge_fit: EdgeFitStage { params: p.edge_fit },
            ray_circles: p.ray_circles,
            hough_circles: p.hough_circles,
            fruit: FruitStage { params: p.clone() },
        })
    }
}

impl ColorContourDetector {
    /// The first three stages: the fruit mask and the circles fitted on its outlines, before
    /// the size test and the pruning.
    ///
    /// # Errors
    /// [`PipelineError::MissingColor`] for a frame without colour.
    pub fn fitted_circles(
        &self,
        frame: &RgbdFrame,
        timings: &mut StageTimings,
    ) -> Result<(Vec<bool>, Vec<ContourCircle>), PipelineError> {
        let fruit = run_stage(&self.color, frame, timings)?;
        let camera = frame.camera();
        // Merged circles no larger than the largest fruit the size test accepts.
        let (_, max_radius_px) = self.fruit.params.radius_px_range(camera.mean_focal_px());
        // The depth is only read by the depth cut and the depth spheres: no scan for readings
        // without them.
        let depth = frame.depth();
        let depth_m = ((self.depth_cut.is_some() || self.depth_spheres.is_some())
            && depth.has_readings())
        .then(|| depth.as_slice());
        let circles = self.circles_of_mask(
            &fruit,
            camera.width as usize,
            max_radius_px,
            depth_m.map(|d| (d, *camera)),
            timings,
        )?;
        Ok((fruit, circles))
    }

    /// The circles fitted on the outlines of a fruit mask (row-major, `width` wide): the
    /// mask cleaning, the depth cut when the parameters ask for it and the frame's depth
    /// `depth_m` is given, the contour and edge-fit stages, merged circles at most
    /// `max_radius_px` in radius, and the ray and Hough circles when the parameters ask for them.
    fn circles_of_mask(
        &self,
        fruit: &[bool],
        width: usize,
        max_radius_px: f64,
        depth: Option<(&[f32], PinholeCamera)>,
        timings: &mut StageTimings,
    ) -> Result<Vec<ContourCircle>, PipelineError> {
        let cleaning = MaskCleaningStage {
            closing_px: self.mask_closing_px,
            width,
        };
        let mut cleaned = run_stage(&cleaning, fruit, timings)?;
        if let (Some(params), Some((depth_m, _))) = (self.depth_cut, depth) {
            let cut = DepthCutStage { params, width };
            cleaned = run_stage(&cut, (cleaned.as_slice(), depth_m), timings)?;
        }
        let contour_stage = ContourStage {
            min_component_px: self.min_component_px,
            smoothing_half_window: self.smoothing_half_window,
            width,
        };
        let contours = run_stage(&contour_stage, cleaned.as_slice(), timings)?;
        let mut circles = run_stage(
            &self.edge_fit,
            (contours.as_slice(), max_radius_px),
            timings,
        )?;
        if let Some(params) = self.ray_circles {
            let rays = RayCircleStage { params, width };
            circles.extend(run_stage(&rays, cleaned.as_slice(), timings)?);
        }
        if let Some(params) = self.hough_circles {
            let hough = HoughCircleStage {
                params,
                width,
                max_radius_px,
            };
            circles.extend(run_stage(&hough, cleaned.as_slice(), timings)?);
        }
        if let (Some(params), Some((depth_m, camera))) = (self.depth_spheres, depth) {
            let spheres = DepthSphereStage {
                params,
                camera,
                radius_range_m: self.radius_range_m,
            };
            circles.extend(run_stage(&spheres, (cleaned.as_slice(), depth_m), timings)?);
        }
        Ok(circles)
    }

    /// The compiled colour table and the table value from which a pixel is fruit.
    pub fn color_table(&self) -> (&HSigmaLut, u8) {
        (&self.color.lut, self.color.threshold)
    }

    /// The first three stages on a region of `image` only (the tracker's local re-detection,
    /// [`crate::SampledRegion`]): the circles fitted on the outlines of the region's fruit mask,
    /// in image pixels, before the size test and the pruning. Outlines that the region's border
    /// cuts run straight along it and give no circles there.
    ///
    /// # Errors
    /// Those of the stages (none at present).
    pub fn fitted_circles_in(
        &self,
        image: &ColorImage,
        region: &SampledRegion,
        timings: &mut StageTimings,
    ) -> Result<Vec<ContourCircle>, PipelineError> {
        let (cols, rows) = region.size();
        let fruit = self.color.classify(region.pixels(image), cols, rows);
        Ok(self
            // No cap on merged circles: the region is a few fruit across.
            .circles_of_mask(&fruit, cols, f64::INFINITY, None, timings)?
            .into_iter()
            .map(|c| region.circle_to_image(c))
            .collect())
    }
}

impl Detector for ColorContourDetector {
    fn pipeline(&self) -> &'static str {
        PIPELINE_NAME
    }

    fn detect(
        &self,
        frame: &RgbdFrame,
        timings: &mut StageTimings,
    ) -> Result<Vec<Detection>, PipelineError> {
        let (fruit, circles) = self.fitted_circles(frame, timings)?;
        run_stage(
            &self.fruit,
            (frame, fruit.as_slice(), circles.as_slice()),
            timings,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn built_in() -> ColorContourStageParams {
        let text = ColorContourPipeline::default()
            .default_model()
            .expect("the crate ships a built-in model");
        let model: ModelFile = serde_json::from_str(text).unwrap();
        ColorContourStageParams::from_model(&model).unwrap()
    }

    #[test]
    fn model_files_without_the_pruning_settings_run_the_previous_behaviour() {
        let mut json = serde_json::to_value(built_in()).unwrap();
        let params = json["params"].as_object_mut().unwrap();
        for key in [
            "prune_rank",
            "prune_center_reach",
            "radius_tolerance",
            "hough_circles",
            "depthless_within_reach",
        ] {
            assert!(params.remove(key).is_some(), "{key}");
        }
        assert!(params.remove("ray_circles").is_none_or(|v| v.is_null()));
        let old: ColorContourStageParams = serde_json::from_value(json).unwrap();
        assert_eq!(old.params.ray_circles, None);
        assert_eq!(old.params.hough_circles, None);
        assert!(!old.params.depthless_within_reach);
        assert_eq!(old.params.prune_rank, crate::PruneRank::Score);
        assert_eq!(old.params.prune_center_reach, 0.0);
        // The paper's size test, exactly its range.
        assert_eq!(old.params.radius_tolerance, 0.0);
        assert_eq!(
            old.params.accepted_radius_range_m(),
            old.params.radius_range_m
        );
    }

    #[test]
    fn the_built_in_model_runs_the_documented_defaults_and_bad_settings_are_named() {
        let stage = built_in();
        let defaults = ColorContourParams::default();
        assert_eq!(
            stage.params.color_grow_fraction,
            defaults.color_grow_fraction
        );
        assert_eq!(stage.params.color_grow_seed_px, defaults.color_grow_seed_px);
        assert_eq!(
            stage.params.edge_fit.group_circle,
            defaults.edge_fit.group_circle
        );
        assert_eq!(
            stage.params.edge_fit.merge_max_rms,
            defaults.edge_fit.merge_max_rms
        );
        assert_eq!(stage.params.prune_rank, defaults.prune_rank);
        assert_eq!(stage.params.prune_center_reach, defaults.prune_center_reach);
        assert_eq!(stage.params.radius_tolerance, defaults.radius_tolerance);
        assert_eq!(stage.params.ray_circles, defaults.ray_circles);
        assert!(stage.params.ray_circles.is_none());
        assert_eq!(stage.params.hough_circles, defaults.hough_circles);
        assert!(stage.params.hough_circles.is_some());
        assert_eq!(stage.params.depth_cut, defaults.depth_cut);
        assert!(stage.params.depth_cut.is_some());
        assert!(stage.params.depthless_within_reach && defaults.depthless_within_reach);
        let (lo, hi) = stage.params.accepted_radius_range_m();
        assert!((lo - 0.025 / 1.1).abs() < 1e-12 && (hi - 0.055 * 1.1).abs() < 1e-12);
        // Written before the centre refit existed: runs it with the default tolerance.
        assert_eq!(
            stage.params.depth_refit_tolerance_m,
            defaults.depth_refit_tolerance_m
        );
        assert!(ColorContourDetector::new(&stage).is_ok());
        for (name, change) in [
            (
                "color_grow_fraction",
                (|p: &mut ColorContourParams| p.color_grow_fraction = 1.5)
                    as fn(&mut ColorContourParams),
            ),
            ("color_grow_fraction", |p| p.color_grow_fraction = f64::NAN),
            ("edge_fit.merge_max_rms", |p| {
                p.edge_fit.merge_max_rms = -0.1
            }),
            ("prune_center_reach", |p| p.prune_center_reach = -0.5),
            ("radius_tolerance", |p| p.radius_tolerance = -0.1),
            ("radius_tolerance", |p| p.radius_tolerance = f64::NAN),
            ("prune_center_reach", |p| p.prune_center_reach = f64::NAN),
            ("depth_refit_tolerance_m", |p| {
                p.depth_refit_tolerance_m = -0.01
            }),
            ("depth_refit_tolerance_m", |p| {
                p.depth_refit_tolerance_m = f64::INFINITY
            }),
            ("hough_circles.min_support", |p| {
                p.hough_circles = Some(crate::HoughCircleParams {
                    min_support: 1.5,
                    ..crate::HoughCircleParams::default()
                })
            }),
            ("ray_circles.min_inliers", |p| {
                p.ray_circles = Some(crate::RayCircleParams {
                    min_inliers: 40,
                    ..crate::RayCircleParams::default()
                })
            }),
        ] {
            let mut bad = stage.clone();
            change(&mut bad.params);
            match ColorContourDetector::new(&bad) {
                Err(PipelineError::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
                Err(e) => panic!("{name}: wrong error {e}"),
                Ok(_) => panic!("{name}: accepted"),
            }
        }
    }
}
