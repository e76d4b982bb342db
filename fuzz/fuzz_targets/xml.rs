//! Mitsuba XML scenes: parsing, includes, references and building the scene (BVH, lights) from
//! arbitrary text must end in a scene or an error, never a panic, a hang or a memory blow-up.
//! Relative file names resolve against `scenes/`, so inputs can name the real assets.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/fuzz.xml"));
        let _ = neumann::load::mitsuba::load_scene_text(path, text, &[]);
    }
});
