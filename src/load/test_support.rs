//! What the scene-format tests share: rendering a loaded file, and the comparison of two
//! renders of one scene written in two formats.

use super::SceneFile;
use crate::math::Rgb;

/// The image of `file` at `spp` samples per pixel and `seed`, with the file's filter.
pub fn render(file: &SceneFile, spp: u32, seed: u64) -> Vec<Rgb> {
    let settings = crate::render::RenderSettings { spp, seed, filter: file.filter.clone(), transform: file.transform, ..Default::default() };
    let never = std::sync::atomic::AtomicBool::new(false);
    crate::render::render_integrator(&file.scene, &file.integrator, &settings, &never).unwrap().film.image()
}

/// The mean over pixels and channels.
pub fn mean(img: &[Rgb]) -> f64 {
    img.iter().map(|c| (c.x + c.y + c.z) as f64 / 3.0).sum::<f64>() / img.len() as f64
}

/// relMSE of `a` against `b` (per channel, ε = 0.01).
pub fn rel_mse(a: &[Rgb], b: &[Rgb]) -> f64 {
    let mut s = 0.0;
    for (x, y) in a.iter().zip(b) {
        for k in 0..3 {
            let d = (x[k] - y[k]) as f64;
            s += d * d / ((y[k] as f64).powi(2) + 0.01);
        }
    }
    s / (3 * a.len()) as f64
}

/// Asserts that `file` renders as `reference` (the same scene in another format) does, within
/// noise: 64 spp each (seed 1), means within 0.5 %, and a relMSE at most 1.5 × the relMSE
/// between two seeds of the reference.
pub fn assert_renders_like(file: &SceneFile, reference: &SceneFile) {
    let (a, b) = (render(file, 64, 1), render(reference, 64, 1));
    let (ma, mb) = (mean(&a), mean(&b));
    assert!(mb > 0.01, "the scene is lit: {mb}");
    assert!((ma / mb - 1.0).abs() < 0.005, "means {ma} vs {mb}");
    let noise = rel_mse(&render(reference, 64, 2), &b);
    let diff = rel_mse(&a, &b);
    assert!(diff <= 1.5 * noise, "relMSE {diff} against a noise level of {noise}");
}
