//! Fuzz target `ply`: see `pomona_io::fuzzing::ply`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| pomona_io::fuzzing::ply(data));
