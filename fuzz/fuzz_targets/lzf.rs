//! Fuzz target `lzf`: see `pomona_io::fuzzing::lzf`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| pomona_io::fuzzing::lzf(data));
