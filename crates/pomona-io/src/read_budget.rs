//! The memory budget every reader keeps: decoding a file of `n` bytes allocates at most
//! [`decode_budget_bytes`]`(n)` = 3 × `n` + 48 MiB for what it decodes (pixels, point columns,
//! decompressed payloads), checked from the header *before* allocating.
//!
//! Why: a file's header declares sizes (point counts, image dimensions, uncompressed lengths)
//! that a corrupt or hostile file can set to anything. Bounding the decoded size by the input
//! size keeps a reader's peak memory — the input bytes held in memory plus the decoded data —
//! under 4 × the input size + 64 MiB, whatever the header says. Uncompressed formats stay far
//! below the bound on their own (a point's columns take at most four times its bytes); the
//! check binds on compressed payloads (LZF in PCD, deflate in PNG) whose declared size could
//! otherwise expand a few kilobytes into gigabytes. The constant part admits every real sensor
//! frame (a 1280 × 720 cloud with colour decodes to under 30 MB) however well it compresses.

/// How many bytes of decoded data each input byte may produce, beyond the constant part.
pub const DECODE_BYTES_PER_INPUT_BYTE: u64 = 3;

/// Decoded bytes allowed regardless of the input size.
pub const DECODE_SLACK_BYTES: u64 = 48 << 20;

/// The most bytes a reader may allocate for the decoded content of an input of `input_len`
/// bytes.
pub fn decode_budget_bytes(input_len: u64) -> u64 {
    input_len
        .saturating_mul(DECODE_BYTES_PER_INPUT_BYTE)
        .saturating_add(DECODE_SLACK_BYTES)
}

/// `Some(needed)` when `needed` decoded bytes exceed the budget of an input of `input_len`
/// bytes, `None` when they fit.
pub(crate) fn over_budget(needed: u64, input_len: u64) -> Option<u64> {
    let budget = decode_budget_bytes(input_len);
    (needed > budget).then_some(budget)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budget_grows_with_the_input_and_saturates() {
        assert_eq!(decode_budget_bytes(0), 48 << 20);
        assert_eq!(decode_budget_bytes(1000), 3000 + (48 << 20));
        assert_eq!(decode_budget_bytes(u64::MAX), u64::MAX);
        assert_eq!(over_budget(48 << 20, 0), None);
        assert_eq!(over_budget((48 << 20) + 1, 0), Some(48 << 20));
    }
}
