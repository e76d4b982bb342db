//! Gauss–Legendre quadrature rules of any order (for precomputed BSDF tables).

/// The `n`-point Gauss–Legendre rule on [-1, 1]: nodes (increasing) and weights, exact for
/// polynomials of degree `2n − 1`. Nodes are the roots of the Legendre polynomial `Pₙ`, found by
/// Newton's method from Tricomi's initial guesses; weights `2 / ((1 − x²) Pₙ'(x)²)`.
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    assert!(n >= 1, "a Gauss–Legendre rule needs at least one node");
    let mut nodes = vec![0.0; n];
    let mut weights = vec![0.0; n];
    // Pₙ(x) and Pₙ'(x) by the three-term recurrence.
    let legendre = |x: f64| {
        let (mut p0, mut p1) = (1.0, x);
        for k in 2..=n {
            let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
            p0 = p1;
            p1 = p2;
        }
        let p = if n == 1 { x } else { p1 };
        let pm1 = if n == 1 { 1.0 } else { p0 };
        (p, n as f64 * (x * p - pm1) / (x * x - 1.0))
    };
    for i in 0..n.div_ceil(2) {
        let theta = std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5);
        let mut x = theta.cos();
        for _ in 0..100 {
            let (p, dp) = legendre(x);
            let dx = p / dp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        let (_, dp) = legendre(x);
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        nodes[n - 1 - i] = x;
        weights[n - 1 - i] = w;
        nodes[i] = -x;
        weights[i] = w;
    }
    if n % 2 == 1 {
        // The middle root is exactly 0.
        let (_, dp) = legendre(0.0);
        nodes[n / 2] = 0.0;
        weights[n / 2] = 2.0 / (dp * dp);
    }
    (nodes, weights)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rules integrate monomials of degree < 2n exactly and weights sum to 2.
    #[test]
    fn exact_for_polynomials_up_to_degree_2n_minus_1() {
        for n in [1, 2, 3, 5, 8, 32, 128] {
            let (x, w) = gauss_legendre(n);
            assert!(x.windows(2).all(|p| p[0] < p[1]), "n = {n}: nodes increase");
            for degree in 0..(2 * n).min(40) {
                let got: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(degree as i32)).sum();
                let want = if degree % 2 == 1 { 0.0 } else { 2.0 / (degree + 1) as f64 };
                assert!((got - want).abs() < 1e-12, "n = {n}, x^{degree}: {got} vs {want}");
            }
        }
        // A degree-2n monomial is not exact (the rule is no better than it should be).
        let (x, w) = gauss_legendre(3);
        let got: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(6)).sum();
        assert!((got - 2.0 / 7.0).abs() > 1e-3);
    }
}
