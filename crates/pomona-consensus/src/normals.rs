//! Surface normals by principal component analysis (Hoppe et al. 1992), for the cylinder
//! estimator and the shape descriptor.
//!
//! A point's normal is the direction of least variance of its neighbourhood (the eigenvector of
//! the smallest eigenvalue of the neighbourhood covariance). Two neighbourhoods are offered:
//! * [`KnnNormals`]: the `k` nearest neighbours from a [`KdTree`], for unorganised clouds (e.g. a
//!   cluster after region growing);
//! * [`WindowNormals`]: the valid pixels of a small image window around the point, for organised
//!   clouds — no tree to build and perfectly local memory access, so it is much faster; neighbours
//!   farther than a distance limit are dropped so normals do not bend across depth edges.
//!
//! PCA gives a direction without sign; every normal is flipped to face the viewpoint (by default
//! the camera origin), so visible surfaces have normals pointing at the camera.
//!
//! Invalid (non-finite) points get no normal (`None`, or `NaN` in the `f32` cloud form matching
//! [`PointCloud::with_normals`]); so do points whose neighbourhood is too small or degenerate
//! (collinear). Results do not depend on the number of threads.

use nalgebra::{Matrix3, Point3, Unit, Vector3};
use pomona_core::PointCloud;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{ConsensusError, KdTree};

/// Smallest neighbourhood (including the point) that defines a plane.
const MIN_NEIGHBOURS: usize = 3;

/// The PCA normal of a neighbourhood (least-variance direction), unoriented; `None` for fewer than
/// three points or a collinear/degenerate neighbourhood.
pub fn pca_normal(neighbours: &[Point3<f64>]) -> Option<Unit<Vector3<f64>>> {
    if neighbours.len() < MIN_NEIGHBOURS {
        return None;
    }
    let n = neighbours.len() as f64;
    let mean = neighbours
        .iter()
        .fold(Vector3::zeros(), |a, p| a + p.coords)
        / n;
    let mut sums = OuterSums::default();
    for p in neighbours {
        sums.add(&(p.coords - mean));
    }
    smallest_eigenvector(&sums.matrix())
}

/// The six distinct sums of the outer products `d dᵀ` of a set of vectors: each entry the same
/// products added in the same order as summing full 3×3 outer products (which are symmetric), at
/// half the work.
#[derive(Debug, Clone, Copy, Default)]
struct OuterSums {
    xx: f64,
    xy: f64,
    xz: f64,
    yy: f64,
    yz: f64,
    zz: f64,
}

impl OuterSums {
    fn add(&mut self, d: &Vector3<f64>) {
        self.xx += d.x * d.x;
        self.xy += d.x * d.y;
        self.xz += d.x * d.z;
        self.yy += d.y * d.y;
        self.yz += d.y * d.z;
        self.zz += d.z * d.z;
    }

    /// The sums less `sum mᵀ`, for vectors adding up to `sum` with mean `m`: the scatter about
    /// the mean (`Σ d dᵀ − (Σ d)(Σ d)ᵀ / n`), entry by entry.
    fn less_mean(self, sum: &Vector3<f64>, m: &Vector3<f64>) -> Self {
        Self {
            xx: self.xx - sum.x * m.x,
            xy: self.xy - sum.x * m.y,
            xz: self.xz - sum.x * m.z,
            yy: self.yy - sum.y * m.y,
            yz: self.yz - sum.y * m.z,
            zz: self.zz - sum.z * m.z,
        }
    }

    fn matrix(&self) -> Matrix3<f64> {
        let Self {
            xx,
            xy,
            xz,
            yy,
            yz,
            zz,
        } = *self;
        Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
    }
}

/// Unit eigenvector of the smallest eigenvalue of a symmetric positive semi-definite 3×3 matrix,
/// in closed form (trigonometric eigenvalues, then a cross product of two rows of `A − λI`):
/// several times faster than an iterative solver, which matters at one call per pixel. `None`
/// when the smallest eigenvalue is not simple (a line or a point: no unique normal).
pub fn smallest_eigenvector(a: &Matrix3<f64>) -> Option<Unit<Vector3<f64>>> {
    let off = a[(0, 1)] * a[(0, 1)] + a[(0, 2)] * a[(0, 2)] + a[(1, 2)] * a[(1, 2)];
    let q = a.trace() / 3.0;
    let d = Vector3::new(a[(0, 0)] - q, a[(1, 1)] - q, a[(2, 2)] - q);
    let p2 = d.norm_squared() + 2.0 * off;
    if !(p2 > 0.0 && p2.is_finite()) {
        return None; // isotropic (or zero, or non-finite): no preferred direction
    }
    let p = (p2 / 6.0).sqrt();
    let b = (a - Matrix3::identity() * q) / p;
    let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    let largest = q + 2.0 * p * phi.cos();
    let smallest = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    let middle = 3.0 * q - largest - smallest;
    // A line (two vanishing eigenvalues) or a repeated smallest eigenvalue has no normal.
    // (acos loses ~1e-8 relative precision near r = ±1, hence the 1e-6 margin.)
    if !(largest > 0.0 && middle - smallest > 1e-6 * largest) {
        return None;
    }
    let m = a - Matrix3::identity() * smallest;
    let (r0, r1, r2) = (
        m.row(0).transpose(),
        m.row(1).transpose(),
        m.row(2).transpose(),
    );
    let candidates = [r0.cross(&r1), r0.cross(&r2), r1.cross(&r2)];
    let best = candidates
        .iter()
        .max_by(|x, y| x.norm_squared().total_cmp(&y.norm_squared()))?;
    Unit::try_new(*best, 0.0)
}

/// Flips `normal` so that it points towards `viewpoint` from `point`.
pub fn orient_towards(
    normal: Unit<Vector3<f64>>,
    point: &Point3<f64>,
    viewpoint: &Point3<f64>,
) -> Unit<Vector3<f64>> {
    if normal.dot(&(viewpoint - point)) < 0.0 {
        -normal
    } else {
        normal
    }
}

fn to_f32_or_nan(n: Option<Unit<Vector3<f64>>>) -> Vector3<f32> {
    match n {
        Some(n) => n.into_inner().cast::<f32>(),
        None => Vector3::repeat(f32::NAN),
    }
}

fn cloud_points_f64(cloud: &PointCloud) -> Vec<Point3<f64>> {
    cloud.points().iter().map(|p| p.cast::<f64>()).collect()
}

/// Parameters of [`KnnNormals`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct KnnNormalParams {
    /// Neighbours per point, including the point itself (default 16).
    pub k: usize,
    /// Normals are oriented towards this point (default: the camera origin).
    pub viewpoint: Point3<f64>,
}

impl Default for KnnNormalParams {
    fn default() -> Self {
        Self {
            k: 16,
            viewpoint: Point3::origin(),
        }
    }
}

impl KnnNormalParams {
    /// Validates into a [`KnnNormals`].
    ///
    /// # Errors
    /// [`ConsensusError::InvalidParameter`] when `k < 3` or the viewpoint is not finite.
    pub fn check(self) -> Result<KnnNormals, ConsensusError> {
        if self.k < MIN_NEIGHBOURS {
            return Err(ConsensusError::InvalidParameter {
                name: "k",
                value: self.k as f64,
                reason: "must be at least 3",
            });
        }
        check_viewpoint(&self.viewpoint)?;
        Ok(KnnNormals { params: self })
    }
}

fn check_viewpoint(v: &Point3<f64>) -> Result<(), ConsensusError> {
    match v.iter().find(|c| !c.is_finite()) {
        Some(&c) => Err(ConsensusError::InvalidParameter {
            name: "viewpoint",
            value: c,
            reason: "must be finite",
        }),
        None => Ok(()),
    }
}

/// PCA normals over k nearest neighbours (unorganised clouds); build with
/// [`KnnNormalParams::check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KnnNormals {
    params: KnnNormalParams,
}

impl KnnNormals {
    /// One oriented normal per input point (`None` for invalid points or degenerate
    /// neighbourhoods).
    pub fn estimate(&self, points: &[Point3<f64>]) -> Vec<Option<Unit<Vector3<f64>>>> {
        let tree = KdTree::build(points);
        let k = self.params.k;
        let vp = self.params.viewpoint;
        // Queries in tree order: consecutive points share leaves, so the search stays in cache,
        // and the previous query's k-th distance bounds this one's (triangle inequality), which
        // prunes the search from the start. The bound only saves work: a bound that proves too
        // small (fewer than k found, e.g. from rounding) is dropped and the query repeated, so
        // the result is always exactly `nearest_k`'s.
        let order: Vec<(usize, Point3<f64>)> = tree.tree_order().collect();
        let wanted = k.min(tree.len());
        let in_tree_order: Vec<Option<Unit<Vector3<f64>>>> = order
            .par_iter()
            .map_init(
                || (Vec::with_capacity(k), Vec::with_capacity(k), None),
                |(found, neigh, previous): &mut (_, _, Option<(Point3<f64>, f64)>), (_, p)| {
                    let bound2 = previous.map_or(f64::INFINITY, |(q, kth): (Point3<f64>, f64)| {
                        let r = (p - q).norm() + kth;
                        r * r * (1.0 + 1e-9)
                    });
                    tree.nearest_k_within(p, k, bound2, found);
                    if found.len() < wanted {
                        tree.nearest_k(p, k, found);
                    }
                    *previous = found.last().map(|&(_, d2)| (*p, d2.sqrt()));
                    neigh.clear();
                    neigh.extend(found.iter().map(|&(i, _)| points[i]));
                    pca_normal(neigh).map(|n| orient_towards(n, p, &vp))
                },
            )
            .collect();
        // Non-finite points are not in the tree and keep `None`.
        let mut out = vec![None; points.len()];
        for ((i, _), n) in order.iter().zip(in_tree_order) {
            out[*i] = n;
        }
        out
    }

    /// Normals for any cloud (its grid is ignored), `NaN` where undefined, ready for
    /// [`PointCloud::with_normals`].
    pub fn estimate_cloud(&self, cloud: &PointCloud) -> Vec<Vector3<f32>> {
        self.estimate(&cloud_points_f64(cloud))
            .into_iter()
            .map(to_f32_or_nan)
            .collect()
    }
}

/// Parameters of [`WindowNormals`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WindowNormalParams {
    /// Half-size of the square pixel window: 2 gives 5×5 (default).
    pub half_window: u32,
    /// Neighbours farther than this from the centre point are ignored, metres (default 20 mm):
    /// keeps normals from bending across depth discontinuities.
    pub max_neighbor_distance_m: f64,
    /// Minimum neighbours (including the point) for a normal (default 5).
    pub min_neighbors: usize,
    /// Normals are oriented towards this point (default: the camera origin).
    pub viewpoint: Point3<f64>,
    /// The focal length, px, that `half_window` is meant for (default `None`, and in files
    /// written before it existed: the window is the same number of pixels on every camera).
    /// When set, [`WindowNormals::for_focal`] scales the window to a frame's focal length so
    /// that it spans the same angle, and so the same surface patch at a given depth, on every
    /// camera: 5×5 pixels at a Kinect v2's 365 px become 11×11 on a 1080p Azure Kinect (917 px)
    /// and 3×3 on an SR4000 (220 px). A fixed pixel window on a high-resolution camera takes
    /// its normals from a patch a few millimetres wide, where depth noise and quantisation
    /// dominate the surface's shape.
    #[serde(default)]
    pub reference_focal_px: Option<f64>,
    /// With `reference_focal_px`: scale the window only on cameras whose focal length is above
    /// this, px; the others keep `half_window` as it is (default `None`, and in older files:
    /// every camera is scaled). A model's classifier learnt the normals of its training
    /// cameras' own windows; set to the finest training camera's focal length, the window is
    /// left alone on every camera the model has seen and grows to the reference patch on finer
    /// ones it has not. `symmetry` and `viewer-pose` use 615 px (the D435, the finest camera of
    /// their built-in training frames): on a 1080p Azure Kinect the fixed 5×5 window spans
    /// 8 mm of a fruit at 1.5 m, where registered depth is noise (docs/results.md,
    /// "Normals on a finer camera than the training ones").
    #[serde(default)]
    pub scale_above_focal_px: Option<f64>,
    /// Pixels between the window's samples along each axis (default 1: every pixel of the
    /// window); `half_window` counts samples. [`WindowNormals::for_focal`] sets it when
    /// `keep_sample_count` is on and keeps it otherwise.
    #[serde(default = "one")]
    pub sample_step_px: u32,
    /// With `reference_focal_px`: scale the window's *span* to the focal length but keep about
    /// the number of samples the reference window has, by sampling every
    /// `s = ⌊fx / reference_focal_px⌋`-th pixel (default off, and in older files: every pixel).
    /// On a 1080p Azure Kinect (917 px against 365) the 5×5 reference window becomes 11×11
    /// pixels, 121 samples, when off; when on, 7×7 samples two pixels apart (a 13-pixel span),
    /// 49 samples. Depth pixels next to each other on such a camera see nearly the same surface
    /// point, so the extra samples add little but time: the normal is a plane fit to the
    /// patch, and the patch is what the reference window defines.
    #[serde(default)]
    pub keep_sample_count: bool,
    /// The depth, metres, at which the window has the size the other settings give it
    /// (default `None`, and in older files: the same pixels at every depth). When set, the
    /// window at a pixel of depth `z` spans `reference_depth_m / z` times as many pixels, so
    /// that every normal is a plane fit to about the same patch of surface, in millimetres,
    /// whatever the distance: a fixed 5×5 window of a Kinect v2 spans about 2 mm of a fruit at
    /// 0.4 m and 8 mm of one at 1.5 m, so a classifier trained on fruit at one distance meets
    /// other normals at another. With [`WindowNormalParams::keep_sample_count`] a grown window
    /// is sampled more sparsely, so the cost per normal stays about that of the reference
    /// window; without it, every pixel of the grown window is read. Windows stay between 3×3
    /// and 65×65 pixels.
    #[serde(default)]
    pub reference_depth_m: Option<f64>,
    /// With `reference_depth_m`: only grow the window for nearer surfaces, keeping the
    /// camera's window beyond the reference depth (default off, and in older files: the window
    /// shrinks there too). Depth noise grows with distance, and a fixed pixel window's growing
    /// patch averages it; on 40-frame test sets it kept the near fruit's gain and gave up less
    /// than shrinking at distance, so shape-fit's new models use it (docs/results.md, "Normal
    /// window scaled to the depth").
    #[serde(default)]
    pub grow_only: bool,
}

fn one() -> u32 {
    1
}

impl Default for WindowNormalParams {
    fn default() -> Self {
        Self {
            half_window: 2,
            max_neighbor_distance_m: 0.02,
            min_neighbors: 5,
            viewpoint: Point3::origin(),
            reference_focal_px: None,
            scale_above_focal_px: None,
            sample_step_px: 1,
            keep_sample_count: false,
            reference_depth_m: None,
            grow_only: false,
        }
    }
}

/// Largest half window [`WindowNormals::for_focal`] scales to (a 65×65 window).
const MAX_SCALED_HALF_WINDOW: f64 = 32.0;

impl WindowNormalParams {
    /// Validates into a [`WindowNormals`].
    ///
    /// # Errors
    /// [`ConsensusError::InvalidParameter`] when the window is empty, the distance is not finite
    /// and positive, `min_neighbors < 3`, or the viewpoint is not finite.
    pub fn check(self) -> Result<WindowNormals, ConsensusError> {
        if self.half_window == 0 {
            return Err(ConsensusError::InvalidParameter {
                name: "half_window",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        if self.sample_step_px == 0 {
            return Err(ConsensusError::InvalidParameter {
                name: "sample_step_px",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        crate::consensus::check_positive("max_neighbor_distance_m", self.max_neighbor_distance_m)?;
        if self.min_neighbors < MIN_NEIGHBOURS {
            return Err(ConsensusError::InvalidParameter {
                name: "min_neighbors",
                value: self.min_neighbors as f64,
                reason: "must be at least 3",
            });
        }
        check_viewpoint(&self.viewpoint)?;
        if let Some(f) = self.reference_focal_px {
            crate::consensus::check_positive("reference_focal_px", f)?;
        }
        if let Some(z) = self.reference_depth_m {
            crate::consensus::check_positive("reference_depth_m", z)?;
        }
        if let Some(f) = self.scale_above_focal_px {
            crate::consensus::check_positive("scale_above_focal_px", f)?;
        }
        Ok(WindowNormals {
            params: self,
            reference: self,
            focal_ratio: 1.0,
        })
    }
}

/// PCA normals over an image window (organised clouds); build with
/// [`WindowNormalParams::check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowNormals {
    /// The window for this camera (after [`WindowNormals::for_focal`]).
    params: WindowNormalParams,
    /// The parameters as checked, before any scaling: what the depth scaling starts from.
    reference: WindowNormalParams,
    /// The camera's focal length over `reference_focal_px` (1 before [`WindowNormals::for_focal`]).
    focal_ratio: f64,
}

impl WindowNormals {
    /// These normals for a camera of focal length `fx_px`: the half window scaled by
    /// `fx_px / reference_focal_px` (rounded, at least 1, at most 32) when
    /// [`WindowNormalParams::reference_focal_px`] is set; unchanged otherwise, or when `fx_px`
    /// is not a positive number. With [`WindowNormalParams::keep_sample_count`] the samples are
    /// `s = ⌊fx_px / reference_focal_px⌋` pixels apart and the half window, counted in samples,
    /// is scaled by the ratio over `s`. With [`WindowNormalParams::scale_above_focal_px`],
    /// cameras at or below that focal length are left unchanged.
    ///
    /// ```
    /// use pomona_consensus::WindowNormalParams;
    /// let normals = WindowNormalParams {
    ///     reference_focal_px: Some(365.0),
    ///     ..WindowNormalParams::default()
    /// }
    /// .check()?;
    /// assert_eq!(normals.for_focal(917.0).params().half_window, 5);
    /// assert_eq!(normals.for_focal(220.0).params().half_window, 1);
    /// let sparse = WindowNormalParams {
    ///     reference_focal_px: Some(365.0),
    ///     keep_sample_count: true,
    ///     ..WindowNormalParams::default()
    /// }
    /// .check()?;
    /// let on_azure_kinect = sparse.for_focal(917.0);
    /// assert_eq!(on_azure_kinect.params().sample_step_px, 2);
    /// assert_eq!(on_azure_kinect.params().half_window, 3); // 7×7 samples over 13×13 pixels
    /// assert_eq!(sparse.for_focal(365.0).params().sample_step_px, 1);
    /// let every_third = WindowNormalParams {
    ///     reference_focal_px: Some(365.0),
    ///     sample_step_px: 3,
    ///     ..WindowNormalParams::default()
    /// }
    /// .check()?;
    /// assert_eq!(every_third.for_focal(917.0).params().sample_step_px, 3); // kept as set
    /// # Ok::<(), pomona_consensus::ConsensusError>(())
    /// ```
    pub fn for_focal(&self, fx_px: f64) -> Self {
        let finer_than_floor = self
            .reference
            .scale_above_focal_px
            .is_none_or(|floor| fx_px > floor);
        match self.reference.reference_focal_px {
            Some(reference) if fx_px.is_finite() && fx_px > 0.0 && finer_than_floor => {
                let ratio = fx_px / reference;
                let (half_window, sample_step_px) = self.scaled_window(ratio);
                Self {
                    params: WindowNormalParams {
                        half_window,
                        sample_step_px,
                        ..self.reference
                    },
                    focal_ratio: ratio,
                    ..*self
                }
            }
            _ => *self,
        }
    }

    /// The reference window scaled by `ratio` in span: `(half window in samples, pixels between
    /// samples)`, with the samples spread out by `⌊ratio⌋` when `keep_sample_count` is on.
    fn scaled_window(&self, ratio: f64) -> (u32, u32) {
        let r = &self.reference;
        let (step, samples_per_step) = if r.keep_sample_count {
            let step = ratio.floor().clamp(1.0, MAX_SCALED_HALF_WINDOW);
            (step as u32, ratio / step)
        } else {
            (r.sample_step_px, ratio)
        };
        let scaled = (f64::from(r.half_window) * samples_per_step).round();
        (scaled.clamp(1.0, MAX_SCALED_HALF_WINDOW) as u32, step)
    }

    /// The window at a point `depth_m` away: this camera's window, or with
    /// [`WindowNormalParams::reference_depth_m`] the one scaled to that depth (its reach in
    /// pixels capped at [`MAX_SCALED_HALF_WINDOW`]; with [`WindowNormalParams::grow_only`] the
    /// camera's window wherever that would be smaller, without rescaling it).
    fn window_at(&self, depth_m: f64) -> (u32, u32) {
        let camera = (self.params.half_window, self.params.sample_step_px);
        let Some(z_ref) = self.reference.reference_depth_m.filter(|_| depth_m > 0.0) else {
            return camera;
        };
        let half = f64::from(self.reference.half_window);
        let ratio = (half * self.focal_ratio * z_ref / depth_m).min(MAX_SCALED_HALF_WINDOW) / half;
        if self.reference.grow_only && ratio <= self.focal_ratio {
            return camera;
        }
        self.scaled_window(ratio)
    }

    /// The validated parameters.
    pub fn params(&self) -> &WindowNormalParams {
        &self.params
    }

    /// One oriented normal per grid point, `NaN` where undefined, ready for
    /// [`PointCloud::with_normals`].
    ///
    /// # Errors
    /// [`ConsensusError::NotOrganized`] when the cloud has no grid.
    pub fn estimate_cloud(&self, cloud: &PointCloud) -> Result<Vec<Vector3<f32>>, ConsensusError> {
        Ok(self
            .estimate(cloud)?
            .into_iter()
            .map(to_f32_or_nan)
            .collect())
    }

    /// One oriented normal per grid point (`None` where undefined).
    ///
    /// # Errors
    /// [`ConsensusError::NotOrganized`] when the cloud has no grid.
    pub fn estimate(
        &self,
        cloud: &PointCloud,
    ) -> Result<Vec<Option<Unit<Vector3<f64>>>>, ConsensusError> {
        let (w, h) = cloud.grid().ok_or(ConsensusError::NotOrganized {
            what: "window normals",
        })?;
        let (w, h) = (w as usize, h as usize);
        // The `f32` points are widened as they are read, as in `estimate_at`.
        let pts = cloud.points();
        let mut out = vec![None; pts.len()];
        out.par_chunks_mut(w.max(1))
            .enumerate()
            .for_each(|(v, row)| {
                for (u, slot) in row.iter_mut().enumerate() {
                    *slot = self.normal_at(pts, |q| q.cast::<f64>(), w, h, u, v);
                }
            });
        Ok(out)
    }

    /// Normals of the grid points `indices` only (row-major `v * width + u`), in that order —
    /// for a detector that needs normals on its clusters, not the whole frame. Indices outside
    /// the grid get `None`.
    ///
    /// # Errors
    /// [`ConsensusError::NotOrganized`] when the cloud has no grid.
    pub fn estimate_at(
        &self,
        cloud: &PointCloud,
        indices: &[usize],
    ) -> Result<Vec<Option<Unit<Vector3<f64>>>>, ConsensusError> {
        let (w, h) = cloud.grid().ok_or(ConsensusError::NotOrganized {
            what: "window normals",
        })?;
        let (w, h) = (w as usize, h as usize);
        let raw = cloud.points();
        // Converting the window on the fly keeps this O(|indices|), independent of frame size.
        Ok(indices
            .iter()
            .map(|&i| {
                if i >= w * h {
                    return None;
                }
                self.normal_at(raw, |q| q.cast::<f64>(), w, h, i % w, i / w)
            })
            .collect())
    }

    /// The window fit at pixel `(u, v)` of the `w × h` grid `pts`, read through `point`, in one
    /// pass: the kept samples' offsets `d` from the centre point are summed with their six
    /// products, and the scatter matrix `Σ (p − p̄)(p − p̄)ᵀ` is `Σ d dᵀ − (Σ d)(Σ d)ᵀ / n` — the
    /// same matrix as [`pca_normal`]'s two passes up to rounding (the offsets are at most
    /// `max_neighbor_distance_m`, so nothing large cancels), without collecting the samples.
    fn normal_at<P: Copy>(
        &self,
        pts: &[P],
        point: impl Fn(P) -> Point3<f64>,
        w: usize,
        h: usize,
        u: usize,
        v: usize,
    ) -> Option<Unit<Vector3<f64>>> {
        let p = &self.params;
        let centre = point(pts[v * w + u]);
        if !centre.iter().all(|c| c.is_finite()) {
            return None;
        }
        let (half_window, step) = self.window_at(centre.z);
        let step = step.max(1) as usize;
        // The window's reach in pixels, trimmed at the image border to whole steps so that the
        // samples stay on the lattice through (u, v).
        let reach = half_window as usize * step;
        let (u0, v0) = (
            u - (u.min(reach) / step) * step,
            v - (v.min(reach) / step) * step,
        );
        let (u1, v1) = ((u + reach).min(w - 1), (v + reach).min(h - 1));
        let max_d2 = p.max_neighbor_distance_m * p.max_neighbor_distance_m;
        let mut count = 0usize;
        let mut sum = Vector3::zeros();
        let mut sums = OuterSums::default();
        for vv in (v0..=v1).step_by(step) {
            for &q in pts[vv * w + u0..=vv * w + u1].iter().step_by(step) {
                let d = point(q) - centre;
                // NaN fails the comparison, so invalid pixels drop out here.
                if d.norm_squared() <= max_d2 {
                    count += 1;
                    sum += d;
                    sums.add(&d);
                }
            }
        }
        if count < p.min_neighbors.max(MIN_NEIGHBOURS) {
            return None;
        }
        let scatter = sums.less_mean(&sum, &(sum / count as f64)).matrix();
        smallest_eigenvector(&scatter).map(|n| orient_towards(n, &centre, &p.viewpoint))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn angle_deg(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
        a.normalize()
            .dot(&b.normalize())
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
    }

    /// A tilted plane and a sphere cap seen from the origin, as an organised grid of rays.
    fn organised_scene(surface: &str) -> (PointCloud, Vec<Option<Vector3<f64>>>) {
        let (w, h) = (80u32, 60u32);
        let f = 200.0;
        let centre = Point3::new(0.0, 0.0, 0.8);
        let r = 0.08;
        let plane_n = Vector3::new(0.2, -0.3, -1.0).normalize();
        let mut pts = Vec::new();
        let mut truth = Vec::new();
        for v in 0..h {
            for u in 0..w {
                let d = Vector3::new((u as f64 - 40.0) / f, (v as f64 - 30.0) / f, 1.0).normalize();
                let hit = match surface {
                    "plane" => {
                        // plane through (0,0,0.8) with normal plane_n
                        let t = plane_n.dot(&centre.coords) / plane_n.dot(&d);
                        Some((Point3::from(d * t), plane_n))
                    }
                    _ => {
                        let b = d.dot(&centre.coords);
                        let disc = b * b - (centre.coords.norm_squared() - r * r);
                        (disc > 0.0).then(|| {
                            let p = Point3::from(d * (b - disc.sqrt()));
                            (p, (p - centre).normalize())
                        })
                    }
                };
                match hit {
                    Some((p, n)) => {
                        pts.push(p.cast::<f32>());
                        truth.push(Some(if n.dot(&(-p.coords)) < 0.0 { -n } else { n }));
                    }
                    None => {
                        pts.push(Point3::new(f32::NAN, f32::NAN, f32::NAN));
                        truth.push(None);
                    }
                }
            }
        }
        (PointCloud::organized(w, h, pts).unwrap(), truth)
    }

    #[test]
    fn plane_and_sphere_normals_within_two_degrees() {
        let knn = KnnNormalParams::default().check().unwrap();
        let win = WindowNormalParams::default().check().unwrap();
        for surface in ["plane", "sphere"] {
            let (cloud, truth) = organised_scene(surface);
            let by_window = win.estimate(&cloud).unwrap();
            let some: Vec<usize> = (0..truth.len()).step_by(7).collect();
            let at = win.estimate_at(&cloud, &some).unwrap();
            for (k, &i) in some.iter().enumerate() {
                assert_eq!(at[k], by_window[i]);
            }
            let pts = cloud_points_f64(&cloud);
            let by_knn = knn.estimate(&pts);
            let mut checked = 0;
            for i in 0..truth.len() {
                let Some(t) = truth[i] else {
                    assert!(by_window[i].is_none() && by_knn[i].is_none());
                    continue;
                };
                // Skip the sphere's silhouette, where the window straddles the edge.
                if surface == "sphere" && t.dot(&(-pts[i].coords.normalize())) < 0.5 {
                    continue;
                }
                for n in [by_window[i], by_knn[i]] {
                    let n = n.unwrap();
                    let a = angle_deg(&n, &t);
                    assert!(a < 2.0, "{surface} point {i}: {a} deg");
                }
                checked += 1;
            }
            assert!(checked > 500, "{surface}: {checked}");
        }
    }

    /// A strided window is the plain window over the sub-grid of every `step`-th pixel through
    /// the point (also at the image border), and still gives the surface's normal.
    #[test]
    fn strided_window_samples_the_lattice_through_each_point() {
        let (cloud, truth) = organised_scene("sphere");
        let (w, h) = (80usize, 60usize);
        let step = 2;
        let strided = WindowNormalParams {
            half_window: 3,
            sample_step_px: step as u32,
            ..WindowNormalParams::default()
        }
        .check()
        .unwrap();
        let plain = WindowNormalParams {
            half_window: 3,
            ..WindowNormalParams::default()
        }
        .check()
        .unwrap();
        let pts = cloud_points_f64(&cloud);
        let mut checked = 0;
        for (u, v) in [(0, 0), (1, 1), (40, 30), (41, 29), (79, 59), (3, 58)] {
            // The sub-grid of pixels congruent to (u, v) modulo the step, as its own cloud.
            let (su, sv) = (u % step, v % step);
            let (gw, gh) = ((w - su).div_ceil(step), (h - sv).div_ceil(step));
            let sub: Vec<Point3<f32>> = (0..gh)
                .flat_map(|gv| (0..gw).map(move |gu| (su + gu * step, sv + gv * step)))
                .map(|(x, y)| cloud.points()[y * w + x])
                .collect();
            let sub = PointCloud::organized(gw as u32, gh as u32, sub).unwrap();
            let want = plain
                .estimate_at(&sub, &[(v / step) * gw + u / step])
                .unwrap()[0];
            let got = strided.estimate_at(&cloud, &[v * w + u]).unwrap()[0];
            assert_eq!(got, want, "pixel ({u}, {v})");
            if let (Some(n), Some(t)) = (got, truth[v * w + u]) {
                if t.dot(&(-pts[v * w + u].coords.normalize())) > 0.5 {
                    assert!(angle_deg(&n, &t) < 2.0);
                    checked += 1;
                }
            }
        }
        assert!(checked >= 2, "{checked}");
    }

    #[test]
    fn closed_form_eigenvector_matches_iterative_solver() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        for _ in 0..2000 {
            let m = Matrix3::from_fn(|_, _| rng.gen_range(-1.0..1.0));
            // Covariance-like: M Mᵀ with a random anisotropy.
            let s = Matrix3::from_diagonal(&Vector3::new(
                1.0,
                rng.gen_range(0.05..1.0),
                rng.gen_range(0.0..0.3),
            ));
            let a = m * s * m.transpose();
            let eig = nalgebra::SymmetricEigen::new(a);
            let k = eig.eigenvalues.imin();
            let mut sorted = [eig.eigenvalues[0], eig.eigenvalues[1], eig.eigenvalues[2]];
            sorted.sort_by(f64::total_cmp);
            if sorted[1] - sorted[0] < 1e-3 * sorted[2] {
                continue; // nearly repeated: direction ill-defined for both solvers
            }
            let want = eig.eigenvectors.column(k).into_owned();
            let got = smallest_eigenvector(&a).unwrap();
            assert!(angle_deg(&got, &want).min(angle_deg(&-got.into_inner(), &want)) < 1e-3);
        }
        assert!(smallest_eigenvector(&Matrix3::identity()).is_none());
        assert!(
            smallest_eigenvector(&Matrix3::from_diagonal(&Vector3::new(1.0, 0.0, 0.0))).is_none()
        );
    }

    /// The kNN normals are exactly those of brute-force neighbours (sorted by squared distance,
    /// then index) fed to `pca_normal`: the tree, its query order and the bounds from the
    /// previous query change only the speed. Also independent of the thread count.
    #[test]
    fn knn_normals_equal_brute_force_neighbourhoods_on_any_thread_count() {
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        // A noisy wavy surface with sparse clutter, duplicates and an invalid point.
        let mut pts: Vec<Point3<f64>> = (0..1500)
            .map(|_| {
                let (x, y): (f64, f64) = (rng.gen_range(-0.2..0.2), rng.gen_range(-0.2..0.2));
                Point3::new(
                    x,
                    y,
                    1.0 + 0.03 * (x * 30.0).sin() + rng.gen_range(-0.001..0.001),
                )
            })
            .collect();
        pts.extend((0..60).map(|_| {
            Point3::new(
                rng.gen_range(-0.3..0.3),
                rng.gen_range(-0.3..0.3),
                rng.gen_range(0.6..1.4),
            )
        }));
        pts[7] = pts[8];
        pts[9] = Point3::new(f64::NAN, 0.0, 1.0);
        let params = KnnNormalParams {
            k: 20,
            viewpoint: Point3::new(0.1, 0.0, 0.0),
        };
        let knn = params.check().unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let two = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let got = one.install(|| knn.estimate(&pts));
        assert_eq!(got, two.install(|| knn.estimate(&pts)));
        for (i, p) in pts.iter().enumerate() {
            if !p.x.is_finite() {
                assert!(got[i].is_none());
                continue;
            }
            let mut all: Vec<(f64, usize)> = pts
                .iter()
                .enumerate()
                .filter(|(_, q)| q.x.is_finite())
                .map(|(j, q)| {
                    let (dx, dy, dz) = (q.x - p.x, q.y - p.y, q.z - p.z);
                    (dx * dx + dy * dy + dz * dz, j)
                })
                .collect();
            all.sort_by(|a, b| a.partial_cmp(b).unwrap());
            let neigh: Vec<Point3<f64>> = all[..params.k].iter().map(|&(_, j)| pts[j]).collect();
            let want = pca_normal(&neigh).map(|n| orient_towards(n, p, &params.viewpoint));
            assert_eq!(got[i], want, "point {i}");
        }
    }

    #[test]
    fn six_sums_equal_the_full_outer_products_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        for n in [3usize, 7, 25, 121] {
            for _ in 0..50 {
                let pts: Vec<Point3<f64>> = (0..n)
                    .map(|_| {
                        Point3::new(
                            rng.gen_range(-0.02..0.02),
                            rng.gen_range(-0.02..0.02),
                            1.2 + rng.gen_range(-0.004..0.004),
                        )
                    })
                    .collect();
                let mean = pts.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / n as f64;
                let mut cov = Matrix3::<f64>::zeros();
                for p in &pts {
                    let d = p.coords - mean;
                    cov += d * d.transpose();
                }
                assert_eq!(pca_normal(&pts), smallest_eigenvector(&cov), "{n}");
            }
        }
    }

    #[test]
    fn window_normals_equal_pca_of_the_gathered_window() {
        // A noisy bumpy surface with holes, as an organised grid.
        let (w, h) = (40usize, 30usize);
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let points: Vec<Point3<f32>> = (0..w * h)
            .map(|i| {
                let (u, v) = ((i % w) as f64, (i / w) as f64);
                if rng.gen_bool(0.08) {
                    return Point3::new(f32::NAN, f32::NAN, f32::NAN);
                }
                let z = 0.8
                    + 0.01 * (u * 0.3).sin()
                    + 0.02 * (v * 0.2).cos()
                    + rng.gen_range(-0.003..0.003);
                Point3::new(
                    ((u - 20.0) * z / 300.0) as f32,
                    ((v - 15.0) * z / 300.0) as f32,
                    z as f32,
                )
            })
            .collect();
        let cloud = PointCloud::organized(w as u32, h as u32, points).unwrap();
        let pts: Vec<Point3<f64>> = cloud.points().iter().map(|p| p.cast::<f64>()).collect();
        for half_window in [2u32, 5] {
            let params = WindowNormalParams {
                half_window,
                max_neighbor_distance_m: 0.015,
                ..WindowNormalParams::default()
            };
            let got = params.check().unwrap().estimate(&cloud).unwrap();
            let hw = half_window as usize;
            let mut defined = 0;
            for (i, centre) in pts.iter().enumerate() {
                let (u, v) = (i % w, i / w);
                let mut neigh = Vec::new();
                for vv in v.saturating_sub(hw)..(v + hw + 1).min(h) {
                    for uu in u.saturating_sub(hw)..(u + hw + 1).min(w) {
                        let q = pts[vv * w + uu];
                        if (q - centre).norm_squared() <= 0.015 * 0.015 {
                            neigh.push(q);
                        }
                    }
                }
                let want = (centre.z.is_finite() && neigh.len() >= params.min_neighbors)
                    .then(|| {
                        pca_normal(&neigh).map(|n| orient_towards(n, centre, &params.viewpoint))
                    })
                    .flatten();
                match (got[i], want) {
                    (Some(g), Some(e)) => assert!(
                        (g.into_inner() - e.into_inner()).norm() < 1e-9,
                        "pixel {i}, half window {half_window}: {g:?} vs {e:?}"
                    ),
                    (g, e) => assert_eq!(g, e, "pixel {i}, half window {half_window}"),
                }
                defined += usize::from(want.is_some());
            }
            assert!(defined > w * h / 2, "{defined}");
        }
    }

    #[test]
    fn unorganised_noisy_plane_normals_face_the_viewpoint() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let pts: Vec<Point3<f64>> = (0..3000)
            .map(|_| Point3::new(rng.gen_range(-0.2..0.2), rng.gen_range(-0.2..0.2), 1.0))
            .collect();
        let normals = KnnNormalParams {
            k: 12,
            ..Default::default()
        }
        .check()
        .unwrap()
        .estimate(&pts);
        for n in &normals {
            let n = n.unwrap();
            assert!(angle_deg(&n, &-Vector3::z()) < 1e-6);
        }
        assert!(WindowNormalParams::default()
            .check()
            .unwrap()
            .estimate(&PointCloud::unorganized(vec![]))
            .is_err());
        assert!(KnnNormalParams {
            k: 2,
            ..Default::default()
        }
        .check()
        .is_err());
    }

    #[test]
    fn a_reference_focal_length_scales_the_window_to_the_camera() {
        let fixed = WindowNormalParams::default().check().unwrap();
        assert_eq!(
            fixed.for_focal(917.0),
            fixed,
            "no reference: pixels stay pixels"
        );
        let scaled = WindowNormalParams {
            reference_focal_px: Some(365.0),
            ..WindowNormalParams::default()
        }
        .check()
        .unwrap();
        for (fx, want) in [
            (365.0, 2),
            (615.0, 3),
            (917.0, 5),
            (220.0, 1),
            (10.0, 1),
            (1e6, 32),
        ] {
            assert_eq!(scaled.for_focal(fx).params().half_window, want, "fx {fx}");
        }
        for bad in [0.0, -1.0, f64::NAN] {
            assert_eq!(scaled.for_focal(bad), scaled, "fx {bad}");
        }
        let floored = WindowNormalParams {
            reference_focal_px: Some(365.0),
            scale_above_focal_px: Some(615.0),
            ..WindowNormalParams::default()
        }
        .check()
        .unwrap();
        for (fx, want) in [(220.0, 2), (365.0, 2), (615.0, 2), (917.0, 5)] {
            assert_eq!(floored.for_focal(fx).params().half_window, want, "fx {fx}");
        }
        assert_eq!(
            floored.for_focal(615.0),
            floored,
            "at the floor: as checked"
        );
        for bad in [0.0, -3.0, f64::INFINITY] {
            let p = WindowNormalParams {
                reference_focal_px: Some(bad),
                ..WindowNormalParams::default()
            };
            assert!(p.check().is_err(), "{bad}");
            let p = WindowNormalParams {
                scale_above_focal_px: Some(bad),
                ..WindowNormalParams::default()
            };
            assert!(p.check().is_err(), "floor {bad}");
        }
    }

    #[test]
    fn a_reference_depth_scales_the_window_with_each_points_depth() {
        // The plane lies at 0.75–0.85 m: a 5×5 window meant for 1.6 m spans 9×9 pixels there,
        // one meant for 0.4 m 3×3, or 5×5 when it may only grow; sparse sampling keeps 5×5
        // samples two pixels apart.
        let (cloud, _) = organised_scene("plane");
        let window = |half_window, sample_step_px, reference_depth_m, sparse, grow_only| {
            WindowNormalParams {
                half_window,
                sample_step_px,
                reference_depth_m,
                keep_sample_count: sparse,
                grow_only,
                ..WindowNormalParams::default()
            }
            .check()
            .unwrap()
            .estimate(&cloud)
            .unwrap()
        };
        let fixed =
            |half_window, sample_step_px| window(half_window, sample_step_px, None, false, false);
        // Each case holds where the scaled reach 2 · z_ref / z rounds to the fixed window (and,
        // when sparse, where ⌊z_ref / z⌋ = 2 pixels between samples).
        type Normals = Vec<Option<Unit<Vector3<f64>>>>;
        type Case = (Normals, Normals, fn(f64) -> bool);
        let cases: [Case; 5] = [
            (window(2, 1, Some(1.6), false, true), fixed(4, 1), |z| {
                (3.2 / z).round() == 4.0
            }),
            (window(2, 1, Some(1.6), false, false), fixed(4, 1), |z| {
                (3.2 / z).round() == 4.0
            }),
            (window(2, 1, Some(0.4), false, false), fixed(1, 1), |z| {
                (0.8 / z).round() == 1.0
            }),
            (window(2, 1, Some(0.4), false, true), fixed(2, 1), |_| true),
            (window(2, 1, Some(1.6), true, false), fixed(2, 2), |z| {
                (1.6 / z).floor() == 2.0 && (1.6 / z).round() == 2.0
            }),
        ];
        for (k, (scaled, fixed, applies)) in cases.iter().enumerate() {
            let mut compared = 0;
            for (i, p) in cloud.points().iter().enumerate() {
                let z = f64::from(p.z);
                if z.is_finite() && applies(z) {
                    assert_eq!(scaled[i], fixed[i], "case {k}, pixel {i}");
                    compared += 1;
                }
            }
            assert!(compared > 500, "case {k}: {compared} pixels");
        }
        let at_reference = window(2, 1, Some(0.8), false, false);
        let differs = at_reference
            .iter()
            .zip(fixed(2, 1))
            .filter(|(a, b)| **a != *b)
            .count();
        assert!(differs < cloud.points().len() / 10, "{differs}");
        let bad = WindowNormalParams {
            reference_depth_m: Some(0.0),
            ..WindowNormalParams::default()
        };
        assert!(bad.check().is_err());
    }

    #[test]
    fn parameters_written_before_the_reference_focal_length_read_as_fixed_pixels() {
        let mut json = serde_json::to_value(WindowNormalParams {
            reference_focal_px: Some(365.0),
            ..WindowNormalParams::default()
        })
        .unwrap();
        let fields = json.as_object_mut().unwrap();
        fields.remove("reference_focal_px");
        assert!(fields.remove("reference_depth_m").is_some());
        assert!(fields.remove("grow_only").is_some());
        let old: WindowNormalParams = serde_json::from_value(json).unwrap();
        assert_eq!(old, WindowNormalParams::default());
    }
}
