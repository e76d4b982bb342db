//! Gauss–Legendre quadrature.

/// Integral of `f` over `[a, b]` by 5-point Gauss–Legendre quadrature (exact for polynomials of
/// degree ≤ 9).
pub fn gauss_legendre_5(a: f64, b: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
    let half = 0.5 * (b - a);
    let mid = 0.5 * (a + b);
    GL5.iter().map(|&(x, w)| w * f(mid + half * x)).sum::<f64>() * half
}

/// Nodes and weights of 5-point Gauss–Legendre quadrature on [-1, 1].
pub(crate) const GL5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

/// Integral over the rectangle `[x0, x1] × [y0, y1]` by the 5×5 tensor-product rule.
pub(crate) fn gauss_legendre_5x5(x0: f64, x1: f64, y0: f64, y1: f64, mut f: impl FnMut(f64, f64) -> f64) -> f64 {
    let (hx, mx) = (0.5 * (x1 - x0), 0.5 * (x0 + x1));
    let (hy, my) = (0.5 * (y1 - y0), 0.5 * (y0 + y1));
    let mut sum = 0.0;
    for &(yn, yw) in &GL5 {
        for &(xn, xw) in &GL5 {
            sum += xw * yw * f(mx + hx * xn, my + hy * yn);
        }
    }
    sum * hx * hy
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_for_degree_nine() {
        let i = gauss_legendre_5(0.0, 2.0, |x| x.powi(9));
        assert!((i - 2f64.powi(10) / 10.0).abs() < 1e-9);
        let w: f64 = GL5.iter().map(|p| p.1).sum();
        assert!((w - 2.0).abs() < 1e-12);
        let j = gauss_legendre_5x5(0.0, 1.0, 0.0, 3.0, |x, y| x * x * y);
        assert!((j - 1.5).abs() < 1e-12);
    }
}
