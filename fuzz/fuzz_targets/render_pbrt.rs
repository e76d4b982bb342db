//! pbrt-v4 scenes rendered: whatever a pbrt-v4 file that loads holds (its own plugins too: the
//! realistic camera, layered and hair BSDFs, curves, bilinear patches, procedural textures,
//! grid, cloud and emissive media), rendering a few pixels of it with its own integrator,
//! sampler and filter must end in an image or an error, never a panic or a hang. Each render
//! is a window of at most 4 × 4 pixels in the middle of the film at no more than 2 samples per
//! pixel, on one thread, as the `render` target does for Mitsuba XML.
#![no_main]
use libfuzzer_sys::fuzz_target;
use neumann::render::{render_integrator, RenderSettings};
use std::sync::atomic::AtomicBool;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/fuzz.pbrt"));
    let Ok(file) = neumann::load::pbrt::load_pbrt_text(path, text, &Default::default()) else { return };
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
