//! `pomona.synth(...)`: render a synthetic RGB-D dataset with exact truth (as `pomona synth`),
//! for tests, training and benchmarks without a sensor.

use std::path::PathBuf;

use pomona_synth::{
    generate_dataset, CameraPreset, DatasetSpec, Domain, FruitChoice, LightPreset, NoiseModel,
    SceneSpec,
};
use pyo3::prelude::*;

use crate::py_dataset::Dataset;
use crate::py_error::to_py;

/// Renders ``frames`` synthetic frames into the new folder ``out`` and returns it as a
/// ``Dataset``. The same arguments and ``seed`` give byte-identical files.
///
/// ``fruit``: ``pepper``, ``eggplant``, ``guava``, ``apple``, ``orange`` or ``mixed``;
/// ``camera``: ``kinect-v2``, ``sr4000``, ``d435`` or ``azure-kinect``; ``domain``: ``wide``
/// (domain-randomised worlds), ``narrow`` (the original crop row) or ``orchard`` (citrus rows
/// under the ``light`` preset, with the orchard's backgrounds, as ``pomona synth --domain
/// orchard``); ``light``: ``day``, ``dim``, ``harsh``, ``low-sun`` or ``backlight`` (narrow and
/// orchard domains; the wide domain draws its own); ``noise``: a depth-noise model (``none``,
/// ``low``, ``tof``, ``tof-multipath``, ``stereo``), by default ``none`` for the narrow domain
/// and the camera's own model otherwise.
///
/// Raises ``PomonaError`` for an unknown name, a folder that already holds a dataset, or an
/// unwritable file.
#[pyfunction]
#[allow(clippy::too_many_arguments)] // one per keyword argument of the Python function
#[pyo3(signature = (out, frames, seed, *, fruit = "pepper", camera = "kinect-v2", domain = "wide", light = "day", noise = None))]
pub fn synth(
    py: Python<'_>,
    out: PathBuf,
    frames: u32,
    seed: u64,
    fruit: &str,
    camera: &str,
    domain: &str,
    light: &str,
    noise: Option<&str>,
) -> PyResult<Dataset> {
    let fruit: FruitChoice = fruit.parse().map_err(to_py)?;
    let preset: CameraPreset = camera.parse().map_err(to_py)?;
    let domain: Domain = domain.parse().map_err(to_py)?;
    let light: LightPreset = light.parse().map_err(to_py)?;
    let noise = match (noise, domain) {
        (Some(name), _) => name.parse().map_err(to_py)?,
        (None, Domain::Narrow) => NoiseModel::None,
        (None, Domain::Wide | Domain::Orchard) => NoiseModel::for_camera(preset),
    };
    if frames == 0 {
        return Err(to_py("frames must be at least 1"));
    }
    if out.join("camera.json").exists() {
        return Err(to_py(format!(
            "{} already holds a dataset (camera.json); choose a new folder",
            out.display()
        )));
    }
    let scene = SceneSpec {
        fruit,
        camera: preset.camera(),
        noise,
        domain,
        light,
        backgrounds: domain.default_backgrounds(),
        ..SceneSpec::default()
    };
    let spec = DatasetSpec::new(scene, frames, seed);
    py.detach(|| generate_dataset(&spec, &out, &|_| {}))
        .map_err(to_py)?;
    pomona::Dataset::open(&out)
        .map(Dataset::from_inner)
        .map_err(to_py)
}
