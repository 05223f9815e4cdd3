//! The registry of detection pipelines the binary ships.
//!
//! `pomona train`, `detect`, `experiment` and `demo` look pipelines up here by name and know
//! nothing else about them. To add a detector, add its crate to this crate's `Cargo.toml` and one
//! line to [`all`].

use anyhow::{bail, Result};
use pomona_pipeline::Pipeline;

/// Every pipeline the binary knows, in the order `pomona demo` runs them.
pub fn all() -> Vec<Box<dyn Pipeline>> {
    vec![
        Box::new(pomona_shapefit::ShapeFitPipeline::default()),
        Box::new(pomona_symmetry::SymmetryPipeline::default()),
        Box::new(pomona_symmetry::ViewerPosePipeline::default()),
    ]
}

/// The names of `pipelines`, comma-separated (for messages).
pub fn names(pipelines: &[Box<dyn Pipeline>]) -> String {
    if pipelines.is_empty() {
        return "none are registered yet".to_owned();
    }
    pipelines
        .iter()
        .map(|p| p.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Finds the pipeline called `name` in `pipelines`.
///
/// # Errors
/// An unknown name, with the list of known ones.
pub fn find<'a>(pipelines: &'a [Box<dyn Pipeline>], name: &str) -> Result<&'a dyn Pipeline> {
    match pipelines.iter().find(|p| p.name() == name) {
        Some(p) => Ok(p.as_ref()),
        None => bail!(
            "unknown pipeline `{name}`; known pipelines: {}",
            names(pipelines)
        ),
    }
}

/// The registered pipeline called `name`.
///
/// # Errors
/// An unknown name, with the list of registered ones.
pub fn by_name(name: &str) -> Result<Box<dyn Pipeline>> {
    let mut pipelines = all();
    match pipelines.iter().position(|p| p.name() == name) {
        Some(i) => Ok(pipelines.swap_remove(i)),
        None => bail!(
            "unknown pipeline `{name}`; known pipelines: {}",
            names(&pipelines)
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_names_list_the_known_ones() {
        let err = by_name("no-such-detector").err().map(|e| format!("{e:#}"));
        let err = err.unwrap_or_default();
        assert!(err.contains("no-such-detector"), "{err}");
        assert!(err.contains("known pipelines"), "{err}");
        for p in all() {
            assert!(err.contains(p.name()), "{err}");
            assert_eq!(by_name(p.name()).map(|q| q.name()).ok(), Some(p.name()));
        }
    }
}
