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
//!
//! JSON files are the exception to "decoded size from the header": they declare no sizes, but
//! a generic JSON value (the `extra` keys of truth files, say) takes up to about 25 times its
//! text in memory (`[0,0,0,…]` is two bytes per element, a `serde_json::Value` 32). So JSON
//! files are read with [`read_json_text`], which refuses files over a size cap
//! ([`MAX_JSON_FILE_BYTES`] for the small dataset and detection files) before reading them.

use std::io::Read as _;
use std::path::Path;

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

/// Largest camera, truth or detection JSON file read: far above any real one (a truth file with
/// a thousand fruits is about 250 KB), and small enough that parsing the worst JSON of this size
/// stays within the budget.
pub const MAX_JSON_FILE_BYTES: u64 = 2 << 20;

/// Reads the UTF-8 text of the JSON file at `path`, refusing a file larger than `max_bytes`
/// before reading it.
///
/// # Errors
/// The I/O error, or one of kind [`std::io::ErrorKind::InvalidData`] for a file over the cap or
/// not UTF-8.
pub fn read_json_text(path: &Path, max_bytes: u64) -> std::io::Result<String> {
    let file = std::fs::File::open(path)?;
    let too_big = |len: u64| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("JSON file of {len} bytes is over the {max_bytes}-byte limit"),
        )
    };
    let len = file.metadata()?.len();
    if len > max_bytes {
        return Err(too_big(len));
    }
    let mut text = String::with_capacity(len as usize);
    // The file may have grown since: read no more than the cap allows.
    file.take(max_bytes + 1).read_to_string(&mut text)?;
    if text.len() as u64 > max_bytes {
        return Err(too_big(text.len() as u64));
    }
    Ok(text)
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

    #[test]
    fn json_over_the_cap_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.json");
        std::fs::write(&path, "[1, 2]").unwrap();
        assert_eq!(read_json_text(&path, 6).unwrap(), "[1, 2]");
        let err = read_json_text(&path, 5).unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::InvalidData);
        assert!(err.to_string().contains("6 bytes"), "{err}");
    }
}
