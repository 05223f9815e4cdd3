//! Approximate-time synchronisation of colour, depth and camera info by header stamp.
//!
//! Cameras stamp colour and depth separately, so the stamps of one exposure differ by up to a
//! frame interval's fraction (RealSense aligned depth usually carries the colour stamp exactly;
//! other drivers do not). For each colour stamp, the depth stamp nearest to it is taken if it is
//! within the tolerance (the earlier one on a tie); the camera info is the latest at or before
//! the colour stamp, or the first one when all come later (a driver publishing it once).

/// The index of the stamp in sorted `depth_ns` nearest to `color_ns`, if within `tolerance_ns`.
pub fn nearest_within(depth_ns: &[u64], color_ns: u64, tolerance_ns: u64) -> Option<usize> {
    let after = depth_ns.partition_point(|&d| d < color_ns);
    let candidates = [
        after.checked_sub(1),
        (after < depth_ns.len()).then_some(after),
    ];
    candidates
        .into_iter()
        .flatten()
        .map(|i| (depth_ns[i].abs_diff(color_ns), i))
        .min()
        .filter(|&(gap, _)| gap <= tolerance_ns)
        .map(|(_, i)| i)
}

/// The index of the latest stamp in sorted `info_ns` at or before `color_ns`, else 0 (the first);
/// `None` only when there are none.
pub fn latest_at_or_before(info_ns: &[u64], color_ns: u64) -> Option<usize> {
    if info_ns.is_empty() {
        return None;
    }
    Some(
        info_ns
            .partition_point(|&s| s <= color_ns)
            .saturating_sub(1),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_depth_within_tolerance() {
        let depth = [100, 200, 300];
        assert_eq!(nearest_within(&depth, 190, 20), Some(1));
        assert_eq!(nearest_within(&depth, 215, 20), Some(1));
        assert_eq!(nearest_within(&depth, 250, 60), Some(1), "tie: the earlier");
        assert_eq!(nearest_within(&depth, 250, 20), None);
        assert_eq!(nearest_within(&depth, 0, 100), Some(0));
        assert_eq!(nearest_within(&depth, 400, 100), Some(2));
        assert_eq!(nearest_within(&depth, 401, 100), None);
        assert_eq!(nearest_within(&[], 5, 100), None);
    }

    #[test]
    fn latest_info_or_the_first() {
        let info = [100, 200];
        assert_eq!(latest_at_or_before(&info, 50), Some(0));
        assert_eq!(latest_at_or_before(&info, 100), Some(0));
        assert_eq!(latest_at_or_before(&info, 199), Some(0));
        assert_eq!(latest_at_or_before(&info, 200), Some(1));
        assert_eq!(latest_at_or_before(&info, 999), Some(1));
        assert_eq!(latest_at_or_before(&[], 5), None);
    }
}
