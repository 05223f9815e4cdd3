//! Fuzz target `pcd`: see `pomona_io::fuzzing::pcd`.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| pomona_io::fuzzing::pcd(data));
