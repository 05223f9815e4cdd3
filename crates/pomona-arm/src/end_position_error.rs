//! How far the true robot's end lands from the target when it moves to the encoder readings a
//! mapping (the learned network, or Eq. 18 + nominal kinematics) gives for the target's pixels:
//! the figure `pomona arm eval` reports, in millimetres.

use serde::{Deserialize, Serialize};

use crate::{ArmJoints, ArmSample, ArmSimulation, ShotPixels};

/// Summary of end-position errors over a set of targets.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EndPositionError {
    /// Targets the mapping gave readings for.
    pub count: usize,
    /// Targets it gave none for (the mapping failed, e.g. a degenerate disparity).
    pub failed: usize,
    /// Median error, millimetres.
    pub median: f64,
    /// 95th percentile, millimetres (nearest rank).
    pub p95: f64,
    /// Largest error, millimetres.
    pub max: f64,
}

impl EndPositionError {
    /// Moves the true robot `sim` to `mapping(pixels)` for every sample and measures the
    /// distance from its end to the target; `None` when there is no sample with readings.
    pub fn measure(
        sim: &ArmSimulation,
        samples: &[ArmSample],
        mapping: impl Fn(&ShotPixels) -> Option<ArmJoints>,
    ) -> Option<Self> {
        let mut errors_mm: Vec<f64> = samples
            .iter()
            .filter_map(|s| {
                let readings = mapping(&s.pixels)?;
                Some((sim.end_position(&readings) - s.target_in_hub).norm() * 1e3)
            })
            .filter(|e| e.is_finite())
            .collect();
        if errors_mm.is_empty() {
            return None;
        }
        errors_mm.sort_by(f64::total_cmp);
        let n = errors_mm.len();
        let rank = |q: f64| errors_mm[((q * n as f64).ceil() as usize).clamp(1, n) - 1];
        let median = pomona_core::quantile(&errors_mm, 0.5)?;
        Some(Self {
            count: n,
            failed: samples.len() - n,
            median,
            p95: rank(0.95),
            max: errors_mm[n - 1],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ArmRig, CalibrationErrors};

    #[test]
    fn exact_readings_give_zero_and_a_known_offset_its_size() {
        let sim = ArmSimulation::new(ArmRig::default(), CalibrationErrors::none());
        let samples = sim.random_samples(20, 4).unwrap();
        let by_target =
            |p: &ShotPixels| samples.iter().find(|s| s.pixels == *p).map(|s| s.readings);
        let exact = EndPositionError::measure(&sim, &samples, by_target).unwrap();
        assert!(exact.max < 1e-9 && exact.count == 20 && exact.failed == 0);
        // 10 mm too far out along the link, everywhere.
        let longer = EndPositionError::measure(&sim, &samples, |p| {
            by_target(p).map(|q| ArmJoints {
                r_m: q.r_m + 0.01,
                ..q
            })
        })
        .unwrap();
        assert!((longer.median - 10.0).abs() < 1e-9 && (longer.p95 - 10.0).abs() < 1e-9);
        let none = EndPositionError::measure(&sim, &samples, |_| None);
        assert!(none.is_none());
    }
}
