//! Cast shadows of the wide domain: is the sun visible from a surface point?
//!
//! A shadow ray runs from the point towards the sun, so every shadow ray is parallel to one
//! direction `L`. Projected along `L` onto a plane, each ray becomes a single point and each
//! object's bounding sphere a disc. [`ShadowGrid`] bins those discs in a 2D grid over that plane;
//! a shadow query looks up one cell and runs the exact ray test only against objects whose
//! bounding sphere the ray passes (the disc contains the point and the sphere is not wholly
//! behind it). Leaves, stems and fruit cast shadows; the backdrop does not (it is behind
//! everything).

use nalgebra::{Point3, Unit, Vector3};

use crate::Scene;

/// Largest number of grid cells per side.
const MAX_CELLS_PER_SIDE: usize = 256;
/// Smallest cell edge, metres.
const MIN_CELL_M: f64 = 0.01;
/// Casters with a bounding radius above this (long stalks, posts, pipes) are kept out of the
/// grid and tested on every query, so they do not stretch the grid, metres.
const BIG_CASTER_M: f64 = 0.3;
/// Shadow rays start this far towards the sun from the surface point, metres (no self-hits on
/// round-off).
const SHADOW_BIAS_M: f64 = 2e-4;

/// A scene object that can cast a shadow, as an index into the scene's lists.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Occluder {
    /// `scene.leaves[k]`.
    Leaf(u32),
    /// `scene.stems[k]`.
    Stem(u32),
    /// `scene.fruits[k]`.
    Fruit(u32),
}

/// One object's bounding sphere.
#[derive(Debug, Clone, Copy)]
struct Caster {
    object: Occluder,
    center: Point3<f64>,
    radius: f64,
}

/// Bounding discs of all casters, binned on the plane perpendicular to the sun direction.
pub(crate) struct ShadowGrid<'a> {
    scene: &'a Scene,
    towards_sun: Unit<Vector3<f64>>,
    e1: Vector3<f64>,
    e2: Vector3<f64>,
    origin: (f64, f64),
    cell_m: f64,
    cells: (usize, usize),
    /// Caster indices per cell, concatenated; `starts[c]..starts[c + 1]` is cell `c`.
    members: Vec<u32>,
    starts: Vec<usize>,
    casters: Vec<Caster>,
    /// Casters too large for the grid, tested on every query.
    big: Vec<Caster>,
}

impl<'a> ShadowGrid<'a> {
    /// Bins every leaf, stem and fruit of `scene` for the scene's light direction.
    pub(crate) fn new(scene: &'a Scene) -> Self {
        let towards_sun = scene.light.towards_light;
        let l = towards_sun.into_inner();
        let helper = if l.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let e1 = l.cross(&helper).normalize();
        let e2 = l.cross(&e1);
        let mut casters = Vec::new();
        for (k, leaf) in scene.leaves.iter().enumerate() {
            casters.push(Caster {
                object: Occluder::Leaf(k as u32),
                center: leaf.center,
                radius: leaf.bounding_radius_m(),
            });
        }
        for (k, stem) in scene.stems.iter().enumerate() {
            casters.push(Caster {
                object: Occluder::Stem(k as u32),
                center: nalgebra::center(&stem.start, &stem.end),
                radius: 0.5 * (stem.end - stem.start).norm() + stem.radius_m,
            });
        }
        for (k, fruit) in scene.fruits.iter().enumerate() {
            casters.push(Caster {
                object: Occluder::Fruit(k as u32),
                center: fruit.center,
                radius: fruit.bounding_radius_m(),
            });
        }
        let (big, casters): (Vec<Caster>, Vec<Caster>) =
            casters.into_iter().partition(|c| c.radius > BIG_CASTER_M);
        let project = |p: &Point3<f64>| (p.coords.dot(&e1), p.coords.dot(&e2));
        let (mut lo, mut hi) = ((f64::MAX, f64::MAX), (f64::MIN, f64::MIN));
        for c in &casters {
            let (x, y) = project(&c.center);
            lo = (lo.0.min(x - c.radius), lo.1.min(y - c.radius));
            hi = (hi.0.max(x + c.radius), hi.1.max(y + c.radius));
        }
        if casters.is_empty() {
            lo = (0.0, 0.0);
            hi = (1.0, 1.0);
        }
        let extent = (hi.0 - lo.0).max(hi.1 - lo.1).max(MIN_CELL_M);
        let cell_m = (extent / MAX_CELLS_PER_SIDE as f64).max(MIN_CELL_M);
        let nx = (((hi.0 - lo.0) / cell_m).ceil() as usize).clamp(1, MAX_CELLS_PER_SIDE);
        let ny = (((hi.1 - lo.1) / cell_m).ceil() as usize).clamp(1, MAX_CELLS_PER_SIDE);
        let cell_of =
            |v: f64, o: f64, n: usize| (((v - o) / cell_m).floor().max(0.0) as usize).min(n - 1);
        // Counting pass, then filling pass (compressed rows).
        let mut counts = vec![0usize; nx * ny + 1];
        let mut spans = Vec::with_capacity(casters.len());
        for c in &casters {
            let (x, y) = project(&c.center);
            let span = (
                cell_of(x - c.radius, lo.0, nx),
                cell_of(x + c.radius, lo.0, nx),
                cell_of(y - c.radius, lo.1, ny),
                cell_of(y + c.radius, lo.1, ny),
            );
            for j in span.2..=span.3 {
                for i in span.0..=span.1 {
                    counts[j * nx + i + 1] += 1;
                }
            }
            spans.push(span);
        }
        for i in 1..counts.len() {
            counts[i] += counts[i - 1];
        }
        let starts = counts.clone();
        let mut fill = counts;
        let mut members = vec![0u32; starts[nx * ny]];
        for (k, span) in spans.iter().enumerate() {
            for j in span.2..=span.3 {
                for i in span.0..=span.1 {
                    let cell = j * nx + i;
                    members[fill[cell]] = k as u32;
                    fill[cell] += 1;
                }
            }
        }
        Self {
            scene,
            towards_sun,
            e1,
            e2,
            origin: lo,
            cell_m,
            cells: (nx, ny),
            members,
            starts,
            casters,
            big,
        }
    }

    /// Whether the sun is visible from scene point `p` (on the surface of `skip`, which is not
    /// tested: a surface does not shadow itself here; the diffuse term darkens its far side).
    pub(crate) fn sun_visible(&self, p: &Point3<f64>, skip: Option<Occluder>) -> bool {
        let l = self.towards_sun.into_inner();
        let origin = p + l * SHADOW_BIAS_M;
        if self.big.iter().any(|c| self.blocks(c, &origin, skip)) {
            return false;
        }
        let (x, y) = (p.coords.dot(&self.e1), p.coords.dot(&self.e2));
        let (i, j) = (
            ((x - self.origin.0) / self.cell_m).floor(),
            ((y - self.origin.1) / self.cell_m).floor(),
        );
        if i < 0.0 || j < 0.0 || i >= self.cells.0 as f64 || j >= self.cells.1 as f64 {
            return true;
        }
        let cell = j as usize * self.cells.0 + i as usize;
        !self.members[self.starts[cell]..self.starts[cell + 1]]
            .iter()
            .any(|&k| self.blocks(&self.casters[k as usize], &origin, skip))
    }

    /// Whether caster `c` (unless it is `skip`) blocks the ray from `origin` towards the sun.
    fn blocks(&self, c: &Caster, origin: &Point3<f64>, skip: Option<Occluder>) -> bool {
        if Some(c.object) == skip {
            return false;
        }
        let l = self.towards_sun.into_inner();
        let to_center = c.center - origin;
        let along = to_center.dot(&l);
        // Sphere wholly behind the point, or the ray passes outside it.
        if along < -c.radius || to_center.norm_squared() - along * along > c.radius * c.radius {
            return false;
        }
        match c.object {
            Occluder::Leaf(k) => self.scene.leaves[k as usize]
                .intersect(origin, &l)
                .is_some(),
            Occluder::Stem(k) => self.scene.stems[k as usize].intersect(origin, &l).is_some(),
            Occluder::Fruit(k) => self.scene.fruits[k as usize]
                .intersect(origin, &l)
                .is_some(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Backdrop, BackdropKind, Leaf, LeafFamily, Light, Material, NoiseModel};
    use nalgebra::Rotation3;

    /// A scene with one flat leaf at (0, 0, 0.5) facing the camera and the sun straight behind
    /// the camera (towards −z).
    fn scene() -> Scene {
        let leaf = Leaf {
            center: Point3::new(0.0, 0.0, 0.5),
            orientation: Rotation3::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI),
            half_length_m: 0.05,
            half_width_m: 0.025,
            bend_along: 0.0,
            bend_across: 0.0,
            material: Material {
                albedo: [0.1, 0.3, 0.1],
                specular: 0.0,
                shininess: 1.0,
            },
            family: LeafFamily::Elliptic,
        };
        Scene {
            fruits: Vec::new(),
            leaves: vec![leaf],
            stems: Vec::new(),
            backdrop: Backdrop {
                point: Point3::new(0.0, 0.0, 1.0),
                normal: Unit::new_normalize(-Vector3::z()),
                texture_seed: 1,
                kind: BackdropKind::Soil,
            },
            light: Light {
                towards_light: Unit::new_normalize(-Vector3::z()),
                intensity: 1.0,
                ambient: 0.2,
                color: [1.0; 3],
                image_noise_sigma: 0.0,
            },
            noise: NoiseModel::None,
            noise_seed: 0,
            shadows: true,
            image_effects: None,
            max_depth_m: f64::INFINITY,
            truth_extra: serde_json::Map::new(),
        }
    }

    #[test]
    fn a_leaf_shadows_the_ground_behind_it_only() {
        let s = scene();
        let grid = ShadowGrid::new(&s);
        // Straight behind the leaf (the sun is behind the camera): in shadow.
        assert!(!grid.sun_visible(&Point3::new(0.0, 0.0, 1.0), None));
        assert!(!grid.sun_visible(&Point3::new(0.03, 0.01, 1.0), None));
        // Beside the leaf's outline: lit.
        assert!(grid.sun_visible(&Point3::new(0.0, 0.04, 1.0), None));
        assert!(grid.sun_visible(&Point3::new(0.2, 0.0, 1.0), None));
        // In front of the leaf: lit; the leaf does not shadow itself.
        assert!(grid.sun_visible(&Point3::new(0.0, 0.0, 0.3), None));
        assert!(grid.sun_visible(&Point3::new(0.0, 0.0, 0.5), Some(Occluder::Leaf(0))));
    }

    #[test]
    fn rendered_shadow_darkens_the_ground() {
        let cam = crate::CameraPreset::Sr4000.camera();
        // Colour bytes of `s` rendered with and without shadows.
        let with_and_without = |mut s: crate::Scene| {
            let with = crate::render(&s, &cam).unwrap();
            s.shadows = false;
            let without = crate::render(&s, &cam).unwrap();
            let rgb = |r: &crate::RenderedFrame| r.frame.color().unwrap().as_rgb().to_vec();
            (rgb(&with), rgb(&without))
        };
        let (a, b) = with_and_without(scene());
        // With the sun straight behind the camera the shadow lies behind the leaf, hidden by
        // it; moving the sun sideways uncovers it.
        assert_eq!(
            a, b,
            "a shadow straight behind the leaf is hidden by the leaf"
        );
        let mut s = scene();
        s.light.towards_light = Unit::new_normalize(Vector3::new(-0.3, 0.0, -1.0));
        let (a, b) = with_and_without(s);
        let darker = a
            .iter()
            .zip(b.iter())
            .filter(|(x, y)| u16::from(**x) + 10 < u16::from(**y))
            .count();
        let brighter = a.iter().zip(b.iter()).filter(|(x, y)| **x > **y).count();
        assert!(darker > 100, "only {darker} channels darkened");
        assert_eq!(brighter, 0);
    }
}
