//! Sine and cosine for the sampling warps, by polynomials instead of a libm call.
//!
//! The warps need `sin`/`cos` of angles they build themselves: `2π u` for `u ∈ [0, 1)` and the
//! concentric map's wedge angle in `[-π/4, π/4]`. On `[-π/4, π/4]` the Taylor series of sine
//! to degree 9 and of cosine to degree 8 are exact to below 3·10⁻⁸ (truncation error
//! `x¹¹/11!` and `x¹⁰/10!` at `π/4`), i.e. within an ulp or two of `f32` after Horner
//! evaluation; `2π u` is first reduced to that interval by quadrant, exactly in `u`.

use std::f32::consts::TAU;

/// `(sin x, cos x)` for `|x| ≤ π/4` (absolute error below 2·10⁻⁷; larger `x` lose accuracy).
#[inline(always)]
pub fn sin_cos_quarter(x: f32) -> (f32, f32) {
    let x2 = x * x;
    // sin x = x (1 - x²/3! + x⁴/5! - x⁶/7! + x⁸/9!)
    let s = x * (1.0 + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0)))));
    // cos x = 1 - x²/2! + x⁴/4! - x⁶/6! + x⁸/8!
    let c = 1.0 + x2 * (-0.5 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40_320.0))));
    (s, c)
}

/// `(sin 2πu, cos 2πu)` for `u ∈ [0, 1]` (absolute error below 2·10⁻⁷): `u` is split into a
/// quarter turn `q` and a remainder `r ∈ [-1/8, 1/8]` (exact in `f32`), the remainder's sine
/// and cosine come from [`sin_cos_quarter`] and are rotated by `q` quarter turns.
#[inline(always)]
pub fn sin_cos_2pi(u: f32) -> (f32, f32) {
    let q = super::round(4.0 * u);
    let (s, c) = sin_cos_quarter(TAU * (u - 0.25 * q));
    match q as i32 & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_matches_f64_on_its_interval() {
        let mut worst = 0.0f64;
        for k in -100_000..=100_000 {
            let x = k as f32 / 100_000.0 * std::f32::consts::FRAC_PI_4;
            let (s, c) = sin_cos_quarter(x);
            let (es, ec) = (x as f64).sin_cos();
            worst = worst.max((s as f64 - es).abs()).max((c as f64 - ec).abs());
        }
        assert!(worst < 2e-7, "{worst}");
    }

    #[test]
    fn full_turn_matches_f64_including_quadrant_edges() {
        let mut worst = 0.0f64;
        let edges = [0.0f32, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875, 1.0 - f32::EPSILON / 2.0, 1.0];
        let grid = (0..=200_000).map(|k| k as f32 / 200_000.0);
        let near_edges = edges.iter().flat_map(|&e| [e, f32::from_bits(e.to_bits().saturating_sub(1)), e + 1e-7]);
        for u in grid.chain(near_edges).filter(|u| (0.0..=1.0).contains(u)) {
            let (s, c) = sin_cos_2pi(u);
            let (es, ec) = (std::f64::consts::TAU * u as f64).sin_cos();
            worst = worst.max((s as f64 - es).abs()).max((c as f64 - ec).abs());
        }
        assert!(worst < 2e-7, "{worst}");
    }
}
