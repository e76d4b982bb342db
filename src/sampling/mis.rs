//! Multiple importance sampling weights (Veach & Guibas 1995).
//!
//! When a quantity can be sampled by several strategies, the combined estimator
//! `Σ_s 1/n_s Σ_i w_s(X_{s,i}) f(X_{s,i}) / p_s(X_{s,i})` is unbiased whenever the weights sum to
//! one wherever `f ≠ 0`. The balance heuristic `w_s = n_s p_s / Σ_k n_k p_k` is provably close
//! to optimal; the power heuristic (β = 2) does better when one strategy is much better than the
//! others. All pdfs passed to one call must be in the same measure (usually solid angle).

/// Balance heuristic weight of strategy f: `n_f p_f / (n_f p_f + n_g p_g)`. An infinite `f_pdf`
/// (a delta distribution) gets weight 1; `0/0` gives 0.
#[inline]
pub fn balance_heuristic(nf: u32, f_pdf: f32, ng: u32, g_pdf: f32) -> f32 {
    let f = nf as f32 * f_pdf;
    let g = ng as f32 * g_pdf;
    if f.is_infinite() {
        return 1.0;
    }
    if f + g <= 0.0 {
        return 0.0;
    }
    f / (f + g)
}

/// Power heuristic weight (β = 2) of strategy f: `(n_f p_f)² / ((n_f p_f)² + (n_g p_g)²)`. An
/// infinite (or overflowing) `n_f p_f` gets weight 1; `0/0` gives 0.
#[inline]
pub fn power_heuristic(nf: u32, f_pdf: f32, ng: u32, g_pdf: f32) -> f32 {
    let f = nf as f32 * f_pdf;
    let g = ng as f32 * g_pdf;
    let (f2, g2) = (f * f, g * g);
    if f2.is_infinite() {
        return if g2.is_infinite() { 0.5 } else { 1.0 };
    }
    if f2 + g2 <= 0.0 {
        return 0.0;
    }
    f2 / (f2 + g2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{power::sample_power, Pcg32};

    #[test]
    fn weights_sum_to_one() {
        for (a, b) in [(0.3f32, 2.0f32), (1e-20, 5.0), (7.0, 7.0), (1e30, 1e-30)] {
            for (na, nb) in [(1, 1), (1, 4), (3, 2)] {
                let s = balance_heuristic(na, a, nb, b) + balance_heuristic(nb, b, na, a);
                assert!((s - 1.0).abs() < 1e-6, "{a} {b}");
                let s = power_heuristic(na, a, nb, b) + power_heuristic(nb, b, na, a);
                assert!((s - 1.0).abs() < 1e-6, "{a} {b}");
            }
        }
        assert_eq!(power_heuristic(1, f32::INFINITY, 1, 3.0), 1.0);
        assert_eq!(power_heuristic(1, 3.0, 1, f32::INFINITY), 0.0);
        assert_eq!(balance_heuristic(1, f32::INFINITY, 1, 3.0), 1.0);
        assert_eq!(power_heuristic(1, 0.0, 1, 0.0), 0.0);
        assert!(power_heuristic(1, 1.0, 1, 0.1) > balance_heuristic(1, 1.0, 1, 0.1));
    }

    /// Estimate ∫₀¹ f with f(x) = x⁴ + x/2 (exact 0.45) by MIS of two strategies: uniform, and the
    /// power law p(x) = 5x⁴. Each MIS estimator must be unbiased, and beat the worse strategy.
    #[test]
    fn mis_estimators_are_unbiased_and_reduce_variance() {
        let f = |x: f32| x.powi(4) + 0.5 * x;
        let exact = 0.45f64;
        let n = 400_000;
        for (name, h) in [("balance", balance_heuristic as fn(u32, f32, u32, f32) -> f32), ("power", power_heuristic)] {
            let mut r = Pcg32::new(12, 0);
            let (mut sum, mut sum2) = (0.0f64, 0.0f64);
            let (mut s_uni, mut s2_uni) = (0.0f64, 0.0f64);
            for _ in 0..n {
                // Strategy 1: uniform.
                let x1 = r.next_f32();
                let p1 = 1.0f32;
                let q1 = 5.0 * x1.powi(4);
                let e1 = (h(1, p1, 1, q1) * f(x1) / p1) as f64;
                // Strategy 2: power law n = 4.
                let s2 = sample_power(r.next_f32(), 4.0);
                let x2 = s2.value;
                let e2 = if s2.pdf > 0.0 { (h(1, s2.pdf, 1, 1.0) * f(x2) / s2.pdf) as f64 } else { 0.0 };
                let e = e1 + e2;
                sum += e;
                sum2 += e * e;
                let eu = f(x1) as f64;
                s_uni += eu;
                s2_uni += eu * eu;
            }
            let mean = sum / n as f64;
            let var = sum2 / n as f64 - mean * mean;
            let var_uni = s2_uni / n as f64 - (s_uni / n as f64).powi(2);
            assert!((mean - exact).abs() < 4.0 * (var / n as f64).sqrt() + 1e-6, "{name}: {mean} vs {exact}");
            // One MIS sample costs two draws: compare with two uniform samples (variance / 2).
            assert!(var < 0.5 * var_uni, "{name}: MIS variance {var} vs uniform {var_uni}");
        }
    }
}
