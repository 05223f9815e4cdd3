//! Approximate-time synchronisation of live colour, depth and camera-info messages.
//!
//! A recording can be synchronised after the fact (every stamp is known, see
//! `pomona_recording::Recording`); on a live bus the depth image of an exposure may arrive before
//! or after its colour image. The rule here gives the same pairs as the recording reader (the
//! depth stamp nearest the colour stamp within the tolerance, the earlier on a tie) without
//! waiting longer than needed: a colour image is decided as soon as a depth image with its exact
//! stamp, or any later one, has arrived — no nearer depth can come after that. Drivers that stamp
//! aligned depth with the colour stamp (the RealSense driver does) are therefore paired on
//! arrival. The camera info is the latest received; until the first one arrives, colour and depth
//! images wait (a driver may start its camera-info topic after its image topics, and a frame
//! decided without it could not be detected).
//!
//! Only the newest frame matters to a robot: when a colour image is paired, older colour images
//! still waiting are dropped (counted), as are depth images older than the one used.

use std::collections::VecDeque;
use std::sync::Arc;

use pomona_recording::{CameraInfo, Image};

/// How many colour and depth messages wait at most (the oldest go first).
pub const PENDING_LIMIT: usize = 16;

/// The three messages of one synchronised frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameMessages<T> {
    /// The colour image (its header names the frame).
    pub color: Image,
    /// The depth image nearest in time (shared: a later colour image may pair with it too).
    pub depth: Arc<Image>,
    /// The camera info.
    pub info: CameraInfo,
    /// What the caller attached to the colour message (e.g. when it arrived).
    pub color_tag: T,
}

/// Counters of what the synchroniser did not pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SyncCounts {
    /// Frames paired.
    pub paired: u64,
    /// Colour images with no depth image within the tolerance.
    pub unmatched_color: u64,
    /// Colour images dropped because a newer one was paired first, arrived after it, or too many
    /// were waiting.
    pub stale_color: u64,
    /// Messages whose header stamp is before the epoch or malformed.
    pub bad_stamp: u64,
}

/// The live synchroniser; `T` is a tag carried with each colour image.
#[derive(Debug, Clone)]
pub struct LiveSync<T> {
    tolerance_ns: u64,
    color: VecDeque<(u64, Image, T)>,
    depth: VecDeque<(u64, Arc<Image>)>,
    info: Option<CameraInfo>,
    last_paired_ns: Option<u64>,
    counts: SyncCounts,
}

impl<T> LiveSync<T> {
    /// A synchroniser pairing colour and depth stamps at most `tolerance_ns` apart.
    pub fn new(tolerance_ns: u64) -> Self {
        Self {
            tolerance_ns,
            color: VecDeque::new(),
            depth: VecDeque::new(),
            info: None,
            last_paired_ns: None,
            counts: SyncCounts::default(),
        }
    }

    /// What was paired and dropped so far.
    pub fn counts(&self) -> SyncCounts {
        self.counts
    }

    /// Adds a colour image; returns the frame it completes, if any.
    pub fn push_color(&mut self, image: Image, tag: T) -> Option<FrameMessages<T>> {
        let Some(stamp) = image.header.stamp_ns() else {
            self.counts.bad_stamp += 1;
            return None;
        };
        if self.last_paired_ns.is_some_and(|last| stamp <= last) {
            self.counts.stale_color += 1;
            return None;
        }
        let at = self.color.partition_point(|(s, _, _)| *s <= stamp);
        self.color.insert(at, (stamp, image, tag));
        if self.color.len() > PENDING_LIMIT {
            self.color.pop_front();
            self.counts.stale_color += 1;
        }
        self.pair()
    }

    /// Adds a depth image; returns the frame it completes, if any.
    pub fn push_depth(&mut self, image: Image) -> Option<FrameMessages<T>> {
        let Some(stamp) = image.header.stamp_ns() else {
            self.counts.bad_stamp += 1;
            return None;
        };
        let at = self.depth.partition_point(|(s, _)| *s <= stamp);
        self.depth.insert(at, (stamp, Arc::new(image)));
        if self.depth.len() > PENDING_LIMIT {
            self.depth.pop_front();
        }
        self.pair()
    }

    /// Replaces the camera info; returns the frame the first camera info completes, if any.
    pub fn push_info(&mut self, info: CameraInfo) -> Option<FrameMessages<T>> {
        let first = self.info.is_none();
        self.info = Some(info);
        if first {
            self.pair()
        } else {
            None
        }
    }

    /// The index of the depth image paired with colour stamp `stamp`: `Some(None)` when decided
    /// unmatched, `None` while a nearer depth image could still arrive.
    fn decide(&self, stamp: u64) -> Option<Option<usize>> {
        let after = self.depth.partition_point(|(s, _)| *s < stamp);
        let exact = self.depth.get(after).is_some_and(|(s, _)| *s == stamp);
        let later = self.depth.iter().any(|(s, _)| *s > stamp);
        if !(exact || later) {
            return None;
        }
        let nearest = [after.checked_sub(1), Some(after)]
            .into_iter()
            .flatten()
            .filter_map(|i| self.depth.get(i).map(|(s, _)| (s.abs_diff(stamp), i)))
            .min()
            .filter(|&(gap, _)| gap <= self.tolerance_ns)
            .map(|(_, i)| i);
        Some(nearest)
    }

    /// Pairs the newest decidable colour image, dropping older ones (nothing is decided before
    /// the first camera info).
    fn pair(&mut self) -> Option<FrameMessages<T>> {
        self.info.as_ref()?;
        let (newest, depth_index) = (0..self.color.len()).rev().find_map(|i| {
            let stamp = self.color[i].0;
            match self.decide(stamp) {
                Some(Some(d)) => Some((i, d)),
                _ => None,
            }
        })?;
        // Colour images before the paired one are stale or undecidable; those decided unmatched
        // count as such.
        for _ in 0..newest {
            if let Some((stamp, _, _)) = self.color.pop_front() {
                match self.decide(stamp) {
                    Some(None) => self.counts.unmatched_color += 1,
                    _ => self.counts.stale_color += 1,
                }
            }
        }
        let (stamp, color, color_tag) = self.color.pop_front()?;
        let depth = Arc::clone(&self.depth.get(depth_index)?.1);
        let info = self.info.clone()?;
        self.depth.drain(..depth_index);
        self.last_paired_ns = Some(stamp);
        self.counts.paired += 1;
        Some(FrameMessages {
            color,
            depth,
            info,
            color_tag,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pomona_recording::Header;

    const MS: u64 = 1_000_000;

    fn image(stamp_ms: u64) -> Image {
        Image {
            header: Header::at(stamp_ms * MS, "cam"),
            ..Image::default()
        }
    }

    fn stamps(frame: Option<FrameMessages<u32>>) -> Option<(u64, u64, u32)> {
        frame.map(|f| {
            (
                f.color.header.stamp_ns().unwrap_or(0) / MS,
                f.depth.header.stamp_ns().unwrap_or(0) / MS,
                f.color_tag,
            )
        })
    }

    fn sync_with_info() -> LiveSync<u32> {
        let mut sync = LiveSync::new(20 * MS);
        sync.push_info(CameraInfo::default());
        sync
    }

    #[test]
    fn exact_stamps_pair_on_arrival_in_either_order() {
        let mut sync = sync_with_info();
        assert_eq!(stamps(sync.push_color(image(100), 1)), None);
        assert_eq!(stamps(sync.push_depth(image(100))), Some((100, 100, 1)));
        assert_eq!(stamps(sync.push_depth(image(133))), None);
        assert_eq!(stamps(sync.push_color(image(133), 2)), Some((133, 133, 2)));
        assert_eq!(sync.counts().paired, 2);
    }

    #[test]
    fn offset_depth_waits_for_a_later_one_then_takes_the_nearest() {
        let mut sync = sync_with_info();
        assert_eq!(stamps(sync.push_depth(image(95))), None);
        assert_eq!(
            stamps(sync.push_color(image(100), 1)),
            None,
            "a nearer depth may come"
        );
        assert_eq!(stamps(sync.push_depth(image(128))), Some((100, 95, 1)));
        // Equal gaps: the earlier depth.
        let mut sync = sync_with_info();
        sync.push_depth(image(90));
        sync.push_color(image(100), 1);
        assert_eq!(stamps(sync.push_depth(image(110))), Some((100, 90, 1)));
    }

    #[test]
    fn no_depth_within_tolerance_is_unmatched_and_the_newest_frame_wins() {
        let mut sync = sync_with_info();
        sync.push_color(image(100), 1);
        sync.push_color(image(133), 2);
        sync.push_color(image(166), 3);
        // Depth at 166 decides all three; 100 and 133 have no depth within 20 ms of them
        // (133 is 33 ms away) and are older than the pair.
        assert_eq!(stamps(sync.push_depth(image(166))), Some((166, 166, 3)));
        let counts = sync.counts();
        assert_eq!(counts.unmatched_color, 2);
        // A colour image older than the last pair is stale.
        assert_eq!(stamps(sync.push_color(image(150), 4)), None);
        assert_eq!(sync.counts().stale_color, 1);
    }

    #[test]
    fn frames_wait_for_the_first_camera_info_and_bad_stamps_are_ignored() {
        let mut sync = LiveSync::new(20 * MS);
        sync.push_color(image(100), 1);
        assert_eq!(stamps(sync.push_depth(image(100))), None);
        assert_eq!(
            stamps(sync.push_info(CameraInfo::default())),
            Some((100, 100, 1))
        );
        assert_eq!(stamps(sync.push_info(CameraInfo::default())), None);
        let mut bad = image(0);
        bad.header.stamp_sec = -1;
        assert_eq!(stamps(sync.push_color(bad.clone(), 9)), None);
        assert_eq!(stamps(sync.push_depth(bad)), None);
        assert_eq!(sync.counts().bad_stamp, 2);
        sync.push_color(image(200), 2);
        assert_eq!(stamps(sync.push_depth(image(200))), Some((200, 200, 2)));
    }

    #[test]
    fn pending_messages_are_bounded() {
        let mut sync = sync_with_info();
        for i in 0..(PENDING_LIMIT as u64 + 5) {
            sync.push_color(image(1000 + i), 0);
        }
        assert_eq!(sync.counts().stale_color, 5);
    }
}
