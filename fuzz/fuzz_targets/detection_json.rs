//! Fuzz target `detection_json`: see `pomona_eval::fuzzing::detection_json`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| pomona_eval::fuzzing::detection_json(data));
