//! Catmull–Rom splines over non-uniform nodes (pbrt-v4's `CatmullRomWeights`,
//! `IntegrateCatmullRom`, `InvertCatmullRom`, `SampleCatmullRom2D`), for tabulated functions
//! such as the BSSRDF profiles of the material layer's `bssrdf` module.
//!
//! On the segment `[x_i, x_{i+1}]` of width `w` the spline is the cubic Hermite interpolant of
//! `f_i`, `f_{i+1}` with derivatives (per unit `t = (x − x_i)/w`) from finite differences of the
//! neighbours, `d_i = w (f_{i+1} − f_{i−1}) / (x_{i+1} − x_{i−1})` (a one-sided difference
//! `f_{i+1} − f_i` at the ends), so the spline passes through every node.

/// The interval `i` with `nodes[i] ≤ x < nodes[i + 1]`, clamped to `0..=len − 2` (`pred(i)` is
/// `nodes[i] ≤ x`, true for a prefix).
#[inline]
fn find_interval(len: usize, pred: impl Fn(usize) -> bool) -> usize {
    // The largest i with pred(i), by bisection over [0, len).
    let (mut lo, mut hi) = (0usize, len);
    while lo + 1 < hi {
        let mid = (lo + hi) / 2;
        if pred(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo.min(len.saturating_sub(2))
}

/// The weights of the four nodes `offset .. offset + 4` (an `offset` of −1 means the first
/// weight is for no node and is zero) whose weighted sum of values is the spline at `x`; `None`
/// outside `[nodes[0], nodes[last]]` (or for NaN).
#[inline]
pub fn catmull_rom_weights(nodes: &[f32], x: f32) -> Option<(isize, [f32; 4])> {
    let n = nodes.len();
    if n < 2 || !(x >= nodes[0] && x <= nodes[n - 1]) {
        return None;
    }
    let idx = find_interval(n, |i| nodes[i] <= x);
    let (x0, x1) = (nodes[idx], nodes[idx + 1]);
    let t = (x - x0) / (x1 - x0);
    let (t2, t3) = (t * t, t * t * t);
    let mut w = [0.0, 2.0 * t3 - 3.0 * t2 + 1.0, -2.0 * t3 + 3.0 * t2, 0.0];
    if idx > 0 {
        let w0 = (t3 - 2.0 * t2 + t) * (x1 - x0) / (x1 - nodes[idx - 1]);
        w[0] = -w0;
        w[2] += w0;
    } else {
        let w0 = t3 - 2.0 * t2 + t;
        w[1] -= w0;
        w[2] += w0;
    }
    if idx + 2 < n {
        let w3 = (t3 - t2) * (x1 - x0) / (nodes[idx + 2] - x0);
        w[1] -= w3;
        w[3] = w3;
    } else {
        let w3 = t3 - t2;
        w[1] -= w3;
        w[2] += w3;
    }
    Some((idx as isize - 1, w))
}

/// The spline's finite-difference derivatives `(d0, d1)` at the ends of segment `i`, per unit
/// `t`, of values read by `f`.
#[inline]
fn derivatives(x: &[f32], f: impl Fn(usize) -> f32, i: usize) -> (f32, f32) {
    let (x0, x1) = (x[i], x[i + 1]);
    let (f0, f1) = (f(i), f(i + 1));
    let width = x1 - x0;
    let d0 = if i > 0 { width * (f1 - f(i - 1)) / (x1 - x[i - 1]) } else { f1 - f0 };
    let d1 = if i + 2 < x.len() { width * (f(i + 2) - f0) / (x[i + 2] - x0) } else { f1 - f0 };
    (d0, d1)
}

/// The spline through `(x, values)` integrated from `x[0]`: the total, with the running
/// integral at every node written to `cdf` (same length; `cdf[0] = 0`).
pub fn integrate_catmull_rom(x: &[f32], values: &[f32], cdf: &mut [f32]) -> f32 {
    assert!(x.len() == values.len() && cdf.len() == x.len() && !x.is_empty());
    let mut sum = 0.0f32;
    cdf[0] = 0.0;
    for i in 0..x.len() - 1 {
        let (d0, d1) = derivatives(x, |k| values[k], i);
        sum += ((d0 - d1) * (1.0 / 12.0) + (values[i] + values[i + 1]) * 0.5) * (x[i + 1] - x[i]);
        cdf[i + 1] = sum;
    }
    sum
}

/// The root in `[0, 1]` of `g(t) = F(t) − u` for increasing `F` with derivative `f` (`eval`
/// returns both), by Newton steps kept inside a shrinking bracket (bisection where a step leaves
/// it), to 10⁻⁶ in `t` or in `F`.
fn newton_bisection(eval: impl Fn(f32) -> (f32, f32)) -> f32 {
    let (mut a, mut b) = (0.0f32, 1.0f32);
    let (fa, fb) = (eval(a).0, eval(b).0);
    if fa >= 0.0 {
        return a;
    }
    if fb <= 0.0 {
        return b;
    }
    let mut t = 0.5f32;
    for _ in 0..100 {
        if !(t > a && t < b) {
            t = 0.5 * (a + b);
        }
        let (g, dg) = eval(t);
        if g.abs() < 1e-6 || b - a < 1e-6 {
            return t;
        }
        if g > 0.0 {
            b = t;
        } else {
            a = t;
        }
        t -= g / dg;
    }
    t.clamp(0.0, 1.0)
}

/// The `x` where the increasing spline through `(x, values)` reaches `u` (`x[0]` below the
/// first value, the last node above the last).
pub fn invert_catmull_rom(x: &[f32], values: &[f32], u: f32) -> f32 {
    let n = values.len();
    if u.is_nan() || u <= values[0] {
        return x[0];
    }
    if u >= values[n - 1] {
        return x[n - 1];
    }
    let i = find_interval(n, |k| values[k] <= u);
    let (f0, f1) = (values[i], values[i + 1]);
    let (d0, d1) = derivatives(x, |k| values[k], i);
    let t = newton_bisection(|t| {
        let (t2, t3) = (t * t, t * t * t);
        let big_f =
            (2.0 * t3 - 3.0 * t2 + 1.0) * f0 + (-2.0 * t3 + 3.0 * t2) * f1 + (t3 - 2.0 * t2 + t) * d0 + (t3 - t2) * d1;
        let small_f = (6.0 * t2 - 6.0 * t) * f0
            + (-6.0 * t2 + 6.0 * t) * f1
            + (3.0 * t2 - 4.0 * t + 1.0) * d0
            + (3.0 * t2 - 2.0 * t) * d1;
        (big_f - u, small_f)
    });
    x[i] + t * (x[i + 1] - x[i])
}

/// A table of functions `f(α, x)` on the grid `nodes1 × nodes2` (`values[i · len2 + j]`, each
/// row with its running integral over `x` in `cdf`, as [`integrate_catmull_rom`] writes it),
/// interpolated over `α` by the spline too.
#[derive(Clone, Copy, Debug)]
pub struct Spline2D<'a> {
    /// Nodes of the first parameter (`α`).
    pub nodes1: &'a [f32],
    /// Nodes of the sampled variable (`x`).
    pub nodes2: &'a [f32],
    /// Function values, a row per `α` node.
    pub values: &'a [f32],
    /// Running integrals of the rows over `x`.
    pub cdf: &'a [f32],
}

impl Spline2D<'_> {
    /// Samples `x` proportionally to the spline `f(α, ·)` with `u ∈ [0, 1)` (pbrt-v4's
    /// `SampleCatmullRom2D`): `(x, f(α, x), density)`, the density `f / ∫ f`; `None` where `α`
    /// is outside the table or the row integrates to nothing.
    pub fn sample(&self, alpha: f32, u: f32) -> Option<(f32, f32, f32)> {
        let (offset, weights) = catmull_rom_weights(self.nodes1, alpha)?;
        let len2 = self.nodes2.len();
        let interpolate = |array: &[f32], idx: usize| {
            let mut v = 0.0;
            for (i, &w) in weights.iter().enumerate() {
                if w != 0.0 {
                    v += array[(offset + i as isize) as usize * len2 + idx] * w;
                }
            }
            v
        };
        let maximum = interpolate(self.cdf, len2 - 1);
        if maximum.is_nan() || maximum <= 0.0 {
            return None;
        }
        let u = u * maximum;
        let idx = find_interval(len2, |i| interpolate(self.cdf, i) <= u);
        let (f0, f1) = (interpolate(self.values, idx), interpolate(self.values, idx + 1));
        let (x0, x1) = (self.nodes2[idx], self.nodes2[idx + 1]);
        let width = x1 - x0;
        let (d0, d1) = derivatives(self.nodes2, |k| interpolate(self.values, k), idx);
        let u = (u - interpolate(self.cdf, idx)) / width;
        let poly = |t: f32| {
            let big_f = t
                * (f0
                    + t * (0.5 * d0
                        + t * ((1.0 / 3.0) * (-2.0 * d0 - d1) + f1 - f0 + t * (0.25 * (d0 + d1) + 0.5 * (f0 - f1)))));
            let small_f = f0 + t * (d0 + t * (-2.0 * d0 - d1 + 3.0 * (f1 - f0) + t * (d0 + d1 + 2.0 * (f0 - f1))));
            (big_f - u, small_f)
        };
        let t = newton_bisection(poly);
        let fval = poly(t).1;
        Some((x0 + width * t, fval, fval / maximum))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;

    /// Non-uniform nodes (pbrt's radius nodes: 0, then geometric) and a smooth function on them.
    fn table() -> (Vec<f32>, Vec<f32>) {
        let mut x = vec![0.0f32, 0.05];
        while x.len() < 24 {
            let last = *x.last().unwrap();
            x.push(last * 1.2);
        }
        let f = x.iter().map(|&x| x * (-x).exp() + 0.1 * (-x * x).exp()).collect();
        (x, f)
    }

    /// The weights sum to one, reproduce the values at the nodes, and interpolate a cubic's
    /// values between them closely (Catmull–Rom reproduces straight lines exactly).
    #[test]
    fn weights_interpolate() {
        let (x, f) = table();
        let eval = |v: f32, f: &[f32]| {
            let (o, w) = catmull_rom_weights(&x, v).unwrap();
            (0..4).filter(|&i| w[i] != 0.0).map(|i| w[i] * f[(o + i as isize) as usize]).sum::<f32>()
        };
        for (i, &xi) in x.iter().enumerate() {
            assert!((eval(xi, &f) - f[i]).abs() < 1e-5, "node {i}");
        }
        let line: Vec<f32> = x.iter().map(|&v| 3.0 * v - 1.0).collect();
        for k in 0..1000 {
            let v = x[x.len() - 1] * k as f32 / 1000.0;
            let (_, w) = catmull_rom_weights(&x, v).unwrap();
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5);
            assert!((eval(v, &line) - (3.0 * v - 1.0)).abs() < 1e-4 * (1.0 + v), "line at {v}");
        }
        assert!(catmull_rom_weights(&x, -0.1).is_none());
        assert!(catmull_rom_weights(&x, f32::NAN).is_none());
        assert!(catmull_rom_weights(&x, x[x.len() - 1] * 1.01).is_none());
    }

    /// The spline's integral equals a fine quadrature of the spline, the running integrals
    /// increase, and inverting them finds the nodes and points between.
    #[test]
    fn integral_and_inverse() {
        let (x, f) = table();
        let mut cdf = vec![0.0; x.len()];
        let total = integrate_catmull_rom(&x, &f, &mut cdf);
        let spline = |v: f32| {
            let (o, w) = catmull_rom_weights(&x, v).unwrap();
            (0..4).filter(|&i| w[i] != 0.0).map(|i| w[i] as f64 * f[(o + i as isize) as usize] as f64).sum::<f64>()
        };
        let n = 200_000;
        let end = x[x.len() - 1] as f64;
        let quad: f64 = (0..n).map(|i| spline(((i as f64 + 0.5) / n as f64 * end) as f32) * end / n as f64).sum();
        assert!((total as f64 - quad).abs() < 1e-4 * quad, "{total} vs {quad}");
        assert!(cdf.windows(2).all(|w| w[1] >= w[0]));
        for (i, &c) in cdf.iter().enumerate().skip(1).take(x.len() - 2) {
            assert!((invert_catmull_rom(&x, &cdf, c) - x[i]).abs() < 1e-4 * (1.0 + x[i]), "node {i}");
        }
        // Between nodes: inverting the spline through the running integrals gives back the
        // point where that spline has the value.
        let through_cdf = |v: f32| {
            let (o, w) = catmull_rom_weights(&x, v).unwrap();
            (0..4).filter(|&i| w[i] != 0.0).map(|i| w[i] * cdf[(o + i as isize) as usize]).sum::<f32>()
        };
        for k in 1..50 {
            let v = end as f32 * k as f32 / 50.0;
            let back = invert_catmull_rom(&x, &cdf, through_cdf(v));
            assert!((back - v).abs() < 1e-3 * (1.0 + v), "{v}: {back}");
        }
        assert_eq!(invert_catmull_rom(&x, &cdf, -1.0), x[0]);
        assert_eq!(invert_catmull_rom(&x, &cdf, 2.0 * total), x[x.len() - 1]);
    }

    /// Sampling a row of a two-parameter table, at an `α` between nodes: χ² of the samples over
    /// 20 bins against the spline's integral over each bin, and the returned density equals
    /// the spline over its integral.
    #[test]
    fn sampling_2d_follows_the_interpolated_row() {
        let (x, f) = table();
        let alphas = [0.0f32, 0.3, 0.7, 1.0];
        let mut values = Vec::new();
        let mut cdf = vec![0.0; x.len() * alphas.len()];
        for (k, &a) in alphas.iter().enumerate() {
            let row: Vec<f32> = f.iter().zip(&x).map(|(&v, &xv)| v * (1.0 + a * xv)).collect();
            integrate_catmull_rom(&x, &row, &mut cdf[k * x.len()..(k + 1) * x.len()]);
            values.extend(row);
        }
        let table = Spline2D { nodes1: &alphas, nodes2: &x, values: &values, cdf: &cdf };
        let alpha = 0.5f32;
        let (o, w) = catmull_rom_weights(&alphas, alpha).unwrap();
        let row = |v: f32| {
            let (o2, w2) = catmull_rom_weights(&x, v).unwrap();
            let mut s = 0.0f64;
            for (i, &wi) in w.iter().enumerate() {
                for (j, &wj) in w2.iter().enumerate() {
                    if wi != 0.0 && wj != 0.0 {
                        let idx = (o + i as isize) as usize * x.len() + (o2 + j as isize) as usize;
                        s += (wi * wj) as f64 * values[idx] as f64;
                    }
                }
            }
            s
        };
        let end = x[x.len() - 1];
        let bins = 20;
        let m = 2000;
        let mut expect = vec![0.0f64; bins];
        for (b, e) in expect.iter_mut().enumerate() {
            let (lo, hi) = (end * b as f32 / bins as f32, end * (b + 1) as f32 / bins as f32);
            *e = (0..m).map(|i| row(lo + (hi - lo) * (i as f32 + 0.5) / m as f32) * (hi - lo) as f64 / m as f64).sum();
        }
        let total: f64 = expect.iter().sum();
        let n = 100_000;
        let mut counts = vec![0usize; bins];
        let mut rng = Pcg32::new(4, 4);
        for _ in 0..n {
            let (v, fv, pdf) = table.sample(alpha, rng.next_f32()).unwrap();
            assert!((fv as f64 - row(v)).abs() < 1e-3 * (1.0 + row(v)), "value at {v}: {fv} vs {}", row(v));
            assert!((pdf as f64 - row(v) / total).abs() < 2e-3 * (1.0 + row(v) / total), "density at {v}");
            counts[((v / end * bins as f32) as usize).min(bins - 1)] += 1;
        }
        let chi2: f64 = counts
            .iter()
            .zip(&expect)
            .map(|(&c, &e)| {
                let e = e / total * n as f64;
                (c as f64 - e).powi(2) / e
            })
            .sum();
        // 19 degrees of freedom: p = 1e-4 at 50.
        assert!(chi2 < 50.0, "χ² {chi2}: {counts:?}");
        assert!(table.sample(1.5, 0.5).is_none());
    }
}
