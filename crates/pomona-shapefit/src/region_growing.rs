//! Seed 002's clustering of the masked depth image by region growing: a pixel joins its
//! 8-neighbour's cluster when their depths differ by at most a threshold (5 mm); clusters
//! smaller than a minimum size (150 px at the paper's 512×424) are dropped as background.
//!
//! Region growing is linear in the number of pixels, which is why the paper prefers it to
//! Euclidean clustering on the point cloud.

use serde::{Deserialize, Serialize};

use crate::OversizedSplit;

/// Parameters of region growing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RegionGrowingParams {
    /// Largest depth step between neighbours of one cluster, metres (paper: 5 mm).
    pub max_step_m: f64,
    /// Smallest cluster kept, in pixels of the reference camera (paper: 150).
    pub min_pixels: usize,
    /// Focal length, pixels, of the camera `min_pixels` refers to (paper: Kinect v2 depth,
    /// 365 px). Other cameras scale the minimum by `(fx / reference_focal_px)²`, so a cluster
    /// keeps the same solid angle — the same fruit at the same distance — whatever the sensor's
    /// resolution or field of view.
    pub reference_focal_px: f64,
    /// Pixels within this many pixels (8-neighbour steps) of a cluster's outline are dropped
    /// after the size test (not in the paper; 0 = off). Depth at a silhouette mixes the fruit
    /// and what lies behind it (time-of-flight flying pixels, depth registered to a
    /// higher-resolution colour camera), which pulls points backwards and swells fitted
    /// spheres; the rim is where that happens. Absent in older model files (then 0).
    #[serde(default)]
    pub rim_px: usize,
    /// Depth-scaled minimum (set by training's size prior, see `crate::SizePrior`): when
    /// present it replaces `min_pixels`, and a cluster is kept when it covers at least
    /// `fraction` of the image area of a sphere of `radius_m` at the cluster's median depth,
    /// `π (radius_m · fx / z)²` (at least 10 px). A fixed pixel count cannot serve a scene
    /// whose fruit stand 1–2 m from the camera: a limit that rejects leaf specks at 1 m
    /// rejects whole apples at 1.9 m. Absent in older model files (then `None`).
    #[serde(default)]
    pub min_fruit_area: Option<MinFruitArea>,
    /// Clusters larger than any fruit grown again with a smaller step where their surface
    /// separates (not in the paper; see [`OversizedSplit`]; never in a colour model's depth
    /// proposals). Absent in older model files (then off).
    #[serde(default)]
    pub split_oversized: Option<OversizedSplit>,
}

/// The smallest cluster as a fraction of the image area of the smallest expected fruit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MinFruitArea {
    /// Radius of the smallest expected fruit, metres.
    pub radius_m: f64,
    /// Fraction of its projected disc a cluster must cover, in `(0, 1]`.
    pub fraction: f64,
}

impl MinFruitArea {
    /// The minimum cluster size, pixels, at depth `z_m` for focal length `fx_px` (at least 10).
    pub fn min_pixels_at(&self, fx_px: f64, z_m: f64) -> usize {
        if z_m.is_nan() || z_m <= 0.0 {
            return usize::MAX;
        }
        let r_px = self.radius_m * fx_px / z_m;
        ((self.fraction * std::f64::consts::PI * r_px * r_px).round() as usize).max(10)
    }
}

impl Default for RegionGrowingParams {
    fn default() -> Self {
        Self {
            max_step_m: 0.005,
            min_pixels: 150,
            reference_focal_px: 365.0,
            rim_px: 0,
            min_fruit_area: None,
            split_oversized: None,
        }
    }
}

impl RegionGrowingParams {
    /// The minimum cluster size for a camera of focal length `fx_px` (at least 10, or
    /// `min_pixels` if that is smaller).
    pub fn min_pixels_for(&self, fx_px: f64) -> usize {
        let ratio = fx_px / self.reference_focal_px;
        let scaled = self.min_pixels as f64 * ratio * ratio;
        (scaled.round() as usize).max(self.min_pixels.min(10))
    }
}

/// Groups valid pixels (finite `depth_m` where `keep` is true) of an image taken with focal
/// length `fx_px` into clusters of pixel indices,
/// in raster order of their first pixel; clusters below the size limit are dropped.
pub fn grow_regions(
    width: usize,
    height: usize,
    fx_px: f64,
    depth_m: &[f32],
    keep: &[bool],
    params: &RegionGrowingParams,
) -> Vec<Vec<usize>> {
    let n = width * height;
    if depth_m.len() != n || keep.len() != n {
        return Vec::new();
    }
    let min_pixels = params.min_pixels_for(fx_px);
    let step = params.max_step_m as f32;
    let labels = connected_components(width, height, depth_m, keep, step);
    // Pixels per component, in raster order (so sorted), for components that may be big enough.
    let smallest = match &params.min_fruit_area {
        None => min_pixels,
        Some(_) => 10,
    };
    let wanted: Vec<bool> = labels.sizes.iter().map(|&s| s >= smallest).collect();
    let mut pixels: Vec<Vec<usize>> = labels
        .sizes
        .iter()
        .zip(&wanted)
        .map(|(&size, &w)| Vec::with_capacity(if w { size } else { 0 }))
        .collect();
    for (i, &label) in labels.label.iter().enumerate() {
        if wanted.get(label as usize) == Some(&true) {
            pixels[label as usize].push(i);
        }
    }
    let mut clusters: Vec<Vec<usize>> = pixels
        .into_iter()
        .zip(wanted)
        .filter(|(cluster, wanted)| {
            *wanted
                && match &params.min_fruit_area {
                    None => cluster.len() >= min_pixels,
                    Some(area) => {
                        cluster.len() >= 10
                            && cluster.len()
                                >= area.min_pixels_at(fx_px, median_depth(depth_m, cluster))
                    }
                }
        })
        .map(|(cluster, _)| cluster)
        .collect();
    if let Some(split) = &params.split_oversized {
        clusters = split.apply(width, height, fx_px, depth_m, clusters, params);
    }
    if params.rim_px > 0 {
        for cluster in &mut clusters {
            *cluster = erode(width, height, cluster, params.rim_px);
        }
        clusters.retain(|c| !c.is_empty());
    }
    clusters
}

/// [`grow_regions`] with the mask holding exactly `pixels` (row-major indices), computed on
/// their bounding box and a one-pixel margin, so that its cost follows the pixels rather than
/// the image: the same clusters in the same order. Indices outside the image are ignored.
pub fn grow_regions_over(
    width: usize,
    height: usize,
    fx_px: f64,
    depth_m: &[f32],
    pixels: &[usize],
    params: &RegionGrowingParams,
) -> Vec<Vec<usize>> {
    let n = width * height;
    if depth_m.len() != n {
        return Vec::new();
    }
    let inside = || pixels.iter().copied().filter(|&i| i < n);
    // Bounding box (columns u0..=u1, rows v0..=v1) with a one-pixel margin, in one pass.
    let Some((u0, u1, v0, v1)) = inside().fold(None, |b, i| {
        let (u, v) = (i % width, i / width);
        Some(match b {
            None => (u, u, v, v),
            Some((a, b, c, d)) => (u.min(a), u.max(b), v.min(c), v.max(d)),
        })
    }) else {
        return Vec::new();
    };
    let (u0, u1) = (u0.saturating_sub(1), (u1 + 1).min(width - 1));
    let (v0, v1) = (v0.saturating_sub(1), (v1 + 1).min(height - 1));
    let (w, h) = (u1 - u0 + 1, v1 - v0 + 1);
    let to_box = |i: usize| (i / width - v0) * w + (i % width - u0);
    let mut keep = vec![false; w * h];
    for i in inside() {
        keep[to_box(i)] = true;
    }
    let depth: Vec<f32> = (v0..=v1)
        .flat_map(|v| depth_m[v * width + u0..=v * width + u1].iter().copied())
        .collect();
    grow_regions(w, h, fx_px, &depth, &keep, params)
        .into_iter()
        .map(|cluster| {
            cluster
                .into_iter()
                .map(|j| (v0 + j / w) * width + u0 + j % w)
                .collect()
        })
        .collect()
}

/// The connected components of the valid pixels: `label[i]` numbers pixel `i`'s component
/// (`u32::MAX` for invalid pixels), components numbered in raster order of their first pixel;
/// `sizes[c]` is component `c`'s pixel count.
struct Components {
    label: Vec<u32>,
    sizes: Vec<usize>,
}

/// Components of the graph whose nodes are the valid pixels (finite depth, `keep`) and whose
/// edges join 8-neighbours with depths at most `step` apart — what growing a region from each
/// unreached valid pixel in raster order finds, in the same order, but by one raster scan with
/// union–find over the four neighbours already scanned (left, and the three above) and one
/// labelling scan, rather than a stack-driven fill that tests all eight neighbours of every
/// pixel. Each union keeps the smaller index as the root, so a component's root is its first
/// pixel in raster order.
fn connected_components(
    width: usize,
    height: usize,
    depth_m: &[f32],
    keep: &[bool],
    step: f32,
) -> Components {
    const NONE: u32 = u32::MAX;
    let n = width * height;
    // Filled in raster order (no pass to pre-fill it): every read is of the current pixel or an
    // earlier one.
    let mut parent: Vec<u32> = Vec::with_capacity(n);
    let find = |parent: &mut [u32], mut i: u32| {
        while parent[i as usize] != i {
            let grand = parent[parent[i as usize] as usize];
            parent[i as usize] = grand; // path halving
            i = grand;
        }
        i
    };
    for v in 0..height {
        for u in 0..width {
            let i = v * width + u;
            let d = depth_m[i];
            if !keep[i] || !d.is_finite() {
                parent.push(NONE);
                continue;
            }
            // `root`: the root of i's component so far (i's parent is kept pointing at it).
            let mut root = i as u32;
            parent.push(root);
            let mut join = |parent: &mut [u32], j: usize| {
                // An invalid neighbour has no parent (NaN depth would fail the test anyway).
                if parent[j] == NONE || (depth_m[j] - d).abs() > step {
                    return;
                }
                if parent[j] == root {
                    return; // already in i's tree, next to its root (what `find` would say)
                }
                let other = find(parent, j as u32);
                if other < root {
                    parent[root as usize] = other;
                    root = other;
                } else if other > root {
                    parent[other as usize] = root;
                }
            };
            if u > 0 {
                join(&mut parent, i - 1);
            }
            if v > 0 {
                let above = i - width;
                if u > 0 {
                    join(&mut parent, above - 1);
                }
                join(&mut parent, above);
                if u + 1 < width {
                    join(&mut parent, above + 1);
                }
            }
            parent[i] = root;
        }
    }
    // Labelled in place, in raster order: a root (its own parent) opens the next component; any
    // other pixel's parent is an earlier pixel of its component (unions and path halving only
    // ever point to smaller indices), whose entry already holds the component's number.
    let mut sizes = Vec::new();
    for i in 0..n {
        let p = parent[i];
        if p == NONE {
            continue;
        }
        let c = if p as usize == i {
            sizes.push(0);
            (sizes.len() - 1) as u32
        } else {
            parent[p as usize]
        };
        parent[i] = c;
        sizes[c as usize] += 1;
    }
    Components {
        label: parent,
        sizes,
    }
}

/// The image area, pixels, of a disc of radius `r` metres at `cluster`'s median depth
/// (`depth_m`, focal length `fx_px`): `π (r · fx_px / z)²`, as a function of `r`; `None` when
/// the median depth is not a positive number. What the size tests on whole clusters compare
/// their pixel counts with.
pub(crate) fn disc_area_px(
    depth_m: &[f32],
    fx_px: f64,
    cluster: &[usize],
) -> Option<impl Fn(f64) -> f64> {
    let z_m = median_depth(depth_m, cluster);
    (z_m.is_finite() && z_m > 0.0)
        .then_some(move |r_m: f64| std::f64::consts::PI * (r_m * fx_px / z_m).powi(2))
}

/// Median depth of the pixels of `cluster` (all finite); `NaN` for an empty cluster.
pub(crate) fn median_depth(depth_m: &[f32], cluster: &[usize]) -> f64 {
    let mut z: Vec<f32> = cluster.iter().map(|&i| depth_m[i]).collect();
    let mid = z.len() / 2;
    if z.is_empty() {
        return f64::NAN;
    }
    let (_, m, _) = z.select_nth_unstable_by(mid, f32::total_cmp);
    f64::from(*m)
}

/// The pixels of a sorted `cluster` whose every pixel within `rim_px` 8-neighbour steps (a
/// square of side `2 rim_px + 1`) belongs to the cluster; sorted.
fn erode(width: usize, height: usize, cluster: &[usize], rim_px: usize) -> Vec<usize> {
    let r = rim_px as isize;
    let mut current = cluster.to_vec();
    // Separable: a (2r+1)-pixel erosion along rows, then along columns.
    for (du, dv) in [(1isize, 0isize), (0, 1)] {
        let previous = std::mem::take(&mut current);
        let run_inside = |i: usize| {
            let (u, v) = ((i % width) as isize, (i / width) as isize);
            (-r..=r).all(|k| {
                let (nu, nv) = (u + k * du, v + k * dv);
                nu >= 0
                    && nv >= 0
                    && nu < width as isize
                    && nv < height as isize
                    && previous
                        .binary_search(&(nv as usize * width + nu as usize))
                        .is_ok()
            })
        };
        current = previous
            .iter()
            .copied()
            .filter(|&i| run_inside(i))
            .collect();
    }
    current
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Region growing as the definition reads: a stack-driven fill of the 8-neighbours from
    /// each unreached valid pixel in raster order; every component, with its pixels sorted.
    fn flood_fill(
        width: usize,
        height: usize,
        depth: &[f32],
        keep: &[bool],
        step: f32,
    ) -> Vec<Vec<usize>> {
        let mut reached = vec![false; depth.len()];
        let mut out = Vec::new();
        for seed in 0..depth.len() {
            if reached[seed] || !keep[seed] || !depth[seed].is_finite() {
                continue;
            }
            reached[seed] = true;
            let (mut cluster, mut stack) = (vec![seed], vec![seed]);
            while let Some(i) = stack.pop() {
                let (u, v) = (i % width, i / width);
                for nv in v.saturating_sub(1)..=(v + 1).min(height - 1) {
                    for nu in u.saturating_sub(1)..=(u + 1).min(width - 1) {
                        let j = nv * width + nu;
                        if !reached[j] && keep[j] && (depth[j] - depth[i]).abs() <= step {
                            reached[j] = true;
                            cluster.push(j);
                            stack.push(j);
                        }
                    }
                }
            }
            cluster.sort_unstable();
            out.push(cluster);
        }
        out
    }

    #[test]
    fn growing_over_a_pixel_list_is_growing_over_its_mask() {
        // Random depth terraces and random pixel lists (dense blobs and scattered specks, some
        // touching the image's border), under each way a cluster's size is limited and with a
        // rim: the bounding-box computation gives the whole image's clusters.
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (width, height) = (40, 30);
        let settings = [
            RegionGrowingParams {
                min_pixels: 4,
                reference_focal_px: 100.0,
                ..RegionGrowingParams::default()
            },
            RegionGrowingParams {
                min_fruit_area: Some(MinFruitArea {
                    radius_m: 0.01,
                    fraction: 0.5,
                }),
                ..RegionGrowingParams::default()
            },
            RegionGrowingParams {
                min_pixels: 4,
                reference_focal_px: 100.0,
                rim_px: 2,
                ..RegionGrowingParams::default()
            },
        ];
        for trial in 0..60 {
            let depth: Vec<f32> = (0..width * height)
                .map(|_| 0.5 + 0.004 * rng.gen_range(0..3) as f32)
                .collect();
            let (cu, cv) = (rng.gen_range(0..width), rng.gen_range(0..height));
            let reach = rng.gen_range(2..15) as i64;
            let pixels: Vec<usize> = (0..width * height)
                .filter(|&i| {
                    let (du, dv) = (
                        (i % width) as i64 - cu as i64,
                        (i / width) as i64 - cv as i64,
                    );
                    du.abs().max(dv.abs()) <= reach && rng.gen_bool(0.8)
                })
                .collect();
            let mut keep = vec![false; width * height];
            for &i in &pixels {
                keep[i] = true;
            }
            let params = &settings[trial % settings.len()];
            assert_eq!(
                grow_regions_over(width, height, 100.0, &depth, &pixels, params),
                grow_regions(width, height, 100.0, &depth, &keep, params),
                "trial {trial}"
            );
        }
        assert!(grow_regions_over(4, 4, 100.0, &[0.5; 16], &[], &settings[0]).is_empty());
    }

    #[test]
    fn components_are_those_of_the_flood_fill_in_the_same_order() {
        // Random terraces with holes, masked pixels and ramps: many components of every shape
        // (U-shapes and spirals merge late in a raster scan).
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut next = || rng.gen::<u64>();
        for (width, height) in [(1, 1), (1, 7), (9, 1), (23, 17), (64, 48)] {
            for _ in 0..20 {
                let n = width * height;
                let depth: Vec<f32> = (0..n)
                    .map(|i| match next() % 10 {
                        0 => f32::NAN,
                        r => 0.5 + 0.004 * (r % 3) as f32 + 0.0001 * (i % width) as f32,
                    })
                    .collect();
                let keep: Vec<bool> = (0..n).map(|_| next() % 7 != 0).collect();
                let expected = flood_fill(width, height, &depth, &keep, 0.005);
                let labels = connected_components(width, height, &depth, &keep, 0.005);
                let mut found: Vec<Vec<usize>> = vec![Vec::new(); labels.sizes.len()];
                for (i, &c) in labels.label.iter().enumerate() {
                    if c != u32::MAX {
                        found[c as usize].push(i);
                    }
                }
                assert_eq!(found, expected, "{width}×{height}");
                let sizes: Vec<usize> = expected.iter().map(Vec::len).collect();
                assert_eq!(labels.sizes, sizes);
            }
        }
    }

    #[test]
    fn splits_at_depth_steps_and_drops_small_clusters() {
        // 40×10 image: left half at 0.5 m, right half at 0.52 m (20 mm step), a 3-pixel speck.
        let (w, h) = (40, 10);
        let mut depth = vec![0.5f32; w * h];
        for v in 0..h {
            for u in 20..w {
                depth[v * w + u] = 0.52;
            }
        }
        let keep = vec![true; w * h];
        let params = RegionGrowingParams {
            min_pixels: 50,
            ..Default::default()
        };
        let clusters = grow_regions(w, h, 365.0, &depth, &keep, &params);
        assert_eq!(clusters.len(), 2);
        assert_eq!(clusters[0].len(), 200);
        let mut masked = keep.clone();
        masked[5] = false;
        assert_eq!(
            grow_regions(w, h, 365.0, &depth, &masked, &params)[0].len(),
            199
        );
    }

    #[test]
    fn slopes_grow_but_jumps_do_not() {
        // A ramp rising 4 mm per pixel stays one cluster; diagonal neighbours connect.
        let (w, h) = (30, 3);
        let depth: Vec<f32> = (0..w * h).map(|i| 0.5 + 0.004 * (i % w) as f32).collect();
        let params = RegionGrowingParams {
            min_pixels: 10,
            ..Default::default()
        };
        assert_eq!(
            grow_regions(w, h, 365.0, &depth, &vec![true; w * h], &params).len(),
            1
        );
        let mut diag = vec![f32::NAN; 9];
        for i in [0, 4, 8] {
            diag[i] = 1.0;
        }
        let p = RegionGrowingParams {
            min_pixels: 3,
            ..Default::default()
        };
        let c = grow_regions(3, 3, 365.0, &diag, &[true; 9], &p);
        assert_eq!(c, vec![vec![0, 4, 8]]);
    }

    #[test]
    fn rim_erosion_drops_outline_pixels() {
        // A 10×8 block in a 20×20 image: one pixel of rim leaves 8×6, two leave 6×4.
        let (w, h) = (20, 20);
        let mut depth = vec![f32::NAN; w * h];
        for v in 5..13 {
            for u in 3..13 {
                depth[v * w + u] = 0.8;
            }
        }
        let keep = vec![true; w * h];
        let with_rim = |rim_px| RegionGrowingParams {
            min_pixels: 10,
            rim_px,
            ..Default::default()
        };
        let full = grow_regions(w, h, 365.0, &depth, &keep, &with_rim(0));
        assert_eq!(full[0].len(), 80);
        let one = grow_regions(w, h, 365.0, &depth, &keep, &with_rim(1));
        assert_eq!(one[0].len(), 48);
        assert!(one[0].contains(&(6 * w + 4)) && !one[0].contains(&(5 * w + 4)));
        assert_eq!(
            grow_regions(w, h, 365.0, &depth, &keep, &with_rim(2))[0].len(),
            24
        );
        assert!(grow_regions(w, h, 365.0, &depth, &keep, &with_rim(4)).is_empty());
    }

    #[test]
    fn depth_scaled_minimum_keeps_far_fruit_and_drops_near_specks() {
        // Two 12×12 blocks (144 px): one at 2 m, one at 0.5 m. A 30 mm fruit at fx 365 covers
        // π·5.5² ≈ 94 px at 2 m and π·21.9² ≈ 1507 px at 0.5 m; a quarter of that is the limit.
        let (w, h) = (40, 20);
        let mut depth = vec![f32::NAN; w * h];
        for v in 2..14 {
            for u in 2..14 {
                depth[v * w + u] = 2.0;
                depth[v * w + u + 20] = 0.5;
            }
        }
        let params = RegionGrowingParams {
            min_fruit_area: Some(MinFruitArea {
                radius_m: 0.03,
                fraction: 0.25,
            }),
            ..Default::default()
        };
        let clusters = grow_regions(w, h, 365.0, &depth, &vec![true; w * h], &params);
        assert_eq!(clusters.len(), 1);
        assert_eq!(depth[clusters[0][0]], 2.0);
        let area = params.min_fruit_area.unwrap();
        assert_eq!(area.min_pixels_at(365.0, 2.0), 24);
        assert_eq!(area.min_pixels_at(365.0, 0.5), 377);
        assert_eq!(area.min_pixels_at(365.0, 0.0), usize::MAX);
    }

    #[test]
    fn minimum_scales_with_resolution() {
        let p = RegionGrowingParams::default();
        assert_eq!(p.min_pixels_for(365.0), 150);
        assert_eq!(p.min_pixels_for(917.0), 947); // Azure Kinect colour
        assert_eq!(p.min_pixels_for(182.5), 38); // half resolution
        assert_eq!(p.min_pixels_for(10.0), 10);
    }
}
