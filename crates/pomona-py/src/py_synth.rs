//! `pomona.synth(...)`: render a synthetic RGB-D dataset with exact truth (as `pomona synth`),
//! for tests, training and benchmarks without a sensor.

use std::path::PathBuf;

use pomona_synth::{
    generate_dataset, CameraPreset, DatasetSpec, Domain, FruitChoice, NoiseModel, SceneSpec,
};
use pyo3::prelude::*;

use crate::py_dataset::Dataset;
use crate::py_error::to_py;

/// Renders ``frames`` synthetic frames into the new folder ``out`` and returns it as a
/// ``Dataset``. The same arguments and ``seed`` give byte-identical files.
///
/// ``fruit``: ``pepper``, ``eggplant``, ``guava``, ``apple``, ``orange`` or ``mixed``;
/// ``camera``: ``kinect-v2``, ``sr4000``, ``d435`` or ``azure-kinect``; ``domain``: ``wide``
/// (domain-randomised worlds) or ``narrow`` (the original crop row); ``noise``: a depth-noise
/// model (``none``, ``low``, ``tof``, ``tof-multipath``, ``stereo``), by default ``none`` for
/// the narrow domain and the camera's own model for the wide one.
///
/// Raises ``PomonaError`` for an unknown name, a folder that already holds a dataset, or an
/// unwritable file.
#[pyfunction]
#[allow(clippy::too_many_arguments)] // one per keyword argument of the Python function
#[pyo3(signature = (out, frames, seed, *, fruit = "pepper", camera = "kinect-v2", domain = "wide", noise = None))]
pub fn synth(
    py: Python<'_>,
    out: PathBuf,
    frames: u32,
    seed: u64,
    fruit: &str,
    camera: &str,
    domain: &str,
    noise: Option<&str>,
) -> PyResult<Dataset> {
    let fruit: FruitChoice = fruit.parse().map_err(to_py)?;
    let preset: CameraPreset = camera.parse().map_err(to_py)?;
    let domain: Domain = serde_json::from_value(serde_json::Value::from(domain))
        .map_err(|_| to_py(format!("unknown domain `{domain}`; known: narrow, wide")))?;
    let noise =
        match (noise, domain) {
            (Some(name), _) => name.parse().map_err(to_py)?,
            (None, Domain::Narrow) => NoiseModel::None,
            (None, Domain::Wide) => NoiseModel::for_camera(preset),
            (_, Domain::Orchard) => return Err(to_py(
                "domain `orchard` (its backgrounds and light presets) is available from the CLI: \
                 `pomona synth --domain orchard`",
            )),
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
        ..SceneSpec::default()
    };
    let spec = DatasetSpec::new(scene, frames, seed);
    py.detach(|| generate_dataset(&spec, &out, &|_| {}))
        .map_err(to_py)?;
    pomona::Dataset::open(&out)
        .map(Dataset::from_inner)
        .map_err(to_py)
}
