//! The light tracer's render driver: passes of `W × H` light paths (one per pixel of the whole
//! film, so a pass adds one sample per pixel), traced in fixed-size chunks over rayon and
//! splatted through the reconstruction filter.
//!
//! Lights at infinity cannot be connected to the camera, so each pass also traces one camera ray
//! per pixel (uniform in the pixel) and splats what an escaping one sees of them.
//!
//! Determinism: chunk `c` of pass `k` draws its random numbers from its own PCG stream
//! `(seed, k·2³² + c)`, records its splats in order, and the chunks' records are added to the
//! pass image in chunk order, so the image is bit-identical for a seed whatever the number
//! of threads. Each pass is added to the film as one sample per pixel (its per-pixel variance
//! is then the variance between passes).

use super::{RenderError, RenderOutcome, RenderSettings, Scheduler};
use crate::film::filter::Filter;
use crate::film::Film;
use crate::integrator::LightTracer;
use crate::math::{Rgb, Vec2};
use crate::sampling::Pcg32;
use crate::scene::Scene;
use std::sync::atomic::AtomicBool;

/// A chunk's splats `(pixel, value)` in order, and its count of non-finite splats dropped.
type ChunkSplats = (Vec<(u32, Rgb)>, u64);

/// Light paths per parallel work item.
const CHUNK: u64 = 4096;

/// Where a splat at film position `film` lands: `(pixel index in the window, weight)` for every
/// pixel whose filter support covers it, the weights being the filter normalised to unit
/// integral (so the splat's total over pixels is its value, as filter importance sampling's).
struct Splatter {
    filter: Filter,
    /// `1 / (∫ f₁)²`.
    norm: f32,
    window: [u32; 4],
}

impl Splatter {
    fn new(filter: &Filter, window: [u32; 4]) -> Splatter {
        let radius = filter.radius();
        let n = 4096;
        let integral: f64 =
            (0..n).map(|i| filter.eval_1d(-radius + (i as f32 + 0.5) * 2.0 * radius / n as f32) as f64).sum::<f64>()
                * (2.0 * radius as f64 / n as f64);
        Splatter { filter: filter.clone(), norm: (1.0 / (integral * integral)) as f32, window }
    }

    fn splat(&self, film: Vec2, value: Rgb, out: &mut Vec<(u32, Rgb)>) {
        let [wx, wy, w, h] = self.window;
        if self.filter.is_pixel_box() {
            let (x, y) = (
                (crate::math::floor(film.x) as i64).saturating_sub(wx as i64),
                (crate::math::floor(film.y) as i64).saturating_sub(wy as i64),
            );
            if x >= 0 && y >= 0 && x < w as i64 && y < h as i64 {
                out.push(((y as u32) * w + x as u32, value));
            }
            return;
        }
        let lo = [wx as i64, wy as i64];
        let hi = [(wx + w) as i64 - 1, (wy + h) as i64 - 1];
        self.filter.footprint([0, 0], film, lo, hi, |x, y, f| {
            out.push((((y - wy as i64) as u32) * w + (x - wx as i64) as u32, value * (f * self.norm)));
        });
    }
}

/// Renders `scene` by light tracing. Settings as for [`super::render`]; `spp` counts passes of
/// `W × H` light paths (`W × H` the whole film, also with a crop window). The sampler choice is
/// ignored (light paths use independent PCG streams).
pub fn render_light_paths(
    scene: &Scene,
    tracer: &LightTracer,
    settings: &RenderSettings,
    cancel: &AtomicBool,
) -> Result<RenderOutcome, RenderError> {
    render_light_paths_with(scene, tracer, settings, cancel, &mut |_, _| {})
}

/// [`render_light_paths`] calling `after_pass(film, spp_done)` after every pass.
pub fn render_light_paths_with(
    scene: &Scene,
    tracer: &LightTracer,
    settings: &RenderSettings,
    cancel: &AtomicBool,
    after_pass: &mut dyn FnMut(&Film, u32),
) -> Result<RenderOutcome, RenderError> {
    let cam = scene.camera();
    let window = super::crop_window(settings, cam)?;
    let [_, _, width, height] = window;
    if settings.terms > 0 {
        return Err(RenderError::NoTerms { integrator: "ptracer" });
    }
    if scene.lights().is_empty() {
        return Err(RenderError::NoEmitters);
    }
    if cam.projection() != crate::camera::Projection::Perspective {
        return Err(RenderError::Unsupported(
            "the light tracer (ptracer) needs a perspective or thin-lens camera: an orthographic, spherical, realistic, batch or meter one cannot be connected to".into(),
        ));
    }
    let splatter = Splatter::new(&settings.filter, window);
    let paths_per_pass = cam.width() as u64 * cam.height() as u64;
    let chunks = paths_per_pass.div_ceil(CHUNK);
    let scheduler = Scheduler::new(settings, cancel, paths_per_pass, "light paths")?;
    let mut film = Film::new(width, height);
    let mut image = vec![[0.0f64; 3]; (width * height) as usize];
    // Lights at infinity seen directly: no light path reaches the camera from them, so camera
    // rays that escape the scene (one per pixel per pass) see them, as in Mitsuba's ptracer.
    let sees_sky = !scene.infinite_lights().is_empty() && !tracer.settings.hide_emitters && tracer.settings.allows(1);
    let film_width = cam.width() as u64;
    // One pass per sample per pixel: each pass is added to the film as one sample per pixel.
    let trace_chunk = |c: usize, pass: u32, _: u32| {
        let c = c as u64;
        let mut rng = Pcg32::new(settings.seed, ((pass as u64) << 32) | c);
        let mut out = Vec::new();
        let mut dropped = 0u64;
        let n = CHUNK.min(paths_per_pass - c * CHUNK);
        for _ in 0..n {
            tracer.trace(scene, &mut rng, &mut |film, value| {
                if value.is_finite() {
                    splatter.splat(film, settings.transform.apply(value), &mut out);
                } else {
                    dropped += 1;
                }
            });
        }
        if sees_sky {
            // The chunk's pixels of the whole film (as many as its light paths).
            for j in c * CHUNK..c * CHUNK + n {
                let (x, y) = ((j % film_width) as f32, (j / film_width) as f32);
                let film_pos = Vec2::new(x + rng.next_f32(), y + rng.next_f32());
                let ray = cam.generate_ray(film_pos, Vec2::new(rng.next_f32(), rng.next_f32()));
                let ray = match scene.motion_shutter() {
                    Some((open, close)) => cam.ray_at_time(&ray, open + (close - open) * rng.next_f32()).0,
                    None => ray,
                };
                if scene.intersect(&ray).is_some() {
                    continue;
                }
                let le: Rgb =
                    scene.infinite_lights().iter().map(|&i| scene.lights()[i as usize].le_escaped(ray.o, ray.d)).sum();
                if le.is_finite() {
                    splatter.splat(film_pos, settings.transform.apply(le), &mut out);
                } else {
                    dropped += 1;
                }
            }
        }
        ((out, dropped), n)
    };
    // Pass k seeds its paths with k: a part of a split render traces passes [first, end).
    let (first, end) = super::sample_range(settings)?;
    let mut done = first;
    let passes =
        scheduler.run_from(first, end, 1, chunks as usize, trace_chunk, |records: Vec<Option<ChunkSplats>>, _| {
            // A pass that cancellation cut short is left out: its pixels would miss paths.
            if records.iter().any(Option::is_none) {
                return std::ops::ControlFlow::Continue(());
            }
            image.fill([0.0; 3]);
            let mut dropped = 0;
            for (out, d) in records.into_iter().flatten() {
                dropped += d;
                for (i, v) in out {
                    let px = &mut image[i as usize];
                    for c in 0..3 {
                        px[c] += v[c] as f64;
                    }
                }
            }
            film.add_pass(&image, dropped);
            done += 1;
            after_pass(&film, done);
            std::ops::ControlFlow::Continue(())
        });
    Ok(RenderOutcome { film, interrupted: passes.interrupted, elapsed: passes.elapsed, report: Vec::new() })
}
