//! The depth unit of a dataset extracted from a recording: the dataset stores depth as 16-bit
//! integers times a unit (`camera.json`'s `depth_unit_m`), so the unit decides what survives.
//!
//! * `16UC1` depth is millimetres already: 1 mm keeps every value exactly.
//! * `32FC1` depth (metres as floats) is rounded to the finest unit of the ladder
//!   [`FLOAT_DEPTH_UNITS_M`] (0.1 mm upwards) whose 65 535 steps still reach the recording's
//!   farthest depth, so nothing is clipped and the rounding error is at most half that unit
//!   (0.05 mm for scenes within 6.5 m).

use crate::{Recording, RecordingError, DEPTH_16UC1_UNIT_M};

/// Units tried for float depth, finest first, metres.
pub const FLOAT_DEPTH_UNITS_M: [f64; 8] = [1e-4, 2e-4, 5e-4, 1e-3, 2e-3, 5e-3, 1e-2, 1e-1];

/// The finest unit of [`FLOAT_DEPTH_UNITS_M`] at which `max_depth_m` fits in 16 bits (the
/// coarsest when none does; `None` depth: the finest).
pub fn finest_unit_m(max_depth_m: Option<f32>) -> f64 {
    let max = max_depth_m.map_or(0.0, f64::from);
    FLOAT_DEPTH_UNITS_M
        .into_iter()
        .find(|unit| (max / unit).round() <= f64::from(u16::MAX))
        .unwrap_or(FLOAT_DEPTH_UNITS_M[FLOAT_DEPTH_UNITS_M.len() - 1])
}

/// The depth unit that stores `recording`'s depth without loss: 1 mm when every frame's depth
/// is `16UC1`, else [`finest_unit_m`] of its farthest depth.
///
/// # Errors
/// As [`Recording::max_depth_m`].
pub fn dataset_depth_unit_m(recording: &Recording) -> Result<f64, RecordingError> {
    if recording.depth_is_millimetres()? {
        Ok(DEPTH_16UC1_UNIT_M)
    } else {
        Ok(finest_unit_m(recording.max_depth_m()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finest_unit_that_reaches_the_farthest_depth() {
        assert_eq!(finest_unit_m(None), 1e-4);
        assert_eq!(finest_unit_m(Some(4.5)), 1e-4);
        assert_eq!(finest_unit_m(Some(6.6)), 2e-4);
        assert_eq!(finest_unit_m(Some(20.0)), 5e-4);
        assert_eq!(finest_unit_m(Some(1e9)), 0.1);
    }
}
