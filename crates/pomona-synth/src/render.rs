//! The renderer: a per-pixel ray caster with a z-buffer, producing colour, depth, instance mask
//! and truth in one pass over the scene.
//!
//! Why ray casting: every object has an exact ray query (analytic for leaves, stems and the
//! background, implicit-surface marching for fruit), so depth, mask and visibility are exact with
//! no tessellation error. Each object is only tested on the pixels of its screen-space bounding
//! box (the projection of a cube around its bounding sphere), which keeps a 512×424 frame near
//! 0.1 s on one core.
//!
//! Steps:
//! 1. z-buffer: for every object and every pixel of its box, intersect the pixel ray; keep the
//!    nearest hit. Rays are `C + t·R·(x', y', 1)` with `(x', y')` the normalised pixel
//!    coordinates, so the ray parameter `t` *is* the camera-frame z of the hit (depth images
//!    hold z, not ray length). A fruit also counts every pixel its ray hits at all: that is the
//!    pixel count "rendered alone", the denominator of visibility.
//! 2. shading: Blinn–Phong at each pixel's visible surface; mild Gaussian image noise; sRGB-like
//!    gamma 1/2.2 to 8 bits.
//! 3. depth noise per [`crate::NoiseModel`].
//! 4. truth: every fruit with at least one visible pixel, in scene order; mask id `k` is the
//!    k-th of them (1-based). Fruit wholly hidden or out of view are not listed.

use nalgebra::{Isometry3, Point2, Point3, Vector3};
use pomona_core::{
    ColorImage, DepthImage, FrameTruth, FruitTruth, ImageCircle, InstanceMask, PinholeCamera,
    PixelBox, RgbdFrame,
};

use crate::depth_noise::SurfaceSample;
use crate::rng::{sub_rng, NormalSampler};
use crate::shadow::{Occluder, ShadowGrid};
use crate::{Material, Scene, SynthError};

/// One rendered view: the RGB-D frame, its truth and its instance mask.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderedFrame {
    /// Colour and depth on the camera's pixel grid.
    pub frame: RgbdFrame,
    /// Every visible fruit, in the camera frame of this view; `complete` is `true`.
    pub truth: FrameTruth,
    /// 0 = not fruit, `k` = the k-th fruit of `truth.fruits` (1-based).
    pub mask: InstanceMask,
}

/// What a pixel's ray hit first.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Hit {
    Nothing,
    Backdrop,
    Stem(u32),
    Leaf(u32, f32),
    Fruit(u32),
}

/// Renders the primary view: the camera sits at the scene origin looking down +z.
///
/// # Errors
/// [`SynthError::Core`] only if an image could not be assembled (a bug).
pub fn render(scene: &Scene, camera: &PinholeCamera) -> Result<RenderedFrame, SynthError> {
    render_view(scene, camera, &Isometry3::identity(), 0)
}

/// Renders the scene through a camera with pose `camera_from_scene` (maps scene points into the
/// camera frame). Truth is expressed in that camera's frame. `noise_stream` selects independent
/// image and depth noise (0 for the primary view, 1 for the stereo view).
///
/// # Errors
/// [`SynthError::Core`] only if an image could not be assembled (a bug).
pub fn render_view(
    scene: &Scene,
    camera: &PinholeCamera,
    camera_from_scene: &Isometry3<f64>,
    noise_stream: u64,
) -> Result<RenderedFrame, SynthError> {
    camera.validate()?;
    let view = View::new(camera, camera_from_scene);
    let (w, h) = (camera.width as usize, camera.height as usize);
    let z = z_buffer(scene, &view, w, h);
    let (mut rgb_linear, surfaces) = shade(scene, &view, &z);
    if let Some(effects) = &scene.image_effects {
        effects.apply(&mut rgb_linear, w, h);
    }
    let color = encode_color(scene, camera, &rgb_linear, noise_stream)?;
    let depth_image = noisy_depth(scene, camera, &surfaces, noise_stream)?;
    let (truth, mask) = truth_and_mask(scene, camera, camera_from_scene, &z)?;
    let frame = RgbdFrame::new(*camera, depth_image, Some(color))?;
    Ok(RenderedFrame { frame, truth, mask })
}

/// The nearest surface along each pixel's ray.
struct ZBuffer {
    width: usize,
    /// Ray parameter of the nearest hit per pixel (infinite where nothing is hit).
    depth: Vec<f64>,
    hits: Vec<Hit>,
    /// Per fruit: pixels its surface covers with nothing in front (for visibility).
    alone: Vec<usize>,
}

/// Step 1: ray-casts the backdrop, stems, leaves and fruit, keeping the nearest hit per pixel.
fn z_buffer(scene: &Scene, view: &View<'_>, w: usize, h: usize) -> ZBuffer {
    let n = w * h;
    let mut depth = vec![f64::INFINITY; n];
    let mut hits = vec![Hit::Nothing; n];
    let full = Some((0, w - 1, 0, h - 1));
    view.each_pixel(full, |i, o, d| {
        if let Some(t) = scene.backdrop.intersect(o, d) {
            depth[i] = t;
            hits[i] = Hit::Backdrop;
        }
    });
    for (k, stem) in scene.stems.iter().enumerate() {
        let r = stem.radius_m;
        let rect = view.screen_rect(&[(stem.start, r), (stem.end, r)]);
        view.each_pixel(rect, |i, o, d| {
            if let Some(t) = stem.intersect(o, d) {
                if t < depth[i] {
                    depth[i] = t;
                    hits[i] = Hit::Stem(k as u32);
                }
            }
        });
    }
    for (k, leaf) in scene.leaves.iter().enumerate() {
        let rect = view.screen_rect(&leaf.box_corners().map(|p| (p, 0.0)));
        view.each_pixel(rect, |i, o, d| {
            if let Some(hit) = leaf.intersect(o, d) {
                if hit.t < depth[i] {
                    depth[i] = hit.t;
                    hits[i] = Hit::Leaf(k as u32, hit.across as f32);
                }
            }
        });
    }
    let mut alone = vec![0usize; scene.fruits.len()];
    for (k, fruit) in scene.fruits.iter().enumerate() {
        let rect = view.screen_rect(&[(fruit.center, fruit.bounding_radius_m())]);
        view.each_pixel(rect, |i, o, d| {
            if let Some(t) = fruit.intersect(o, d) {
                alone[k] += 1;
                if t < depth[i] {
                    depth[i] = t;
                    hits[i] = Hit::Fruit(k as u32);
                }
            }
        });
    }
    ZBuffer {
        width: w,
        depth,
        hits,
        alone,
    }
}

/// Step 2: linear radiance per pixel (sun with optional cast shadows, sky light) and what the
/// depth sensor's noise model needs to know about each surface.
fn shade(scene: &Scene, view: &View<'_>, z: &ZBuffer) -> (Vec<[f64; 3]>, Vec<SurfaceSample>) {
    let n = z.depth.len();
    let full = Some((0, z.width - 1, 0, n / z.width - 1));
    let mut rgb_linear = vec![[0.0f64; 3]; n];
    let mut surfaces = vec![
        SurfaceSample {
            z: f64::NAN,
            amplitude: 0.0,
            cos_incidence: 0.0,
            no_return: false,
        };
        n
    ];
    let shadows = scene.shadows.then(|| ShadowGrid::new(scene));
    view.each_pixel(full, |i, o, d| {
        let t = z.depth[i];
        let p = o + d * t;
        // Time-of-flight sensors see in the near infrared, where living plant tissue reflects
        // strongly whatever its visible colour (a dark purple eggplant is bright at 850 nm), so
        // plant surfaces get a floor on the amplitude that drives dropouts; the backdrop keeps
        // its visible luminance.
        let hit = z.hits[i];
        let plant = !matches!(hit, Hit::Backdrop | Hit::Nothing);
        let (normal, material) = match hit {
            Hit::Nothing => {
                if let Some(sky) = scene.backdrop.sky_radiance(d) {
                    rgb_linear[i] = sky;
                }
                return;
            }
            Hit::Backdrop => (
                scene.backdrop.normal.into_inner(),
                scene.backdrop.material_at(&p),
            ),
            Hit::Stem(k) => {
                let s = &scene.stems[k as usize];
                (s.normal_at(&p), s.material)
            }
            Hit::Leaf(k, across) => {
                let l = &scene.leaves[k as usize];
                (l.normal_at(&p), leaf_material(&l.material, across as f64))
            }
            Hit::Fruit(k) => {
                let f = &scene.fruits[k as usize];
                (f.normal_at(&p), f.material_at(&p))
            }
        };
        let to_viewer = (-d).normalize();
        let cos_raw = normal.dot(&to_viewer);
        // Thin surfaces are seen from either side; closed ones face the viewer anyway.
        let normal = if cos_raw < 0.0 { -normal } else { normal };
        let cos_incidence = cos_raw.abs();
        rgb_linear[i] = match &shadows {
            None => scene.light.shade(&material, &normal, &to_viewer),
            Some(grid) => {
                let skip = match hit {
                    Hit::Leaf(k, _) => Some(Occluder::Leaf(k)),
                    Hit::Stem(k) => Some(Occluder::Stem(k)),
                    Hit::Fruit(k) => Some(Occluder::Fruit(k)),
                    Hit::Nothing | Hit::Backdrop => None,
                };
                // Only surfaces facing the sun can be shadowed.
                let facing = normal.dot(scene.light.towards_light.as_ref()) > 0.0;
                let sun = if facing && !grid.sun_visible(&p, skip) {
                    0.0
                } else {
                    1.0
                };
                scene.light.shade_lit(&material, &normal, &to_viewer, sun)
            }
        };
        surfaces[i] = SurfaceSample {
            z: t,
            amplitude: nir_reflectance(&material, plant) * cos_incidence,
            cos_incidence,
            no_return: matches!(hit, Hit::Backdrop) && !scene.backdrop.returns_depth(),
        };
    });
    (rgb_linear, surfaces)
}

/// The 8-bit colour image: gamma-encoded radiance plus sensor noise (noise stream
/// `2 * noise_stream`).
fn encode_color(
    scene: &Scene,
    camera: &PinholeCamera,
    rgb_linear: &[[f64; 3]],
    noise_stream: u64,
) -> Result<ColorImage, SynthError> {
    let mut noise_rng = sub_rng(scene.noise_seed, 2 * noise_stream);
    let gamma = GammaTable::new();
    let sigma = scene.light.image_noise_sigma;
    let mut normal = NormalSampler::default();
    let mut rgb = Vec::with_capacity(3 * rgb_linear.len());
    for px in rgb_linear {
        for &c in px {
            let value = gamma.encode(c) + sigma * normal.sample(&mut noise_rng);
            rgb.push(value.round().clamp(0.0, 255.0) as u8);
        }
    }
    Ok(ColorImage::from_rgb(camera.width, camera.height, rgb)?)
}

/// Step 3: the depth image through the scene's sensor noise model (noise stream
/// `2 * noise_stream + 1`), cut at the scene's maximum depth.
fn noisy_depth(
    scene: &Scene,
    camera: &PinholeCamera,
    surfaces: &[SurfaceSample],
    noise_stream: u64,
) -> Result<DepthImage, SynthError> {
    let w = camera.width as usize;
    let mut depth_rng = sub_rng(scene.noise_seed, 2 * noise_stream + 1);
    let mut depth_m = scene.noise.apply(surfaces, w, camera.fx, &mut depth_rng);
    if scene.max_depth_m.is_finite() {
        for z in &mut depth_m {
            if f64::from(*z) > scene.max_depth_m {
                *z = f32::NAN;
            }
        }
    }
    Ok(DepthImage::from_meters(
        camera.width,
        camera.height,
        depth_m,
    )?)
}

/// Step 4: truth of every visible fruit (in the camera frame) and the instance mask.
fn truth_and_mask(
    scene: &Scene,
    camera: &PinholeCamera,
    camera_from_scene: &Isometry3<f64>,
    z: &ZBuffer,
) -> Result<(FrameTruth, InstanceMask), SynthError> {
    let w = z.width;
    let mut visible = vec![0usize; scene.fruits.len()];
    let mut boxes = vec![(usize::MAX, usize::MAX, 0usize, 0usize); scene.fruits.len()];
    for (i, hit) in z.hits.iter().enumerate() {
        if let Hit::Fruit(k) = hit {
            let k = *k as usize;
            let (u, v) = (i % w, i / w);
            visible[k] += 1;
            let b = &mut boxes[k];
            *b = (b.0.min(u), b.1.min(v), b.2.max(u), b.3.max(v));
        }
    }
    let mut mask_id = vec![0u16; scene.fruits.len()];
    let mut fruits = Vec::new();
    for (k, fruit) in scene.fruits.iter().enumerate() {
        if visible[k] == 0 || fruits.len() >= u16::MAX as usize {
            continue;
        }
        let b = boxes[k];
        let center_m = camera_from_scene * fruit.center;
        let circle = ImageCircle::of_sphere(camera, &center_m, 0.5 * fruit.diameter_m());
        fruits.push(FruitTruth {
            id: k.to_string(),
            kind: fruit.kind.name().to_string(),
            center_m: Some(center_m),
            diameter_m: Some(fruit.diameter_m()),
            axis: Some(camera_from_scene.rotation * fruit.axis()),
            bbox_px: Some(PixelBox::new(
                b.0 as f64, b.1 as f64, b.2 as f64, b.3 as f64,
            )?),
            center_px: circle.map(|c| c.center_px),
            radius_px: circle.map(|c| c.radius_px),
            visibility: Some(visible[k] as f64 / z.alone[k].max(visible[k]) as f64),
            extra: serde_json::Map::new(),
        });
        mask_id[k] = fruits.len() as u16;
    }
    let ids = z
        .hits
        .iter()
        .map(|hit| match hit {
            Hit::Fruit(k) => mask_id[*k as usize],
            _ => 0,
        })
        .collect();
    let mask = InstanceMask::from_ids(camera.width, camera.height, ids)?;
    let truth = FrameTruth {
        complete: true,
        fruits,
        extra: scene.truth_extra.clone(),
    };
    Ok((truth, mask))
}

/// Leaf colour with a lighter midrib and slightly darker margins.
/// Near-infrared reflectance used as the return amplitude of depth noise (see `render`).
fn nir_reflectance(material: &Material, plant: bool) -> f64 {
    if plant {
        material.luminance().max(PLANT_NIR_REFLECTANCE)
    } else {
        material.luminance()
    }
}

/// Lower bound of plant tissue's near-infrared reflectance (leaves and fruit reflect roughly
/// 0.4–0.6 at 850 nm; 0.3 leaves room for shading and wet surfaces).
const PLANT_NIR_REFLECTANCE: f64 = 0.3;

fn leaf_material(base: &Material, across: f64) -> Material {
    let f = if across.abs() < 0.06 {
        1.35
    } else {
        1.0 - 0.15 * across * across
    };
    base.tinted([f, f, f])
}

/// The camera of one view, expressed in the scene frame.
struct View<'a> {
    camera: &'a PinholeCamera,
    camera_from_scene: &'a Isometry3<f64>,
    /// Camera centre in the scene frame.
    origin: Point3<f64>,
    /// Columns of the camera-to-scene rotation.
    axes: [Vector3<f64>; 3],
}

impl<'a> View<'a> {
    fn new(camera: &'a PinholeCamera, camera_from_scene: &'a Isometry3<f64>) -> Self {
        let scene_from_camera = camera_from_scene.inverse();
        let r = scene_from_camera.rotation.to_rotation_matrix();
        let m = r.matrix();
        Self {
            camera,
            camera_from_scene,
            origin: scene_from_camera * Point3::origin(),
            axes: [
                m.column(0).into_owned(),
                m.column(1).into_owned(),
                m.column(2).into_owned(),
            ],
        }
    }

    /// Calls `f(index, ray origin, ray direction)` for every pixel of an inclusive rectangle
    /// `(u0, u1, v0, v1)`, row by row. Directions have camera-frame z = 1.
    fn each_pixel(
        &self,
        rect: Option<(usize, usize, usize, usize)>,
        mut f: impl FnMut(usize, &Point3<f64>, &Vector3<f64>),
    ) {
        let Some((u0, u1, v0, v1)) = rect else {
            return;
        };
        let c = self.camera;
        let w = c.width as usize;
        if c.distortion.is_some() {
            // Rays through the distorted pixel model.
            for v in v0..=v1 {
                for u in u0..=u1 {
                    let n = c.normalised(&Point2::new(u as f64, v as f64));
                    let dir = self.axes[0] * n.x + self.axes[1] * n.y + self.axes[2];
                    f(v * w + u, &self.origin, &dir);
                }
            }
            return;
        }
        for v in v0..=v1 {
            let y = (v as f64 - c.cy) / c.fy;
            let row = self.axes[1] * y + self.axes[2];
            for u in u0..=u1 {
                let x = (u as f64 - c.cx) / c.fx;
                let dir = self.axes[0] * x + row;
                f(v * w + u, &self.origin, &dir);
            }
        }
    }

    /// The pixel rectangle covering a union of spheres `(centre in scene frame, radius)`, or
    /// `None` when it is wholly outside the image. Conservative: projects the corners of a cube
    /// around each sphere; any corner at or behind the camera plane means "whole image".
    fn screen_rect(&self, spheres: &[(Point3<f64>, f64)]) -> Option<(usize, usize, usize, usize)> {
        let c = self.camera;
        let (mut umin, mut vmin, mut umax, mut vmax) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for (center, r) in spheres {
            let pc = self.camera_from_scene * center;
            for corner in 0..8 {
                let s = |bit: i32| if corner & bit != 0 { *r } else { -*r };
                let q = pc + Vector3::new(s(1), s(2), s(4));
                if q.z <= 1e-3 {
                    return Some((0, c.width as usize - 1, 0, c.height as usize - 1));
                }
                let Some(px) = c.project(&q) else {
                    return Some((0, c.width as usize - 1, 0, c.height as usize - 1));
                };
                // Distortion bends the cube's edges: a few pixels of slack keep it conservative.
                let slack = if c.distortion.is_some() { 3.0 } else { 0.0 };
                let (u, v) = (px.x, px.y);
                umin = umin.min(u - slack);
                umax = umax.max(u + slack);
                vmin = vmin.min(v - slack);
                vmax = vmax.max(v + slack);
            }
        }
        let (wmax, hmax) = (c.width as f64 - 1.0, c.height as f64 - 1.0);
        if umax < 0.0 || vmax < 0.0 || umin > wmax || vmin > hmax {
            return None;
        }
        Some((
            umin.floor().max(0.0) as usize,
            umax.ceil().min(wmax) as usize,
            vmin.floor().max(0.0) as usize,
            vmax.ceil().min(hmax) as usize,
        ))
    }
}

/// Linear `[0, ∞)` → 8-bit level through a 1/2.2 power (clipping above 1), via a lookup table.
struct GammaTable(Vec<f64>);

impl GammaTable {
    const SIZE: usize = 4096;

    fn new() -> Self {
        Self(
            (0..=Self::SIZE)
                .map(|i| 255.0 * (i as f64 / Self::SIZE as f64).powf(1.0 / 2.2))
                .collect(),
        )
    }

    fn encode(&self, linear: f64) -> f64 {
        let x = linear.clamp(0.0, 1.0) * Self::SIZE as f64;
        let i = (x as usize).min(Self::SIZE - 1);
        let f = x - i as f64;
        self.0[i] * (1.0 - f) + self.0[i + 1] * f
    }
}
