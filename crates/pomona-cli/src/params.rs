//! `--set key=value` on the command line: the values are [`pomona::ParamOverride`]s (parsed by
//! its `FromStr`); detection-time overrides go to [`pomona::DetectorBuilder::overrides`], and
//! training-time ones to the pipeline's training parameters here.

use anyhow::Result;
use pomona::{apply_overrides, ParamOverride, Pipeline};

/// `pipeline` with `overrides` applied to its training parameters (`None` without overrides).
///
/// # Errors
/// An unknown key or a value of the wrong type (listing the keys there are), or parameters the
/// pipeline rejects.
pub fn configured(
    pipeline: &dyn Pipeline,
    overrides: &[ParamOverride],
) -> Result<Option<Box<dyn Pipeline>>> {
    if overrides.is_empty() {
        return Ok(None);
    }
    let mut train_params = pipeline.train_params();
    apply_overrides(&mut train_params, overrides, "training parameters")?;
    Ok(Some(pipeline.with_train_params(train_params)?))
}
