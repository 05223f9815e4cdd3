//! Wall time per stage, accumulated over frames, for `--timings` and the per-stage tables the
//! papers report.

use std::time::Duration;

/// Accumulated wall time per stage name, in first-seen order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StageTimings {
    entries: Vec<(&'static str, Duration, u32)>,
}

impl StageTimings {
    /// Adds one run of `stage` lasting `elapsed`.
    pub fn add(&mut self, stage: &'static str, elapsed: Duration) {
        match self.entries.iter_mut().find(|e| e.0 == stage) {
            Some(e) => {
                e.1 += elapsed;
                e.2 += 1;
            }
            None => self.entries.push((stage, elapsed, 1)),
        }
    }

    /// Adds every entry of `other` (for example another frame's timings).
    pub fn merge(&mut self, other: &StageTimings) {
        for &(stage, elapsed, runs) in &other.entries {
            match self.entries.iter_mut().find(|e| e.0 == stage) {
                Some(e) => {
                    e.1 += elapsed;
                    e.2 += runs;
                }
                None => self.entries.push((stage, elapsed, runs)),
            }
        }
    }

    /// `(stage, total time, number of runs)` in first-seen order.
    pub fn entries(&self) -> &[(&'static str, Duration, u32)] {
        &self.entries
    }

    /// Total time over all stages.
    pub fn total(&self) -> Duration {
        self.entries.iter().map(|e| e.1).sum()
    }

    /// A plain-text table of mean milliseconds per run and share of the total.
    pub fn table(&self) -> String {
        let total = self.total().as_secs_f64().max(f64::MIN_POSITIVE);
        let mut s = format!(
            "{:<22} {:>10} {:>7} {:>6}\n",
            "stage", "ms/run", "share", "runs"
        );
        for &(stage, elapsed, runs) in &self.entries {
            let ms = 1e3 * elapsed.as_secs_f64() / runs.max(1) as f64;
            let share = 100.0 * elapsed.as_secs_f64() / total;
            s.push_str(&format!("{stage:<22} {ms:>10.2} {share:>6.1}% {runs:>6}\n"));
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accumulates_and_merges_by_name() {
        let mut a = StageTimings::default();
        a.add("mask", Duration::from_millis(2));
        a.add("fit", Duration::from_millis(6));
        a.add("mask", Duration::from_millis(4));
        let mut b = StageTimings::default();
        b.add("fit", Duration::from_millis(2));
        b.add("svm", Duration::from_millis(1));
        a.merge(&b);
        assert_eq!(a.entries()[0], ("mask", Duration::from_millis(6), 2));
        assert_eq!(a.entries()[1], ("fit", Duration::from_millis(8), 2));
        assert_eq!(a.entries()[2].0, "svm");
        assert_eq!(a.total(), Duration::from_millis(15));
        assert!(a.table().contains("mask"));
    }
}
