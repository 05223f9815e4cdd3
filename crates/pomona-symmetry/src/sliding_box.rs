//! The 3D sliding box: fixed-size cubes on a regular grid of centres, each cut out of the
//! organised cloud (seed 000 §3.2, seed 003 §3).
//!
//! Most of space is empty, so boxes are rejected as early and cheaply as possible, in order:
//! 1. centres outside the working range `[min_range_m, max_range_m]` or outside the image;
//! 2. centres whose pixel is outside the pruning mask (when pruning is on);
//! 3. centres not just behind the surface seen through them (a fruit's centre is behind its
//!    visible skin by about its radius): the observed depth at the centre's pixel must lie within
//!    `[z − box/2, z + max_in_front_m]`, or `[z − box/2, z − min_behind_m]` when
//!    `min_behind_m > 0`;
//! 4. flat boxes (optional, `max_normal_coherence`): nearly parallel normals mean a leaf or the
//!    backdrop, never a fruit;
//! 5. boxes with too few points, counted in O(1) with a summed-volume table over stride-sized
//!    voxels (an over-estimate by at most one voxel layer), then exactly while cutting the box.
//!
//! Box centres sit on multiples of the stride in the camera frame, so the grid does not depend
//! on the frame's content and results do not depend on the thread count. A box reads every
//! `step`-th pixel of the rectangle it covers (at most about `max_points`); optionally, on
//! high-resolution cameras (`align_samples_min_focal_px`, off by default), the samples start on
//! multiples of the step, so that overlapping boxes read, and need normals at, the same pixels.

use std::ops::RangeInclusive;

use nalgebra::{Point3, Unit, Vector3};
use pomona_pipeline::{PipelineError, Stage};
use rayon::prelude::*;

use crate::{PruningMask, SceneCloud, SlidingBoxParams};

/// The points of one box, with their normals.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxPatch {
    /// Box centre, camera frame, metres.
    pub center: Point3<f64>,
    /// Points inside the box (thinned to at most `max_points`).
    pub points: Vec<Point3<f64>>,
    /// Unit normal of each point, oriented towards the camera.
    pub normals: Vec<Unit<Vector3<f64>>>,
}

/// A box that passed early rejection, before normals are known: its centre and the pixels
/// (row-major indices, thinned) whose points lie inside it. Detection estimates normals only at
/// the union of these pixels, then [`SlidingBox::cut`]s the boxes.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxCandidate {
    /// Box centre, camera frame, metres.
    pub center: Point3<f64>,
    /// Pixels whose points lie inside the box (thinned by `step`).
    pub pixels: Vec<u32>,
    /// The thinning step, pixels.
    step: usize,
}

/// Cuts boxes out of a [`SceneCloud`]; stage `sliding-box`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlidingBox {
    params: SlidingBoxParams,
}

impl SlidingBox {
    /// A sliding box with validated parameters (see [`crate::StageParams::validate`]).
    pub fn new(params: SlidingBoxParams) -> Self {
        Self { params }
    }

    /// Half the box edge, metres.
    pub fn half_m(&self) -> f64 {
        0.5 * self.params.box_size_m
    }

    /// Box centres that pass rejection rules 1–3 and 5 (see the module docs), in grid order.
    pub fn centres(&self, cloud: &SceneCloud, mask: Option<&PruningMask>) -> Vec<Point3<f64>> {
        let p = &self.params;
        let Some(voxels) = VoxelCounts::build(cloud, p) else {
            return Vec::new();
        };
        let half = self.half_m();
        let k = (half / p.stride_m).floor() as i64;
        let mut out = Vec::new();
        // Centres reach half a box beyond the occupied voxels.
        for iz in voxels.lo[2] - k..=voxels.hi[2] + k {
            let z = iz as f64 * p.stride_m;
            if z < p.min_range_m || z > p.max_range_m {
                continue;
            }
            let (xs, ys) = (
                voxels.lo[0] - k..=voxels.hi[0] + k,
                voxels.lo[1] - k..=voxels.hi[1] + k,
            );
            let (xs, ys) = match in_view(&cloud.camera, z, p.stride_m) {
                Some((x, y)) => (clip(xs, x), clip(ys, y)),
                None => (xs, ys),
            };
            for iy in ys {
                for ix in xs.clone() {
                    let c = Point3::new(ix as f64 * p.stride_m, iy as f64 * p.stride_m, z);
                    if c.coords.norm() > p.max_range_m {
                        continue;
                    }
                    let Some((u, v)) = cloud
                        .camera
                        .project(&c)
                        .and_then(|px| cloud.camera.pixel_of(&px))
                    else {
                        continue;
                    };
                    if mask.is_some_and(|m| !m.get(u as usize, v as usize)) {
                        continue;
                    }
                    let Some(surface) = cloud.point_at(u as usize, v as usize) else {
                        continue;
                    };
                    let upper = if p.min_behind_m > 0.0 {
                        z - p.min_behind_m
                    } else {
                        z + p.max_in_front_m
                    };
                    if surface.z < z - half || surface.z > upper {
                        continue;
                    }
                    if voxels.count_around([ix, iy, iz], k) < p.min_points {
                        continue;
                    }
                    out.push(c);
                }
            }
        }
        out
    }

    /// The points of the box centred at `center`, or `None` when it holds fewer than
    /// `min_points` points with normals (estimated before thinning).
    pub fn patch(&self, cloud: &SceneCloud, center: Point3<f64>) -> Option<BoxPatch> {
        self.candidate(cloud, center)
            .and_then(|c| self.cut(cloud, &c))
    }

    /// The pixels of the box centred at `center` (normals are not read), or `None` when even
    /// counting every point inside it the box has fewer than `min_points` (estimated before
    /// thinning) — a box [`SlidingBox::cut`] would reject whatever the normals.
    pub fn candidate(&self, cloud: &SceneCloud, center: Point3<f64>) -> Option<BoxCandidate> {
        let p = &self.params;
        let half = self.half_m();
        let cam = &cloud.camera;
        // Pixel rectangle covering the box: project its eight corners.
        let (mut umin, mut umax, mut vmin, mut vmax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for corner in 0..8 {
            let s = |bit: i32| if corner & bit == 0 { -half } else { half };
            let q = center + Vector3::new(s(1), s(2), s(4));
            if q.z <= 1e-3 {
                return None;
            }
            let px = cam.project(&q)?;
            umin = umin.min(px.x);
            umax = umax.max(px.x);
            vmin = vmin.min(px.y);
            vmax = vmax.max(px.y);
        }
        let (w, h) = (cloud.width() as f64, cloud.height() as f64);
        let u0 = umin.round().clamp(0.0, w - 1.0) as usize;
        let u1 = umax.round().clamp(0.0, w - 1.0) as usize;
        let v0 = vmin.round().clamp(0.0, h - 1.0) as usize;
        let v1 = vmax.round().clamp(0.0, h - 1.0) as usize;
        let area = ((u1 - u0 + 1) * (v1 - v0 + 1)) as f64;
        // Thin by a pixel step so that at most about `max_points` pixels are read, on the
        // lattice where normals exist.
        let g = p.pixel_lattice.max(1);
        let step = ((area / p.max_points as f64).sqrt().ceil() as usize).max(1);
        let step = step.div_ceil(g) * g;
        // Samples on multiples of the step are shared by every box of that step; otherwise on
        // the normals' lattice from the box's corner (the step is a multiple of the lattice).
        let align = p.align_samples_min_focal_px.is_some_and(|f| cam.fx >= f);
        let start = if align { step } else { g };
        let (u0, v0) = (u0.div_ceil(start) * start, v0.div_ceil(start) * start);
        if u0 > u1 || v0 > v1 {
            return None;
        }
        let mut pixels = Vec::new();
        let width = cloud.width();
        for v in (v0..=v1).step_by(step) {
            for u in (u0..=u1).step_by(step) {
                let i = v * width + u;
                let d = cloud.point(i) - center;
                if d.x.abs() <= half && d.y.abs() <= half && d.z.abs() <= half {
                    pixels.push(i as u32); // NaN fails the test above
                }
            }
        }
        if pixels.len() * step * step < p.min_points || pixels.len() < 3 {
            return None;
        }
        Some(BoxCandidate {
            center,
            pixels,
            step,
        })
    }

    /// The patch of a candidate: its points that have normals, or `None` when fewer than
    /// `min_points` (estimated before thinning) remain, or the box is flat
    /// (`max_normal_coherence`).
    pub fn cut(&self, cloud: &SceneCloud, candidate: &BoxCandidate) -> Option<BoxPatch> {
        let p = &self.params;
        let step = candidate.step;
        let mut points = Vec::with_capacity(candidate.pixels.len());
        let mut normals = Vec::with_capacity(candidate.pixels.len());
        for &i in &candidate.pixels {
            if let Some(n) = cloud.normal(i as usize) {
                points.push(cloud.point(i as usize));
                normals.push(n);
            }
        }
        if points.len() * step * step < p.min_points || points.len() < 3 {
            return None;
        }
        if p.max_normal_coherence < 1.0 {
            let sum: Vector3<f64> = normals
                .iter()
                .map(|n: &Unit<Vector3<f64>>| n.into_inner())
                .sum();
            if sum.norm() > p.max_normal_coherence * normals.len() as f64 {
                return None;
            }
        }
        Some(BoxPatch {
            center: candidate.center,
            points,
            normals,
        })
    }

    /// Candidates of every box passing rules 1–3 and 5, in grid order (parallel,
    /// order-preserving); no normal is read.
    pub fn candidates(&self, cloud: &SceneCloud, mask: Option<&PruningMask>) -> Vec<BoxCandidate> {
        self.centres(cloud, mask)
            .into_par_iter()
            .filter_map(|c| self.candidate(cloud, c))
            .collect()
    }

    /// Patches of `candidates` (parallel, order-preserving), once the cloud has normals at
    /// their pixels.
    pub fn cut_all(&self, cloud: &SceneCloud, candidates: &[BoxCandidate]) -> Vec<BoxPatch> {
        candidates
            .par_iter()
            .filter_map(|c| self.cut(cloud, c))
            .collect()
    }

    /// Every accepted box of the frame, in grid order (parallel, order-preserving).
    pub fn patches(&self, cloud: &SceneCloud, mask: Option<&PruningMask>) -> Vec<BoxPatch> {
        let centres = self.centres(cloud, mask);
        centres
            .into_par_iter()
            .filter_map(|c| self.patch(cloud, c))
            .collect()
    }
}

/// Stage `sliding-box` of detection: the candidates (early rejection and pixels, no normals).
impl Stage<(&SceneCloud, Option<&PruningMask>), Vec<BoxCandidate>> for SlidingBox {
    fn name(&self) -> &'static str {
        "sliding-box"
    }

    fn run(
        &self,
        (cloud, mask): (&SceneCloud, Option<&PruningMask>),
    ) -> Result<Vec<BoxCandidate>, PipelineError> {
        Ok(self.candidates(cloud, mask))
    }
}

/// Stage `box-cut` of detection: candidates → patches once normals are known.
pub(crate) struct BoxCut<'a>(pub(crate) &'a SlidingBox);

impl Stage<(&SceneCloud, &[BoxCandidate]), Vec<BoxPatch>> for BoxCut<'_> {
    fn name(&self) -> &'static str {
        "box-cut"
    }

    fn run(
        &self,
        (cloud, candidates): (&SceneCloud, &[BoxCandidate]),
    ) -> Result<Vec<BoxPatch>, PipelineError> {
        Ok(self.0.cut_all(cloud, candidates))
    }
}

/// Node indices along x and along y (inclusive) outside which a centre at depth `z` projects
/// outside the image, with a node of margin on each side (`None` for a camera with lens
/// distortion, whose projection is not bounded this simply): skipping them changes nothing but
/// the time spent on a wide camera's empty space.
fn in_view(
    camera: &pomona_core::PinholeCamera,
    z: f64,
    stride_m: f64,
) -> Option<(RangeInclusive<i64>, RangeInclusive<i64>)> {
    if camera.distortion.is_some() {
        return None;
    }
    // Pixel centres are integers: the image spans [-0.5, size - 0.5) in continuous coordinates.
    let nodes = |size: u32, c: f64, f: f64| {
        let lo = (-0.5 - c) * z / f / stride_m;
        let hi = (size as f64 - 0.5 - c) * z / f / stride_m;
        lo.floor() as i64 - 1..=hi.ceil() as i64 + 1
    };
    Some((
        nodes(camera.width, camera.cx, camera.fx),
        nodes(camera.height, camera.cy, camera.fy),
    ))
}

/// The intersection of two inclusive ranges (empty when they do not meet).
fn clip(a: RangeInclusive<i64>, b: RangeInclusive<i64>) -> RangeInclusive<i64> {
    *a.start().max(b.start())..=*a.end().min(b.end())
}

/// Point counts per stride-sized voxel (voxel `i` is centred on grid node `i · stride`) with a
/// summed-volume table for O(1) box counts.
struct VoxelCounts {
    lo: [i64; 3],
    hi: [i64; 3],
    dims: [usize; 3],
    /// Inclusive prefix sums with a zero border: `(dims + 1)^3` entries.
    sat: Vec<u32>,
}

impl VoxelCounts {
    fn build(cloud: &SceneCloud, p: &SlidingBoxParams) -> Option<Self> {
        let inv = 1.0 / p.stride_m;
        let reach = p.max_range_m + p.box_size_m;
        // Every point within reach falls in a node index within ±`half_side` on x and y and in
        // 0..=`half_side` on z, so one pass counts into a dense grid of that extent and finds
        // the occupied bounds; the table is then summed over the occupied sub-grid only.
        // (`StageParams::validate` bounds the grid's size.)
        let half_side = (reach * inv).ceil() as i64 + 1;
        let side = (2 * half_side + 1) as usize;
        let depth = (half_side + 1) as usize;
        let mut grid = vec![0u32; side * side * depth];
        let mut lo = [i64::MAX; 3];
        let mut hi = [i64::MIN; 3];
        for q in cloud.points() {
            if !(q.z.is_finite() && q.z > 0.0 && q.coords.norm() <= reach) {
                continue;
            }
            let i = [
                (q.x * inv).round() as i64,
                (q.y * inv).round() as i64,
                (q.z * inv).round() as i64,
            ];
            for a in 0..3 {
                lo[a] = lo[a].min(i[a]);
                hi[a] = hi[a].max(i[a]);
            }
            let (x, y) = ((i[0] + half_side) as usize, (i[1] + half_side) as usize);
            grid[(i[2] as usize * side + y) * side + x] += 1;
        }
        if lo[0] > hi[0] {
            return None;
        }
        let dims = [0, 1, 2].map(|a| (hi[a] - lo[a] + 1) as usize);
        let (sx, sy) = (dims[0] + 1, dims[1] + 1);
        let mut sat = vec![0u32; sx * sy * (dims[2] + 1)];
        let at = |x: usize, y: usize, z: usize| (z * sy + y) * sx + x;
        for z in 0..dims[2] {
            let gz = (lo[2] + z as i64) as usize;
            for y in 0..dims[1] {
                let gy = (lo[1] + y as i64 + half_side) as usize;
                let row = (gz * side + gy) * side;
                let gx = (lo[0] + half_side) as usize;
                sat[at(1, y + 1, z + 1)..at(dims[0] + 1, y + 1, z + 1)]
                    .copy_from_slice(&grid[row + gx..row + gx + dims[0]]);
            }
        }
        for z in 1..=dims[2] {
            for y in 1..=dims[1] {
                for x in 1..=dims[0] {
                    let v = sat[at(x, y, z)] as i64
                        + sat[at(x - 1, y, z)] as i64
                        + sat[at(x, y - 1, z)] as i64
                        + sat[at(x, y, z - 1)] as i64
                        - sat[at(x - 1, y - 1, z)] as i64
                        - sat[at(x - 1, y, z - 1)] as i64
                        - sat[at(x, y - 1, z - 1)] as i64
                        + sat[at(x - 1, y - 1, z - 1)] as i64;
                    sat[at(x, y, z)] = v as u32;
                }
            }
        }
        Some(Self { lo, hi, dims, sat })
    }

    /// Points in the voxels within `k` of node `i` along every axis.
    fn count_around(&self, i: [i64; 3], k: i64) -> usize {
        let (sx, sy) = (self.dims[0] + 1, self.dims[1] + 1);
        let at = |x: usize, y: usize, z: usize| (z * sy + y) * sx + x;
        let mut a = [0usize; 3];
        let mut b = [0usize; 3];
        for d in 0..3 {
            let lo = (i[d] - k - self.lo[d]).clamp(0, self.dims[d] as i64);
            let hi = (i[d] + k - self.lo[d] + 1).clamp(0, self.dims[d] as i64);
            if hi <= lo {
                return 0;
            }
            a[d] = lo as usize;
            b[d] = hi as usize;
        }
        let s = |x: usize, y: usize, z: usize| self.sat[at(x, y, z)] as i64;
        let n =
            s(b[0], b[1], b[2]) - s(a[0], b[1], b[2]) - s(b[0], a[1], b[2]) - s(b[0], b[1], a[2])
                + s(a[0], a[1], b[2])
                + s(a[0], b[1], a[2])
                + s(b[0], a[1], a[2])
                - s(a[0], a[1], a[2]);
        n.max(0) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::PixelNormals;
    use pomona_core::PinholeCamera;

    /// A flat wall at `z` seen by a small camera, normals facing the camera.
    fn wall(z: f64) -> SceneCloud {
        let camera = PinholeCamera::new(64, 48, 60.0, 60.0, 31.5, 23.5).unwrap();
        let points: Vec<_> = (0..48 * 64)
            .map(|i| {
                camera
                    .back_project((i % 64) as f64, (i / 64) as f64, z)
                    .cast::<f32>()
            })
            .collect();
        let pixels: Vec<usize> = (0..points.len()).collect();
        let cloud = pomona_core::PointCloud::organized(64, 48, points).unwrap();
        let mut scene = SceneCloud::new(camera, cloud).unwrap();
        let normals = pixels.iter().map(|_| Some(-Vector3::z_axis()));
        scene.set_normals(PixelNormals::from_estimates(scene.len(), &pixels, normals));
        scene
    }

    #[test]
    fn every_node_seen_by_the_camera_lies_in_the_view_bounds() {
        // An off-centre principal point and unequal focal lengths, so no bound is symmetric.
        let camera = PinholeCamera::new(64, 48, 60.0, 50.0, 40.2, 17.9).unwrap();
        let stride = 0.03;
        for iz in 1..70 {
            let z = iz as f64 * stride;
            let (xs, ys) = in_view(&camera, z, stride).unwrap();
            let (mut lo, mut hi) = ([i64::MAX; 2], [i64::MIN; 2]);
            for iy in -200..=200 {
                for ix in -200..=200 {
                    let c = Point3::new(ix as f64 * stride, iy as f64 * stride, z);
                    let px = camera.project(&c).unwrap();
                    if camera.pixel_of(&px).is_some() {
                        assert!(
                            xs.contains(&ix) && ys.contains(&iy),
                            "node ({ix}, {iy}) at {z}"
                        );
                        lo = [lo[0].min(ix), lo[1].min(iy)];
                        hi = [hi[0].max(ix), hi[1].max(iy)];
                    }
                }
            }
            // Tight: at most two nodes of margin on each side.
            assert!(
                *xs.start() >= lo[0] - 2 && *xs.end() <= hi[0] + 2,
                "x at {z}"
            );
            assert!(
                *ys.start() >= lo[1] - 2 && *ys.end() <= hi[1] + 2,
                "y at {z}"
            );
        }
        let mut distorted = camera;
        distorted.distortion = Some(pomona_core::RadialDistortion { k1: -0.2, k2: 0.05 });
        assert!(in_view(&distorted, 1.0, stride).is_none());
    }

    #[test]
    fn boxes_sit_just_behind_the_surface() {
        let params = SlidingBoxParams {
            min_points: 20,
            ..Default::default()
        };
        let sb = SlidingBox::new(params);
        let cloud = wall(0.8);
        let centres = sb.centres(&cloud, None);
        assert!(!centres.is_empty());
        for c in &centres {
            // 20 mm (min_behind_m) to 60 mm (half a box) behind the wall.
            assert!(c.z >= 0.82 - 1e-9 && c.z <= 0.86 + 1e-9, "{c}");
        }
        let patches = sb.patches(&cloud, None);
        assert!(!patches.is_empty());
        for p in &patches {
            assert!(p.points.len() <= 2 * params.max_points);
            for q in &p.points {
                assert!((q - p.center).amax() <= 0.06 + 1e-12);
            }
        }
    }

    #[test]
    fn mask_and_range_reject_boxes() {
        let sb = SlidingBox::new(SlidingBoxParams {
            min_points: 20,
            ..Default::default()
        });
        let cloud = wall(0.8);
        let empty = PruningMask::new(64, 48, vec![false; 64 * 48]).unwrap();
        assert!(sb.centres(&cloud, Some(&empty)).is_empty());
        let far = SlidingBox::new(SlidingBoxParams {
            max_range_m: 0.5,
            min_points: 20,
            ..Default::default()
        });
        assert!(far.centres(&cloud, None).is_empty());
    }

    #[test]
    fn aligned_boxes_of_one_step_read_one_lattice() {
        let cloud = wall(0.8);
        // The wall's camera has a focal length of 60 px.
        let boxes = |align_samples_min_focal_px| {
            let sb = SlidingBox::new(SlidingBoxParams {
                min_points: 20,
                max_points: 30,
                align_samples_min_focal_px,
                ..Default::default()
            });
            sb.candidates(&cloud, None)
        };
        let (aligned, corner) = (boxes(Some(60.0)), boxes(None));
        assert_eq!(boxes(Some(60.1)), corner);
        assert_eq!(aligned.len(), corner.len());
        let lattice = |c: &BoxCandidate| {
            let (u, v) = (c.pixels[0] as usize % 64, c.pixels[0] as usize / 64);
            (u % c.step, v % c.step)
        };
        assert!(aligned.iter().all(|c| c.step > 1 && lattice(c) == (0, 0)));
        assert!(corner.iter().any(|c| lattice(c) != (0, 0)));
        for (a, c) in aligned.iter().zip(&corner) {
            // The same box and step; the same rectangle from a start less than a step further
            // on, so at most one sample row and column fewer or more.
            assert_eq!((a.center, a.step), (c.center, c.step));
            let (na, nc) = (a.pixels.len() as f64, c.pixels.len() as f64);
            assert!(
                (na - nc).abs() <= 2.0 * na.max(nc).sqrt() + 1.0,
                "{na} vs {nc}"
            );
        }
    }

    #[test]
    fn voxel_counts_match_brute_force() {
        let cloud = wall(0.7);
        let p = SlidingBoxParams {
            stride_m: 0.02,
            ..Default::default()
        };
        let vc = VoxelCounts::build(&cloud, &p).unwrap();
        let node = [0i64, 0, 35];
        let brute = cloud
            .points()
            .filter(|q| {
                (0..3).all(|a| {
                    let i = (q[a] / p.stride_m).round() as i64;
                    (i - node[a]).abs() <= 3
                })
            })
            .count();
        assert_eq!(vc.count_around(node, 3), brute);
        assert!(brute > 0);
    }
}
