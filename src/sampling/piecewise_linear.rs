//! Piecewise-linear 1D distribution on an interval, sampled by inversion (Mitsuba's
//! `ContinuousDistribution`).
//!
//! A function given by its values `f_0 … f_{n-1}` at `n ≥ 2` evenly spaced nodes of `[min, max]`
//! (spacing `Δ = (max - min)/(n - 1)`), linear between them, defines the density
//! `p(x) = f(x) / ∫f` with `∫f = Σ Δ (f_i + f_{i+1}) / 2` (trapezoids). Its CDF is piecewise
//! quadratic: sampling finds the segment by a binary search over the trapezoids' cumulative
//! areas, then solves the quadratic inside it in the cancellation-free form
//! `t = 2c / (f_i + √(f_i² + 2 (f_{i+1} - f_i) c))`, `c` the area still to cover (in units of
//! `Δ`).

use super::Sample;
use crate::math::ONE_MINUS_EPSILON;

/// Piecewise-linear density on `[min, max]` through values at evenly spaced nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct PiecewiseLinear1D {
    /// The values at the nodes.
    func: Vec<f32>,
    /// `cdf[0] = 0 … cdf[n-1] = 1`: the normalised area left of each node.
    cdf: Vec<f32>,
    /// `∫f` over `[min, max]`.
    integral: f32,
    min: f32,
    max: f32,
}

impl PiecewiseLinear1D {
    /// Density proportional to the linear interpolation of `func` (values at `func.len()`
    /// evenly spaced nodes from `min` to `max`). Errors name what is wrong: fewer than two
    /// values, a negative or non-finite value, no mass, an empty interval.
    pub fn new(func: &[f32], min: f32, max: f32) -> Result<PiecewiseLinear1D, String> {
        if func.len() < 2 {
            return Err(format!("needs at least two values, got {}", func.len()));
        }
        if let Some(f) = func.iter().find(|f| !(f.is_finite() && **f >= 0.0)) {
            return Err(format!("values must be finite and non-negative, got {f}"));
        }
        if max.partial_cmp(&min) != Some(std::cmp::Ordering::Greater) || !(max - min).is_finite() {
            return Err(format!("the interval [{min}, {max}] is empty"));
        }
        let delta = (max - min) as f64 / (func.len() - 1) as f64;
        let mut cdf = Vec::with_capacity(func.len());
        cdf.push(0.0f64);
        for w in func.windows(2) {
            cdf.push(cdf.last().unwrap() + 0.5 * (w[0] as f64 + w[1] as f64) * delta);
        }
        let integral = *cdf.last().unwrap();
        if integral <= 0.0 || !integral.is_finite() {
            return Err("the values hold no mass (all zero)".into());
        }
        let mut cdf: Vec<f32> = cdf.iter().map(|c| (c / integral) as f32).collect();
        *cdf.last_mut().unwrap() = 1.0;
        Ok(PiecewiseLinear1D { func: func.to_vec(), cdf, integral: integral as f32, min, max })
    }

    /// `∫f` over the interval.
    pub fn integral(&self) -> f32 {
        self.integral
    }

    /// Node spacing `Δ`.
    #[inline]
    fn spacing(&self) -> f32 {
        (self.max - self.min) / (self.func.len() - 1) as f32
    }

    /// Segment holding `x` (clamped to the interval) and the position `t ∈ [0, 1]` in it.
    #[inline]
    fn segment(&self, x: f32) -> (usize, f32) {
        let s = (x - self.min) / self.spacing();
        let i = (s as isize).clamp(0, self.func.len() as isize - 2) as usize;
        (i, (s - i as f32).clamp(0.0, 1.0))
    }

    /// Density at `x` (0 outside `[min, max]`), length measure.
    #[inline]
    pub fn pdf(&self, x: f32) -> f32 {
        if !(x >= self.min && x <= self.max) {
            return 0.0;
        }
        let (i, t) = self.segment(x);
        (self.func[i] + t * (self.func[i + 1] - self.func[i])) / self.integral
    }

    /// `x ∈ [min, max]` by inversion of the CDF, with its density (length measure). Domain
    /// `u ∈ [0,1)`. Segments of zero area are never entered.
    #[inline]
    pub fn sample(&self, u: f32) -> Sample<f32> {
        let n = self.func.len();
        // The last node whose CDF is ≤ u, among the segments' left nodes; a segment of zero
        // area has equal CDFs at both ends and is skipped by the search.
        let i = self.cdf[..n - 1].partition_point(|&c| c <= u).saturating_sub(1);
        let (f0, f1) = (self.func[i], self.func[i + 1]);
        // The area to cover inside the segment, in units of the spacing.
        let c = ((u - self.cdf[i]) * self.integral / self.spacing()).max(0.0);
        let denom = f0 + (f0 * f0 + 2.0 * (f1 - f0) * c).max(0.0).sqrt();
        let t = if denom > 0.0 { (2.0 * c / denom).clamp(0.0, ONE_MINUS_EPSILON) } else { 0.0 };
        let x = (self.min + (i as f32 + t) * self.spacing()).min(self.max);
        Sample::length(x, (f0 + t * (f1 - f0)) / self.integral)
    }

    /// The CDF at `x`: the `u` that [`Self::sample`] maps to `x`.
    #[inline]
    pub fn cdf(&self, x: f32) -> f32 {
        if x <= self.min {
            return 0.0;
        }
        if x >= self.max {
            return 1.0;
        }
        let (i, t) = self.segment(x);
        let (f0, f1) = (self.func[i], self.func[i + 1]);
        self.cdf[i] + (f0 * t + 0.5 * (f1 - f0) * t * t) * self.spacing() / self.integral
    }

    /// The mean of `x` under the density, in closed form (each segment's first moment).
    pub fn mean(&self) -> f64 {
        let d = self.spacing() as f64;
        let m: f64 = self
            .func
            .windows(2)
            .enumerate()
            .map(|(i, w)| {
                let (a, f0, f1) = (self.min as f64 + i as f64 * d, w[0] as f64, w[1] as f64);
                // ∫₀^Δ (a + s) (f0 + (f1 - f0) s / Δ) ds
                a * d * (f0 + f1) / 2.0 + d * d * (f0 / 2.0 + (f1 - f0) / 3.0)
            })
            .sum();
        m / self.integral as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_1d, integrate_pdf_1d, ks_1d, Chi2Config};

    /// Rising, falling, flat and zero segments (a zero-area segment in the middle).
    fn dist() -> PiecewiseLinear1D {
        PiecewiseLinear1D::new(&[0.5, 2.0, 0.0, 0.0, 1.0, 1.0, 6.0], -1.0, 2.0).unwrap()
    }

    /// χ² against the density on cells finer than the segments; the density integrates to one;
    /// Kolmogorov–Smirnov against the closed-form CDF; the closed-form mean is the samples'.
    #[test]
    fn sampling_matches_pdf_cdf_and_mean() {
        let d = dist();
        let out = chi2_1d(
            (-1.0, 2.0),
            60,
            1_000_000,
            |r| Some(d.sample(r.next_f32()).value as f64),
            |x| d.pdf(x as f32) as f64,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        let integral = integrate_pdf_1d((-1.0, 2.0), 600, |x| d.pdf(x as f32) as f64);
        assert!((integral - 1.0).abs() < 1e-4, "{integral}");
        let ks =
            ks_1d(200_000, |r| d.sample(r.next_f32()).value as f64, |x| d.cdf(x as f32) as f64, &Chi2Config::default());
        assert!(ks.passed(), "{ks}");
        let mut r = crate::sampling::Pcg32::new(3, 1);
        let n = 400_000;
        let mean = (0..n).map(|_| d.sample(r.next_f32()).value as f64).sum::<f64>() / n as f64;
        assert!((mean - d.mean()).abs() < 5e-3, "{mean} vs {}", d.mean());
    }

    /// Each sample's pdf is `pdf` at its value, the CDF inverts the sampling, no sample lands
    /// where the density is zero, and bad tables are refused with a reason.
    #[test]
    fn sample_pdf_and_cdf_agree_and_bad_tables_are_refused() {
        let d = dist();
        let mut r = crate::sampling::Pcg32::new(8, 8);
        for _ in 0..100_000 {
            let u = r.next_f32();
            let s = d.sample(u);
            assert!(s.pdf > 0.0, "zero density sampled at {}", s.value);
            assert!((s.pdf - d.pdf(s.value)).abs() < 1e-5 * s.pdf.max(1.0), "x = {}", s.value);
            assert!((d.cdf(s.value) - u).abs() < 1e-4, "u = {u}");
        }
        assert_eq!(d.sample(0.0).value, -1.0);
        assert!(d.sample(ONE_MINUS_EPSILON).value <= 2.0);
        assert!((d.integral() - (1.25 + 1.0 + 0.0 + 0.5 + 1.0 + 3.5) * 0.5).abs() < 1e-5);
        assert_eq!(d.pdf(-1.5), 0.0);
        assert_eq!(d.pdf(f32::NAN), 0.0);
        for (bad, why) in [
            (vec![1.0], "at least two"),
            (vec![1.0, -1.0], "non-negative"),
            (vec![1.0, f32::NAN], "non-negative"),
            (vec![0.0, 0.0, 0.0], "no mass"),
        ] {
            let e = PiecewiseLinear1D::new(&bad, 0.0, 1.0).unwrap_err();
            assert!(e.contains(why), "{bad:?}: {e}");
        }
        assert!(PiecewiseLinear1D::new(&[1.0, 1.0], 1.0, 1.0).unwrap_err().contains("empty"));
        // Uniform: linear CDF, constant density.
        let u = PiecewiseLinear1D::new(&[3.0, 3.0, 3.0], -1.0, 1.0).unwrap();
        assert!((u.sample(0.25).value + 0.5).abs() < 1e-6 && (u.pdf(0.3) - 0.5).abs() < 1e-6);
    }
}
