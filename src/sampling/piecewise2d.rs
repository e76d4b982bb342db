//! Piecewise-constant 2D distribution by marginal and conditional densities (environment maps).
//!
//! A function tabulated on an `nu × nv` grid over `[0,1]²` has density
//! `p(u, v) = f(u, v) / ∫∫f`. Factor it as `p(u, v) = p_v(v) p(u | v)`: the **marginal**
//! `p_v(v) = ∫ p(u, v) du` (one piecewise-constant 1D distribution over the rows) and one
//! **conditional** `p(u | v) = p(u, v) / p_v(v)` per row. Sampling inverts the marginal with
//! `ξ₂` to pick the row, then that row's conditional with `ξ₁`. The density is per unit area of
//! the parameter square; a lat-long environment map converts it to solid angle with the
//! `1 / (2π² sin θ)` Jacobian.

use super::{PiecewiseConstant1D, Sample};
use crate::math::Vec2;

/// Piecewise-constant density on `[0,1]²` (row-major, `nv` rows of `nu` values).
#[derive(Clone, Debug)]
pub struct PiecewiseConstant2D {
    conditionals: Vec<PiecewiseConstant1D>,
    marginal: PiecewiseConstant1D,
    nu: usize,
    nv: usize,
}

impl PiecewiseConstant2D {
    /// Density proportional to `|func|` (row-major: `func[v * nu + u]`). `None` if the sizes
    /// disagree, a value is not finite, or the function is zero everywhere. Rows that are zero
    /// get a uniform conditional that is never selected (their marginal probability is 0).
    pub fn new(func: &[f32], nu: usize, nv: usize) -> Option<PiecewiseConstant2D> {
        if nu == 0 || nv == 0 || func.len() != nu * nv || func.iter().any(|f| !f.is_finite()) {
            return None;
        }
        let uniform = vec![1.0f32; nu];
        let mut row_integrals = Vec::with_capacity(nv);
        let conditionals = func
            .chunks_exact(nu)
            .map(|row| {
                let integral: f64 = row.iter().map(|f| f.abs() as f64).sum::<f64>() / nu as f64;
                row_integrals.push(integral as f32);
                PiecewiseConstant1D::new(row, 0.0, 1.0).or_else(|| PiecewiseConstant1D::new(&uniform, 0.0, 1.0))
            })
            .collect::<Option<Vec<_>>>()?;
        let marginal = PiecewiseConstant1D::new(&row_integrals, 0.0, 1.0)?;
        Some(PiecewiseConstant2D { conditionals, marginal, nu, nv })
    }

    /// Grid size `(nu, nv)`.
    pub fn resolution(&self) -> (usize, usize) {
        (self.nu, self.nv)
    }

    /// `∫∫f` over the unit square.
    pub fn integral(&self) -> f32 {
        self.marginal.integral()
    }

    /// A point of `[0,1)²` with density `f / ∫∫f` (area measure on the parameter square).
    /// Domain `u ∈ [0,1)²`: `u.y` picks the row (marginal), `u.x` the column (conditional).
    #[inline]
    pub fn sample(&self, u: Vec2) -> Sample<Vec2> {
        let (sv, row) = self.marginal.sample(u.y);
        let (su, _) = self.conditionals[row].sample(u.x);
        Sample::area(Vec2::new(su.value, sv.value), sv.pdf * su.pdf)
    }

    /// Density at `p` (area measure on the unit square; 0 outside it).
    #[inline]
    pub fn pdf(&self, p: Vec2) -> f32 {
        if !(0.0..=1.0).contains(&p.x) || !(0.0..=1.0).contains(&p.y) {
            return 0.0;
        }
        let iu = ((p.x * self.nu as f32) as usize).min(self.nu - 1);
        let iv = ((p.y * self.nv as f32) as usize).min(self.nv - 1);
        // p_v(v) p(u | v); zero rows have a marginal of 0 (their uniform conditional is unused).
        let row = &self.conditionals[iv];
        self.marginal.func(iv) / self.marginal.integral() * row.func(iu) / row.integral()
    }

    /// The `u` that [`Self::sample`] maps to `p` (where the density is positive).
    #[inline]
    pub fn invert(&self, p: Vec2) -> Vec2 {
        let iv = ((p.y * self.nv as f32) as usize).min(self.nv - 1);
        Vec2::new(self.conditionals[iv].invert(p.x), self.marginal.invert(p.y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{check_inverse, chi2_2d, integrate_pdf_2d, u2, Chi2Config, Rect};

    fn image() -> (Vec<f32>, usize, usize) {
        let (nu, nv) = (8usize, 6usize);
        let f = (0..nu * nv)
            .map(|k| {
                let (i, j) = (k % nu, k / nu);
                if j == 2 {
                    0.0 // a black row
                } else if i == 5 && j == 4 {
                    200.0 // a hot spot
                } else {
                    ((i * 13 + j * 7) % 5) as f32
                }
            })
            .collect();
        (f, nu, nv)
    }

    #[test]
    fn chi2_with_cells_aligned_to_texels() {
        let (f, nu, nv) = image();
        let d = PiecewiseConstant2D::new(&f, nu, nv).unwrap();
        // 40 × 30 cells: each lies in one texel (5 × 5 per texel).
        let out = chi2_2d(
            &Rect::UNIT,
            [40, 30],
            1_000_000,
            |r| Some(d.sample(u2(r)).value),
            |p| d.pdf(*p) as f64,
            &Chi2Config::default(),
        );
        assert!(out.passed(), "{out}");
        assert!((integrate_pdf_2d(&Rect::UNIT, [40, 30], |p| d.pdf(*p) as f64) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn sample_matches_pdf_and_inverts() {
        let (f, nu, nv) = image();
        let d = PiecewiseConstant2D::new(&f, nu, nv).unwrap();
        let mut r = crate::sampling::Pcg32::new(3, 3);
        for _ in 0..50_000 {
            let s = d.sample(u2(&mut r));
            assert!(s.pdf > 0.0);
            assert!((s.pdf - d.pdf(s.value)).abs() < 1e-4 * s.pdf, "{s:?} vs {}", d.pdf(s.value));
        }
        let e = check_inverse(50_000, 1, 1e-4, |u| Some(d.sample(u).value), |p| Some(d.invert(*p)));
        assert!(e < 1e-3, "{e}");
        assert!(PiecewiseConstant2D::new(&[0.0; 4], 2, 2).is_none());
        assert!(PiecewiseConstant2D::new(&[1.0; 3], 2, 2).is_none());
    }
}
