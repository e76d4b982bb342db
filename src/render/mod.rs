//! The render driver: tiles rendered in parallel (rayon), passes of samples, sample and time
//! budgets, progress, and cancellation (Ctrl-C) that keeps what was rendered.
//!
//! Determinism: pixel sample `i` of pixel `p` depends only on (seed, p, i) through the sampler,
//! each tile adds its pixels' samples in index order, and tiles are merged in a fixed order
//! after each pass. The image is therefore bit-identical for a given seed and sample count
//! whatever the number of threads.

mod error;
mod scheduler;
mod splat;

pub use error::RenderError;
pub use scheduler::{Passes, Scheduler};

pub use splat::render_light_paths;

use crate::film::filter::Filter;
use crate::film::{Film, FilmSample, TileBuffer};
use crate::integrator::radiosity::{Radiosity, RadiosityIntegrator};
use crate::integrator::{AnyIntegrator, Integrator};
use crate::math::{Rgb, Vec2};
use crate::sampling::sampler::SamplerKind;
use crate::scene::Scene;
use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Render settings.
#[derive(Clone, Debug)]
pub struct RenderSettings {
    /// Samples per pixel (the target; with a time budget, the most that will be taken).
    pub spp: u32,
    /// Stop starting new passes once this much time is used.
    pub time_budget: Option<Duration>,
    /// Seed of all sampling.
    pub seed: u64,
    /// Worker threads (0: one per core).
    pub threads: usize,
    /// Tile edge in pixels.
    pub tile_size: u32,
    /// Sampler.
    pub sampler: SamplerKind,
    /// Whether to draw a progress bar on the terminal.
    pub progress: bool,
    /// Pixel reconstruction filter (applied by weighted splatting, see [`crate::film`]).
    pub filter: Filter,
    /// Crop window `[x0, y0, width, height]` of the camera's film to render (the output image is
    /// the window; default: the whole film).
    pub window: Option<[u32; 4]>,
    /// Record per-pixel coverage (alpha, which the integrators report with each sample): the
    /// filter-weighted fraction of camera rays that hit a surface.
    pub alpha: bool,
    /// Keep this many Neumann-series terms per pixel (`Lₑ`, `T Lₑ`, …; the last collects all
    /// longer paths), if the integrator separates them; 0: off.
    pub terms: usize,
    /// Render only the sample indices `[first, end)` of every pixel of the `spp`-sample render
    /// (one part of a render split over machines; `spp` still fixes the sampler's sequence, so
    /// the parts together take exactly the samples of the whole render). Default: `[0, spp)`.
    pub sample_range: Option<(u32, u32)>,
    /// The crop `window` is a tile of this larger window `[x0, y0, width, height]` (the image of a
    /// render split into tiles): the pixels of that window around the tile whose filter footprint
    /// reaches into it are sampled too, as the whole window's render samples them, so that tiles
    /// rendered separately assemble into exactly that render.
    pub tile_of: Option<[u32; 4]>,
    /// Mitsuba's `sample_border`: also sample the pixels outside the image (the crop window, or
    /// the film) within the filter's reach, whose samples the filter splats into its edge
    /// pixels (without it the edge pixels average only the samples inside, over a truncated
    /// footprint).
    pub sample_border: bool,
    /// Adaptive sampling (camera-ray integrators) with Cycles' noise threshold `T`: after
    /// `min_spp` samples, a pixel whose error estimate ([`Film::adaptive_errors`]) is below
    /// `ADAPTIVE_THRESHOLD_SCALE · T` — and so are those of the pixels within
    /// `ADAPTIVE_RADIUS` of it — takes no more
    /// samples; the render ends when every pixel has stopped, at `spp`, or at the time budget.
    /// `None`: every pixel takes every sample.
    pub noise_threshold: Option<f32>,
    /// Samples every pixel takes before adaptive sampling may stop it (Cycles' default:
    /// [`auto_min_spp`]).
    pub min_spp: u32,
    /// What each radiance sample becomes before the film (the film's white balance and clamp).
    pub transform: crate::film::sensor::SampleTransform,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            spp: 16,
            time_budget: None,
            seed: 0,
            threads: 0,
            tile_size: 16,
            sampler: SamplerKind::Independent,
            progress: false,
            filter: Filter::BOX,
            window: None,
            alpha: false,
            terms: 0,
            sample_range: None,
            tile_of: None,
            sample_border: false,
            noise_threshold: None,
            min_spp: 16,
            transform: Default::default(),
        }
    }
}

/// What a render produced.
#[derive(Debug)]
pub struct RenderOutcome {
    /// The accumulated film.
    pub film: Film,
    /// Whether the render was cancelled before reaching its target.
    pub interrupted: bool,
    /// Wall-clock time spent.
    pub elapsed: Duration,
    /// What the integrator has to say about the render beyond the image (radiosity: the solve's
    /// iterations, residuals and power), one line per entry.
    pub report: Vec<String>,
}

impl RenderOutcome {
    /// Samples per second over the whole render.
    pub fn samples_per_second(&self) -> f64 {
        self.film.total_samples() as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }
}

/// The crop window `[x0, y0, width, height]` of `settings` (default: the whole film), checked
/// against the camera's film.
fn crop_window(settings: &RenderSettings, cam: &crate::camera::Camera) -> Result<[u32; 4], RenderError> {
    let window = settings.window.unwrap_or([0, 0, cam.width(), cam.height()]);
    let [x, y, width, height] = window;
    if width == 0
        || height == 0
        || x as u64 + width as u64 > cam.width() as u64
        || y as u64 + height as u64 > cam.height() as u64
    {
        return Err(RenderError::CropWindow {
            x,
            y,
            width,
            height,
            film_width: cam.width(),
            film_height: cam.height(),
        });
    }
    Ok(window)
}

/// Adaptive sampling after a pass: marks the pixels that go on (error at or above `threshold`,
/// or a neighbour's within one pixel — Cycles' dilation, so that a noisy region's edge is not
/// stopped early) and says whether any does.
/// Cycles' factor between the noise threshold a user gives and the error a pixel must fall
/// below (Cycles' `Integrator::get_adaptive_sampling`: "makes the threshold more similar to
/// what it was before"), kept so that a threshold means what it means in Cycles.
pub const ADAPTIVE_THRESHOLD_SCALE: f32 = 5.0;

/// Cycles' automatic minimum sample count for noise threshold `t`: `max(4, ⌈16 / t^0.3⌉)`
/// (0.1 → 32, 0.01 → 64, 0.001 → 128).
pub fn auto_min_spp(t: f32) -> u32 {
    ((16.0 / t.powf(0.3)).ceil().min(1e9) as u32).max(4)
}

/// A pixel goes on sampling while any pixel within this many pixels of it (a 9×9 window) is
/// above the threshold. Cycles dilates by one pixel; a wider window keeps the pixels around a
/// rare bright path (a small light seen in a glossy reflection, a caustic) sampling until they
/// have had their chance to find it too. Measured at equal time (README, "Adaptive sampling"):
/// with one pixel, `small_lights` at T = 0.01 rendered 35× worse than uniformly, with four 1.7×.
pub const ADAPTIVE_RADIUS: usize = 4;

fn update_active(film: &Film, threshold: f32, active: &[AtomicBool]) -> bool {
    let Some(errors) = film.adaptive_errors() else { return true };
    let threshold = ADAPTIVE_THRESHOLD_SCALE * threshold;
    let (w, h) = (film.width() as usize, film.height() as usize);
    let noisy: Vec<bool> = errors.iter().map(|&e| e >= threshold || e.is_nan()).collect();
    // The noisy mask dilated by ADAPTIVE_RADIUS: along rows, then along columns (a square
    // window, 2 (2r + 1) reads per pixel).
    let r = ADAPTIVE_RADIUS;
    let mut rows = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            rows[y * w + x] = (x.saturating_sub(r)..(x + r + 1).min(w)).any(|i| noisy[y * w + i]);
        }
    }
    let mut any = false;
    for y in 0..h {
        for x in 0..w {
            let near = (y.saturating_sub(r)..(y + r + 1).min(h)).any(|j| rows[j * w + x]);
            // A pixel once stopped stays stopped: its estimate no longer changes.
            let on = near && active[y * w + x].load(Ordering::Relaxed);
            active[y * w + x].store(on, Ordering::Relaxed);
            any |= on;
        }
    }
    any
}

/// The pixels a render samples, `([x0, y0, width, height], shift)`: the crop `window`; with
/// [`RenderSettings::tile_of`] also the pixels of the larger window around it whose filter
/// footprint reaches into it; with [`RenderSettings::sample_border`] also those outside the image
/// (the whole window) within the filter's reach. The region is given in film pixels plus `shift`
/// (the filter's border with `sample_border`, else 0), so that pixels left of or above the film
/// have coordinates too: region pixel `(x, y)` is film pixel `(x − shift, y − shift)`.
pub fn sampled_region(settings: &RenderSettings, window: [u32; 4]) -> Result<([u32; 4], u32), RenderError> {
    let b = settings.filter.border();
    let s = if settings.sample_border { b } else { 0 };
    let [x, y, w, h] = window;
    // The whole image's window, with its border when sampled (shifted coordinates).
    let outer = match settings.tile_of {
        Some([ox, oy, ow, oh]) => {
            if x < ox
                || y < oy
                || x as u64 + w as u64 > ox as u64 + ow as u64
                || y as u64 + h as u64 > oy as u64 + oh as u64
            {
                return Err(RenderError::Unsupported(format!(
                    "the tile {w}x{h} at ({x}, {y}) does not lie inside the window {ow}x{oh} at ({ox}, {oy}) it is a tile of"
                )));
            }
            [ox, oy, ow + 2 * s, oh + 2 * s]
        }
        None if s > 0 => [x, y, w + 2 * s, h + 2 * s],
        None => return Ok((window, 0)),
    };
    let [ox, oy, ow, oh] = outer;
    let (x, y) = (x + s, y + s);
    let (x0, y0) = (x.saturating_sub(b).max(ox), y.saturating_sub(b).max(oy));
    let x1 = (x + w).saturating_add(b).min(ox + ow);
    let y1 = (y + h).saturating_add(b).min(oy + oh);
    Ok(([x0, y0, x1 - x0, y1 - y0], s))
}

/// The sample indices `[first, end)` a render takes of every pixel: its
/// [`RenderSettings::sample_range`], checked against `spp`, or all of them.
pub fn sample_range(settings: &RenderSettings) -> Result<(u32, u32), RenderError> {
    match settings.sample_range {
        None => Ok((0, settings.spp.max(1))),
        Some((first, end)) if first < end && end <= settings.spp.max(1) => Ok((first, end)),
        Some((first, end)) => Err(RenderError::Unsupported(format!(
            "the sample range {first}–{end} is empty or lies outside the render's {} samples per pixel",
            settings.spp
        ))),
    }
}

/// Renders `scene` with any of neumann's integrators: camera-ray integrators through
/// [`render`], the light tracer through [`render_light_paths`], radiosity by solving first and
/// then displaying the solution through [`render`].
pub fn render_integrator(
    scene: &Scene,
    integrator: &AnyIntegrator,
    settings: &RenderSettings,
    cancel: &AtomicBool,
) -> Result<RenderOutcome, RenderError> {
    render_integrator_with(scene, integrator, settings, cancel, &mut |_, _| {})
}

/// [`render_integrator`] calling `after_pass(film, spp_done)` after every complete pass (a live
/// preview, checkpoints).
pub fn render_integrator_with(
    scene: &Scene,
    integrator: &AnyIntegrator,
    settings: &RenderSettings,
    cancel: &AtomicBool,
    after_pass: &mut dyn FnMut(&Film, u32),
) -> Result<RenderOutcome, RenderError> {
    let camera = |i: &dyn Integrator, after_pass: &mut dyn FnMut(&Film, u32)| {
        render_from(scene, i, settings, cancel, None, after_pass)
    };
    match integrator {
        AnyIntegrator::Path(i) => camera(i, after_pass),
        AnyIntegrator::Direct(i) => camera(i, after_pass),
        AnyIntegrator::Ptracer(t) => splat::render_light_paths_with(scene, t, settings, cancel, after_pass),
        AnyIntegrator::VolPath(i) => camera(i, after_pass),
        AnyIntegrator::VolPathMis(i) => camera(i, after_pass),
        AnyIntegrator::Moment(i) => camera(i, after_pass),
        AnyIntegrator::Aov(i) => camera(i, after_pass),
        AnyIntegrator::Depth(i) => camera(i, after_pass),
        AnyIntegrator::Radiosity(opts) => {
            let start = Instant::now();
            let solution = Radiosity::solve(scene, opts, cancel).map_err(RenderError::Radiosity)?;
            let mut report = solution.report_lines();
            if let Some(path) = &opts.patches_out {
                std::fs::write(path, solution.to_csv())
                    .map_err(|source| RenderError::Write { path: path.clone(), source })?;
                report.push(format!("wrote the per-patch solution to {}", path.display()));
            }
            let display = RadiosityIntegrator { solution };
            let mut out = render_from(scene, &display, settings, cancel, None, after_pass)?;
            out.elapsed = start.elapsed();
            out.report = report;
            Ok(out)
        }
    }
}

/// Renders `scene` with `integrator`. Returns when the sample target is reached, the time budget
/// is used, or `cancel` becomes true (then the completed tiles of the current pass are kept).
pub fn render(
    scene: &Scene,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    cancel: &AtomicBool,
) -> Result<RenderOutcome, RenderError> {
    render_from(scene, integrator, settings, cancel, None, &mut |_, _| {})
}

/// [`render`] continuing from `start` (a film holding the first `spp` samples of every pixel,
/// e.g. a checkpoint read back), calling `after_pass(film, spp_done)` after every complete pass
/// (to write checkpoints). Passes end at the same sample counts whatever the target, so a render
/// continued from a checkpoint that ended at one is bit-identical to one that never stopped.
pub fn render_from(
    scene: &Scene,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    cancel: &AtomicBool,
    start: Option<(Film, u32)>,
    after_pass: &mut dyn FnMut(&Film, u32),
) -> Result<RenderOutcome, RenderError> {
    let cam = scene.camera();
    let window = crop_window(settings, cam)?;
    // The pixels sampled: the window, or with `tile_of` also its neighbours in the larger window
    // whose filter footprint reaches into it. The film covers them; it is cropped at the end.
    let ([rx, ry, width, height], shift) = sampled_region(settings, window)?;
    let (first_sample, end_sample) = sample_range(settings)?;
    let ts = settings.tile_size.max(1);
    let tiles: Vec<(u32, u32, u32, u32)> = (0..height.div_ceil(ts))
        .flat_map(|ty| (0..width.div_ceil(ts)).map(move |tx| (tx * ts, ty * ts)))
        .map(|(x0, y0)| (x0, y0, ts.min(width - x0), ts.min(height - y0)))
        .collect();
    let prototype = settings.sampler.make(settings.spp.max(1), settings.seed);
    let terms = if integrator.has_terms() { settings.terms } else { 0 };
    if settings.terms > 0 && terms == 0 {
        return Err(RenderError::NoTerms { integrator: integrator.name() });
    }
    let scheduler = Scheduler::new(settings, cancel, width as u64 * height as u64, "samples")?;
    let aov_names = integrator.aov_names();
    let aov_count = aov_names.len();
    let (mut film, first_spp) = match start {
        Some((film, done)) => {
            if (film.width(), film.height()) != (width, height) || film.aov_names() != aov_names.as_slice() {
                return Err(RenderError::Resume(format!(
                    "the saved film is {}×{} with AOVs {:?}, this render {width}×{height} with {:?}",
                    film.width(),
                    film.height(),
                    film.aov_names(),
                    aov_names
                )));
            }
            if !(first_sample..=end_sample).contains(&done) {
                return Err(RenderError::Resume(format!(
                    "the saved film ends at sample {done}, outside this render's samples {first_sample}–{end_sample}"
                )));
            }
            (film, done)
        }
        None => {
            let film = Film::new(width, height).with_terms(terms).with_aovs(aov_names);
            (if settings.noise_threshold.is_some() { film.with_half() } else { film }, first_sample)
        }
    };
    let adaptive = settings.noise_threshold;
    if adaptive.is_some() && first_spp > first_sample {
        return Err(RenderError::Unsupported("adaptive sampling cannot continue a saved render".into()));
    }
    // Which pixels still take samples (adaptive sampling only); written between passes only.
    let pixels = if adaptive.is_some() { width as usize * height as usize } else { 0 };
    let active: Vec<AtomicBool> = (0..pixels).map(|_| AtomicBool::new(true)).collect();
    // Ray differentials where the integrator reads them, scaled to the spacing of the render's
    // samples (Mitsuba's 1/√spp).
    let differential_scale = integrator.wants_differentials().then(|| 1.0 / (settings.spp.max(1) as f32).sqrt());
    let motion = scene.motion_shutter().or(cam.motion_shutter());
    // Samples the integrator traces at once in SIMD lanes (0: one at a time). Not with the
    // Neumann-series terms, AOVs or ray differentials, which only the one-at-a-time entry fills.
    let lanes = if terms == 0 && aov_count == 0 && differential_scale.is_none() { integrator.lanes(scene) } else { 0 };
    let render_tile = |k: usize, first: u32, count: u32| {
        let (x0, y0, w, h) = tiles[k];
        let mut sampler = prototype.clone();
        let mut tile = (TileBuffer::for_tile(x0, y0, w, h, &settings.filter, [width, height]))
            .with_terms(terms)
            .with_aovs(aov_count)
            .with_half(adaptive.is_some());
        let mut sample_terms = vec![Rgb::ZERO; terms];
        let mut aovs = vec![0.0f32; aov_count];
        let mut taken = 0u64;
        // Paths in SIMD lanes: the tile's samples, pixel after pixel, traced `lanes` at a time
        // (a batch spans pixels, so that passes of few samples per pixel fill the lanes too),
        // each with its own sampler (a copy positioned after its camera draws), its camera ray,
        // film position and weight; each finished as below, in the same order.
        let mut lane_samplers = vec![prototype.clone(); lanes];
        let mut lane_rays = Vec::with_capacity(lanes);
        let mut lane_camera: Vec<([u32; 2], u32, Vec2, f32)> = Vec::with_capacity(lanes);
        let mut lane_out = vec![crate::integrator::RadianceSample { l: Rgb::ZERO, alpha: 0.0 }; lanes];
        let flush = |tile: &mut TileBuffer,
                     rays: &mut Vec<crate::math::Ray>,
                     camera: &mut Vec<([u32; 2], u32, Vec2, f32)>,
                     samplers: &mut [crate::sampling::Sampler],
                     out: &mut [crate::integrator::RadianceSample]| {
            let m = rays.len();
            integrator.sample_lanes(scene, rays, &mut samplers[..m], &mut out[..m]);
            for (&(at, i, u_film, ray_weight), &out) in camera.iter().zip(&out[..m]) {
                let mut s = if ray_weight == 0.0 { crate::integrator::RadianceSample { l: Rgb::ZERO, alpha: 0.0 } } else { out };
                if ray_weight != 1.0 {
                    s.l *= ray_weight;
                }
                let alpha = settings.alpha.then_some(s.alpha);
                let l = if settings.transform.is_identity() { s.l } else { settings.transform.apply(s.l) };
                let sample = FilmSample { l, alpha, terms: &[], aovs: &[], half: i % 2 == 1 };
                tile.put(at, u_film, &settings.filter, sample);
            }
            rays.clear();
            camera.clear();
        };
        for y in y0..y0 + h {
            for x in x0..x0 + w {
                if adaptive.is_some() && !active[(y * width + x) as usize].load(Ordering::Relaxed) {
                    continue;
                }
                taken += u64::from(count);
                // Seeded by the film pixel (those left of or above the film wrap around), so a
                // pixel's samples do not depend on whether the border is sampled.
                let pixel = [(x + rx).wrapping_sub(shift), (y + ry).wrapping_sub(shift)];
                let centre = Vec2::new((x + rx) as f32 + 0.5, (y + ry) as f32 + 0.5) - shift as f32;
                if lanes > 1 {
                    for i in first..first + count {
                        // Into the batch: the camera's draws and ray for the sample, as below.
                        sampler.start_pixel_sample(pixel, i, 0);
                        let u_film = sampler.next_2d();
                        let film_pos = centre + (u_film - Vec2::splat(0.5));
                        let u_lens = sampler.next_2d();
                        let (mut ray, ray_weight) = cam.sample_ray(film_pos, u_lens);
                        if let Some((open, close)) = motion {
                            ray = cam.ray_at_time(&ray, open + (close - open) * sampler.next_1d()).0;
                        }
                        lane_samplers[lane_rays.len()].clone_from(&sampler);
                        lane_rays.push(ray);
                        lane_camera.push(([x, y], i, u_film, ray_weight));
                        if lane_rays.len() == lanes {
                            flush(&mut tile, &mut lane_rays, &mut lane_camera, &mut lane_samplers, &mut lane_out);
                        }
                    }
                    continue;
                }
                for i in first..first + count {
                    sampler.start_pixel_sample(pixel, i, 0);
                    // Uniform over the pixel; the filter weighs the sample where it is splatted
                    // (Mitsuba 3's reconstruction).
                    let u_film = sampler.next_2d();
                    let film_pos = centre + (u_film - Vec2::splat(0.5));
                    let u_lens = sampler.next_2d();
                    // Bound in place (a move out of the returned pair was a copy by wide loads
                    // right after the camera wrote the ray field by field: a store-forwarding
                    // stall).
                    let sampled = cam.sample_ray(film_pos, u_lens);
                    let (start_ray, ray_weight) = (&sampled.0, sampled.1);
                    // Where shapes or the camera move, a time uniform over the shutter interval
                    // (one more dimension, drawn only then: static scenes' samples are
                    // unchanged), and the camera's ray moved to where the camera then is.
                    // (Borrowed, not copied: a copy right after the camera wrote the ray field by
                    // field would wait for those stores to reach the cache.)
                    let at_time;
                    let (ray, moved) = match motion {
                        Some((open, close)) => {
                            at_time = cam.ray_at_time(start_ray, open + (close - open) * sampler.next_1d());
                            (&at_time.0, at_time.1.as_ref())
                        }
                        None => (start_ray, None),
                    };
                    sample_terms.fill(Rgb::ZERO);
                    aovs.fill(0.0);
                    let mut s = if ray_weight == 0.0 {
                        // A realistic camera's lens stopped the ray: the sample sees nothing.
                        crate::integrator::RadianceSample { l: Rgb::ZERO, alpha: 0.0 }
                    } else {
                        let differentials = differential_scale.map(|scale| {
                            let d = cam.ray_differentials(film_pos, u_lens, start_ray);
                            moved.map_or(d, |m| d.moved(m)).scaled(ray, scale)
                        });
                        integrator.sample_aovs(
                            scene,
                            ray,
                            differentials.as_ref(),
                            &mut sampler,
                            &mut sample_terms,
                            &mut aovs,
                        )
                    };
                    if ray_weight != 1.0 {
                        // An irradiance meter's or a realistic camera's rays (the AOVs stay
                        // unweighted, as in Mitsuba).
                        s.l *= ray_weight;
                        sample_terms.iter_mut().for_each(|t| *t *= ray_weight);
                    }
                    let alpha = settings.alpha.then_some(s.alpha);
                    let l = if settings.transform.is_identity() {
                        s.l
                    } else {
                        sample_terms.iter_mut().for_each(|t| *t = settings.transform.apply_linear(*t));
                        settings.transform.apply(s.l)
                    };
                    let sample = FilmSample { l, alpha, terms: &sample_terms, aovs: &aovs, half: i % 2 == 1 };
                    tile.put([x, y], u_film, &settings.filter, sample);
                }
            }
        }
        if !lane_rays.is_empty() {
            flush(&mut tile, &mut lane_rays, &mut lane_camera, &mut lane_samplers, &mut lane_out);
        }
        (tile, taken)
    };
    let mut done = first_spp;
    // A part of a split render keeps whole passes only: its file says which samples it holds.
    let whole_passes_only = settings.sample_range.is_some();
    let passes = scheduler.run_from(first_spp, end_sample, 16, tiles.len(), render_tile, |results, count| {
        let complete = results.iter().all(Option::is_some);
        if complete || !whole_passes_only {
            for tile in results.iter().flatten() {
                film.merge(tile);
            }
        }
        if complete {
            done += count;
            after_pass(&film, done);
            if let Some(threshold) = adaptive {
                if done >= settings.min_spp.max(2) && !update_active(&film, threshold, &active) {
                    return ControlFlow::Break(());
                }
            }
        }
        ControlFlow::Continue(())
    });
    let [wx, wy, ww, wh] = window;
    let (wx, wy) = (wx + shift, wy + shift);
    if [rx, ry, width, height] != [wx, wy, ww, wh] {
        film = film.crop(wx - rx, wy - ry, ww, wh);
    }
    Ok(RenderOutcome { film, interrupted: passes.interrupted, elapsed: passes.elapsed, report: Vec::new() })
}

#[cfg(test)]
mod tests {
    /// Cycles' automatic minimum sample counts, as its source comments them.
    #[test]
    fn cycles_min_samples() {
        assert_eq!(super::auto_min_spp(0.1), 32);
        assert_eq!(super::auto_min_spp(0.01), 64);
        assert_eq!(super::auto_min_spp(0.001), 128);
        assert_eq!(super::auto_min_spp(1e6), 4);
        assert!(super::auto_min_spp(1e-30) > 1_000_000);
    }

    use super::*;
    use crate::integrator::PathIntegrator;
    use crate::scene::cornell::cornell_box;

    #[test]
    fn deterministic_across_thread_counts_and_tile_sizes() {
        let scene = cornell_box(24, 20).unwrap();
        let integrator = PathIntegrator::default();
        let never = AtomicBool::new(false);
        let mut images = Vec::new();
        for (threads, tile) in [(1, 16), (2, 16), (3, 5)] {
            let settings = RenderSettings { spp: 4, seed: 7, threads, tile_size: tile, ..Default::default() };
            let out = render(&scene, &integrator, &settings, &never).unwrap();
            assert_eq!(out.film.spp_range(), (4, 4));
            images.push(out.film.image());
        }
        assert!(images.iter().all(|im| *im == images[0]), "images differ between thread counts");
        let other_seed =
            render(&scene, &integrator, &RenderSettings { spp: 4, seed: 8, ..Default::default() }, &never).unwrap();
        assert_ne!(other_seed.film.image(), images[0]);
    }

    /// Alpha is the fraction of camera rays that hit something: 1 inside a sphere's image, 0
    /// outside, fractional on its silhouette.
    #[test]
    fn alpha_records_coverage() {
        use crate::camera::{Camera, FovAxis};
        use crate::geometry::{Geometry, Sphere};
        use crate::material::{Bsdf, Diffuse};
        use crate::math::{Rgb, Transform, Vec3};
        let mut b = crate::scene::SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0, false)), m, None);
        b.add_point_light(Vec3::ZERO, Rgb::ONE);
        b.set_camera(Camera::perspective(Transform::IDENTITY, 40.0, FovAxis::X, 9, 9).unwrap());
        let scene = b.build().unwrap();
        let settings = RenderSettings { spp: 64, alpha: true, ..Default::default() };
        let out = render(&scene, &PathIntegrator::default(), &settings, &AtomicBool::new(false)).unwrap();
        let alpha = out.film.alpha();
        assert_eq!(alpha[4 * 9 + 4], 1.0, "centre");
        assert_eq!(alpha[0], 0.0, "corner");
        assert!(alpha.iter().any(|&a| a > 0.0 && a < 1.0), "silhouette pixels are partly covered");
    }

    /// The Neumann-series terms: the total of a render that keeps them is bit-identical to a
    /// normal render with the same seed, the terms add up to it, `Lₑ` is the light seen directly,
    /// and a depth-limited render has no longer terms.
    #[test]
    fn neumann_terms_sum_to_the_render() {
        let scene = cornell_box(16, 16).unwrap();
        let integrator = PathIntegrator::with_max_depth(6);
        let never = AtomicBool::new(false);
        let plain =
            render(&scene, &integrator, &RenderSettings { spp: 8, seed: 4, ..Default::default() }, &never).unwrap();
        let settings = RenderSettings { spp: 8, seed: 4, terms: 6, ..Default::default() };
        let split = render(&scene, &integrator, &settings, &never).unwrap();
        assert!(split.film.image() == plain.film.image(), "total differs from the plain render");
        let total = split.film.image();
        let terms: Vec<Vec<crate::math::Rgb>> = (0..6).map(|k| split.film.term_image(k)).collect();
        for (i, t) in total.iter().enumerate() {
            let sum: crate::math::Rgb = terms.iter().map(|im| im[i]).sum();
            assert!((sum - *t).abs().max_element() <= 1e-5 * t.max_element().max(1.0), "pixel {i}: {sum} vs {t}");
        }
        // Lₑ: only the light's pixels (radiance (18.4, 14.0, 6.75)) are non-zero.
        let lit: Vec<usize> = (0..total.len()).filter(|&i| terms[0][i].max_element() > 0.0).collect();
        assert!(!lit.is_empty() && lit.len() < 16, "{} light pixels", lit.len());
        assert!(terms[1].iter().filter(|c| c.max_element() > 0.0).count() > total.len() / 2, "direct light");
        assert!(terms[2].iter().any(|c| c.max_element() > 0.0), "one bounce");
        let direct = PathIntegrator::with_max_depth(2);
        let two = render(&scene, &direct, &RenderSettings { spp: 4, terms: 4, ..Default::default() }, &never).unwrap();
        assert!((2..4).all(|k| two.film.term_image(k).iter().all(|c| *c == crate::math::Rgb::ZERO)));
        assert!(two.film.term_image(1).iter().any(|c| c.max_element() > 0.0));
    }

    #[test]
    fn cancellation_keeps_completed_work() {
        let scene = cornell_box(16, 16).unwrap();
        let cancelled = AtomicBool::new(true);
        let out =
            render(&scene, &PathIntegrator::default(), &RenderSettings { spp: 8, ..Default::default() }, &cancelled)
                .unwrap();
        assert!(out.interrupted);
        assert_eq!(out.film.total_samples(), 0);
    }

    /// A render stopped at a pass boundary, saved, read back and continued to a larger target is
    /// bit-identical to one that never stopped (the film's bytes, hence the image); a truncated
    /// or mismatched state is refused.
    #[test]
    fn resumed_renders_are_bit_identical() {
        use crate::film::state::StateInfo;
        let scene = crate::scene::cornell::cornell_box(20, 12).unwrap();
        let integrator = crate::integrator::PathIntegrator::default();
        let never = AtomicBool::new(false);
        let info = |spp_done| StateInfo { fingerprint: 42, spp_done, seed: 3 };
        let whole = render(&scene, &integrator, &RenderSettings { spp: 40, seed: 3, ..Default::default() }, &never).unwrap();
        let mut saved = None;
        render_from(&scene, &integrator, &RenderSettings { spp: 16, seed: 3, ..Default::default() }, &never, None, &mut |f, done| {
            saved = Some(f.state_bytes(&info(done)))
        })
        .unwrap();
        let bytes = saved.unwrap();
        let (film, read) = Film::from_state_bytes(&bytes).unwrap();
        assert_eq!(read, info(16));
        let resumed = render_from(
            &scene,
            &integrator,
            &RenderSettings { spp: 40, seed: 3, ..Default::default() },
            &never,
            Some((film, read.spp_done)),
            &mut |_, _| {},
        )
        .unwrap();
        assert_eq!(resumed.film.spp_range(), (40, 40));
        assert_eq!(resumed.film.state_bytes(&info(40)), whole.film.state_bytes(&info(40)), "bit-identical");
        for n in [0, 15, 40, bytes.len() - 1] {
            assert!(Film::from_state_bytes(&bytes[..n]).is_err(), "{n} bytes");
        }
        let other = crate::scene::cornell::cornell_box(8, 8).unwrap();
        let (film, _) = Film::from_state_bytes(&bytes).unwrap();
        let e = render_from(&other, &integrator, &RenderSettings { spp: 32, ..Default::default() }, &never, Some((film, 16)), &mut |_, _| {});
        assert!(matches!(e, Err(RenderError::Resume(_))));
    }

    /// The render loop's batches in SIMD lanes (spanning pixels and passes) give the film the
    /// one-sample-at-a-time loop gives, byte for byte: the Cornell box (constant diffuse BSDFs,
    /// which the path tracer traces in lanes) with a box and a Gaussian filter (splats over
    /// neighbours), with adaptive sampling (pixels that stop), one and two threads.
    #[test]
    fn lanes_render_the_film_of_one_sample_at_a_time() {
        use crate::film::state::StateInfo;
        use crate::integrator::PathIntegrator;
        /// The path tracer without its lanes.
        struct OneAtATime(PathIntegrator);
        impl Integrator for OneAtATime {
            fn name(&self) -> &'static str {
                "path, one sample at a time"
            }
            fn sample(&self, scene: &Scene, ray: &crate::math::Ray, sampler: &mut crate::sampling::Sampler, terms: &mut [Rgb]) -> crate::integrator::RadianceSample {
                self.0.sample(scene, ray, sampler, terms)
            }
        }
        let scene = crate::scene::cornell::cornell_box(23, 17).unwrap();
        let path = PathIntegrator::default();
        assert!(path.lane_support(&scene));
        let never = AtomicBool::new(false);
        let info = StateInfo { fingerprint: 1, spp_done: 0, seed: 0 };
        for settings in [
            RenderSettings { spp: 13, seed: 5, threads: 1, ..Default::default() },
            RenderSettings { spp: 24, seed: 6, threads: 2, tile_size: 8, filter: Filter::gaussian(0.5).unwrap(), ..Default::default() },
            RenderSettings { spp: 64, seed: 7, threads: 2, noise_threshold: Some(0.05), ..Default::default() },
        ] {
            let lanes = render(&scene, &path, &settings, &never).unwrap();
            let single = render(&scene, &OneAtATime(path.clone()), &settings, &never).unwrap();
            assert!(lanes.film.state_bytes(&info) == single.film.state_bytes(&info), "{settings:?}");
        }
    }

    /// Adaptive sampling: the less noisy pixels stop early, the noisy ones go on; a threshold every pixel meets ends the render at the minimum; the
    /// result does not depend on the thread count; without a threshold nothing changes.
    /// (Threshold 0.02: errors compared with 0.1, Cycles' factor 5. The 9×9 window keeps quiet pixels
    /// next to noisy ones going, so the pixels that take every sample are a mix: the pixels
    /// stopped early have under 0.6 of their mean noise; stopping at random would give 1.)
    #[test]
    fn adaptive_sampling_stops_converged_pixels() {
        let scene = cornell_box(64, 64).unwrap();
        let integrator = PathIntegrator::default();
        let never = AtomicBool::new(false);
        let settings = |threads, threshold| RenderSettings {
            spp: 128,
            seed: 4,
            threads,
            noise_threshold: Some(threshold),
            min_spp: 16,
            ..Default::default()
        };
        let a = render(&scene, &integrator, &settings(1, 0.02), &never).unwrap().film;
        let b = render(&scene, &integrator, &settings(2, 0.02), &never).unwrap().film;
        assert!(a.image() == b.image() && a.sample_counts() == b.sample_counts(), "deterministic");
        let counts = a.sample_counts();
        let (lo, hi) = a.spp_range();
        assert!(lo <= 32 && hi == 128, "some pixels stop early, some take every sample: {lo}..{hi}");
        let uniform = render(&scene, &integrator, &RenderSettings { spp: 128, seed: 4, ..Default::default() }, &never).unwrap().film;
        let emitted = uniform.image();
        // Samples go where the noise is: the pixels that stopped early are, by the uniform
        // render's own variance estimate, much less noisy (relative to √brightness, the rule's
        // measure) than those that took every sample.
        let var = uniform.variance_of_mean();
        let noise = |k: usize| (var[k].x + var[k].y + var[k].z).sqrt() / (1e-4 + (emitted[k].x + emitted[k].y + emitted[k].z).sqrt());
        let mean_noise = |pick: &dyn Fn(f32) -> bool| {
            let ks: Vec<usize> = (0..counts.len()).filter(|&k| pick(counts[k])).collect();
            ks.iter().map(|&k| noise(k)).sum::<f32>() / ks.len().max(1) as f32
        };
        let (early, full) = (mean_noise(&|c| c < 128.0), mean_noise(&|c| c == 128.0));
        assert!(early < 0.6 * full, "noise of pixels stopped early {early}, of the others {full}");
        assert!(counts.iter().filter(|&&c| c == 128.0).count() > counts.len() / 4, "noisy pixels go on");
        let all = render(&scene, &integrator, &settings(2, 1e9), &never).unwrap();
        assert_eq!(all.film.spp_range(), (16, 16), "every pixel converged: the render ends");
        assert!(!all.interrupted);
        // The errors: 0 for a pixel whose samples agree, and the even-sample image is the mean
        // of the even-numbered samples exactly.
        let mut tile = TileBuffer::new(0, 0, 2, 1).with_half(true);
        for i in 0..8u32 {
            let l = Rgb::splat(if i % 2 == 0 { 1.0 } else { 3.0 });
            tile.put([0, 0], Vec2::splat(0.5), &Filter::BOX, FilmSample { l, half: i % 2 == 1, ..Default::default() });
            tile.put([1, 0], Vec2::splat(0.5), &Filter::BOX, FilmSample { l: Rgb::ONE, half: i % 2 == 1, ..Default::default() });
        }
        let mut film = Film::new(2, 1).with_half();
        film.merge(&tile);
        let errors = film.adaptive_errors().unwrap();
        assert_eq!(errors[1], 0.0);
        assert!((errors[0] - 3.0 / (1e-4 + 6f32.sqrt())).abs() < 1e-4, "|2 - 3|·3 / √6: {}", errors[0]);
        assert_eq!(film.even_image().unwrap(), vec![Rgb::ONE, Rgb::ONE]);
        assert_eq!(film.image()[0], Rgb::splat(2.0));
        assert!(Film::new(1, 1).adaptive_errors().is_none());
    }

    /// One noisy pixel keeps exactly the pixels within `ADAPTIVE_RADIUS` of it sampling (a
    /// square window, cut at the film's edge); a pixel once stopped stays stopped.
    #[test]
    fn adaptive_window_around_a_noisy_pixel() {
        let (w, h) = (20u32, 14u32);
        let noisy_at = |film_x: u32, film_y: u32| {
            let mut tile = TileBuffer::new(0, 0, w, h).with_half(true);
            for y in 0..h {
                for x in 0..w {
                    for i in 0..8u32 {
                        let v = if (x, y) == (film_x, film_y) && i % 2 == 0 { 3.0 } else { 1.0 };
                        let s = FilmSample { l: Rgb::splat(v), half: i % 2 == 1, ..Default::default() };
                        tile.put([x, y], Vec2::splat(0.5), &Filter::BOX, s);
                    }
                }
            }
            let mut film = Film::new(w, h).with_half();
            film.merge(&tile);
            film
        };
        let r = ADAPTIVE_RADIUS as i64;
        for (cx, cy) in [(10u32, 7u32), (1, 12)] {
            let active: Vec<AtomicBool> = (0..w * h).map(|_| AtomicBool::new(true)).collect();
            assert!(update_active(&noisy_at(cx, cy), 0.01, &active));
            for y in 0..h {
                for x in 0..w {
                    let inside = (x as i64 - cx as i64).abs() <= r && (y as i64 - cy as i64).abs() <= r;
                    assert_eq!(active[(y * w + x) as usize].load(Ordering::Relaxed), inside, "({x}, {y}) around ({cx}, {cy})");
                }
            }
            // The noisy pixel moves: pixels already stopped stay stopped.
            assert!(update_active(&noisy_at(cx + 1, cy), 0.01, &active));
            let far = (cx as i64 + 1 + r) as u32;
            if far < w {
                assert!(!active[(cy * w + far) as usize].load(Ordering::Relaxed), "stopped pixels stay stopped");
            }
        }
    }

    #[test]
    fn time_budget_renders_whole_passes() {
        let scene = cornell_box(16, 16).unwrap();
        let settings =
            RenderSettings { spp: 1 << 20, time_budget: Some(Duration::from_millis(300)), ..Default::default() };
        let out = render(&scene, &PathIntegrator::default(), &settings, &AtomicBool::new(false)).unwrap();
        let (lo, hi) = out.film.spp_range();
        assert!(lo >= 1 && lo == hi, "whole passes only: {lo}..{hi}");
        assert!(out.elapsed < Duration::from_millis(1500), "{:?}", out.elapsed);
    }

    /// `sample_border`: with a box filter nothing outside the image is within reach (the same
    /// image); with a Gaussian of border 2 the pixels within 2 of the film's edge gather the
    /// samples taken outside, the others keep their values (their samples are seeded by film
    /// pixel), and a crop window gathers its neighbours' samples as the uncropped render does.
    #[test]
    fn sample_border_samples_outside_the_image() {
        let scene = cornell_box(24, 20).unwrap();
        let never = AtomicBool::new(false);
        let run = |settings: RenderSettings| render(&scene, &PathIntegrator::default(), &settings, &never).unwrap();
        let base = RenderSettings { spp: 4, seed: 3, ..Default::default() };
        let image = |s: RenderSettings| run(s).film.image();
        assert_eq!(image(base.clone()), image(RenderSettings { sample_border: true, ..base.clone() }));
        let gauss = RenderSettings { filter: Filter::gaussian(0.5).unwrap(), ..base };
        assert_eq!(gauss.filter.border(), 2);
        let (plain, border) = (image(gauss.clone()), image(RenderSettings { sample_border: true, ..gauss.clone() }));
        assert_eq!(border.len(), 24 * 20);
        let close = |a: Rgb, b: Rgb| (a - b).abs().max_element() <= 1e-5 * a.abs().max_element().max(1e-3);
        let (mut edge, mut changed) = (0, 0);
        for y in 0..20 {
            for x in 0..24 {
                let (p, q) = (plain[y * 24 + x], border[y * 24 + x]);
                if x < 2 || y < 2 || x >= 22 || y >= 18 {
                    edge += 1;
                    changed += usize::from(!close(p, q));
                } else {
                    assert!(close(p, q), "pixel ({x}, {y}) {p} vs {q}");
                }
            }
        }
        // (Some edge pixels see only the black opening of the box, with or without.)
        assert!(changed * 10 >= edge * 7, "{changed} of {edge} edge pixels changed");
        // A crop window with its border (reaching outside the film on the left): the whole
        // bordered render's pixels there (up to the order of the sums).
        let crop = image(RenderSettings { window: Some([1, 3, 9, 7]), sample_border: true, ..gauss.clone() });
        let whole = image(RenderSettings { sample_border: true, ..gauss });
        for y in 0..7 {
            for x in 0..9 {
                let (p, q) = (crop[y * 9 + x], whole[(y + 3) * 24 + x + 1]);
                assert!(close(p, q), "({x}, {y}) {p} vs {q}");
            }
        }
    }

    /// Render errors are typed and say what is wrong.
    #[test]
    fn errors_are_typed() {
        let scene = cornell_box(8, 8).unwrap();
        let never = AtomicBool::new(false);
        let settings = RenderSettings { window: Some([4, 4, 8, 8]), ..Default::default() };
        let e = render(&scene, &PathIntegrator::default(), &settings, &never).unwrap_err();
        assert!(matches!(e, RenderError::CropWindow { film_width: 8, x: 4, .. }), "{e:?}");
        assert!(e.to_string().contains("does not fit in the 8x8 film"), "{e}");
        let direct = crate::integrator::DirectIntegrator::default();
        let e = render(&scene, &direct, &RenderSettings { terms: 3, ..Default::default() }, &never).unwrap_err();
        assert!(matches!(e, RenderError::NoTerms { integrator: "direct" }), "{e:?}");
    }
}
