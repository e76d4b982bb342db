//! The film: per-pixel accumulation of radiance samples (box reconstruction filter), with a
//! guard that drops non-finite samples, and image output ([`output`]).
//!
//! Sums are kept in `f64` so that millions of samples per pixel lose nothing to round-off, and
//! sums of squares give the per-pixel variance of the mean (used by tests for 3σ bounds). Each
//! tile accumulates its pixels' samples in sample-index order and tiles are merged in a fixed
//! order, so images are bit-identical for a given seed whatever the number of threads.

pub mod filter;
pub mod output;

use crate::math::Rgb;

/// Per-pixel sums shared by tiles and the film: radiance and its square (f64), sample counts,
/// coverage (alpha) and, optionally, the Neumann-series terms.
#[derive(Clone, Debug)]
struct Pixels {
    sum: Vec<[f64; 3]>,
    sum_sq: Vec<[f64; 3]>,
    count: Vec<u32>,
    alpha: Vec<f64>,
    /// `term_count` sums per pixel.
    terms: Vec<[f64; 3]>,
    term_count: usize,
    dropped: u64,
}

impl Pixels {
    fn new(n: usize) -> Pixels {
        Pixels {
            sum: vec![[0.0; 3]; n],
            sum_sq: vec![[0.0; 3]; n],
            count: vec![0; n],
            alpha: vec![0.0; n],
            terms: Vec::new(),
            term_count: 0,
            dropped: 0,
        }
    }

    fn keep_terms(&mut self, count: usize) {
        self.terms = vec![[0.0; 3]; self.count.len() * count];
        self.term_count = count;
    }
}

/// Accumulated samples of a rectangle of pixels.
#[derive(Clone, Debug)]
pub struct TileBuffer {
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    px: Pixels,
}

impl TileBuffer {
    /// An empty tile.
    pub fn new(x0: u32, y0: u32, width: u32, height: u32) -> TileBuffer {
        TileBuffer { x0, y0, width, height, px: Pixels::new((width * height) as usize) }
    }

    /// The same tile keeping `count` Neumann-series terms per pixel.
    pub fn with_terms(mut self, count: usize) -> TileBuffer {
        self.px.keep_terms(count);
        self
    }

    /// Adds a sample's terms to pixel `(x, y)` (dropped, like [`TileBuffer::add`], if any
    /// component is not finite: call with the sample's total).
    #[inline]
    pub fn add_terms(&mut self, x: u32, y: u32, total: Rgb, terms: &[Rgb]) {
        if !total.is_finite() || self.px.term_count == 0 {
            return;
        }
        let i = ((y - self.y0) * self.width + (x - self.x0)) as usize * self.px.term_count;
        for (k, t) in terms.iter().take(self.px.term_count).enumerate() {
            for c in 0..3 {
                self.px.terms[i + k][c] += t[c] as f64;
            }
        }
    }

    /// Adds a coverage sample (1: the camera ray hit a surface, 0: it escaped) to pixel `(x, y)`.
    #[inline]
    pub fn add_alpha(&mut self, x: u32, y: u32, a: f32) {
        let i = ((y - self.y0) * self.width + (x - self.x0)) as usize;
        self.px.alpha[i] += a as f64;
    }

    /// Adds a radiance sample to pixel `(x, y)` (image coordinates, inside the tile). Samples
    /// with a NaN or infinite component are dropped and counted instead.
    #[inline]
    pub fn add(&mut self, x: u32, y: u32, l: Rgb) {
        if !l.is_finite() {
            self.px.dropped += 1;
            return;
        }
        let i = ((y - self.y0) * self.width + (x - self.x0)) as usize;
        let s = &mut self.px.sum[i];
        let q = &mut self.px.sum_sq[i];
        for c in 0..3 {
            let v = l[c] as f64;
            s[c] += v;
            q[c] += v * v;
        }
        self.px.count[i] += 1;
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
}

impl Film {
    /// An empty `width × height` film.
    pub fn new(width: u32, height: u32) -> Film {
        Film { width, height, px: Pixels::new((width as usize) * (height as usize)) }
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
            .count
            .iter()
            .enumerate()
            .map(|(i, &n)| {
                let s = self.px.terms[i * self.px.term_count + k];
                if n == 0 {
                    Rgb::ZERO
                } else {
                    Rgb::new(s[0] as f32, s[1] as f32, s[2] as f32) / n as f32
                }
            })
            .collect()
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Adds a tile's samples.
    pub fn merge(&mut self, tile: &TileBuffer) {
        for ty in 0..tile.height {
            for tx in 0..tile.width {
                let ti = (ty * tile.width + tx) as usize;
                let fi = ((tile.y0 + ty) * self.width + tile.x0 + tx) as usize;
                for c in 0..3 {
                    self.px.sum[fi][c] += tile.px.sum[ti][c];
                    self.px.sum_sq[fi][c] += tile.px.sum_sq[ti][c];
                }
                self.px.count[fi] += tile.px.count[ti];
                self.px.alpha[fi] += tile.px.alpha[ti];
                for k in 0..self.px.term_count.min(tile.px.term_count) {
                    let (a, b) = (fi * self.px.term_count + k, ti * tile.px.term_count + k);
                    for c in 0..3 {
                        self.px.terms[a][c] += tile.px.terms[b][c];
                    }
                }
            }
        }
        self.px.dropped += tile.px.dropped;
    }

    /// Adds one sample to every pixel: a whole image (row-major, this film's size), as the
    /// light tracer produces per pass. Counts `dropped` non-finite splats left out of it.
    pub fn add_pass(&mut self, image: &[[f64; 3]], dropped: u64) {
        assert_eq!(image.len(), self.px.sum.len(), "pass image size");
        for (i, v) in image.iter().enumerate() {
            for (c, x) in v.iter().enumerate() {
                self.px.sum[i][c] += x;
                self.px.sum_sq[i][c] += x * x;
            }
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

    /// Total samples accumulated.
    pub fn total_samples(&self) -> u64 {
        self.px.count.iter().map(|&c| c as u64).sum()
    }

    /// The pixel estimates (mean radiance per pixel; 0 where there is no sample), row-major from
    /// the top-left.
    pub fn image(&self) -> Vec<Rgb> {
        self.px
            .sum
            .iter()
            .zip(&self.px.count)
            .map(|(s, &n)| if n == 0 { Rgb::ZERO } else { Rgb::new(s[0] as f32, s[1] as f32, s[2] as f32) / n as f32 })
            .map(|c| if c.is_finite() { c } else { Rgb::ZERO })
            .collect()
    }

    /// Per-pixel coverage (alpha): the fraction of the pixel's samples whose camera ray hit a
    /// surface, if the renderer recorded it (0 otherwise).
    pub fn alpha(&self) -> Vec<f32> {
        self.px
            .alpha
            .iter()
            .zip(&self.px.count)
            .map(|(&a, &n)| if n == 0 { 0.0 } else { (a / n as f64) as f32 })
            .collect()
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

    /// Estimated variance of each pixel's mean, `s² / n` per channel (0 with fewer than two
    /// samples).
    pub fn variance_of_mean(&self) -> Vec<Rgb> {
        self.px
            .sum
            .iter()
            .zip(&self.px.sum_sq)
            .zip(&self.px.count)
            .map(|((s, q), &n)| {
                if n < 2 {
                    return Rgb::ZERO;
                }
                let n = n as f64;
                let v = |c: usize| (((q[c] - s[c] * s[c] / n) / (n - 1.0)).max(0.0) / n) as f32;
                Rgb::new(v(0), v(1), v(2))
            })
            .collect()
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
        assert_eq!(f.spp_range(), (0, 2));
    }
}
