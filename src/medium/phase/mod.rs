//! Phase functions: the angular distribution of light scattered in a medium, per unit solid
//! angle (sr⁻¹), normalised over the sphere. They are perfectly importance-sampled, so
//! `eval = pdf` and the sampling weight is 1.
//!
//! Convention (Mitsuba 3): `wo` points back toward where the light goes (the previous path
//! vertex, `-ray.d`), `wi` toward where it comes from (the next vertex); both world, unit.
//! Forward scattering (light continuing straight on) is `wi = -wo`; the deflection angle θ is
//! measured from there, `cos θ = -wo·wi`.
//!
//! | Mitsuba plugin | variant | file |
//! |---|---|---|
//! | `isotropic`, `hg`, `rayleigh` | [`PhaseFunction::Isotropic`], [`PhaseFunction::HenyeyGreenstein`], [`PhaseFunction::Rayleigh`] | here |
//! | `tabphase` | [`PhaseFunction::Tabulated`] | [`tabulated`] |
//! | `blendphase` | [`PhaseFunction::Blend`] | [`blend`] |
//! | `sggx` | [`PhaseFunction::Sggx`] | [`sggx`] |

pub mod blend;
pub mod sggx;
pub mod tabulated;

pub use blend::BlendPhase;
pub use sggx::SggxPhase;
pub use tabulated::TabulatedPhase;

use crate::image::VolumeSource;
use crate::math::{Frame, Vec2, Vec3, INV_4PI, PI};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::{sample_uniform_sphere, Sample};
use std::sync::Arc;

/// A phase function (closed set).
#[derive(Clone, Debug)]
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
    /// Mitsuba's `rayleigh`: scattering by particles much smaller than the wavelength,
    /// `p(θ) = 3 (1 + cos² θ) / (16 π)`, as much forward as backward.
    Rayleigh,
    /// Mitsuba's `tabphase`: a table over `cos θ`.
    Tabulated(Arc<TabulatedPhase>),
    /// Mitsuba's `blendphase`: a mixture of two phase functions by a weight that may vary in
    /// space.
    Blend(Arc<BlendPhase>),
    /// Mitsuba's `sggx`: specular microflakes of the SGGX distribution, a matrix per point; its
    /// medium's extinction depends on direction ([`SggxPhase`]).
    Sggx(Arc<SggxPhase>),
}

impl PhaseFunction {
    /// Density of scattering from `wo` into `wi` at the world point `p` (sr⁻¹), which is also
    /// the sampling pdf. Only a blend with a spatially varying weight reads `p`.
    #[inline]
    pub fn eval(&self, p: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            PhaseFunction::Isotropic => INV_4PI,
            // Light arrives travelling along -wi and leaves along wo: cos θ = (-wi)·wo.
            PhaseFunction::HenyeyGreenstein { g } => hg(-wo.dot(wi), *g),
            PhaseFunction::Rayleigh => rayleigh(-wo.dot(wi)),
            PhaseFunction::Tabulated(t) => t.eval(-wo.dot(wi)),
            PhaseFunction::Blend(b) => b.eval(p, wo, wi),
            PhaseFunction::Sggx(s) => s.eval(p, wo, wi),
        }
    }

    /// Samples `wi` for `wo` at `p` from `u ∈ [0,1)²`; the pdf equals [`PhaseFunction::eval`].
    #[inline]
    pub fn sample(&self, p: Vec3, wo: Vec3, u: Vec2) -> Sample<Vec3> {
        match self {
            PhaseFunction::Isotropic => sample_uniform_sphere(u),
            PhaseFunction::HenyeyGreenstein { g } => {
                let g = *g;
                // Invert the CDF of cos θ (pbrt-v4 §11.3.1): for |g| small it is uniform.
                let cos = if g.abs() < 1e-3 {
                    1.0 - 2.0 * u.x
                } else {
                    let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u.x);
                    ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
                };
                Sample::solid_angle(deflect(wo, cos, u.y), hg(cos, g))
            }
            PhaseFunction::Rayleigh => {
                let cos = sample_rayleigh_cos(u.x);
                Sample::solid_angle(deflect(wo, cos, u.y), rayleigh(cos))
            }
            PhaseFunction::Tabulated(t) => {
                let (cos, pdf) = t.sample_cos(u.x);
                Sample::solid_angle(deflect(wo, cos, u.y), pdf)
            }
            PhaseFunction::Blend(b) => b.sample(p, wo, u),
            PhaseFunction::Sggx(s) => s.sample(p, wo, u),
        }
    }

    /// Mean cosine of the deflection angle at `p` (0 for isotropic and Rayleigh scattering);
    /// `None` where it depends on the direction of travel (SGGX, also inside a blend).
    pub fn mean_cosine(&self, p: Vec3) -> Option<f32> {
        match self {
            PhaseFunction::Isotropic | PhaseFunction::Rayleigh => Some(0.0),
            PhaseFunction::HenyeyGreenstein { g } => Some(*g),
            PhaseFunction::Tabulated(t) => Some(t.mean_cosine()),
            PhaseFunction::Blend(b) => b.mean_cosine(p),
            PhaseFunction::Sggx(_) => None,
        }
    }

    /// The SGGX flakes whose projected area scales the medium's extinction (Mitsuba's
    /// `Microflake` phase functions), if this is one.
    pub fn microflakes(&self) -> Option<&Arc<SggxPhase>> {
        match self {
            PhaseFunction::Sggx(s) => Some(s),
            _ => None,
        }
    }
}

/// The direction deflected from the forward one (`-wo`) by an angle of cosine `cos`, at azimuth
/// `2π u_phi` about it.
#[inline]
fn deflect(wo: Vec3, cos: f32, u_phi: f32) -> Vec3 {
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u_phi;
    Frame::from_z(-wo).to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos))
}

/// Henyey–Greenstein density for the cosine of the deflection angle.
#[inline]
fn hg(cos: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    INV_4PI * (1.0 - g * g) / (denom * denom.max(1e-12).sqrt())
}

/// Rayleigh density `3 (1 + cos²) / 16π` for the cosine of the deflection angle.
#[inline]
fn rayleigh(cos: f32) -> f32 {
    3.0 / (16.0 * PI) * (1.0 + cos * cos)
}

/// `cos θ` of Rayleigh scattering by inverting its CDF `F(μ) = (μ³ + 3μ + 4) / 8` (Mitsuba's
/// closed form): `μ³ + 3μ - 2z = 0` with `z = 4u - 2` has the one real root
/// `∛(z + √(z² + 1)) + ∛(z - √(z² + 1))` (Cardano).
#[inline]
fn sample_rayleigh_cos(u: f32) -> f32 {
    let z = 2.0 * (2.0 * u - 1.0);
    let root = (z * z + 1.0).sqrt();
    ((z + root).cbrt() + (z - root).cbrt()).clamp(-1.0, 1.0)
}

/// Every phase plugin by its (Mitsuba) name.
const PHASE_PLUGINS: &[&str] = &["isotropic", "hg", "rayleigh", "tabphase", "blendphase", "sggx"];

impl PhaseFunction {
    /// Mitsuba's phase plugins: `isotropic`; `hg` with `g` (0.8, in (-1, 1)); `rayleigh`;
    /// `tabphase` with `values` (see [`TabulatedPhase::from_props`]); `blendphase` with
    /// `weight` and two nested phases (see [`BlendPhase::from_props`]); `sggx` with its `S`
    /// grid ([`SggxPhase::from_props`]). `files` reads grid volumes.
    pub fn from_props(p: &Obj, files: &mut dyn VolumeSource) -> PropResult<PhaseFunction> {
        p.built.set(true);
        match p.ty.as_str() {
            "blendphase" => return Ok(PhaseFunction::Blend(Arc::new(BlendPhase::from_props(p, files)?))),
            "sggx" => return Ok(PhaseFunction::Sggx(Arc::new(SggxPhase::from_props(p, files)?))),
            "isotropic" | "hg" | "rayleigh" | "tabphase" => p.check_children(&[])?,
            _ => {}
        }
        match p.ty.as_str() {
            "isotropic" => Ok(PhaseFunction::Isotropic),
            "hg" => {
                let g = p.float_checked("g", 0.8, |g| g > -1.0 && g < 1.0, "a number in (-1, 1)")?;
                Ok(PhaseFunction::HenyeyGreenstein { g })
            }
            "rayleigh" => Ok(PhaseFunction::Rayleigh),
            "tabphase" => Ok(PhaseFunction::Tabulated(Arc::new(TabulatedPhase::from_props(p)?))),
            _ => Err(p.unknown_plugin(PHASE_PLUGINS)),
        }
    }
}

/// The `(wo, wi)` pairs (not normalised) at which `tools/mitsuba/phase_values.py` prints
/// Mitsuba's densities, for the tests that compare with them.
#[cfg(test)]
pub(crate) const PROBE_PAIRS: [([f32; 3], [f32; 3]); 5] = [
    ([0.0, 0.0, 1.0], [0.0, 0.0, -1.0]),
    ([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]),
    ([0.3, -0.5, 0.81], [0.7, 0.1, -0.2]),
    ([0.6, 0.0, 0.8], [0.0, 1.0, 0.0]),
    ([1.0, 2.0, 3.0], [-1.0, 0.5, 0.2]),
];

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::GridVolume;
    use crate::math::Transform;
    use crate::medium::volume::{GridFilter, GridWrap, Volume};
    use crate::testkit::{chi2_2d, integrate_pdf_2d, u2, Chi2Config, SPHERE};

    fn tabulated(values: &[f32]) -> PhaseFunction {
        PhaseFunction::Tabulated(Arc::new(TabulatedPhase::new(values).unwrap()))
    }

    fn blend(w: f32, a: PhaseFunction, b: PhaseFunction) -> PhaseFunction {
        PhaseFunction::Blend(Arc::new(BlendPhase::new(Volume::constant(Rgb::splat(w), Transform::IDENTITY), [a, b])))
    }

    /// A blend whose weight is a 2×1×1 grid over the unit cube: 0 at x = 0 rising to 1.5 at
    /// x = 1 (clamped to 1 from x = 2/3 on).
    fn varying_blend() -> PhaseFunction {
        let grid = GridVolume { res: [2, 1, 1], channels: 1, bbox: [[0.0; 3], [1.0; 3]], data: vec![0.0, 1.5] };
        let weight = Volume::grid(Arc::new(grid), GridFilter::Trilinear, GridWrap::Clamp, Transform::IDENTITY).unwrap();
        let phases = [PhaseFunction::HenyeyGreenstein { g: 0.8 }, tabulated(&[3.0, 0.5, 0.1, 0.0, 1.0])];
        PhaseFunction::Blend(Arc::new(BlendPhase::new(weight, phases)))
    }

    use crate::math::Rgb;

    /// SGGX flakes of the matrices `texels` along x (one texel: everywhere).
    fn sggx(texels: &[[f32; 6]]) -> PhaseFunction {
        let grid = GridVolume {
            res: [texels.len(), 1, 1],
            channels: 6,
            bbox: [[0.0; 3], [1.0; 3]],
            data: texels.iter().flatten().copied().collect(),
        };
        let s = crate::texture::volume::Volume6::grid(
            Arc::new(grid),
            GridFilter::Trilinear,
            GridWrap::Clamp,
            Transform::IDENTITY,
        );
        PhaseFunction::Sggx(Arc::new(SggxPhase::new(s.unwrap())))
    }

    /// Every phase function at a few points: samples follow the density (χ² over the sphere,
    /// around an arbitrary `wo`), the density integrates to one, each sample's pdf is the
    /// density at it, and the samples' mean cosine of deflection is `mean_cosine`. Isotropic,
    /// forward and backward HG lobes, Rayleigh, tables (a forward peak with a back lobe, one with
    /// a zero segment), constant blends (including weights 0 and 1), a blend whose weight
    /// varies in space (read at three points, one where it is clamped), and SGGX flakes (three
    /// matrices, one with eigenvalues above 1, and flakes varying in space).
    #[test]
    fn sampling_matches_eval_and_pdf_integrates_to_one() {
        let wo = Vec3::new(0.3, -0.5, 0.81).normalize();
        let origin = Vec3::ZERO;
        let cases = [
            (PhaseFunction::Isotropic, origin),
            (PhaseFunction::HenyeyGreenstein { g: 0.7 }, origin),
            (PhaseFunction::HenyeyGreenstein { g: -0.4 }, origin),
            (PhaseFunction::HenyeyGreenstein { g: 0.0005 }, origin),
            (PhaseFunction::Rayleigh, origin),
            (tabulated(&[1.5, 0.3, 0.2, 0.3, 0.8, 3.0, 10.0]), origin),
            (tabulated(&[0.0, 0.0, 2.0, 1.0]), origin),
            (blend(0.3, PhaseFunction::HenyeyGreenstein { g: 0.6 }, PhaseFunction::Rayleigh), origin),
            (blend(0.0, PhaseFunction::Rayleigh, PhaseFunction::HenyeyGreenstein { g: -0.9 }), origin),
            (blend(1.0, PhaseFunction::Rayleigh, PhaseFunction::HenyeyGreenstein { g: -0.9 }), origin),
            (varying_blend(), Vec3::new(0.1, 0.5, 0.5)),
            (varying_blend(), Vec3::new(0.4, 0.5, 0.5)),
            (varying_blend(), Vec3::new(0.9, 0.5, 0.5)),
            (sggx(&[[1.0, 0.2, 0.05, 0.0, 0.0, 0.0]]), origin),
            (sggx(&[[0.6, 0.5, 0.3, 0.2, -0.1, 0.15]]), origin),
            (sggx(&[[2.5, 0.4, 1.2, 0.3, 0.5, -0.2]]), origin),
            // Surface-like flakes varying in space (a 2×1×1 grid), read between its texels.
            (sggx(&[[0.05, 0.05, 1.0, 0.0, 0.0, 0.0], [1.0, 0.1, 0.1, 0.0, 0.2, 0.0]]), Vec3::new(0.4, 0.5, 0.5)),
        ];
        for (k, (phase, p)) in cases.into_iter().enumerate() {
            let integral = integrate_pdf_2d(&SPHERE, [32, 64], |w| phase.eval(p, wo, *w) as f64);
            assert!((integral - 1.0).abs() < 2e-3, "{phase:?}: ∫ p = {integral}");
            let out = chi2_2d(
                &SPHERE,
                [51, 101],
                400_000,
                |r| Some(phase.sample(p, wo, u2(r)).value),
                |w| phase.eval(p, wo, *w) as f64,
                &Chi2Config::default().with_seed(k as u64),
            );
            assert!(out.passed(), "{phase:?} at {p}: {out}");
            let mut rng = crate::sampling::Pcg32::new(9, k as u64);
            let n = 200_000;
            let mut mean = 0.0f64;
            for _ in 0..n {
                let s = phase.sample(p, wo, u2(&mut rng));
                assert!(s.pdf > 0.0, "{phase:?}: a sample of zero density");
                assert!((s.pdf - phase.eval(p, wo, s.value)).abs() <= 1e-3 * s.pdf.max(1.0), "{phase:?}");
                mean += (-wo).dot(s.value) as f64;
            }
            mean /= n as f64;
            if let Some(want) = phase.mean_cosine(p) {
                assert!((mean - want as f64).abs() < 0.01, "{phase:?} at {p}: mean cosine {mean}");
            }
        }
    }

    /// The densities Mitsuba 3.9.1 gives for the same phase functions and directions
    /// (`tools/mitsuba/phase_values.py`): Rayleigh, a table (values separated by commas and
    /// spaces), a blend with a constant weight and one whose weight is an RGB volume (Mitsuba
    /// weighs by the channels' mean).
    #[test]
    fn matches_mitsuba_densities() {
        let pairs = PROBE_PAIRS;
        let rgb_weight = Volume::constant(Rgb::new(0.2, 0.4, 0.9), Transform::IDENTITY);
        let cases = [
            (PhaseFunction::Rayleigh, [0.1193662, 0.1193662, 0.05968354, 0.0596831, 0.0608728]),
            (
                tabulated(&[1.5, 0.3, 0.2, 0.3, 0.8, 3.0, 10.0]),
                [0.4613186, 0.0691978, 0.01402826, 0.01383956, 0.0118856],
            ),
            (
                blend(0.3, PhaseFunction::HenyeyGreenstein { g: 0.6 }, PhaseFunction::Rayleigh),
                [0.5928523, 0.04451365, 0.04046455, 0.04038304, 0.03711033],
            ),
            (
                PhaseFunction::Blend(Arc::new(BlendPhase::new(
                    rgb_weight,
                    [PhaseFunction::Isotropic, tabulated(&[0.0, 1.0])],
                ))),
                [0.1193662, 0.03978873, 0.07968597, 0.07957747, 0.07395984],
            ),
        ];
        for (phase, expected) in cases {
            for ((wo, wi), want) in pairs.iter().zip(expected) {
                let (wo, wi) = (Vec3::from(*wo).normalize(), Vec3::from(*wi).normalize());
                let got = phase.eval(Vec3::new(0.2, 0.3, 0.4), wo, wi);
                assert!((got - want).abs() <= 2e-5 * want, "{phase:?} {wo} {wi}: {got} vs Mitsuba's {want}");
            }
        }
    }
}
