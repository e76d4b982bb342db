//! Mitsuba XML scenes rendered: whatever a scene that loads holds (hostile numbers in any
//! plugin's parameters, odd nestings), rendering a few pixels of it with its own integrator,
//! sampler and filter must end in an image or an error, never a panic or a hang. The same
//! structure-aware inputs as the `xml` target (start from its corpus); each render is a window
//! of at most 4 × 4 pixels in the middle of the film at no more than 2 samples per pixel, on
//! one thread.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "xml_mutator.rs"]
mod xml_mutator;
use neumann::render::{render_integrator, RenderSettings};
use std::sync::atomic::AtomicBool;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/fuzz.xml"));
    let Ok(file) = neumann::load::mitsuba::load_scene_text(path, text, &[]) else { return };
    let cam = file.scene.camera();
    let (w, h) = (cam.width().min(4), cam.height().min(4));
    let window = [(cam.width() - w) / 2, (cam.height() - h) / 2, w, h];
    let settings = RenderSettings {
        spp: file.spp.clamp(1, 2),
        seed: file.seed,
        threads: 1,
        sampler: file.sampler,
        filter: file.filter.clone(),
        alpha: file.alpha,
        transform: file.transform,
        window: Some(window),
        sample_border: file.sample_border,
        ..Default::default()
    };
    let _ = render_integrator(&file.scene, &file.integrator, &settings, &AtomicBool::new(false));
});
