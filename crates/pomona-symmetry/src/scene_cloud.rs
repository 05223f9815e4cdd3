//! The frame as the detectors see it: an organised cloud with a PCA normal at the pixels that
//! need one.
//!
//! Normals come from `pomona-consensus`'s [`WindowNormals`] (plane fit over an image window,
//! oriented towards the camera). On organised clouds the window search is O(1) per point, while a
//! kd-tree (`KnnNormals`) costs a tree build plus a log-time query per point for the same
//! plane-fit normal; the bench `normals` compares the two (42.5 ms vs 260 ms on a Kinect v2
//! frame, one thread). Normals are only computed on a pixel lattice (every `pixel_lattice`-th
//! row and column; the window itself still uses every pixel), since boxes read only those.
//! The window is the one [`WindowNormals::for_focal`] gives the frame's camera: the same
//! pixels on the cameras a model was trained on, grown to the same surface patch on finer
//! ones when the parameters say so (`scale_above_focal_px`).
//!
//! Detection goes further (exact, ours): boxes are thinned to at most `max_points` pixels, so
//! normals are estimated only at the pixels some box reads ([`NormalStage::points`], then
//! [`NormalStage::normals_at`] on the union of the boxes' pixels). Each normal is the same
//! window fit as for the whole frame (`WindowNormals::estimate_at`), so every box and every
//! detection is unchanged (unit test `on_demand_normals_give_the_same_patches`).
//!
//! Memory is per pixel, and at 1920×1080 every byte per pixel is 2 MB that the kernel must
//! hand out zeroed, frame after frame. So the points stay in the frame's `f32` cloud and are
//! widened to `f64` when read (the values the detectors saw before, when a second `f64` copy was
//! kept), and normals live in a compact list with a 4-byte slot per pixel ([`PixelNormals`])
//! rather than a 32-byte `Option` per pixel.

use nalgebra::{Point3, Unit, Vector3};
use pomona_consensus::{WindowNormalParams, WindowNormals};
use pomona_core::{PinholeCamera, PointCloud, RgbdFrame};
use pomona_pipeline::{PipelineError, Stage};
use rayon::prelude::*;

use crate::{BoxCandidate, SymmetryError};

/// Unit normals at some pixels of an organised cloud: a slot per pixel into a compact list.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PixelNormals {
    /// Index into `normals` per pixel, [`PixelNormals::NONE`] where there is no normal.
    slot: Vec<u32>,
    normals: Vec<Unit<Vector3<f64>>>,
}

impl PixelNormals {
    const NONE: u32 = u32::MAX;

    /// No normal at any pixel.
    pub fn none() -> Self {
        Self::default()
    }

    /// The normals of `pixels` (row-major indices into a grid of `len` pixels), one estimate per
    /// listed pixel; `None` estimates and pixels outside the grid are left without a normal.
    pub(crate) fn from_estimates(
        len: usize,
        pixels: &[usize],
        estimates: impl IntoIterator<Item = Option<Unit<Vector3<f64>>>>,
    ) -> Self {
        let mut slot = vec![Self::NONE; len];
        let mut normals = Vec::new();
        for (&i, n) in pixels.iter().zip(estimates) {
            if let (Some(n), Some(s)) = (n, slot.get_mut(i)) {
                *s = normals.len() as u32;
                normals.push(n);
            }
        }
        Self { slot, normals }
    }

    /// The normal at pixel `i` (row-major), if estimated and defined.
    pub fn get(&self, i: usize) -> Option<Unit<Vector3<f64>>> {
        match self.slot.get(i) {
            Some(&s) if s != Self::NONE => self.normals.get(s as usize).copied(),
            _ => None,
        }
    }

    /// Number of pixels with a normal.
    pub fn count(&self) -> usize {
        self.normals.len()
    }
}

/// An organised cloud with normals.
#[derive(Debug, Clone)]
pub struct SceneCloud {
    /// Camera of the frame.
    pub camera: PinholeCamera,
    /// The organised points (row-major pixel order, camera frame, metres; `NaN` where depth is
    /// missing), as back-projected from the frame.
    cloud: PointCloud,
    /// Normals oriented towards the camera where estimated.
    normals: PixelNormals,
}

impl SceneCloud {
    /// A scene cloud without normals from an organised cloud of `camera`'s size.
    ///
    /// # Errors
    /// [`SymmetryError::NotOrganized`] when `cloud` is not a grid of the camera's size.
    pub fn new(camera: PinholeCamera, cloud: PointCloud) -> Result<Self, SymmetryError> {
        if cloud.grid() != Some((camera.width, camera.height)) {
            return Err(SymmetryError::NotOrganized {
                expected: (camera.width, camera.height),
                found: cloud.grid(),
            });
        }
        Ok(Self {
            camera,
            cloud,
            normals: PixelNormals::none(),
        })
    }

    /// The frame's scene cloud without normals.
    fn of_frame(frame: &RgbdFrame) -> Self {
        Self {
            camera: *frame.camera(),
            cloud: frame.to_cloud(),
            normals: PixelNormals::none(),
        }
    }

    /// Grid width.
    pub fn width(&self) -> usize {
        self.camera.width as usize
    }

    /// Grid height.
    pub fn height(&self) -> usize {
        self.camera.height as usize
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.cloud.len()
    }

    /// Whether the grid is empty.
    pub fn is_empty(&self) -> bool {
        self.cloud.is_empty()
    }

    /// The point of pixel `i` (row-major), non-finite where depth is missing.
    ///
    /// # Panics
    /// When `i` is outside the grid.
    pub fn point(&self, i: usize) -> Point3<f64> {
        self.cloud.points()[i].cast::<f64>()
    }

    /// Every point in row-major pixel order (non-finite where depth is missing).
    pub fn points(&self) -> impl Iterator<Item = Point3<f64>> + '_ {
        self.cloud.points().iter().map(|p| p.cast::<f64>())
    }

    /// The observed point at pixel `(u, v)` when valid.
    pub fn point_at(&self, u: usize, v: usize) -> Option<Point3<f64>> {
        if u >= self.width() || v >= self.height() {
            return None;
        }
        self.cloud
            .points()
            .get(v * self.width() + u)
            .filter(|p| p.z.is_finite())
            .map(|p| p.cast::<f64>())
    }

    /// The normal at pixel `i` (row-major), if estimated and defined.
    pub fn normal(&self, i: usize) -> Option<Unit<Vector3<f64>>> {
        self.normals.get(i)
    }

    /// The normals.
    pub fn normals(&self) -> &PixelNormals {
        &self.normals
    }

    /// Replaces the normals.
    pub fn set_normals(&mut self, normals: PixelNormals) {
        self.normals = normals;
    }

    /// The underlying `f32` cloud.
    pub fn cloud(&self) -> &PointCloud {
        &self.cloud
    }
}

/// Stage `normals`: frame → [`SceneCloud`].
#[derive(Debug, Clone)]
pub struct NormalStage {
    normals: WindowNormals,
    lattice: usize,
}

impl NormalStage {
    /// Validates the window parameters.
    ///
    /// # Errors
    /// [`SymmetryError::Normals`] for invalid parameters.
    pub fn new(params: WindowNormalParams, lattice: usize) -> Result<Self, SymmetryError> {
        Ok(Self {
            normals: params.check()?,
            lattice: lattice.max(1),
        })
    }

    /// Builds the scene cloud of `frame`, with normals at every lattice pixel.
    ///
    /// # Errors
    /// [`SymmetryError::Normals`] (only if the cloud were not organised, which frames always are).
    pub fn cloud(&self, frame: &RgbdFrame) -> Result<SceneCloud, SymmetryError> {
        let mut scene = SceneCloud::of_frame(frame);
        let (w, h) = (scene.width(), scene.height());
        let g = self.lattice;
        let pixels: Vec<usize> = (0..h)
            .step_by(g)
            .flat_map(|v| (0..w).step_by(g).map(move |u| v * w + u))
            .collect();
        let normals = self.estimate(&scene.cloud, scene.camera.fx, &pixels)?;
        scene.normals = normals;
        Ok(scene)
    }

    /// The frame as a [`SceneCloud`] with no normals yet (stage `cloud` of detection).
    pub fn points(&self, frame: &RgbdFrame) -> SceneCloud {
        SceneCloud::of_frame(frame)
    }

    /// Normals of `scene` at every pixel some candidate box reads, none elsewhere.
    ///
    /// # Errors
    /// [`SymmetryError::Normals`] when the cloud is not organised.
    pub fn normals_at(
        &self,
        scene: &SceneCloud,
        candidates: &[BoxCandidate],
    ) -> Result<PixelNormals, SymmetryError> {
        let n = scene.len();
        let mut needed = vec![false; n];
        for c in candidates {
            for &i in &c.pixels {
                if let Some(slot) = needed.get_mut(i as usize) {
                    *slot = true;
                }
            }
        }
        let idx: Vec<usize> = (0..n).filter(|&i| needed[i]).collect();
        self.estimate(&scene.cloud, scene.camera.fx, &idx)
    }

    /// Normals at `pixels` (in parallel chunks; the result does not depend on the thread count).
    fn estimate(
        &self,
        cloud: &PointCloud,
        fx_px: f64,
        pixels: &[usize],
    ) -> Result<PixelNormals, SymmetryError> {
        let window = self.normals.for_focal(fx_px);
        let found: Vec<Vec<Option<Unit<Vector3<f64>>>>> = pixels
            .par_chunks(2048)
            .map(|chunk| window.estimate_at(cloud, chunk))
            .collect::<Result<_, _>>()?;
        Ok(PixelNormals::from_estimates(
            cloud.len(),
            pixels,
            found.into_iter().flatten(),
        ))
    }
}

/// Stage `cloud` of detection: frame → scene cloud without normals.
pub(crate) struct CloudStage<'a>(pub(crate) &'a NormalStage);

impl Stage<&RgbdFrame, SceneCloud> for CloudStage<'_> {
    fn name(&self) -> &'static str {
        "cloud"
    }

    fn run(&self, frame: &RgbdFrame) -> Result<SceneCloud, PipelineError> {
        Ok(self.0.points(frame))
    }
}

/// Stage `normals` of detection: normals at the candidates' pixels.
impl Stage<(&SceneCloud, &[BoxCandidate]), PixelNormals> for NormalStage {
    fn name(&self) -> &'static str {
        "normals"
    }

    fn run(
        &self,
        (scene, candidates): (&SceneCloud, &[BoxCandidate]),
    ) -> Result<PixelNormals, PipelineError> {
        Ok(self.normals_at(scene, candidates)?)
    }
}

impl Stage<&RgbdFrame, SceneCloud> for NormalStage {
    fn name(&self) -> &'static str {
        "normals"
    }

    fn run(&self, frame: &RgbdFrame) -> Result<SceneCloud, PipelineError> {
        Ok(self.cloud(frame)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{SlidingBox, SlidingBoxParams};
    use pomona_synth::{render, CameraPreset, NoiseModel, SceneSpec};

    #[test]
    fn on_demand_normals_give_the_same_patches() {
        let spec = SceneSpec {
            camera: CameraPreset::Sr4000.camera(),
            noise: NoiseModel::Tof,
            ..SceneSpec::default()
        };
        // The last two with samples aligned to the boxes' steps (on every focal length).
        let aligned = Some(1.0);
        for (frame_index, lattice, align) in [
            (0, 1, None),
            (1, 1, None),
            (2, 2, None),
            (3, 1, aligned),
            (4, 2, aligned),
        ] {
            let scene = spec.sample_frame(7, frame_index).unwrap();
            let frame = render(&scene, &spec.camera).unwrap().frame;
            let stage = NormalStage::new(WindowNormalParams::default(), lattice).unwrap();
            let sb = SlidingBox::new(SlidingBoxParams {
                pixel_lattice: lattice,
                align_samples_min_focal_px: align,
                ..SlidingBoxParams::default()
            });
            let full = stage.cloud(&frame).unwrap();
            let expected = sb.patches(&full, None);
            let mut lazy = stage.points(&frame);
            let candidates = sb.candidates(&lazy, None);
            let normals = stage.normals_at(&lazy, &candidates).unwrap();
            lazy.set_normals(normals);
            let estimated = lazy.normals().count();
            let got = sb.cut_all(&lazy, &candidates);
            assert!(expected.len() > 20, "{}", expected.len());
            assert_eq!(got, expected);
            assert!(estimated < full.normals().count());
        }
    }

    #[test]
    fn the_window_grows_only_on_cameras_finer_than_the_floor() {
        let floored = crate::StageParams::symmetry().normals;
        let fixed = NormalStage::new(WindowNormalParams::default(), 1).unwrap();
        let scaled = NormalStage::new(floored, 1).unwrap();
        let window = floored.check().unwrap();
        for (camera, grows) in [
            (CameraPreset::Sr4000, false),
            (CameraPreset::KinectV2, false),
            (CameraPreset::D435, false),
            (CameraPreset::AzureKinect, true),
        ] {
            let spec = SceneSpec {
                camera: camera.camera(),
                noise: NoiseModel::Tof,
                ..SceneSpec::default()
            };
            let scene = spec.sample_frame(3, 0).unwrap();
            let frame = render(&scene, &spec.camera).unwrap().frame;
            let kept = fixed.cloud(&frame).unwrap();
            let got = scaled.cloud(&frame).unwrap();
            let fx = spec.camera.fx;
            assert_eq!(window.for_focal(fx) != window, grows, "{camera:?}");
            let same = (0..got.len()).all(|i| got.normal(i) == kept.normal(i));
            assert_eq!(same, !grows, "{camera:?}: normals as the fixed window's");
        }
    }
}
