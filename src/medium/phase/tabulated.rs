//! Mitsuba's `tabphase`: a phase function given as a table of values over the cosine of the
//! deflection angle, `cos θ ∈ [-1, 1]` at evenly spaced nodes (`-1` backward, `+1` forward),
//! linear between them. The table is normalised, so only its shape matters:
//! `p(θ) = f(cos θ) / (2π ∫₋₁¹ f)`. Sampled exactly (the CDF of a piecewise-linear density, see
//! [`PiecewiseLinear1D`]) with a uniform azimuth.

use crate::math::INV_2PI;
use crate::props::{Obj, Result as PropResult};
use crate::sampling::PiecewiseLinear1D;

/// A tabulated phase function.
#[derive(Clone, Debug, PartialEq)]
pub struct TabulatedPhase {
    /// The density of `cos θ` on `[-1, 1]`.
    cos: PiecewiseLinear1D,
}

impl TabulatedPhase {
    /// From the table's values at evenly spaced cosines from -1 to 1 (at least two, finite,
    /// non-negative, not all zero; otherwise the reason).
    pub fn new(values: &[f32]) -> Result<TabulatedPhase, String> {
        Ok(TabulatedPhase { cos: PiecewiseLinear1D::new(values, -1.0, 1.0)? })
    }

    /// Density (sr⁻¹) at the deflection cosine `cos` (clamped to [-1, 1] against round-off).
    #[inline]
    pub fn eval(&self, cos: f32) -> f32 {
        self.cos.pdf(cos.clamp(-1.0, 1.0)) * INV_2PI
    }

    /// A deflection cosine from `u ∈ [0, 1)` and the density (sr⁻¹) of the directions it stands
    /// for (with a uniform azimuth).
    #[inline]
    pub fn sample_cos(&self, u: f32) -> (f32, f32) {
        let s = self.cos.sample(u);
        (s.value, s.pdf * INV_2PI)
    }

    /// Mean cosine of the deflection.
    pub fn mean_cosine(&self) -> f32 {
        self.cos.mean() as f32
    }

    /// `tabphase` with `values`: a string of numbers separated by commas and/or spaces.
    pub fn from_props(o: &Obj) -> PropResult<TabulatedPhase> {
        let text = o.string("values")?;
        let values = text
            .split([',', ' ', '\t', '\n', '\r'])
            .filter(|t| !t.is_empty())
            .map(|t| t.parse::<f32>().map_err(|_| o.error_at("values", format!("'{t}' is not a number"))))
            .collect::<PropResult<Vec<f32>>>()?;
        TabulatedPhase::new(&values).map_err(|e| o.error_at("values", format!("the table {e}")))
    }
}
