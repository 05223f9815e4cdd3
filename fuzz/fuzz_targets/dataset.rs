//! Fuzz target `dataset`: see `pomona_io::fuzzing::dataset`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| pomona_io::fuzzing::dataset(data));
