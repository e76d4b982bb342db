//! Discrete distributions by inversion: the CDF and a binary search.
//!
//! For weights `w_i ≥ 0`, the probabilities are `p_i = w_i / Σw` and the CDF is
//! `P_i = Σ_{j<i} p_j`. Inversion selects the `i` with `P_i ≤ ξ < P_{i+1}` by binary search in
//! O(log n); the leftover `(ξ - P_i) / p_i` is again uniform on `[0,1)` and can be reused
//! ("sample reuse") for a continuous choice that follows. See [`super::alias`] for O(1)
//! sampling.

use super::Sample;
use crate::math::ONE_MINUS_EPSILON;

/// A discrete distribution over `0..n` stored as its CDF.
#[derive(Clone, Debug)]
pub struct DiscreteCdf {
    /// Normalized probabilities `p_i`.
    pmf: Vec<f32>,
    /// `cdf[i] = Σ_{j<i} p_j`, `cdf[0] = 0`, `cdf[n] = 1`.
    cdf: Vec<f32>,
    /// Sum of the weights.
    total: f64,
}

impl DiscreteCdf {
    /// Distribution proportional to `weights`. `None` if there are no weights, any is negative
    /// or not finite, or all are zero.
    pub fn new(weights: &[f32]) -> Option<DiscreteCdf> {
        if weights.is_empty() || weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
            return None;
        }
        let total: f64 = weights.iter().map(|&w| w as f64).sum();
        if total <= 0.0 {
            return None;
        }
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0);
        for &w in weights {
            acc += w as f64;
            cdf.push((acc / total) as f32);
        }
        // Exact endpoint despite round-off; trailing zero weights keep cdf = 1.
        let n = weights.len();
        cdf[n] = 1.0;
        let pmf = weights.iter().map(|&w| (w as f64 / total) as f32).collect();
        Some(DiscreteCdf { pmf, cdf, total })
    }

    /// Number of outcomes.
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// Whether there are no outcomes (never true for a constructed distribution).
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Sum of the weights the distribution was built from.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// Probability of outcome `i` (0 out of range).
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// The CDF table, `len() + 1` entries from 0 to 1.
    pub fn cdf(&self) -> &[f32] {
        &self.cdf
    }

    /// Outcome `i` with `P_i ≤ u < P_{i+1}` (outcomes of zero weight are never returned), its
    /// probability (discrete measure), and the remapped uniform `(u - P_i) / p_i ∈ [0,1)`.
    /// Domain `u ∈ [0,1)`.
    #[inline]
    pub fn sample(&self, u: f32) -> (Sample<usize>, f32) {
        let n = self.pmf.len();
        // Largest i in 0..n with cdf[i] <= u.
        let i = self.cdf[..n].partition_point(|&c| c <= u).saturating_sub(1);
        let p = self.pmf[i];
        let remapped = ((u - self.cdf[i]) / p).clamp(0.0, ONE_MINUS_EPSILON);
        (Sample::discrete(i, p), remapped)
    }

    /// The `u` interval start of outcome `i` (its inverse): any `u ∈ [P_i, P_{i+1})` maps to `i`.
    #[inline]
    pub fn invert(&self, i: usize) -> Option<f32> {
        (i < self.pmf.len()).then(|| self.cdf[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_discrete, Chi2Config};

    #[test]
    fn cdf_sampling_chi2_with_zero_weights() {
        let w = [0.0f32, 3.0, 1.0, 0.0, 0.0, 10.0, 0.5, 0.0];
        let d = DiscreteCdf::new(&w).unwrap();
        let out = chi2_discrete(
            w.len(),
            1_000_000,
            |r| Some(d.sample(r.next_f32()).0.value),
            |i| d.pmf(i) as f64,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        let total: f32 = (0..w.len()).map(|i| d.pmf(i)).sum();
        assert!((total - 1.0).abs() < 1e-6);
        assert!((d.pmf(5) - 10.0 / 14.5).abs() < 1e-6);
        // Zero-weight outcomes are unreachable even at the CDF's plateaus.
        for &u in &[0.0f32, d.cdf()[1], d.cdf()[3], d.cdf()[5], ONE_MINUS_EPSILON] {
            let (s, _) = d.sample(u);
            assert!(w[s.value] > 0.0, "u = {u} selected zero-weight outcome {}", s.value);
        }
    }

    #[test]
    fn remapped_u_is_uniform_and_inverse_brackets() {
        let d = DiscreteCdf::new(&[1.0, 2.0, 3.0, 4.0]).unwrap();
        let out = crate::testkit::chi2_1d(
            (0.0, 1.0),
            20,
            200_000,
            |r| Some(d.sample(r.next_f32()).1 as f64),
            |_| 1.0,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        for i in 0..4 {
            let u = d.invert(i).unwrap();
            assert_eq!(d.sample(u).0.value, i);
        }
        assert!(d.invert(4).is_none());
    }

    #[test]
    fn rejects_bad_weights() {
        assert!(DiscreteCdf::new(&[]).is_none());
        assert!(DiscreteCdf::new(&[0.0, 0.0]).is_none());
        assert!(DiscreteCdf::new(&[1.0, -1.0]).is_none());
        assert!(DiscreteCdf::new(&[1.0, f32::NAN]).is_none());
        assert!(DiscreteCdf::new(&[f32::INFINITY]).is_none());
    }
}
