//! A shard of a detection run (`pomona detect --shard I/N`): task `I` of `N` processes every
//! `N`-th frame of the dataset's sorted frame list, starting at frame `I` (0-based).
//!
//! Why: a season of recordings is more frames than one machine handles, and array jobs
//! (Kubernetes Indexed Jobs, Slurm job arrays) give each task only its index. The choice depends
//! only on the sorted frame names, `I` and `N`, so `N` tasks writing into one output folder
//! produce exactly the files of one unsharded run (each frame's file is the same bytes whichever
//! task writes it), and a restarted task with `--resume` picks up where it stopped. Frames are
//! dealt round-robin rather than in blocks so that every shard gets a share of each part of the
//! recording (scenes, and so detection costs, change along it). Each shard lists its failures in
//! its own file (`failures.shard-I-of-N.json`, see `pomona_eval::failures_file`), so shards
//! never overwrite each other's list.

use std::fmt;
use std::str::FromStr;

/// Task `index` of `count` (0-based: `0 <= index < count`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This task's index, from 0.
    pub index: usize,
    /// How many tasks share the run.
    pub count: usize,
}

impl Shard {
    /// Whether the frame at `position` of the sorted frame list belongs to this shard.
    pub fn owns(&self, position: usize) -> bool {
        position % self.count == self.index
    }

    /// This shard's frames of `frames` (the dataset's sorted list), in order.
    pub fn select<'a>(&self, frames: &'a [String]) -> Vec<&'a String> {
        frames
            .iter()
            .enumerate()
            .filter(|(i, _)| self.owns(*i))
            .map(|(_, f)| f)
            .collect()
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl FromStr for Shard {
    type Err = String;

    /// Parses `I/N`.
    ///
    /// # Errors
    /// Not of the form `I/N` with whole numbers, `N` zero, or `I >= N` (the message says which).
    fn from_str(s: &str) -> Result<Self, String> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("expected I/N (task I of N, 0-based, e.g. 0/4), got `{s}`"))?;
        let number = |t: &str, what: &str| {
            t.trim()
                .parse::<usize>()
                .map_err(|e| format!("{what} `{t}` in `{s}` is not a whole number: {e}"))
        };
        let (index, count) = (number(i, "shard index")?, number(n, "shard count")?);
        if count == 0 {
            return Err(format!("shard count must be at least 1, got `{s}`"));
        }
        if index >= count {
            return Err(format!(
                "shard index is 0-based and must be below the count {count}, got `{s}` \
                 (with Slurm arrays use --array=0-{})",
                count - 1
            ));
        }
        Ok(Self { index, count })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_i_of_n_and_explains_bad_input() {
        assert_eq!("3/8".parse::<Shard>(), Ok(Shard { index: 3, count: 8 }));
        assert_eq!(
            "0/1".parse::<Shard>().map(|s| s.to_string()),
            Ok("0/1".into())
        );
        for (bad, word) in [
            ("3", "expected I/N"),
            ("a/2", "shard index `a`"),
            ("1/-2", "shard count `-2`"),
            ("0/0", "at least 1"),
            ("2/2", "0-based"),
        ] {
            let err = bad.parse::<Shard>().unwrap_err();
            assert!(err.contains(word), "{bad}: {err}");
        }
    }

    #[test]
    fn the_shards_of_a_run_partition_its_frames_in_order() {
        let frames: Vec<String> = (0..10).map(|i| format!("{i:03}")).collect();
        let count = 3;
        let shards: Vec<Vec<&String>> = (0..count)
            .map(|index| Shard { index, count }.select(&frames))
            .collect();
        assert_eq!(shards[1], [&frames[1], &frames[4], &frames[7]]);
        let mut all: Vec<&String> = shards.concat();
        all.sort();
        assert_eq!(all, frames.iter().collect::<Vec<_>>());
        assert_eq!(Shard { index: 0, count: 1 }.select(&frames).len(), 10);
        assert!(Shard {
            index: 5,
            count: 20
        }
        .select(&frames[..3])
        .is_empty());
    }
}
