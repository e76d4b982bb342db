//! Stanford PLY meshes (ASCII and binary) from arbitrary bytes.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = neumann::load::ply::parse_ply(data);
});
