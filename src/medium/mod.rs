//! Participating media: Mitsuba's `homogeneous` medium with a phase function ([`phase`]).
//!
//! A medium has extinction `σₜ` (m⁻¹, per colour channel), single-scattering albedo
//! `α = σₛ / σₜ` and a phase function. Along a ray, the transmittance over a distance t is
//! `Tr(t) = e^(-σₜ t)` and the free-flight distance to the next interaction has the exponential
//! density `σₜ e^(-σₜ t)`, sampled by inversion `t = -ln(1 - ξ) / σₜ`
//! ([`crate::sampling::sample_exponential`]).
//!
//! Colour: the three channels have different `σₜ`; a channel is chosen uniformly for each
//! distance, and the density used is the average over channels (one-sample MIS over the
//! channels, as Mitsuba's RGB modes), so every channel's estimate stays unbiased.
//!
//! Media sit inside shapes (`interior`, `exterior` on the shape) and around the camera (the
//! sensor's medium). A shape with a `null` BSDF is an index-matched boundary: rays cross it and
//! change medium.

pub mod phase;

pub use phase::PhaseFunction;

use crate::math::spectrum::SpectrumKind;
use crate::math::Rgb;
use crate::props::{Obj, Result as PropResult, SceneError};
use crate::sampling::sample_exponential;

/// A homogeneous participating medium.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// Extinction coefficient σₜ (m⁻¹ per channel).
    pub sigma_t: Rgb,
    /// Single-scattering albedo σₛ/σₜ per channel, in [0, 1].
    pub albedo: Rgb,
    /// Phase function.
    pub phase: PhaseFunction,
}

/// What a free-flight sample found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FreeFlight {
    /// A scattering event at distance `t`; `weight = σₛ Tr(t) / p(t)` multiplies the path
    /// throughput (absorption included: the path continues with the scattered fraction).
    Scatter {
        /// Distance along the (unit-direction) ray.
        t: f32,
        /// Throughput factor.
        weight: Rgb,
    },
    /// No interaction before `t_max` (the next surface); `weight = Tr(t_max) / P(pass)`.
    Pass {
        /// Throughput factor.
        weight: Rgb,
    },
}

impl Medium {
    /// A homogeneous medium; `None` unless σₜ ≥ 0 and the albedo lies in [0, 1].
    pub fn new(sigma_t: Rgb, albedo: Rgb, phase: PhaseFunction) -> Option<Medium> {
        let ok = (0..3).all(|c| sigma_t[c] >= 0.0 && sigma_t[c].is_finite() && (0.0..=1.0).contains(&albedo[c]));
        ok.then_some(Medium { sigma_t, albedo, phase })
    }

    /// Transmittance `e^(-σₜ t)` over distance `t` (per channel).
    #[inline]
    pub fn transmittance(&self, t: f32) -> Rgb {
        if t.is_infinite() {
            return Rgb::new(
                f32::from(self.sigma_t.x == 0.0),
                f32::from(self.sigma_t.y == 0.0),
                f32::from(self.sigma_t.z == 0.0),
            );
        }
        Rgb::new((-self.sigma_t.x * t).exp(), (-self.sigma_t.y * t).exp(), (-self.sigma_t.z * t).exp())
    }

    /// Samples the distance to the next interaction along a ray with unit direction, up to
    /// `t_max` (possibly infinite). `u_channel` picks the channel, `u` the distance.
    #[inline]
    pub fn sample_free_flight(&self, t_max: f32, u_channel: f32, u: f32) -> FreeFlight {
        let c = ((u_channel * 3.0) as usize).min(2);
        let sigma = self.sigma_t[c];
        let t = if sigma > 0.0 { sample_exponential(u, sigma).value } else { f32::INFINITY };
        if t < t_max {
            let tr = self.transmittance(t);
            // p(t) = mean over channels of σ_c e^(-σ_c t).
            let pdf = (self.sigma_t * tr).element_sum() / 3.0;
            let weight = if pdf > 0.0 { self.sigma_t * self.albedo * tr / pdf } else { Rgb::ZERO };
            FreeFlight::Scatter { t, weight }
        } else {
            let tr = self.transmittance(t_max);
            // P(pass) = mean over channels of e^(-σ_c t_max).
            let p = tr.element_sum() / 3.0;
            FreeFlight::Pass { weight: if p > 0.0 { tr / p } else { Rgb::ZERO } }
        }
    }
}

/// A medium plugin's constructor.
pub type MediumPlugin = fn(&Obj) -> PropResult<Medium>;

/// Every medium plugin by its (Mitsuba) name.
pub const MEDIUM_PLUGINS: &[(&str, MediumPlugin)] = &[("homogeneous", Medium::from_props)];

impl Medium {
    /// Mitsuba's `homogeneous`: `sigma_t` (1 m⁻¹) × `scale` (1), `albedo` (0.75), and one nested
    /// `<phase>` (isotropic if none; see [`PhaseFunction::from_props`]).
    pub fn from_props(o: &Obj) -> PropResult<Medium> {
        o.check_children(&["phase"])?;
        let scale = o.float_checked("scale", 1.0, |s| s >= 0.0 && s.is_finite(), "a non-negative number")?;
        let sigma_t = o.rgb("sigma_t", Rgb::ONE, SpectrumKind::Illuminant)? * scale;
        if !(0..3).all(|c| sigma_t[c] >= 0.0 && sigma_t[c].is_finite()) {
            return Err(o.error_at("sigma_t", format!("sigma_t must be non-negative, got {sigma_t}")));
        }
        let albedo = o.rgb("albedo", Rgb::splat(0.75), SpectrumKind::Reflectance)?;
        if !(0..3).all(|c| (0.0..=1.0).contains(&albedo[c])) {
            return Err(o.error_at("albedo", format!("albedo must lie in [0, 1], got {albedo}")));
        }
        let phases = o.nested("phase");
        if phases.len() > 1 {
            return Err(SceneError::at(&phases[1].loc, "a medium takes one <phase>"));
        }
        let phase = match phases.first() {
            None => PhaseFunction::Isotropic,
            Some(p) => PhaseFunction::from_props(p)?,
        };
        Medium::new(sigma_t, albedo, phase).ok_or_else(|| o.error("invalid medium parameters"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;

    /// The free-flight estimator is unbiased per channel for a medium whose channels differ:
    /// `E[weight · 1(pass)] = Tr(t_max)` and `E[weight · 1(scatter)] = ∫₀^t_max σₛ Tr(t) dt =
    /// α (1 - Tr(t_max))`.
    #[test]
    fn free_flight_is_unbiased_per_channel() {
        let m = Medium::new(Rgb::new(0.5, 2.0, 4.0), Rgb::new(0.9, 0.5, 0.2), PhaseFunction::Isotropic).unwrap();
        let t_max = 0.7f32;
        let mut rng = Pcg32::new(1, 2);
        let n = 400_000;
        let (mut pass, mut scatter) = ([0.0f64; 3], [0.0f64; 3]);
        for _ in 0..n {
            match m.sample_free_flight(t_max, rng.next_f32(), rng.next_f32()) {
                FreeFlight::Pass { weight } => (0..3).for_each(|c| pass[c] += weight[c] as f64),
                FreeFlight::Scatter { t, weight } => {
                    assert!(t >= 0.0 && t < t_max);
                    (0..3).for_each(|c| scatter[c] += weight[c] as f64)
                }
            }
        }
        for c in 0..3 {
            let tr = (-(m.sigma_t[c] as f64) * t_max as f64).exp();
            let (p, s) = (pass[c] / n as f64, scatter[c] / n as f64);
            assert!((p - tr).abs() < 0.01 * tr, "channel {c}: pass {p} vs {tr}");
            let expect = m.albedo[c] as f64 * (1.0 - tr);
            assert!((s - expect).abs() < 0.01 * expect, "channel {c}: scatter {s} vs {expect}");
        }
        assert!(Medium::new(Rgb::ONE, Rgb::splat(1.5), PhaseFunction::Isotropic).is_none());
        assert!(Medium::new(Rgb::splat(-1.0), Rgb::ONE, PhaseFunction::Isotropic).is_none());
    }
}
