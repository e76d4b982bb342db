//! One-sample Kolmogorov–Smirnov test for 1D samplers.

use super::stats::kolmogorov_sf;
use super::Chi2Config;
use crate::sampling::rng::Pcg32;
use std::fmt;

/// Result of a Kolmogorov–Smirnov test.
#[derive(Clone, Debug)]
pub struct KsOutcome {
    /// Largest distance `D = sup |F_n(x) - F(x)|` between empirical and claimed CDFs.
    pub d: f64,
    /// Number of samples.
    pub n: usize,
    /// p-value by the Kolmogorov distribution with Stephens' small-sample correction.
    pub p_value: f64,
    /// Per-test significance level (Šidák-corrected).
    pub alpha: f64,
}

impl KsOutcome {
    /// Whether the samples are compatible with the CDF.
    pub fn passed(&self) -> bool {
        self.p_value >= self.alpha
    }
}

impl fmt::Display for KsOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "KS D = {:.5} (n = {}), p = {:.3e} (rejected below {:.3e}): {}",
            self.d,
            self.n,
            self.p_value,
            self.alpha,
            if self.passed() { "accepted" } else { "REJECTED" }
        )
    }
}

/// Kolmogorov–Smirnov test of `n` draws of `sample` against the continuous CDF `cdf`.
pub fn ks_1d(
    n: usize,
    mut sample: impl FnMut(&mut Pcg32) -> f64,
    cdf: impl Fn(f64) -> f64,
    cfg: &Chi2Config,
) -> KsOutcome {
    let mut rng = Pcg32::new(cfg.seed, 0x4b53);
    let mut xs: Vec<f64> = (0..n).map(|_| sample(&mut rng)).collect();
    xs.sort_by(|a, b| a.total_cmp(b));
    let nf = n as f64;
    let mut d: f64 = 0.0;
    for (i, &x) in xs.iter().enumerate() {
        let f = cdf(x);
        if f.is_nan() || x.is_nan() {
            d = 1.0;
            break;
        }
        d = d.max(((i + 1) as f64 / nf - f).abs()).max((f - i as f64 / nf).abs());
    }
    let sn = nf.sqrt();
    let p_value = kolmogorov_sf((sn + 0.12 + 0.11 / sn) * d);
    KsOutcome { d, n, p_value, alpha: cfg.per_test_alpha() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ks_accepts_uniform_and_rejects_skew() {
        let cfg = Chi2Config::default();
        let ok = ks_1d(100_000, |r| r.next_f64(), |x| x.clamp(0.0, 1.0), &cfg);
        assert!(ok.passed(), "{ok}");
        let bad = ks_1d(100_000, |r| r.next_f64().powf(1.02), |x| x.clamp(0.0, 1.0), &cfg);
        assert!(!bad.passed(), "{bad}");
    }
}
