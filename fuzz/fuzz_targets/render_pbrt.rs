//! pbrt-v4 scenes rendered: whatever a pbrt-v4 file that loads holds (its own plugins too: the
//! realistic camera, layered and hair BSDFs, curves, bilinear patches, procedural textures,
//! grid, cloud and emissive media), rendering a few pixels of it with its own integrator,
//! sampler and filter must end in an image or an error, never a panic or a hang, as the
//! `render` target asks of Mitsuba XML (`render_window.rs`).
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "render_window.rs"]
mod render_window;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/fuzz.pbrt"));
    if let Ok(file) = neumann::load::pbrt::load_pbrt_text(path, text, &Default::default()) {
        render_window::render_window(&file);
    }
});
