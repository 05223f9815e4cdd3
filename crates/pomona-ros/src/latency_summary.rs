//! Medians of a node's recent frame timings: what "image in → detections out" costs beyond
//! detection itself (decoding the messages, building and publishing the answer, waiting in the
//! mailbox).

use serde::Serialize;

use crate::FrameTiming;

/// Medians (and the 95th percentile of latency) over a window of published frames, ms.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LatencySummary {
    /// Frames summarised.
    pub frames: usize,
    /// Colour image arrival → detections published, median.
    pub latency_ms_median: f64,
    /// The same, 95th percentile.
    pub latency_ms_p95: f64,
    /// Detection alone, median.
    pub detect_ms_median: f64,
    /// Decoding the messages into a frame, median.
    pub decode_ms_median: f64,
    /// Latency minus detection time per frame, median: the node's own cost.
    pub overhead_ms_median: f64,
}

impl LatencySummary {
    /// The summary of `timings`; `None` when there are none.
    pub fn of(timings: &[FrameTiming]) -> Option<Self> {
        if timings.is_empty() {
            return None;
        }
        let sorted = |f: fn(&FrameTiming) -> f64| {
            let mut v: Vec<f64> = timings.iter().map(f).collect();
            v.sort_by(f64::total_cmp);
            v
        };
        // `timings` is not empty, so neither is any list.
        let quantile = |v: &[f64], q: f64| pomona_core::quantile(v, q).unwrap_or(f64::NAN);
        let latency = sorted(|t| t.latency_ms);
        Some(Self {
            frames: timings.len(),
            latency_ms_median: quantile(&latency, 0.5),
            latency_ms_p95: quantile(&latency, 0.95),
            detect_ms_median: quantile(&sorted(|t| t.detect_ms), 0.5),
            decode_ms_median: quantile(&sorted(|t| t.decode_ms), 0.5),
            overhead_ms_median: quantile(&sorted(|t| t.latency_ms - t.detect_ms), 0.5),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn timing(latency_ms: f64, detect_ms: f64) -> FrameTiming {
        FrameTiming {
            stamp_ns: 0,
            latency_ms,
            decode_ms: 1.0,
            detect_ms,
            detections: 0,
        }
    }

    #[test]
    fn medians_and_percentile() {
        assert_eq!(LatencySummary::of(&[]), None);
        let timings: Vec<FrameTiming> = (1..=5)
            .map(|i| timing(f64::from(i) * 10.0 + 2.0, f64::from(i) * 10.0))
            .collect();
        let s = LatencySummary::of(&timings).unwrap_or_else(|| unreachable!());
        assert_eq!(s.frames, 5);
        assert_eq!(s.latency_ms_median, 32.0);
        assert!((s.latency_ms_p95 - 50.0).abs() < 1e-9, "{s:?}");
        assert_eq!(s.detect_ms_median, 30.0);
        assert_eq!(s.overhead_ms_median, 2.0);
        assert_eq!(s.decode_ms_median, 1.0);
    }
}
