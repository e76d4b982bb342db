//! Mitsuba XML scenes rendered: whatever a scene that loads holds (hostile numbers in any
//! plugin's parameters, odd nestings), rendering a few pixels of it with its own integrator,
//! sampler and filter must end in an image or an error, never a panic or a hang. The same
//! structure-aware inputs as the `xml` target (start from its corpus); each render is a window
//! of at most 4 × 4 pixels in the middle of the film at no more than 2 samples per pixel, on
//! one thread (`render_window.rs`).
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "xml_mutator.rs"]
mod xml_mutator;
#[path = "render_window.rs"]
mod render_window;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/fuzz.xml"));
    if let Ok(file) = neumann::load::mitsuba::load_scene_text(path, text, &[]) {
        render_window::render_window(&file);
    }
});
