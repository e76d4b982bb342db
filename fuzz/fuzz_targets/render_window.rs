//! What the render targets (`render`, `render_pbrt`) do with a scene that loaded: render a
//! window of at most 4 × 4 pixels in the middle of its film at no more than 2 samples per
//! pixel, on one thread, with its own integrator, sampler and filter. Any outcome but a panic
//! or a hang is fine.
use neumann::load::SceneFile;
use neumann::render::{render_integrator, RenderSettings};
use std::sync::atomic::AtomicBool;

pub fn render_window(file: &SceneFile) {
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
}
