//! Monte Carlo estimators outside the renderer proper: the textbook examples that show how
//! `F_N = 1/N Σ f(Xᵢ)/p(Xᵢ)` behaves, and the statistics to judge them.

pub mod irradiance;

/// The result of a Monte Carlo estimate from `n` independent samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The estimate `F_N` (mean of the per-sample values `f(Xᵢ)/p(Xᵢ)`).
    pub value: f64,
    /// Unbiased sample variance of the per-sample values.
    pub sample_variance: f64,
    /// Number of samples.
    pub n: usize,
}

impl Estimate {
    /// Accumulates per-sample values with Welford's algorithm (stable in one pass).
    pub fn from_values(values: impl IntoIterator<Item = f64>) -> Estimate {
        let (mut n, mut mean, mut m2) = (0usize, 0.0f64, 0.0f64);
        for x in values {
            n += 1;
            let d = x - mean;
            mean += d / n as f64;
            m2 += d * (x - mean);
        }
        Estimate { value: mean, sample_variance: if n > 1 { m2 / (n - 1) as f64 } else { 0.0 }, n }
    }

    /// Standard error of the estimate, `√(s² / N)`.
    pub fn std_error(&self) -> f64 {
        (self.sample_variance / self.n.max(1) as f64).sqrt()
    }
}

/// Least-squares slope of `ln y` against `ln x`: the convergence order of an error measured at
/// several sample counts (≈ -1/2 for the RMSE of plain Monte Carlo, -1 for its MSE). Points
/// with non-positive coordinates are ignored; `None` with fewer than two usable points.
pub fn loglog_slope(points: &[(f64, f64)]) -> Option<f64> {
    let pts: Vec<(f64, f64)> =
        points.iter().filter(|(x, y)| *x > 0.0 && *y > 0.0).map(|(x, y)| (x.ln(), y.ln())).collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_matches_two_pass() {
        let xs = [1.0, 4.0, 2.5, -3.0, 10.0];
        let e = Estimate::from_values(xs);
        let mean = xs.iter().sum::<f64>() / 5.0;
        let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / 4.0;
        assert!((e.value - mean).abs() < 1e-12 && (e.sample_variance - var).abs() < 1e-12);
        assert!((e.std_error() - (var / 5.0).sqrt()).abs() < 1e-12);
    }

    #[test]
    fn slope_of_exact_power_laws() {
        for k in [-1.0, -0.5, 2.0] {
            let pts: Vec<(f64, f64)> = (1..8).map(|i| (2f64.powi(i), 3.0 * 2f64.powi(i).powf(k))).collect();
            assert!((loglog_slope(&pts).unwrap() - k).abs() < 1e-12);
        }
        assert!(loglog_slope(&[(1.0, 1.0)]).is_none());
        assert!(loglog_slope(&[(1.0, 1.0), (1.0, 2.0)]).is_none());
    }
}
