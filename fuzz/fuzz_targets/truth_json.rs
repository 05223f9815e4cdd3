//! Fuzz target `truth_json`: see `pomona_io::fuzzing::truth_json`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| pomona_io::fuzzing::truth_json(data));
