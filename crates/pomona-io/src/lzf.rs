//! LZF, the small LZ77-style byte compressor of Marc Lehmann's liblzf, which PCL uses for the
//! payload of `DATA binary_compressed` PCD files.
//!
//! An LZF stream is a sequence of chunks, each introduced by a control byte `c`:
//!
//! * `c < 32`: a *literal run*: the next `c + 1` bytes are copied to the output as they are.
//! * otherwise a *back-reference*: `len = c >> 5` (if 7, one more byte is added to it), then one
//!   byte `lo`; `len + 2` bytes are copied from `((c & 31) << 8 | lo) + 1` bytes back in the output
//!   (the source may overlap the bytes being written, which repeats a short pattern).
//!
//! The stream carries no length of its own, so [`decompress`] takes the length the caller expects
//! (PCD stores it in its header) and fails with an [`LzfError`] on any disagreement: it never
//! writes past that length, never reads past the input, never panics, and allocates exactly that
//! many bytes. [`compress`] is a deterministic single-pass hash-table compressor producing the same
//! format (readable by liblzf and therefore PCL).

/// Longest literal run one control byte can introduce.
const MAX_LITERAL: usize = 32;
/// Farthest a back-reference can reach (13 bits of offset, biased by one).
const MAX_OFFSET: usize = 1 << 13;
/// Longest back-reference: `7 + 255` from the length bits plus the implied 2.
const MAX_REFERENCE: usize = 7 + 255 + 2;
/// Shortest back-reference worth emitting (it costs 2 bytes, so 3 saves one).
const MIN_MATCH: usize = 3;
/// log2 of the hash-table size.
const HASH_LOG: u32 = 14;

/// The largest factor by which an LZF stream can expand when decompressed: a 3-byte
/// back-reference yields at most 264 bytes. Callers use it to reject implausible declared sizes
/// before allocating.
pub const MAX_EXPANSION_RATIO: usize = MAX_REFERENCE.div_ceil(3);

/// Why an LZF stream could not be decompressed to the expected length.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum LzfError {
    /// The stream decodes to more bytes than expected.
    #[error("LZF data decodes to more than the expected {expected} bytes (at input byte {at})")]
    OutputOverrun {
        /// The expected decompressed length.
        expected: usize,
        /// Offset of the offending control byte in the compressed input.
        at: usize,
    },
    /// The stream ended before producing the expected number of bytes.
    #[error("LZF data ends after {produced} of the expected {expected} bytes")]
    OutputUnderrun {
        /// Bytes produced when the input ran out.
        produced: usize,
        /// The expected decompressed length.
        expected: usize,
    },
    /// A chunk's control byte promises more input bytes than remain.
    #[error(
        "LZF data is truncated: chunk at input byte {at} needs {needed} bytes, {available} remain"
    )]
    TruncatedInput {
        /// Offset of the chunk's control byte in the compressed input.
        at: usize,
        /// Bytes the chunk needs after its control byte.
        needed: usize,
        /// Bytes actually left after the control byte.
        available: usize,
    },
    /// The expected length is more than the input can decode to (checked before allocating).
    #[error("{input} bytes of LZF data cannot decode to the expected {expected} bytes")]
    ImplausibleLength {
        /// The expected decompressed length.
        expected: usize,
        /// Length of the compressed input.
        input: usize,
    },
    /// A back-reference points before the start of the output.
    #[error(
        "LZF back-reference at input byte {at} reaches {distance} bytes back but only {produced} \
         bytes have been produced"
    )]
    BadBackReference {
        /// Offset of the reference's control byte in the compressed input.
        at: usize,
        /// How far back the reference reaches.
        distance: usize,
        /// Bytes produced so far.
        produced: usize,
    },
}

/// Decompresses an LZF stream that must decode to exactly `expected_len` bytes.
///
/// Allocates exactly `expected_len` bytes and nothing else, and only after checking that
/// `input` could decode to that many (at most [`MAX_EXPANSION_RATIO`] times its length); callers
/// bound `expected_len` further when they need to (PCD keeps it within its read budget).
///
/// # Errors
/// [`LzfError::ImplausibleLength`] when `input` is too short to decode to `expected_len` bytes;
/// otherwise [`LzfError`] when the stream is truncated, references data before its start, or decodes to a
/// length other than `expected_len`.
pub fn decompress(input: &[u8], expected_len: usize) -> Result<Vec<u8>, LzfError> {
    if expected_len > input.len().saturating_mul(MAX_EXPANSION_RATIO) {
        return Err(LzfError::ImplausibleLength {
            expected: expected_len,
            input: input.len(),
        });
    }
    let mut out = vec![0_u8; expected_len];
    decompress_into(input, &mut out)?;
    Ok(out)
}

/// Decompresses an LZF stream into `out`, which it must fill exactly.
///
/// # Errors
/// As [`decompress`], with `out.len()` as the expected length.
pub fn decompress_into(input: &[u8], out: &mut [u8]) -> Result<(), LzfError> {
    let expected = out.len();
    let mut ip = 0_usize;
    let mut op = 0_usize;
    while let Some(&ctrl) = input.get(ip) {
        let at = ip;
        ip += 1;
        let ctrl = usize::from(ctrl);
        if ctrl < 32 {
            let len = ctrl + 1;
            let available = input.len() - ip;
            let Some(src) = input.get(ip..ip + len) else {
                return Err(LzfError::TruncatedInput {
                    at,
                    needed: len,
                    available,
                });
            };
            let Some(dst) = out.get_mut(op..op + len) else {
                return Err(LzfError::OutputOverrun { expected, at });
            };
            dst.copy_from_slice(src);
            ip += len;
            op += len;
        } else {
            let mut len = ctrl >> 5;
            let needed = if len == 7 { 2 } else { 1 };
            let available = input.len() - ip;
            if available < needed {
                return Err(LzfError::TruncatedInput {
                    at,
                    needed,
                    available,
                });
            }
            if len == 7 {
                len += usize::from(input[ip]);
                ip += 1;
            }
            let distance = ((ctrl & 0x1f) << 8) + usize::from(input[ip]) + 1;
            ip += 1;
            len += 2;
            if distance > op {
                return Err(LzfError::BadBackReference {
                    at,
                    distance,
                    produced: op,
                });
            }
            if op + len > expected {
                return Err(LzfError::OutputOverrun { expected, at });
            }
            let start = op - distance;
            if distance >= len {
                out.copy_within(start..start + len, op);
            } else {
                // Overlapping copy: each byte may be one this reference has just written.
                for k in 0..len {
                    out[op + k] = out[start + k];
                }
            }
            op += len;
        }
    }
    if op != expected {
        return Err(LzfError::OutputUnderrun {
            produced: op,
            expected,
        });
    }
    Ok(())
}

/// The largest output [`compress`] can produce for `input_len` bytes (all literals: one control
/// byte per 32 input bytes).
pub fn max_compressed_len(input_len: usize) -> usize {
    input_len + input_len.div_ceil(MAX_LITERAL)
}

fn hash3(b: &[u8]) -> usize {
    let v = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
    (v.wrapping_mul(0x9E37_79B1) >> (32 - HASH_LOG)) as usize
}

fn emit_literals(out: &mut Vec<u8>, literals: &[u8]) {
    for chunk in literals.chunks(MAX_LITERAL) {
        // chunks() never yields an empty chunk and each is at most 32 bytes long.
        out.push((chunk.len() - 1) as u8);
        out.extend_from_slice(chunk);
    }
}

/// Compresses `input` into an LZF stream (deterministic: the same input always gives the same
/// bytes). The output is never longer than [`max_compressed_len`]`(input.len())`.
///
/// Decompressing needs the original length, which the stream does not record.
pub fn compress(input: &[u8]) -> Vec<u8> {
    let n = input.len();
    let mut out = Vec::with_capacity(n / 2 + 16);
    // Position + 1 of the last occurrence of each 3-byte hash (0 = none).
    let mut table = vec![0_usize; 1 << HASH_LOG];
    let mut ip = 0_usize;
    let mut literal_start = 0_usize;
    while ip + MIN_MATCH <= n {
        let h = hash3(&input[ip..]);
        let candidate = table[h];
        table[h] = ip + 1;
        if candidate != 0 {
            let r = candidate - 1;
            let distance = ip - r;
            if distance <= MAX_OFFSET && input[r..r + MIN_MATCH] == input[ip..ip + MIN_MATCH] {
                let max_len = MAX_REFERENCE.min(n - ip);
                let mut len = MIN_MATCH;
                while len < max_len && input[r + len] == input[ip + len] {
                    len += 1;
                }
                emit_literals(&mut out, &input[literal_start..ip]);
                let off = distance - 1;
                let l = len - 2;
                if l < 7 {
                    out.push(((l << 5) | (off >> 8)) as u8);
                } else {
                    out.push(((7 << 5) | (off >> 8)) as u8);
                    out.push((l - 7) as u8);
                }
                out.push((off & 0xff) as u8);
                // Index the positions inside the match so later data can refer to them.
                let end = ip + len;
                let mut p = ip + 1;
                while p < end && p + MIN_MATCH <= n {
                    table[hash3(&input[p..])] = p + 1;
                    p += 1;
                }
                ip = end;
                literal_start = ip;
                continue;
            }
        }
        ip += 1;
    }
    emit_literals(&mut out, &input[literal_start..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift) so tests need no dependency.
    fn pseudo_random(len: usize, seed: u64) -> Vec<u8> {
        let mut s = seed.max(1);
        (0..len)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s >> 24) as u8
            })
            .collect()
    }

    fn round_trip(data: &[u8]) -> Vec<u8> {
        let c = compress(data);
        assert!(c.len() <= max_compressed_len(data.len()));
        let d = decompress(&c, data.len()).unwrap();
        assert_eq!(d, data);
        c
    }

    #[test]
    fn round_trips_edge_lengths() {
        for len in [
            0, 1, 2, 3, 4, 31, 32, 33, 64, 65, 263, 264, 265, 8191, 8192, 8193,
        ] {
            round_trip(&pseudo_random(len, len as u64 + 7));
            round_trip(&vec![0xAB; len]);
        }
    }

    #[test]
    fn round_trips_random_data_without_expanding_much() {
        let data = pseudo_random(100_000, 42);
        let c = round_trip(&data);
        assert!(c.len() <= max_compressed_len(data.len()));
    }

    #[test]
    fn compresses_repetitive_data() {
        let data: Vec<u8> = (0..200_000_u32)
            .flat_map(|i| (i % 1000).to_le_bytes())
            .collect();
        let c = round_trip(&data);
        assert!(c.len() < data.len() / 4, "{} vs {}", c.len(), data.len());
        let zeros = vec![0_u8; 1 << 20];
        let c = round_trip(&zeros);
        // Runs of zeros compress at close to the format's maximum ratio.
        assert!(c.len() * (MAX_EXPANSION_RATIO - 1) < zeros.len());
    }

    #[test]
    fn mixed_data_round_trips() {
        let mut data = Vec::new();
        for i in 0..50 {
            data.extend(pseudo_random(100 + i * 37, i as u64 + 1));
            data.extend(std::iter::repeat_n(i as u8, i * 13));
            data.extend_from_slice(b"abcabcabcabcabcabcabc");
        }
        round_trip(&data);
    }

    #[test]
    fn compression_is_deterministic() {
        let data = pseudo_random(10_000, 3)
            .into_iter()
            .map(|b| b & 7)
            .collect::<Vec<_>>();
        assert_eq!(compress(&data), compress(&data));
    }

    #[test]
    fn decodes_hand_made_stream() {
        // "abc" literal, then a reference of len 6 reaching 3 back ("abcabc"), then literal "!".
        let stream = [2, b'a', b'b', b'c', (4 << 5), 2, 0, b'!'];
        assert_eq!(decompress(&stream, 10).unwrap(), b"abcabcabc!");
    }

    #[test]
    fn wrong_lengths_are_errors() {
        let data = pseudo_random(1000, 9);
        let c = compress(&data);
        assert!(matches!(
            decompress(&c, 999),
            Err(LzfError::OutputOverrun { expected: 999, .. })
        ));
        assert!(matches!(
            decompress(&c, 1001),
            Err(LzfError::OutputUnderrun {
                produced: 1000,
                expected: 1001
            })
        ));
        assert!(matches!(
            decompress_into(&[], &mut [0]),
            Err(LzfError::OutputUnderrun { .. })
        ));
        assert_eq!(decompress(&[], 0).unwrap(), Vec::<u8>::new());
        // A length no input of this size can produce is refused before allocating.
        assert!(matches!(
            decompress(&[], 1),
            Err(LzfError::ImplausibleLength {
                expected: 1,
                input: 0
            })
        ));
        assert!(matches!(
            decompress(&c, usize::MAX),
            Err(LzfError::ImplausibleLength { .. })
        ));
        let longest = c.len() * MAX_EXPANSION_RATIO;
        assert!(matches!(
            decompress(&c, longest),
            Err(LzfError::OutputUnderrun { .. })
        ));
    }

    #[test]
    fn corrupt_streams_are_errors() {
        // Reference before any output.
        assert!(matches!(
            decompress(&[0x20, 0x00], 3),
            Err(LzfError::BadBackReference { distance: 1, .. })
        ));
        // Literal run promising more bytes than remain.
        assert!(matches!(
            decompress(&[5, 1, 2], 6),
            Err(LzfError::TruncatedInput {
                needed: 6,
                available: 2,
                ..
            })
        ));
        // Long reference missing its length byte.
        assert!(matches!(
            decompress(&[0, 1, 0xE0], 20),
            Err(LzfError::TruncatedInput { .. })
        ));
        // Reference reaching too far back.
        assert!(matches!(
            decompress(&[0, 1, 0x20, 5], 4),
            Err(LzfError::BadBackReference { distance: 6, .. })
        ));
    }

    #[test]
    fn truncated_and_mutated_streams_never_panic() {
        let data: Vec<u8> = (0..5000_u32).flat_map(|i| (i / 7).to_le_bytes()).collect();
        let c = compress(&data);
        for cut in 0..c.len().min(300) {
            assert!(decompress(&c[..cut], data.len()).is_err());
        }
        let noise = pseudo_random(c.len() * 4, 77);
        for (i, chunk) in noise.chunks(4).take(2000).enumerate() {
            let mut m = c.clone();
            let pos = (usize::from(chunk[0]) << 8 | usize::from(chunk[1])) % m.len();
            m[pos] ^= chunk[2] | 1;
            // Any outcome but a panic is fine; a successful decode has the right length.
            if let Ok(d) = decompress(&m, data.len()) {
                assert_eq!(d.len(), data.len(), "mutation {i}");
            }
        }
        for seed in 1..200 {
            let garbage = pseudo_random(64, seed);
            let _ = decompress(&garbage, 1000);
        }
    }
}
