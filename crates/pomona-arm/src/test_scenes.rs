//! Test fixtures shared by the appearance tests of the stereo rig (`disparity_refinement`,
//! `pair_evidence`): one rig, the fruit radius, and the ray casting their rendered views use.
//! Each test module keeps its own shading and supersampling (their images are what the tests'
//! tolerances were set on); only the geometry lives here.

use nalgebra::{Point3, Vector3};
use pomona_core::PinholeCamera;

use crate::RotatedStereo;

/// Radius of every rendered fruit, metres.
pub(crate) const RADIUS_M: f64 = 0.04;

/// Distance of the flat backdrop behind the fruit, metres (along the primary camera's z).
const BACKDROP_Z_M: f64 = 2.5;

/// A 320×240 camera (f = 400 px) on a rig rotated by 4° with a 0.3 m pivot.
pub(crate) fn rig() -> RotatedStereo {
    let camera = PinholeCamera::new(320, 240, 400.0, 400.0, 159.5, 119.5).unwrap();
    RotatedStereo::new(4f64.to_radians(), 0.3, camera).unwrap()
}

/// The distance along the unit ray `origin + t·dir` to the near surface of the fruit centred
/// at `centre`, if the ray meets it.
pub(crate) fn ray_to_fruit(
    origin: &Point3<f64>,
    dir: &Vector3<f64>,
    centre: &Point3<f64>,
) -> Option<f64> {
    let oc = origin - centre;
    let b = dir.dot(&oc);
    let disc = b * b - (oc.norm_squared() - RADIUS_M * RADIUS_M);
    (disc >= 0.0).then(|| -b - disc.sqrt())
}

/// Where the ray `origin + t·dir` meets the backdrop.
pub(crate) fn backdrop_hit(origin: &Point3<f64>, dir: &Vector3<f64>) -> Point3<f64> {
    let t = (BACKDROP_Z_M - origin.z) / dir.z;
    origin + dir * t
}

/// The image radius, pixels, of a fruit centred at `centre` (primary frame).
pub(crate) fn radius_px(rig: &RotatedStereo, centre: &Point3<f64>) -> f64 {
    rig.camera.fx * (RADIUS_M / centre.coords.norm()).asin().tan()
}
