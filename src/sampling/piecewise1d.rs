//! Piecewise-constant 1D distribution on an interval, sampled by inversion.
//!
//! A function tabulated as `n` constant pieces `f_i` on `[min, max]` (piece width
//! `Δ = (max - min)/n`) defines the density `p(x) = f_i / ∫f` on piece `i`, with
//! `∫f = Σ f_i Δ`. Its CDF is piecewise linear; inverting it is a binary search for the piece
//! followed by a linear solve inside it. The 2D version builds on this one.

use super::Sample;
use crate::math::ONE_MINUS_EPSILON;

/// Piecewise-constant density on `[min, max]`.
#[derive(Clone, Debug)]
pub struct PiecewiseConstant1D {
    func: Vec<f32>,
    /// `cdf[0] = 0 … cdf[n] = 1`.
    cdf: Vec<f32>,
    /// `∫f` over `[min, max]`.
    integral: f32,
    min: f32,
    max: f32,
}

impl PiecewiseConstant1D {
    /// Density proportional to `|func|` on `[min, max]`. `None` if `func` is empty, holds a
    /// non-finite value, integrates to zero, or the interval is empty.
    pub fn new(func: &[f32], min: f32, max: f32) -> Option<PiecewiseConstant1D> {
        if func.is_empty()
            || func.iter().any(|f| !f.is_finite())
            || max.partial_cmp(&min) != Some(std::cmp::Ordering::Greater)
        {
            return None;
        }
        let func: Vec<f32> = func.iter().map(|f| f.abs()).collect();
        let n = func.len();
        let delta = (max - min) as f64 / n as f64;
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0f64);
        for &f in &func {
            cdf.push(cdf.last().unwrap() + f as f64 * delta);
        }
        let integral = cdf[n];
        if integral <= 0.0 {
            return None;
        }
        let cdf: Vec<f32> = cdf.iter().map(|c| (c / integral) as f32).collect();
        let mut cdf = cdf;
        cdf[n] = 1.0;
        Some(PiecewiseConstant1D { func, cdf, integral: integral as f32, min, max })
    }

    /// Number of pieces.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Whether there are no pieces (never true for a constructed distribution).
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// `∫f` over the interval.
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Value of the (absolute) function on piece `i`.
    pub fn func(&self, i: usize) -> f32 {
        self.func[i]
    }

    /// Index of the piece holding `x` (clamped to the interval).
    #[inline]
    fn piece(&self, x: f32) -> usize {
        let n = self.func.len();
        (((x - self.min) / (self.max - self.min) * n as f32) as isize).clamp(0, n as isize - 1) as usize
    }

    /// `x ∈ [min, max)` by inversion, with its density `f_i / ∫f` (length measure), and the
    /// piece index. Domain `u ∈ [0,1)`. Pieces of zero value are never returned.
    #[inline]
    pub fn sample(&self, u: f32) -> (Sample<f32>, usize) {
        let n = self.func.len();
        let i = self.cdf[..n].partition_point(|&c| c <= u).saturating_sub(1);
        let width = self.cdf[i + 1] - self.cdf[i];
        let du = if width > 0.0 { ((u - self.cdf[i]) / width).clamp(0.0, ONE_MINUS_EPSILON) } else { 0.0 };
        let x = self.min + (i as f32 + du) * (self.max - self.min) / n as f32;
        (Sample::length(x.min(self.max), self.func[i] / self.integral), i)
    }

    /// Density at `x` (0 outside `[min, max]`), length measure.
    #[inline]
    pub fn pdf(&self, x: f32) -> f32 {
        if x < self.min || x > self.max {
            return 0.0;
        }
        self.func[self.piece(x)] / self.integral
    }

    /// The CDF at `x`: the `u` that [`Self::sample`] maps to `x` (for `x` where the density is
    /// positive).
    #[inline]
    pub fn invert(&self, x: f32) -> f32 {
        if x <= self.min {
            return 0.0;
        }
        if x >= self.max {
            return 1.0;
        }
        let n = self.func.len();
        let i = self.piece(x);
        let x0 = self.min + i as f32 * (self.max - self.min) / n as f32;
        let t = (x - x0) / (self.max - self.min) * n as f32;
        self.cdf[i] + t * (self.cdf[i + 1] - self.cdf[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_1d, integrate_pdf_1d, ks_1d, Chi2Config};

    fn dist() -> PiecewiseConstant1D {
        PiecewiseConstant1D::new(&[1.0, 0.0, 3.0, -2.0, 0.5, 8.0, 0.0, 1.0], -1.0, 3.0).unwrap()
    }

    #[test]
    fn chi2_with_cells_aligned_to_pieces() {
        let d = dist();
        // 8 pieces, 40 cells: every cell lies inside one piece.
        let out = chi2_1d(
            (-1.0, 3.0),
            40,
            1_000_000,
            |r| Some(d.sample(r.next_f32()).0.value as f64),
            |x| d.pdf(x as f32) as f64,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        assert!((integrate_pdf_1d((-1.0, 3.0), 40, |x| d.pdf(x as f32) as f64) - 1.0).abs() < 1e-5);
        let ks = ks_1d(
            200_000,
            |r| d.sample(r.next_f32()).0.value as f64,
            |x| d.invert(x as f32) as f64,
            &Chi2Config::default(),
        );
        assert!(ks.passed(), "{ks}");
    }

    #[test]
    fn sample_pdf_and_invert_agree() {
        let d = dist();
        let mut r = crate::sampling::Pcg32::new(8, 8);
        for _ in 0..100_000 {
            let u = r.next_f32();
            let (s, i) = d.sample(u);
            assert!(d.func(i) > 0.0, "zero piece sampled");
            assert!((s.pdf - d.pdf(s.value)).abs() < 1e-6, "x = {}", s.value);
            assert!((d.invert(s.value) - u).abs() < 1e-4, "u = {u}");
        }
        assert!(PiecewiseConstant1D::new(&[0.0, 0.0], 0.0, 1.0).is_none());
        assert!(PiecewiseConstant1D::new(&[1.0], 1.0, 1.0).is_none());
        assert!((d.integral() - (1.0 + 3.0 + 2.0 + 0.5 + 8.0 + 1.0) * 0.5).abs() < 1e-5);
    }
}
