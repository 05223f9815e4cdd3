//! The frame as the detectors see it: an organised cloud in `f64` with one PCA normal per pixel.
//!
//! Normals come from `pomona-consensus`'s [`WindowNormals`] (plane fit over an image window,
//! oriented towards the camera). On organised clouds the window search is O(1) per point, while a
//! kd-tree (`KnnNormals`) costs a tree build plus a log-time query per point for the same
//! plane-fit normal; the bench `normals` compares the two (42.5 ms vs 260 ms on a Kinect v2
//! frame, one thread). Normals are only computed on a pixel lattice (every `pixel_lattice`-th
//! row and column; the window itself still uses every pixel), since boxes read only those.
//!
//! Detection goes further (exact, ours): boxes are thinned to at most `max_points` pixels, so
//! normals are estimated only at the pixels some box reads ([`NormalStage::points`], then
//! [`NormalStage::normals_at`] on the union of the boxes' pixels). Each normal is the same
//! window fit as for the whole frame (`WindowNormals::estimate_at`), so every box and every
//! detection is unchanged (unit test `on_demand_normals_give_the_same_patches`).

use nalgebra::{Point3, Unit, Vector3};
use pomona_consensus::{WindowNormalParams, WindowNormals};
use pomona_core::{PinholeCamera, PointCloud, RgbdFrame};
use pomona_pipeline::{PipelineError, Stage};
use rayon::prelude::*;

use crate::{BoxCandidate, SymmetryError};

/// An organised cloud with normals.
#[derive(Debug, Clone)]
pub struct SceneCloud {
    /// Camera of the frame.
    pub camera: PinholeCamera,
    /// Points in row-major pixel order, camera frame, metres; non-finite where depth is missing.
    pub points: Vec<Point3<f64>>,
    /// Unit normals oriented towards the camera, `None` where undefined.
    pub normals: Vec<Option<Unit<Vector3<f64>>>>,
}

impl SceneCloud {
    /// Grid width.
    pub fn width(&self) -> usize {
        self.camera.width as usize
    }

    /// Grid height.
    pub fn height(&self) -> usize {
        self.camera.height as usize
    }

    /// The observed point at pixel `(u, v)` when valid.
    pub fn point_at(&self, u: usize, v: usize) -> Option<&Point3<f64>> {
        if u >= self.width() || v >= self.height() {
            return None;
        }
        self.points
            .get(v * self.width() + u)
            .filter(|p| p.z.is_finite())
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

    /// Builds the scene cloud of `frame`.
    ///
    /// # Errors
    /// [`SymmetryError::Normals`] (only if the cloud were not organised, which frames always are).
    pub fn cloud(&self, frame: &RgbdFrame) -> Result<SceneCloud, SymmetryError> {
        let cloud = frame.to_cloud();
        let normals = if self.lattice == 1 {
            self.normals.estimate(&cloud)?
        } else {
            // Only lattice pixels (rows and columns multiple of `lattice`), in parallel rows.
            let (w, h) = (
                frame.camera().width as usize,
                frame.camera().height as usize,
            );
            let g = self.lattice;
            let rows: Vec<Vec<Option<Unit<Vector3<f64>>>>> = (0..h)
                .into_par_iter()
                .map(|v| {
                    if v % g != 0 {
                        return Ok(Vec::new());
                    }
                    let idx: Vec<usize> = (0..w).step_by(g).map(|u| v * w + u).collect();
                    self.normals.estimate_at(&cloud, &idx)
                })
                .collect::<Result<_, _>>()?;
            let mut out = vec![None; w * h];
            for (v, row) in rows.into_iter().enumerate() {
                for (k, n) in row.into_iter().enumerate() {
                    out[v * w + k * g] = n;
                }
            }
            out
        };
        let points = cloud.points().iter().map(|p| p.cast::<f64>()).collect();
        Ok(SceneCloud {
            camera: *frame.camera(),
            points,
            normals,
        })
    }
}

impl NormalStage {
    /// The frame as a point cloud and as a [`SceneCloud`] with no normals yet (stage `cloud`
    /// of detection).
    pub fn points(&self, frame: &RgbdFrame) -> (PointCloud, SceneCloud) {
        let cloud = frame.to_cloud();
        let points: Vec<Point3<f64>> = cloud.points().iter().map(|p| p.cast::<f64>()).collect();
        let normals = vec![None; points.len()];
        let scene = SceneCloud {
            camera: *frame.camera(),
            points,
            normals,
        };
        (cloud, scene)
    }

    /// Normals of `cloud` at every pixel some candidate box reads, `None` elsewhere (one entry
    /// per pixel, as [`SceneCloud::normals`]).
    ///
    /// # Errors
    /// [`SymmetryError::Normals`] when `cloud` is not organised.
    pub fn normals_at(
        &self,
        cloud: &PointCloud,
        candidates: &[BoxCandidate],
    ) -> Result<Vec<Option<Unit<Vector3<f64>>>>, SymmetryError> {
        let n = cloud.points().len();
        let mut needed = vec![false; n];
        for c in candidates {
            for &i in &c.pixels {
                if let Some(slot) = needed.get_mut(i as usize) {
                    *slot = true;
                }
            }
        }
        let idx: Vec<usize> = (0..n).filter(|&i| needed[i]).collect();
        let found: Vec<Vec<Option<Unit<Vector3<f64>>>>> = idx
            .par_chunks(2048)
            .map(|chunk| self.normals.estimate_at(cloud, chunk))
            .collect::<Result<_, _>>()?;
        let mut out = vec![None; n];
        for (&i, normal) in idx.iter().zip(found.into_iter().flatten()) {
            out[i] = normal;
        }
        Ok(out)
    }
}

/// Stage `cloud` of detection: frame → point cloud and normal-less scene cloud.
pub(crate) struct CloudStage<'a>(pub(crate) &'a NormalStage);

impl Stage<&RgbdFrame, (PointCloud, SceneCloud)> for CloudStage<'_> {
    fn name(&self) -> &'static str {
        "cloud"
    }

    fn run(&self, frame: &RgbdFrame) -> Result<(PointCloud, SceneCloud), PipelineError> {
        Ok(self.0.points(frame))
    }
}

/// Stage `normals` of detection: normals at the candidates' pixels.
impl Stage<(&PointCloud, &[BoxCandidate]), Vec<Option<Unit<Vector3<f64>>>>> for NormalStage {
    fn name(&self) -> &'static str {
        "normals"
    }

    fn run(
        &self,
        (cloud, candidates): (&PointCloud, &[BoxCandidate]),
    ) -> Result<Vec<Option<Unit<Vector3<f64>>>>, PipelineError> {
        Ok(self.normals_at(cloud, candidates)?)
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
        for (frame_index, lattice) in [(0, 1), (1, 1), (2, 2)] {
            let scene = spec.sample_frame(7, frame_index).unwrap();
            let frame = render(&scene, &spec.camera).unwrap().frame;
            let stage = NormalStage::new(WindowNormalParams::default(), lattice).unwrap();
            let sb = SlidingBox::new(SlidingBoxParams {
                pixel_lattice: lattice,
                ..SlidingBoxParams::default()
            });
            let full = stage.cloud(&frame).unwrap();
            let expected = sb.patches(&full, None);
            let (points, mut lazy) = stage.points(&frame);
            let candidates = sb.candidates(&lazy, None);
            lazy.normals = stage.normals_at(&points, &candidates).unwrap();
            let estimated = lazy.normals.iter().flatten().count();
            let got = sb.cut_all(&lazy, &candidates);
            assert!(expected.len() > 20, "{}", expected.len());
            assert_eq!(got, expected);
            assert!(estimated < full.normals.iter().flatten().count());
        }
    }
}
