//! glTF files (JSON or GLB) from arbitrary bytes, loaded as `neumann render` loads them: every
//! problem must be an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join("neumann-fuzz.gltf");
    let _ = neumann::load::gltf::load_gltf_bytes(&path, data, &Default::default(), None);
});
