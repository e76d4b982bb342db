//! pbrt-v4 scene text from arbitrary bytes, loaded as `neumann render` loads it: every problem
//! must be an error, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let path = std::env::temp_dir().join("neumann-fuzz.pbrt");
        let _ = neumann::load::pbrt::load_pbrt_text(&path, text, &Default::default());
    }
});
