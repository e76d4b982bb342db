//! The film: per-pixel accumulation of radiance samples through the reconstruction filter,
//! with a guard that drops non-finite samples, and image output ([`output`]).
//!
//! Reconstruction is Mitsuba 3's weighted splatting (its `ImageBlock::put`): a sample taken at
//! film position `x` (uniform over its pixel) adds `f(c − x) L` and `f(c − x)` to every pixel
//! whose centre `c` lies within the filter's radius, and the pixel's value is the ratio
//! `Σ f L / Σ f`. With the box filter this is the plain average of the pixel's own samples; with
//! a wider filter (Mitsuba's default Gaussian) each pixel averages the samples of its
//! neighbourhood, which lowers per-pixel variance several-fold on small bright features compared
//! with filter importance sampling (each sample in one pixel), at the same expected image.
//!
//! Sums are kept in `f64` so that millions of samples per pixel lose nothing to round-off. Each
//! tile accumulates its samples (into its pixels and a border of the filter's radius) in
//! sample-index order and tiles are merged in a fixed order, so images are bit-identical for a
//! given seed and tile size whatever the number of threads.
//!
//! Variance: the pixel value `R = Σ wᵢ Lᵢ / Σ wᵢ` is a weighted mean; its variance is estimated as
//! the weighted sample variance divided by Kish's effective sample count
//! `n_eff = (Σ w)² / Σ w²`: `Var R ≈ (Σ w L² / Σ w − R²) · n_eff / (n_eff − 1) / n_eff` (for unit
//! weights exactly `s² / n`).

#[cfg(feature = "oidn")]
pub mod denoise;
pub mod filter;
pub mod metrics;
pub mod output;
pub mod part;
pub mod sensor;
pub mod sensor_data;
pub mod state;
pub mod tev;

use crate::math::{Rgb, Vec2};
use crate::props::{Obj, Result as PropResult, SceneError};
use filter::Filter;

/// One pixel's filter-weighted sums (f64), kept together so that a splat touches one cache
/// line or two per pixel. The radiance sums and the weight sum form one group of four, their
/// squares another, so that a splat adds each group with one SIMD operation (two of SSE2).
#[derive(Clone, Copy, Debug, Default)]
struct Acc {
    /// `(Σ w L_r, Σ w L_g, Σ w L_b, Σ w)`.
    sum: [f64; 4],
    /// `(Σ w L_r², Σ w L_g², Σ w L_b², Σ w²)`.
    wl2: [f64; 4],
    /// `Σ w a` (coverage).
    alpha: f64,
}

impl Acc {
    /// `Σ w`.
    #[inline(always)]
    fn w(&self) -> f64 {
        self.sum[3]
    }

    /// `Σ w²`.
    #[inline(always)]
    fn w2(&self) -> f64 {
        self.wl2[3]
    }

    /// Adds a sample with filter weight `w`: `x = (L, 1)` is its radiance with a 1 for the
    /// weight sum, `alpha` its coverage. The same products and sums as channel by channel
    /// (`w·1 = w` exactly), in lanes.
    #[inline(always)]
    fn add(&mut self, w: f64, x: [f64; 4], alpha: Option<f64>) {
        let wx = x.map(|v| w * v);
        let y = [x[0], x[1], x[2], w];
        for k in 0..4 {
            self.sum[k] += wx[k];
            self.wl2[k] += wx[k] * y[k];
        }
        if let Some(alpha) = alpha {
            self.alpha += w * alpha;
        }
    }
}

/// A sample prepared for [`Pixels::put`] (by [`Pixels::splat`]): radiance and coverage in
/// f64, and whether the half buffer, terms or AOVs take it too.
struct Splat<'a> {
    /// The radiance, and a 1 (the weight sum's factor; see [`Acc::add`]).
    l: [f64; 4],
    alpha: Option<f64>,
    /// The half buffer is kept and takes this sample.
    half: bool,
    terms: &'a [Rgb],
    aovs: &'a [f32],
    /// Anything beyond radiance and coverage is recorded (half buffer, terms or AOVs).
    extra: bool,
}

/// Per-pixel sums shared by tiles and the film: weighted radiance and the sums its variance
/// needs, sample counts and, optionally, the Neumann-series terms.
#[derive(Clone, Debug)]
struct Pixels {
    acc: Vec<Acc>,
    /// Samples taken inside the pixel.
    count: Vec<u32>,
    /// `term_count` sums `Σ w T` per pixel.
    terms: Vec<[f64; 3]>,
    term_count: usize,
    /// `aov_count` sums `Σ w v` per pixel (arbitrary output variables: named channels).
    aovs: Vec<f64>,
    aov_count: usize,
    /// Adaptive sampling's half buffer: `Σ w L` and `Σ w` of the odd-numbered samples only
    /// (empty unless kept).
    half: Vec<[f64; 4]>,
    dropped: u64,
}

impl Pixels {
    fn new(n: usize) -> Pixels {
        Pixels {
            acc: vec![Acc::default(); n],
            count: vec![0; n],
            terms: Vec::new(),
            term_count: 0,
            aovs: Vec::new(),
            aov_count: 0,
            half: Vec::new(),
            dropped: 0,
        }
    }

    fn keep_half(&mut self) {
        self.half = vec![[0.0; 4]; self.count.len()];
    }

    fn keep_aovs(&mut self, count: usize) {
        self.aovs = vec![0.0; self.count.len() * count];
        self.aov_count = count;
    }

    fn keep_terms(&mut self, count: usize) {
        self.terms = vec![[0.0; 3]; self.count.len() * count];
        self.term_count = count;
    }

    /// `sample` as the pixel sums take it: converted and checked once, for every pixel of its
    /// footprint.
    fn splat<'a>(&self, sample: &FilmSample<'a>) -> Splat<'a> {
        let half = sample.half && !self.half.is_empty();
        Splat {
            l: [f64::from(sample.l.x), f64::from(sample.l.y), f64::from(sample.l.z), 1.0],
            alpha: sample.alpha.map(f64::from),
            half,
            terms: sample.terms,
            aovs: sample.aovs,
            extra: half || self.term_count > 0 || self.aov_count > 0,
        }
    }

    /// Adds `w L` (and `w a`, `w T`, `w v`) to pixel `i`, and to its half buffer if `half`.
    #[inline(always)]
    fn put(&mut self, i: usize, w: f64, s: &Splat) {
        self.acc[i].add(w, s.l, s.alpha);
        if s.extra {
            self.put_extra(i, w, s);
        }
    }

    /// Adds `s` to every pixel of its footprint through `filter` (a sample at `origin + offset`
    /// in a buffer of `size` pixels; see [`Filter::footprint`]). Without a half buffer, terms
    /// or AOVs to take it, the loop adds radiance and coverage alone.
    #[inline(always)]
    fn splat_footprint(&mut self, filter: &Filter, origin: [i64; 2], offset: Vec2, size: [i64; 2], s: &Splat) {
        let hi = [size[0] - 1, size[1] - 1];
        if s.extra {
            filter.footprint(origin, offset, [0, 0], hi, |x, y, w| self.put((y * size[0] + x) as usize, w as f64, s));
        } else {
            let acc = &mut self.acc;
            filter.footprint_rows(origin, offset, [0, 0], hi, |x0, y, wy, wx| {
                let start = (y * size[0] + x0) as usize;
                for (a, &wx) in acc[start..start + wx.len()].iter_mut().zip(wx) {
                    let w = wy * wx;
                    if w != 0.0 {
                        a.add(w as f64, s.l, s.alpha);
                    }
                }
            });
        }
    }

    /// [`Pixels::splat_footprint`] compiled for AVX: each group of four sums of
    /// [`Acc::add`] in one register. Safety: the CPU must have AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn splat_footprint_avx(
        &mut self,
        filter: &Filter,
        origin: [i64; 2],
        offset: Vec2,
        size: [i64; 2],
        s: &Splat,
    ) {
        self.splat_footprint(filter, origin, offset, size, s)
    }

    /// The half buffer's, the terms' and the AOVs' part of [`Pixels::put`].
    fn put_extra(&mut self, i: usize, w: f64, s: &Splat) {
        if s.half {
            let h = &mut self.half[i];
            // (L, 1): the weight sum in h[3] (w·1 = w exactly).
            for (h, l) in h.iter_mut().zip(s.l) {
                *h += w * l;
            }
        }
        if self.term_count > 0 {
            let base = i * self.term_count;
            for (k, t) in s.terms.iter().take(self.term_count).enumerate() {
                for c in 0..3 {
                    self.terms[base + k][c] += w * t[c] as f64;
                }
            }
        }
        if self.aov_count > 0 {
            let out = &mut self.aovs[i * self.aov_count..(i + 1) * self.aov_count];
            for (o, &v) in out.iter_mut().zip(s.aovs) {
                // A non-finite value is dropped alone (counted as 0), not the whole sample.
                if v.is_finite() {
                    *o += w * v as f64;
                }
            }
        }
    }

    /// Adds pixel `j` of `other` to pixel `i`.
    fn add_from(&mut self, i: usize, other: &Pixels, j: usize) {
        let (a, b) = (&mut self.acc[i], &other.acc[j]);
        for c in 0..4 {
            a.sum[c] += b.sum[c];
            a.wl2[c] += b.wl2[c];
        }
        a.alpha += b.alpha;
        self.count[i] += other.count[j];
        if !self.half.is_empty() && !other.half.is_empty() {
            for c in 0..4 {
                self.half[i][c] += other.half[j][c];
            }
        }
        for k in 0..self.term_count.min(other.term_count) {
            let (a, b) = (i * self.term_count + k, j * other.term_count + k);
            for c in 0..3 {
                self.terms[a][c] += other.terms[b][c];
            }
        }
        for k in 0..self.aov_count.min(other.aov_count) {
            self.aovs[i * self.aov_count + k] += other.aovs[j * other.aov_count + k];
        }
    }
}

/// Accumulated samples of a rectangle of pixels: a tile and the border its samples' filter
/// footprints reach into, clipped to the image.
#[derive(Clone, Debug)]
pub struct TileBuffer {
    /// Left column of the buffer (image coordinates).
    pub x0: u32,
    /// Top row of the buffer.
    pub y0: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    px: Pixels,
}

/// Samples accepted by [`TileBuffer::put`]: the radiance, its coverage, its terms and its AOVs.
#[derive(Clone, Copy, Debug, Default)]
pub struct FilmSample<'a> {
    /// Radiance (W m⁻² sr⁻¹ per channel).
    pub l: Rgb,
    /// Coverage (1: the camera ray hit a surface), if recorded.
    pub alpha: Option<f32>,
    /// Neumann-series terms (empty if not recorded).
    pub terms: &'a [Rgb],
    /// Values of the arbitrary output variables, one per channel of
    /// [`Film::with_aovs`] (empty if none are kept).
    pub aovs: &'a [f32],
    /// Whether the sample also goes into the half buffer of adaptive sampling (the
    /// odd-numbered samples of each pixel).
    pub half: bool,
}

impl TileBuffer {
    /// An empty buffer of the pixels `[x0, x0 + width) × [y0, y0 + height)`.
    pub fn new(x0: u32, y0: u32, width: u32, height: u32) -> TileBuffer {
        TileBuffer { x0, y0, width, height, px: Pixels::new((width * height) as usize) }
    }

    /// An empty buffer for the tile `[x0, x0 + width) × [y0, y0 + height)` of an image of
    /// `image_size` pixels, with the border that `filter`'s footprint reaches from samples inside
    /// the tile.
    pub fn for_tile(x0: u32, y0: u32, width: u32, height: u32, filter: &Filter, image_size: [u32; 2]) -> TileBuffer {
        let b = filter.border();
        let (bx0, by0) = (x0.saturating_sub(b), y0.saturating_sub(b));
        let bx1 = (x0 + width).saturating_add(b).min(image_size[0]);
        let by1 = (y0 + height).saturating_add(b).min(image_size[1]);
        TileBuffer::new(bx0, by0, bx1 - bx0, by1 - by0)
    }

    /// The same buffer keeping `count` Neumann-series terms per pixel.
    pub fn with_terms(mut self, count: usize) -> TileBuffer {
        self.px.keep_terms(count);
        self
    }

    /// The same buffer keeping `count` AOV channels per pixel.
    pub fn with_aovs(mut self, count: usize) -> TileBuffer {
        self.px.keep_aovs(count);
        self
    }

    /// The same buffer keeping adaptive sampling's half buffer (if `keep`).
    pub fn with_half(mut self, keep: bool) -> TileBuffer {
        if keep {
            self.px.keep_half();
        }
        self
    }

    /// Adds a sample taken in pixel `pixel` (image coordinates, a pixel of this buffer) at
    /// `offset ∈ [0, 1)²` from the pixel's corner, through `filter`: Mitsuba's weighted splat
    /// over the pixels whose centres lie within the filter's radius, clipped to the buffer.
    /// Samples with a NaN or infinite radiance component are dropped and counted instead (they
    /// count toward their pixel's samples, so a pixel's sample count stays the number of samples
    /// taken in it).
    #[inline]
    pub fn put(&mut self, pixel: [u32; 2], offset: Vec2, filter: &Filter, sample: FilmSample) {
        self.put_with(crate::math::simd::Avx::detect().is_some(), pixel, offset, filter, sample)
    }

    /// [`TileBuffer::put`], its footprint splatted by the AVX loop if `avx` (which the CPU must
    /// then have) or by the portable one.
    #[inline(always)]
    #[cfg_attr(not(target_arch = "x86_64"), allow(unused_variables))]
    fn put_with(&mut self, avx: bool, pixel: [u32; 2], offset: Vec2, filter: &Filter, sample: FilmSample) {
        let (lx, ly) = ((pixel[0] - self.x0) as i64, (pixel[1] - self.y0) as i64);
        let own = ly as usize * self.width as usize + lx as usize;
        self.px.count[own] += 1;
        if !sample.l.is_finite() {
            self.px.dropped += 1;
            return;
        }
        let terms = if sample.terms.iter().all(|t| t.is_finite()) { sample.terms } else { &[] };
        // Converted and checked once for the whole footprint.
        let splat = self.px.splat(&FilmSample { terms, ..sample });
        if filter.is_pixel_box() {
            self.px.put(own, 1.0, &splat);
            return;
        }
        let (origin, width, height) = ([lx, ly], self.width as i64, self.height as i64);
        #[cfg(target_arch = "x86_64")]
        if avx {
            // SAFETY: the caller checked that this CPU has AVX.
            return unsafe { self.px.splat_footprint_avx(filter, origin, offset, [width, height], &splat) };
        }
        self.px.splat_footprint(filter, origin, offset, [width, height], &splat);
    }

    /// Adds a radiance sample with unit weight to pixel `(x, y)` alone (image coordinates,
    /// inside the buffer). Samples with a NaN or infinite component are dropped and counted.
    #[inline]
    pub fn add(&mut self, x: u32, y: u32, l: Rgb) {
        self.put([x, y], Vec2::splat(0.5), &Filter::BOX, FilmSample { l, ..Default::default() });
    }

    /// Non-finite samples dropped so far.
    pub fn dropped(&self) -> u64 {
        self.px.dropped
    }
}

/// The whole image's accumulated samples.
#[derive(Clone, Debug)]
pub struct Film {
    width: u32,
    height: u32,
    px: Pixels,
    aov_names: Vec<String>,
}

impl Film {
    /// Bytes a film needs per pixel with `terms` Neumann-series terms and `aovs` AOV channels:
    /// its accumulators, and the images made from it for writing.
    pub fn bytes_per_pixel(terms: usize, aovs: usize) -> u64 {
        (size_of::<Acc>() + size_of::<u32>() + 24 * terms + 8 * aovs) as u64 + 16 * (1 + terms as u64) + 4 * aovs as u64
    }

    /// An empty `width × height` film.
    pub fn new(width: u32, height: u32) -> Film {
        Film { width, height, px: Pixels::new((width as usize) * (height as usize)), aov_names: Vec::new() }
    }

    /// The same film keeping one AOV channel per name (the integrator's
    /// [`aov_names`](crate::integrator::Integrator::aov_names), in the order its samples give
    /// the values).
    pub fn with_aovs(mut self, names: Vec<String>) -> Film {
        self.px.keep_aovs(names.len());
        self.aov_names = names;
        self
    }

    /// The AOV channels: each name with its image (filter-weighted mean per pixel, like the
    /// radiance; 0 where no sample reached), row-major from the top-left.
    pub fn aov_channels(&self) -> Vec<output::Channel> {
        let n = self.px.aov_count;
        self.aov_names
            .iter()
            .enumerate()
            .map(|(k, name)| {
                let values = (self.px.acc.iter().enumerate())
                    .map(|(i, a)| if a.w() > 0.0 { (self.px.aovs[i * n + k] / a.w()) as f32 } else { 0.0 })
                    .map(|v| if v.is_finite() { v } else { 0.0 })
                    .collect();
                (name.clone(), values)
            })
            .collect()
    }

    /// The same film keeping adaptive sampling's half buffer (the odd-numbered samples' sums).
    pub fn with_half(mut self) -> Film {
        self.px.keep_half();
        self
    }

    /// Adaptive sampling's error estimate per pixel (Cycles' rule): with `I` the pixel's mean
    /// over all its samples and `A` the mean over its odd-numbered samples only,
    /// `|I − A|₁ / (10⁻⁴ + √(I_r + I_g + I_b))` — the difference between the estimate and an
    /// estimate from half of its samples, relative to the square root of the brightness (noise
    /// is judged as the eye sees it in dark and bright regions). `None` without a half buffer;
    /// infinite where the half holds no weight yet.
    pub fn adaptive_errors(&self) -> Option<Vec<f32>> {
        if self.px.half.is_empty() {
            return None;
        }
        let err = |(a, h): (&Acc, &[f64; 4])| {
            if a.w() <= 0.0 || h[3] <= 0.0 {
                return f32::INFINITY;
            }
            let i = [a.sum[0] / a.w(), a.sum[1] / a.w(), a.sum[2] / a.w()];
            let diff: f64 = (0..3).map(|c| (i[c] - h[c] / h[3]).abs()).sum();
            let norm = (i[0] + i[1] + i[2]).max(0.0).sqrt();
            (diff / (1e-4 + norm)) as f32
        };
        Some(self.px.acc.iter().zip(&self.px.half).map(err).collect())
    }

    /// The pixel estimates from the even-numbered samples alone (`(Σ w L − Σ_odd w L) / (Σ w −
    /// Σ_odd w)`), which adaptive sampling's stopping rule does not look at: unbiased whatever
    /// the rule decided. `None` without a half buffer.
    pub fn even_image(&self) -> Option<Vec<Rgb>> {
        if self.px.half.is_empty() {
            return None;
        }
        let px = self.px.acc.iter().zip(&self.px.half).map(|(a, h)| {
            let w = a.w() - h[3];
            if w <= 1e-12 * a.w().max(1e-300) {
                return Rgb::ZERO;
            }
            let c = Rgb::new(((a.sum[0] - h[0]) / w) as f32, ((a.sum[1] - h[1]) / w) as f32, ((a.sum[2] - h[2]) / w) as f32);
            if c.is_finite() {
                c.max(Rgb::ZERO)
            } else {
                Rgb::ZERO
            }
        });
        Some(px.collect())
    }

    /// The same film keeping `count` Neumann-series terms per pixel.
    pub fn with_terms(mut self, count: usize) -> Film {
        self.px.keep_terms(count);
        self
    }

    /// Number of Neumann-series terms kept.
    pub fn term_count(&self) -> usize {
        self.px.term_count
    }

    /// The image of term `k` (0-based: `Tᵏ Lₑ`), averaged over each pixel's samples.
    pub fn term_image(&self, k: usize) -> Vec<Rgb> {
        assert!(k < self.px.term_count, "term {k} of {}", self.px.term_count);
        self.px
            .acc
            .iter()
            .enumerate()
            .map(|(i, a)| {
                let w = a.w();
                let s = self.px.terms[i * self.px.term_count + k];
                if w > 0.0 {
                    Rgb::new(s[0] as f32, s[1] as f32, s[2] as f32) / w as f32
                } else {
                    Rgb::ZERO
                }
            })
            .collect()
    }

    /// The names of the AOV channels the film keeps.
    pub fn aov_names(&self) -> &[String] {
        &self.aov_names
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The sub-rectangle `[x, x + width) × [y, y + height)` of this film (which it must lie in),
    /// with all its sums.
    pub fn crop(&self, x: u32, y: u32, width: u32, height: u32) -> Film {
        assert!(x + width <= self.width && y + height <= self.height, "crop outside the film");
        let mut out = Film::new(width, height).with_terms(self.px.term_count).with_aovs(self.aov_names.clone());
        for ty in 0..height {
            for tx in 0..width {
                let i = ((y + ty) * self.width + x + tx) as usize;
                out.px.add_from((ty * width + tx) as usize, &self.px, i);
            }
        }
        out.px.dropped = self.px.dropped;
        out
    }

    /// Adds a tile's samples (its border included).
    pub fn merge(&mut self, tile: &TileBuffer) {
        for ty in 0..tile.height {
            for tx in 0..tile.width {
                let ti = (ty * tile.width + tx) as usize;
                let fi = ((tile.y0 + ty) * self.width + tile.x0 + tx) as usize;
                self.px.add_from(fi, &tile.px, ti);
            }
        }
        self.px.dropped += tile.px.dropped;
    }

    /// Adds one sample to every pixel: a whole image (row-major, this film's size), as the
    /// light tracer produces per pass. Counts `dropped` non-finite splats left out of it.
    pub fn add_pass(&mut self, image: &[[f64; 3]], dropped: u64) {
        assert_eq!(image.len(), self.px.acc.len(), "pass image size");
        for (i, v) in image.iter().enumerate() {
            let a = &mut self.px.acc[i];
            for (c, x) in v.iter().enumerate() {
                a.sum[c] += x;
                a.wl2[c] += x * x;
            }
            a.sum[3] += 1.0;
            a.wl2[3] += 1.0;
            self.px.count[i] += 1;
        }
        self.px.dropped += dropped;
    }

    /// Non-finite samples dropped.
    pub fn dropped(&self) -> u64 {
        self.px.dropped
    }

    /// Smallest and largest number of samples over the pixels.
    pub fn spp_range(&self) -> (u32, u32) {
        let min = self.px.count.iter().copied().min().unwrap_or(0);
        let max = self.px.count.iter().copied().max().unwrap_or(0);
        (min, max)
    }

    /// Samples per pixel, row-major from the top-left (they differ only in an interrupted
    /// render).
    pub fn sample_counts(&self) -> Vec<f32> {
        self.px.count.iter().map(|&c| c as f32).collect()
    }

    /// Total samples accumulated.
    pub fn total_samples(&self) -> u64 {
        self.px.count.iter().map(|&c| c as u64).sum()
    }

    /// The pixel estimates (filter-weighted mean radiance `Σ w L / Σ w` per pixel; 0 where no
    /// sample reached), row-major from the top-left.
    pub fn image(&self) -> Vec<Rgb> {
        self.px
            .acc
            .iter()
            .map(|a| (&a.sum, a.w()))
            .map(|(s, w)| if w > 0.0 { Rgb::new(s[0] as f32, s[1] as f32, s[2] as f32) / w as f32 } else { Rgb::ZERO })
            .map(|c| if c.is_finite() { c } else { Rgb::ZERO })
            .collect()
    }

    /// Per-pixel coverage (alpha): the fraction of the pixel's samples whose camera ray hit a
    /// surface, if the renderer recorded it (0 otherwise).
    pub fn alpha(&self) -> Vec<f32> {
        self.px.acc.iter().map(|a| if a.w() > 0.0 { (a.alpha / a.w()) as f32 } else { 0.0 }).collect()
    }

    /// Mean over all pixels and channels of the image, and the standard error of that mean
    /// from the per-pixel variances. The channels of one pixel are correlated, so the variance
    /// of their sum is bounded by `(σ_r + σ_g + σ_b)²` (exact when they move together).
    pub fn mean_and_std_error(&self) -> (f64, f64) {
        let img = self.image();
        let var = self.variance_of_mean();
        let n = (img.len() * 3) as f64;
        let mean = img.iter().map(|c| (c.x + c.y + c.z) as f64).sum::<f64>() / n;
        let v = var.iter().map(|c| (c.x.sqrt() + c.y.sqrt() + c.z.sqrt()).powi(2) as f64).sum::<f64>() / (n * n);
        (mean, v.sqrt())
    }

    /// Estimated variance of each pixel's estimate per channel: for `R = Σ w L / Σ w`, the
    /// weighted sample variance `Σ w L² / Σ w − R²` times `1 / (n_eff − 1)`,
    /// `n_eff = (Σ w)² / Σ w²` (module docs); with unit weights exactly `s² / n`. 0 where fewer than about two
    /// samples' worth of weight reached the pixel (`n_eff < 1.5`).
    pub fn variance_of_mean(&self) -> Vec<Rgb> {
        self.px
            .acc
            .iter()
            .map(|a| {
                let (w, w2) = (a.w(), a.w2());
                if w <= 0.0 || w2 <= 0.0 {
                    return Rgb::ZERO;
                }
                let n_eff = w * w / w2;
                if n_eff < 1.5 {
                    return Rgb::ZERO;
                }
                let v = |c: usize| {
                    let r = a.sum[c] / w;
                    ((a.wl2[c] / w - r * r).max(0.0) / (n_eff - 1.0)) as f32
                };
                Rgb::new(v(0), v(1), v(2))
            })
            .collect()
    }
}

/// What a film asks for: its size, the crop window, the alpha channel and the reconstruction
/// filter.
#[derive(Clone, Debug, PartialEq)]
pub struct FilmSettings {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Crop window `[x, y, width, height]`, if any.
    pub window: Option<[u32; 4]>,
    /// Whether an alpha channel is written (`pixel_format` `rgba`, `luminance_alpha`, `xyza`).
    pub alpha: bool,
    /// What the colour channels hold (`pixel_format` `rgb`, `luminance` or `xyz`, with or
    /// without alpha).
    pub colors: output::ColorChannels,
    /// The number type of a written EXR's channels (`component_format`).
    pub component: output::ComponentFormat,
    /// Reconstruction filter.
    pub filter: Filter,
    /// What each sample becomes before the film (white balance, clamp).
    pub transform: sensor::SampleTransform,
    /// Mitsuba's `sample_border`: the pixels within the filter's reach outside the film (or
    /// crop window) are sampled too, their samples splatted into the edge pixels.
    pub sample_border: bool,
}

impl Default for FilmSettings {
    /// Mitsuba's defaults: 768 × 576, RGB, Gaussian filter (σ = 0.5).
    fn default() -> Self {
        FilmSettings {
            width: 768,
            height: 576,
            window: None,
            alpha: false,
            colors: output::ColorChannels::Rgb,
            component: output::ComponentFormat::Float32,
            filter: Filter::gaussian(0.5).unwrap(),
            transform: sensor::SampleTransform::default(),
            sample_border: false,
        }
    }
}

impl FilmSettings {
    /// Mitsuba's `hdrfilm`: `width` (768) and `height` (576) (1 to 16384 each, at most 2²⁶
    /// pixels), `crop_offset_x/y`, `crop_width/height`, `pixel_format` (`rgb`, `rgba`,
    /// `luminance`, `luminance_alpha`, `xyz`, `xyza`: see [`output::ColorChannels`]), one
    /// nested `<rfilter>`; `component_format` (`float32`, `float16`, `uint32`: an EXR's number
    /// type, see [`output::ComponentFormat`]), `file_format` (`openexr`, `rgbe`, `pfm`, `png`),
    /// `sample_border` (false; true: the pixels outside the film or crop window within the
    /// filter's reach are sampled too, as Mitsuba samples them); `banner` and `compensate` are
    /// read (they cannot change the image: the output format follows the output file's
    /// extension, and the sums are f64); neumann's `sensor` (`cie1931`, or one of pbrt-v4's
    /// measured cameras, [`sensor::camera_names`]), `white_balance` (K; 0: none, the default
    /// of `cie1931`; 6500 for a camera; pbrt-v4's `whitebalance`, see [`sensor`]) and
    /// `max_component` (∞: pbrt-v4's `maxcomponentvalue`), measured in the output RGB or, with
    /// `max_component_of` `sensor`, in pbrt-v4's sensor RGB (XYZ, or a camera's raw RGB).
    pub fn from_props(f: &Obj) -> PropResult<FilmSettings> {
        f.built.set(true);
        f.check_children(&["rfilter"])?;
        if f.ty != "hdrfilm" {
            return Err(f.unknown_plugin(&["hdrfilm"]));
        }
        let dim = |name: &str, default: i64| -> PropResult<u32> {
            let v = f.int(name, default)?;
            if (1..=16384).contains(&v) {
                Ok(v as u32)
            } else {
                Err(f.error_at(name, format!("'{name}' must be between 1 and 16384, got {v}")))
            }
        };
        let width = dim("width", 768)?;
        let height = dim("height", 576)?;
        if (width as u64) * (height as u64) > 1 << 26 {
            return Err(f.error(format!("film {width}x{height} is too large (at most 67 million pixels)")));
        }
        let format = f.choice("pixel_format", &["rgb", "rgba", "luminance", "luminance_alpha", "xyz", "xyza"])?;
        let alpha = format.ends_with('a');
        let colors = match format.as_str() {
            "luminance" | "luminance_alpha" => output::ColorChannels::Luminance,
            "xyz" | "xyza" => output::ColorChannels::Xyz,
            _ => output::ColorChannels::Rgb,
        };
        let component = match f.string_opt("component_format")? {
            Some(v) => v.parse::<output::ComponentFormat>().map_err(|e| f.error_at("component_format", e))?,
            None => output::ComponentFormat::Float32,
        };
        f.choice("file_format", &["openexr", "rgbe", "pfm", "png"])?;
        let sample_border = f.bool("sample_border", false)?;
        f.bool("banner", true)?;
        // Mitsuba's Kahan-compensated accumulation in single precision: neumann sums in f64.
        f.bool("compensate", false)?;
        let mut window = None;
        if f.has("crop_width") || f.has("crop_height") || f.has("crop_offset_x") || f.has("crop_offset_y") {
            let ox = f.int("crop_offset_x", 0)?;
            let oy = f.int("crop_offset_y", 0)?;
            let cw = f.int("crop_width", (width as i64).saturating_sub(ox))?;
            let ch = f.int("crop_height", (height as i64).saturating_sub(oy))?;
            let fits = |o: i64, c: i64, n: u32| o >= 0 && c >= 1 && o.saturating_add(c) <= n as i64;
            if !fits(ox, cw, width) || !fits(oy, ch, height) {
                return Err(f.error(format!(
                    "crop window {cw}x{ch} at ({ox}, {oy}) does not fit in the {width}x{height} film"
                )));
            }
            window = Some([ox as u32, oy as u32, cw as u32, ch as u32]);
        }
        let filters = f.nested("rfilter");
        if filters.len() > 1 {
            return Err(SceneError::at(&filters[1].loc, "the film has more than one <rfilter>"));
        }
        let filter = match filters.first() {
            Some(r) => Filter::from_props(r)?,
            None => FilmSettings::default().filter,
        };
        let mut sensors = vec!["cie1931"];
        sensors.extend(sensor::camera_names());
        let camera = f.choice("sensor", &sensors)?;
        // pbrt-v4: a named camera is balanced for 6500 K unless told otherwise.
        let default_kelvin = if camera == "cie1931" { 0.0 } else { 6500.0 };
        let kelvin = f.float_checked(
            "white_balance",
            default_kelvin,
            |k| k == 0.0 || (1000.0..=40000.0).contains(&k),
            "0 (none) or a temperature of 1000–40000 K",
        )?;
        let matrix = if camera == "cie1931" {
            (kelvin != 0.0).then(|| sensor::SampleTransform::white_balance(kelvin))
        } else if kelvin == 0.0 {
            return Err(f.error_at(
                "white_balance",
                format!("the camera sensor '{camera}' needs a white balance (1000–40000 K; 6500 by default)"),
            ));
        } else {
            sensor::camera(&camera, kelvin)
        };
        let max_component = f.float_checked("max_component", f32::INFINITY, |m| m > 0.0, "a positive number")?;
        // Where the clamp measures: the output (neumann's) or, as pbrt-v4, the sensor's RGB.
        let clamp_basis = match f.choice("max_component_of", &["output", "sensor"])?.as_str() {
            "output" => None,
            _ if camera == "cie1931" => Some(sensor::cie1931_sensor_basis()),
            _ => sensor::camera_sensor_basis(&camera, kelvin),
        };
        let transform = sensor::SampleTransform { matrix, max_component, clamp_basis };
        Ok(FilmSettings { width, height, window, alpha, colors, component, filter, transform, sample_border })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_samples_are_dropped_and_counted() {
        let mut t = TileBuffer::new(2, 3, 4, 4);
        t.add(2, 3, Rgb::splat(1.0));
        t.add(2, 3, Rgb::new(f32::NAN, 0.0, 0.0));
        t.add(2, 3, Rgb::new(0.0, f32::INFINITY, 0.0));
        t.add(2, 3, Rgb::splat(3.0));
        let mut f = Film::new(8, 8);
        f.merge(&t);
        assert_eq!(f.dropped(), 2);
        let img = f.image();
        assert_eq!(img[3 * 8 + 2], Rgb::splat(2.0));
        assert!(img.iter().all(|c| c.is_finite()));
        let var = f.variance_of_mean();
        assert!((var[3 * 8 + 2].x - 1.0).abs() < 1e-6, "s² = 2, n = 2 → 1"); // s² = 2, /n = 1
        assert_eq!(f.spp_range(), (0, 4), "dropped samples still count as taken");
    }

    /// Mitsuba's weighted splatting: each pixel is `Σ f(c − x) L / Σ f(c − x)` over the samples
    /// whose footprint covers it, also across tile borders (the tiles' buffers overlap by the
    /// filter's reach and the film adds them), and each sample counts in its own pixel.
    #[test]
    fn gaussian_splat_is_the_filter_weighted_mean() {
        let filter = Filter::gaussian(0.5).unwrap();
        let size = [8, 6];
        // Two tiles side by side: columns 0..4 and 4..8.
        let mut left = TileBuffer::for_tile(0, 0, 4, 6, &filter, size);
        let mut right = TileBuffer::for_tile(4, 0, 4, 6, &filter, size);
        assert_eq!((left.x0, left.width, right.x0, right.width), (0, 6, 2, 6));
        let samples = [
            ([3u32, 2u32], Vec2::new(0.9, 0.5), 1.0f32),
            ([4, 2], Vec2::new(0.2, 0.3), 5.0),
            ([5, 3], Vec2::new(0.5, 0.5), 2.0),
        ];
        for &(px, off, v) in &samples {
            let tile = if px[0] < 4 { &mut left } else { &mut right };
            tile.put(px, off, &filter, FilmSample { l: Rgb::splat(v), ..Default::default() });
        }
        let mut film = Film::new(size[0], size[1]);
        film.merge(&left);
        film.merge(&right);
        let img = film.image();
        for y in 0..6u32 {
            for x in 0..8u32 {
                let (mut wl, mut w) = (0.0f64, 0.0f64);
                for &(px, off, v) in &samples {
                    let dx = x as f32 + 0.5 - (px[0] as f32 + off.x);
                    let dy = y as f32 + 0.5 - (px[1] as f32 + off.y);
                    let f = (filter.eval_1d(dx) * filter.eval_1d(dy)) as f64;
                    wl += f * v as f64;
                    w += f;
                }
                let want = if w > 0.0 { (wl / w) as f32 } else { 0.0 };
                let got = img[(y * 8 + x) as usize].x;
                assert!((got - want).abs() <= 1e-5 * want.max(1.0), "pixel ({x}, {y}): {got} vs {want}");
            }
        }
        // Pixel (3, 2) mixes its own sample with its right neighbour's (from the other tile).
        let mixed = img[(2 * 8 + 3) as usize].x;
        assert!(mixed > 1.0 && mixed < 5.0, "{mixed}");
        assert_eq!(film.total_samples(), 3);
        assert_eq!(film.spp_range(), (0, 1));
    }

    /// A splat of radiance and coverage alone adds the same bits to every pixel's sums as one
    /// that also records AOVs (through `Pixels::put_extra`), and the AVX loop the same as the
    /// portable one, for each filter.
    #[test]
    fn lean_and_general_splats_agree() {
        let mut rng = crate::sampling::Pcg32::new(8, 1);
        for filter in [Filter::gaussian(0.5).unwrap(), Filter::Tent { radius: 1.5 }, Filter::BOX] {
            let mut lean = TileBuffer::new(0, 0, 7, 5);
            let mut general = TileBuffer::new(0, 0, 7, 5).with_aovs(1);
            // The portable loop, where the others run the AVX one on a CPU that has it.
            let mut portable = TileBuffer::new(0, 0, 7, 5);
            for k in 0..200 {
                let px = [k % 7, k % 5];
                let off = Vec2::new(rng.next_f32(), rng.next_f32());
                let l = Rgb::new(rng.next_f32(), 3.0 * rng.next_f32(), 0.1);
                let alpha = (k % 3 != 0).then_some(rng.next_f32());
                lean.put(px, off, &filter, FilmSample { l, alpha, ..Default::default() });
                general.put(px, off, &filter, FilmSample { l, alpha, aovs: &[1.0], ..Default::default() });
                portable.put_with(false, px, off, &filter, FilmSample { l, alpha, ..Default::default() });
            }
            let bits =
                |a: &Acc| [&a.sum[..], &a.wl2[..], &[a.alpha]].concat().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            for ((a, b), c) in lean.px.acc.iter().zip(&general.px.acc).zip(&portable.px.acc) {
                assert_eq!(bits(a), bits(b), "{filter:?}");
                assert_eq!(bits(a), bits(c), "{filter:?}");
            }
            assert!(lean.px.acc.iter().all(|a| a.w() > 0.0), "every pixel reached");
            assert!(general.px.aovs.iter().any(|&v| v > 0.0));
        }
    }

    /// The variance estimate: with unit weights the sample variance of the mean `s²/n`; with
    /// filter weights the weighted variance over `n_eff − 1`, which for samples all equal is 0.
    #[test]
    fn variance_of_the_weighted_mean() {
        let mut t = TileBuffer::new(0, 0, 1, 1);
        for v in [1.0, 2.0, 4.0, 7.0] {
            t.add(0, 0, Rgb::splat(v));
        }
        let mut f = Film::new(1, 1);
        f.merge(&t);
        // mean 3.5, s² = (6.25 + 2.25 + 0.25 + 12.25) / 3 = 7, s²/n = 1.75.
        assert!((f.variance_of_mean()[0].x - 1.75).abs() < 1e-6);
        let filter = Filter::tent(1.5).unwrap();
        let mut t = TileBuffer::for_tile(0, 0, 3, 3, &filter, [3, 3]);
        let mut rng = crate::sampling::Pcg32::new(1, 1);
        for _ in 0..50 {
            let px = [rng.next_u32() % 3, rng.next_u32() % 3];
            t.put(
                px,
                crate::testkit::u2(&mut rng),
                &filter,
                FilmSample { l: Rgb::splat(2.0), ..Default::default() },
            );
        }
        let mut f = Film::new(3, 3);
        f.merge(&t);
        assert!(f.image().iter().all(|c| (c.x - 2.0).abs() < 1e-6));
        assert!(f.variance_of_mean().iter().all(|v| v.x.abs() < 1e-9));
    }
}
