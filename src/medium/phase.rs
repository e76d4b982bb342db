//! Phase functions: the angular distribution of light scattered in a medium, per unit solid
//! angle (sr⁻¹), normalised over the sphere. They are perfectly importance-sampled, so
//! `eval = pdf` and the sampling weight is 1.
//!
//! Convention (Mitsuba 3): `wo` points back toward where the light goes (the previous path
//! vertex, `-ray.d`), `wi` toward where it comes from (the next vertex); both world, unit.
//! Forward scattering (light continuing straight on) is `wi = -wo`.

use crate::math::{Frame, Vec2, Vec3, INV_4PI, PI};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::{sample_uniform_sphere, Sample};

/// A phase function (closed set).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhaseFunction {
    /// Mitsuba's `isotropic`: `1 / 4π`.
    Isotropic,
    /// Mitsuba's `hg` (Henyey–Greenstein) with mean cosine `g ∈ (-1, 1)`: `g > 0` scatters
    /// forward. `p(θ) = (1 - g²) / (4π (1 + g² - 2 g cos θ)^{3/2})` with θ the deflection
    /// angle (between the light's old and new directions).
    HenyeyGreenstein {
        /// Mean cosine of the deflection.
        g: f32,
    },
}

impl PhaseFunction {
    /// Density of scattering from `wo` into `wi` (sr⁻¹), which is also the sampling pdf.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            PhaseFunction::Isotropic => INV_4PI,
            // Light arrives travelling along -wi and leaves along wo: cos θ = (-wi)·wo.
            PhaseFunction::HenyeyGreenstein { g } => hg(-wo.dot(wi), g),
        }
    }

    /// Samples `wi` for `wo` from `u ∈ [0,1)²`; the pdf equals [`PhaseFunction::eval`].
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> Sample<Vec3> {
        match *self {
            PhaseFunction::Isotropic => sample_uniform_sphere(u),
            PhaseFunction::HenyeyGreenstein { g } => {
                // Invert the CDF of cos θ (pbrt-v4 §11.3.1): for |g| small it is uniform.
                let cos = if g.abs() < 1e-3 {
                    1.0 - 2.0 * u.x
                } else {
                    let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u.x);
                    ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
                };
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                let phi = 2.0 * PI * u.y;
                // θ is measured from -wo (forward: wi = -wo).
                let wi = Frame::from_z(-wo).to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos));
                Sample::solid_angle(wi, hg(cos, g))
            }
        }
    }

    /// Mean cosine of the deflection angle (0 for isotropic).
    pub fn mean_cosine(&self) -> f32 {
        match *self {
            PhaseFunction::Isotropic => 0.0,
            PhaseFunction::HenyeyGreenstein { g } => g,
        }
    }
}

/// Henyey–Greenstein density for the cosine of the deflection angle.
#[inline]
fn hg(cos: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    INV_4PI * (1.0 - g * g) / (denom * denom.max(1e-12).sqrt())
}

impl PhaseFunction {
    /// Mitsuba's phase plugins: `isotropic`, and `hg` with `g` (0.8, in (-1, 1)).
    pub fn from_props(p: &Obj) -> PropResult<PhaseFunction> {
        p.built.set(true);
        p.check_children(&[])?;
        match p.ty.as_str() {
            "isotropic" => Ok(PhaseFunction::Isotropic),
            "hg" => {
                let g = p.float_checked("g", 0.8, |g| g > -1.0 && g < 1.0, "a number in (-1, 1)")?;
                Ok(PhaseFunction::HenyeyGreenstein { g })
            }
            _ => Err(p.unknown_plugin(&["isotropic", "hg"])),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testkit::{chi2_2d, integrate_pdf_2d, u2, Chi2Config, SPHERE};

    /// Samples follow the density (χ² over the sphere), for isotropic and for forward and
    /// backward HG lobes around an arbitrary `wo`; the density integrates to one; the mean
    /// cosine of the deflection is g.
    #[test]
    fn sampling_matches_eval_and_pdf_integrates_to_one() {
        let wo = Vec3::new(0.3, -0.5, 0.81).normalize();
        for (k, phase) in [
            PhaseFunction::Isotropic,
            PhaseFunction::HenyeyGreenstein { g: 0.7 },
            PhaseFunction::HenyeyGreenstein { g: -0.4 },
            PhaseFunction::HenyeyGreenstein { g: 0.0005 },
        ]
        .into_iter()
        .enumerate()
        {
            let integral = integrate_pdf_2d(&SPHERE, [32, 64], |w| phase.eval(wo, *w) as f64);
            assert!((integral - 1.0).abs() < 2e-3, "{phase:?}: ∫ p = {integral}");
            let out = chi2_2d(
                &SPHERE,
                [51, 101],
                400_000,
                |r| Some(phase.sample(wo, u2(r)).value),
                |w| phase.eval(wo, *w) as f64,
                &Chi2Config::default().with_seed(k as u64),
            );
            assert!(out.passed(), "{phase:?}: {out}");
            let mut rng = crate::sampling::Pcg32::new(9, k as u64);
            let n = 200_000;
            let mut mean = 0.0f64;
            for _ in 0..n {
                let s = phase.sample(wo, u2(&mut rng));
                assert!((s.pdf - phase.eval(wo, s.value)).abs() <= 1e-3 * s.pdf.max(1.0), "{phase:?}");
                mean += (-wo).dot(s.value) as f64;
            }
            mean /= n as f64;
            assert!((mean - phase.mean_cosine() as f64).abs() < 0.01, "{phase:?}: mean cosine {mean}");
        }
    }
}
