//! Fuzz target `model_file`: see `pomona_learn::fuzzing::model_json`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| pomona_learn::fuzzing::model_json(data));
