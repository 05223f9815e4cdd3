//! The matching flags `pomona eval` and `pomona experiment` share: how a detection is matched to
//! a truth fruit (a 3D centre tolerance, or in the image with `--2d`) and which truth counts
//! (visibility, a band of depths).
//! One struct, flattened into both commands, so the two cannot drift apart.

use pomona_eval::EvalConfig;

/// How detections are matched to truth.
#[derive(Debug, Clone, clap::Args)]
pub struct MatchingArgs {
    /// Largest centre distance, millimetres, at which a detection matches a fruit.
    #[arg(long, default_value_t = 50.0)]
    pub tolerance_mm: f64,
    /// Match in the image instead (seed 004's protocol, for colour-only data): a detection's
    /// circle centre within `--radius-fraction` of the fruit's image radius from the fruit's
    /// circle centre. Truth circles are `center_px`/`radius_px`, else projected from
    /// `center_m`/`diameter_m`, else the box's inscribed circle (docs/formats.md).
    #[arg(long = "2d", conflicts_with = "tolerance_mm")]
    pub image_2d: bool,
    /// With `--2d`: the match radius as a fraction of the truth radius.
    #[arg(long, value_name = "F", default_value_t = 0.5, requires = "image_2d")]
    pub radius_fraction: f64,
    /// Truth fruit less visible than this (0–1) are ignored: neither found nor missed.
    #[arg(long, default_value_t = 0.5)]
    pub min_visibility: f64,
    /// Score one band of depths, `NEAR,FAR` metres (e.g. an arm's reach): truth fruit whose
    /// centre lies outside `NEAR ≤ z < FAR` are ignored, and so are detections outside it that
    /// match no counted fruit.
    #[arg(long, value_name = "NEAR,FAR", value_parser = depth_range, conflicts_with = "image_2d")]
    pub depth_range_m: Option<(f64, f64)>,
}

fn depth_range(s: &str) -> Result<(f64, f64), String> {
    let (near, far) =
        crate::number_pair::parse_number_pair(s, "NEAR,FAR in metres (e.g. 0.3,0.8)")?;
    if !(near >= 0.0 && near < far) {
        return Err(format!("need 0 <= NEAR < FAR metres, got {near},{far}"));
    }
    Ok((near, far))
}

impl Default for MatchingArgs {
    fn default() -> Self {
        Self {
            tolerance_mm: 50.0,
            image_2d: false,
            radius_fraction: 0.5,
            min_visibility: 0.5,
            depth_range_m: None,
        }
    }
}

impl MatchingArgs {
    /// The evaluation parameters these flags set, with the operating point of `base` (its
    /// threshold and confidence) kept. Data without depth is always matched in the image (a
    /// colour-only detector's 3D centre is only a size-prior guess), with a note on stderr when
    /// `--2d` was not given. Not validated: callers validate the whole config.
    pub fn config(&self, base: EvalConfig, data_has_depth: bool) -> EvalConfig {
        let config = EvalConfig {
            tolerance_m: self.tolerance_mm / 1000.0,
            min_visibility: self.min_visibility,
            radius_fraction_2d: self.image_2d.then_some(self.radius_fraction),
            depth_range_m: self.depth_range_m,
            ..base
        }
        .for_data(data_has_depth);
        if config.radius_fraction_2d.is_some() && !self.image_2d {
            eprintln!("note: the data has no depth, so detections are matched in the image (--2d)");
        }
        config
    }
}
