//! The exponential distribution `p(x) = a e^(-a x)` on `[0, ∞)`: free-flight distances in a
//! homogeneous medium with extinction coefficient `a` (m⁻¹).
//!
//! Inversion: `F(x) = 1 - e^(-a x)`, so `x = -ln(1 - ξ) / a`.

use super::Sample;

/// Distance `x = -ln(1 - u) / a` for rate `a > 0` (units of 1/a). Domain `u ∈ [0,1)`; pdf
/// `a e^(-a x)`, length measure.
#[inline]
pub fn sample_exponential(u: f32, a: f32) -> Sample<f32> {
    let x = -(-u).ln_1p() / a;
    Sample::length(x, exponential_pdf(x, a))
}

/// Density `a e^(-a x)` for `x ≥ 0`, 0 for `x < 0` (length measure).
#[inline]
pub fn exponential_pdf(x: f32, a: f32) -> f32 {
    if x < 0.0 {
        0.0
    } else {
        a * crate::math::special::exp(-a * x)
    }
}

/// Inverse (the CDF): `u = 1 - e^(-a x)`.
#[inline]
pub fn invert_exponential(x: f32, a: f32) -> f32 {
    -(-a * x).exp_m1()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_1d, integrate_pdf_1d, ks_1d, Chi2Config};

    #[test]
    fn exponential_chi2_ks_and_normalization() {
        for (k, &a) in [0.1f32, 1.0, 7.5].iter().enumerate() {
            let cfg = Chi2Config::default().with_seed(k as u64);
            // Histogram to 6 mean free paths, the tail (e^-6 ≈ 0.25 %) in the overflow cell.
            let hi = 6.0 / a as f64;
            let out = chi2_1d(
                (0.0, hi),
                60,
                500_000,
                |r| Some(sample_exponential(r.next_f32(), a).value as f64),
                |x| exponential_pdf(x as f32, a) as f64,
                &cfg,
            );
            assert!(out.passed(), "a = {a}: {out}");
            let ks = ks_1d(
                100_000,
                |r| sample_exponential(r.next_f32(), a).value as f64,
                |x| 1.0 - (-(a as f64) * x.max(0.0)).exp(),
                &cfg,
            );
            assert!(ks.passed(), "a = {a}: {ks}");
            let total = integrate_pdf_1d((0.0, 40.0 / a as f64), 400, |x| exponential_pdf(x as f32, a) as f64);
            assert!((total - 1.0).abs() < 1e-5, "∫pdf = {total}");
            for u in [0.0f32, 0.2, 0.7, 0.999] {
                let s = sample_exponential(u, a);
                assert!((invert_exponential(s.value, a) - u).abs() < 1e-5);
                assert!((s.pdf - exponential_pdf(s.value, a)).abs() < 1e-6 * a);
            }
        }
        // Mean free path 1/a.
        let n = 200_000;
        let mut r = crate::sampling::Pcg32::new(1, 1);
        let mean = (0..n).map(|_| sample_exponential(r.next_f32(), 2.0).value as f64).sum::<f64>() / n as f64;
        assert!((mean - 0.5).abs() < 4.0 * 0.5 / (n as f64).sqrt());
    }
}
