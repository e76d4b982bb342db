//! Mitsuba XML scenes: parsing, includes, references and building the scene (BVH, lights) from
//! arbitrary text must end in a scene or an error, never a panic, a hang or a memory blow-up.
//! Relative file names resolve against `scenes/`, so inputs can name the real assets.
//!
//! Structure-aware: besides libFuzzer's byte-level mutations (with `fuzz/xml.dict`), a custom
//! mutator edits at the granularity of elements and attributes — it copies a run of elements to
//! another element boundary (nesting, repetition, reference chains), deletes one, or replaces an
//! attribute's value by a hostile number or a `$parameter` — so most inputs stay well-formed
//! enough to reach the plugins.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "xml_mutator.rs"]
mod xml_mutator;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/fuzz.xml"));
        let _ = neumann::load::mitsuba::load_scene_text(path, text, &[]);
    }
});
