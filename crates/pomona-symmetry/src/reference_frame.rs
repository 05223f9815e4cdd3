//! The reference frame a box's features are expressed in — a swappable stage.
//!
//! * [`SymmetryFrame`] (seed 000 §3.3, seed 003 §3.1): `n_p` = normal of the best symmetry
//!   plane, `r = n_p × (p_v − p)/‖p_v − p‖` (on the plane and on the verge of visibility, Eq. 15)
//!   flipped to point up, `i = n_p × r` (Eq. 16). "Up" is −y in the camera frame (seed 003's
//!   footnote; the camera's y axis points down).
//! * [`FixedFrame`]: the same frame fields filled with fixed camera axes, ignoring the data — the
//!   "without symmetry" column of seed 000 Table 1.
//! * [`ViewerFrame`] (seed 001 §2.1): built from the box centre `c` and the viewpoint `v` only:
//!   `u` points from `c` towards the viewer in the horizontal (x–z) plane, so it depends only on
//!   horizontal translations; `w` is up; the binning plane is the `u`–`w` plane. The seed's
//!   equations for `u` and `w` did not survive in our copy of the text; this is our reading of
//!   its prose (u through the visible part of the fruit, invariant to vertical translation).

use nalgebra::{Point3, Unit, Vector3};
use pomona_pipeline::{PipelineError, Stage};
use rayon::prelude::*;

use crate::{BoxPatch, FrameKind, SymmetryPlaneSearch};

/// "Up" in camera coordinates (y points down).
pub fn up() -> Unit<Vector3<f64>> {
    -Vector3::y_axis()
}

/// An orthonormal frame at a box centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    /// Box centre.
    pub origin: Point3<f64>,
    /// Normal of the binning plane: `n_p` (symmetry / fixed) or `u × w` (viewer).
    pub normal: Unit<Vector3<f64>>,
    /// Reference direction in that plane: `r` (symmetry / fixed) or `u` (viewer).
    pub reference: Unit<Vector3<f64>>,
    /// Third axis: `i = n_p × r` (symmetry / fixed) or `w` (viewer).
    pub third: Unit<Vector3<f64>>,
    /// Mean Eq. 14 score of the symmetry plane, when the frame came from one.
    pub symmetry_score: Option<f64>,
}

/// A way of giving a box a reference frame.
pub trait ReferenceFrame: Send + Sync {
    /// Which frame this is.
    fn kind(&self) -> FrameKind;

    /// The frame of `patch` seen from `viewpoint`, or `None` when it cannot be built (no
    /// symmetry plane with enough support).
    fn frame(&self, patch: &BoxPatch, viewpoint: &Point3<f64>) -> Option<LocalFrame>;
}

/// Eqs. 15–16: the frame of the plane through `p` with normal `n_p`, seen from `viewpoint`, with
/// `r` pointing up (`r · y ≤ 0`). When `n_p` is parallel to the view ray, `r` falls back to up
/// projected on the plane.
pub fn plane_frame(
    p: Point3<f64>,
    n_p: Unit<Vector3<f64>>,
    viewpoint: &Point3<f64>,
) -> Option<LocalFrame> {
    let view = (viewpoint - p).try_normalize(1e-12)?;
    let mut r = n_p.cross(&view);
    if r.norm() < 1e-6 {
        let u = up().into_inner();
        r = u - n_p.into_inner() * u.dot(&n_p);
    }
    let mut r = r.try_normalize(1e-9)?;
    if r.y > 0.0 {
        r = -r;
    }
    let i = n_p.cross(&r);
    Some(LocalFrame {
        origin: p,
        normal: n_p,
        reference: Unit::new_normalize(r),
        third: Unit::new_normalize(i),
        symmetry_score: None,
    })
}

/// Frame from the best reflection-symmetry plane.
#[derive(Debug, Clone, PartialEq)]
pub struct SymmetryFrame {
    search: SymmetryPlaneSearch,
}

impl SymmetryFrame {
    /// Wraps a plane search.
    pub fn new(search: SymmetryPlaneSearch) -> Self {
        Self { search }
    }
}

impl ReferenceFrame for SymmetryFrame {
    fn kind(&self) -> FrameKind {
        FrameKind::Symmetry
    }

    fn frame(&self, patch: &BoxPatch, viewpoint: &Point3<f64>) -> Option<LocalFrame> {
        let plane = self.search.best(patch, viewpoint)?;
        let mut f = plane_frame(patch.center, plane.normal, viewpoint)?;
        f.symmetry_score = Some(plane.score);
        Some(f)
    }
}

/// A fixed frame: `n_p` = camera x, `r` = up (−y), `i = n_p × r` = −z.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FixedFrame;

impl ReferenceFrame for FixedFrame {
    fn kind(&self) -> FrameKind {
        FrameKind::Fixed
    }

    fn frame(&self, patch: &BoxPatch, _viewpoint: &Point3<f64>) -> Option<LocalFrame> {
        let n = Vector3::x_axis();
        let r = up();
        Some(LocalFrame {
            origin: patch.center,
            normal: n,
            reference: r,
            third: Unit::new_normalize(n.cross(&r)),
            symmetry_score: None,
        })
    }
}

/// Seed 001's viewer-based frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ViewerFrame;

impl ReferenceFrame for ViewerFrame {
    fn kind(&self) -> FrameKind {
        FrameKind::Viewer
    }

    fn frame(&self, patch: &BoxPatch, viewpoint: &Point3<f64>) -> Option<LocalFrame> {
        let d = viewpoint - patch.center;
        let u = Vector3::new(d.x, 0.0, d.z).try_normalize(1e-9)?;
        let w = up();
        Some(LocalFrame {
            origin: patch.center,
            normal: Unit::new_normalize(u.cross(&w)),
            reference: Unit::new_normalize(u),
            third: w,
            symmetry_score: None,
        })
    }
}

/// Stage `reference-frame`: one frame per box (parallel, order-preserving).
pub struct FrameStage {
    frame: Box<dyn ReferenceFrame>,
    viewpoint: Point3<f64>,
}

impl FrameStage {
    /// A stage computing `frame` from the camera origin.
    pub fn new(frame: Box<dyn ReferenceFrame>) -> Self {
        Self {
            frame,
            viewpoint: Point3::origin(),
        }
    }

    /// The frame kind.
    pub fn kind(&self) -> FrameKind {
        self.frame.kind()
    }

    /// Frames of `patches`.
    pub fn frames(&self, patches: &[BoxPatch]) -> Vec<Option<LocalFrame>> {
        patches
            .par_iter()
            .map(|p| self.frame.frame(p, &self.viewpoint))
            .collect()
    }
}

impl Stage<&[BoxPatch], Vec<Option<LocalFrame>>> for FrameStage {
    fn name(&self) -> &'static str {
        "reference-frame"
    }

    fn run(&self, patches: &[BoxPatch]) -> Result<Vec<Option<LocalFrame>>, PipelineError> {
        Ok(self.frames(patches))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn orthonormal(f: &LocalFrame) -> bool {
        let (a, b, c) = (f.normal, f.reference, f.third);
        a.dot(&b).abs() < 1e-9 && a.dot(&c).abs() < 1e-9 && b.dot(&c).abs() < 1e-9
    }

    #[test]
    fn symmetry_frame_follows_eqs_15_16() {
        let p = Point3::new(0.1, 0.0, 0.8);
        let n_p = Unit::new_normalize(Vector3::new(1.0, 0.0, 0.2));
        let f = plane_frame(p, n_p, &Point3::origin()).unwrap();
        assert!(orthonormal(&f));
        assert!(f.reference.y <= 0.0, "r points up");
        assert!(
            f.reference.dot(&(Point3::origin() - p)).abs() < 1e-9,
            "verge of visibility"
        );
        assert!((f.third.into_inner() - n_p.cross(&f.reference)).norm() < 1e-12);
        // A vertical plane facing sideways: r is straight up.
        let f = plane_frame(
            Point3::new(0.0, 0.0, 1.0),
            Vector3::x_axis(),
            &Point3::origin(),
        )
        .unwrap();
        assert!((f.reference.into_inner() - Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-12);
        // Plane facing the camera: fallback to up.
        let f = plane_frame(
            Point3::new(0.0, 0.0, 1.0),
            Vector3::z_axis(),
            &Point3::origin(),
        )
        .unwrap();
        assert!(orthonormal(&f) && f.reference.y < -0.99);
    }

    #[test]
    fn viewer_frame_ignores_vertical_offsets() {
        let patch = |y: f64| BoxPatch {
            center: Point3::new(0.2, y, 0.8),
            points: vec![],
            normals: vec![],
        };
        let a = ViewerFrame.frame(&patch(0.0), &Point3::origin()).unwrap();
        let b = ViewerFrame.frame(&patch(-0.3), &Point3::origin()).unwrap();
        assert!(orthonormal(&a));
        assert!((a.reference.into_inner() - b.reference.into_inner()).norm() < 1e-12);
        assert!(a.reference.y.abs() < 1e-12 && a.reference.z < 0.0);
        assert!(orthonormal(
            &FixedFrame.frame(&patch(0.0), &Point3::origin()).unwrap()
        ));
    }
}
