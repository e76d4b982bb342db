//! Mitsuba's `homogeneous` medium: constant extinction `σₜ` (m⁻¹, per colour channel) and
//! single-scattering albedo `α = σₛ / σₜ` everywhere inside the shapes that hold it.
//!
//! Along a ray the transmittance over a distance t is `Tr(t) = e^(-σₜ t)` and the free-flight
//! distance to the next interaction has the exponential density `σₜ e^(-σₜ t)`, sampled by
//! inversion `t = -ln(1 - ξ) / σₜ` ([`crate::sampling::sample_exponential`]).
//!
//! Colour: the three channels have different `σₜ`; a channel is chosen uniformly for each
//! distance, and the density used is the average over channels (one-sample MIS over the
//! channels, Miller et al. 2019's spectral MIS), so every channel's estimate stays unbiased.

use super::FreeFlight;
use crate::math::special::exp;
use crate::math::Rgb;
use crate::sampling::sample_exponential;

/// A homogeneous participating medium's coefficients.
#[derive(Clone, Debug, PartialEq)]
pub struct Homogeneous {
    /// Extinction coefficient σₜ (m⁻¹ per channel).
    pub sigma_t: Rgb,
    /// Single-scattering albedo σₛ/σₜ per channel, in [0, 1].
    pub albedo: Rgb,
}

impl Homogeneous {
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
        Rgb::new(exp(-self.sigma_t.x * t), exp(-self.sigma_t.y * t), exp(-self.sigma_t.z * t))
    }

    /// The light emitted along a segment of length `t` (possibly infinite) toward its start by
    /// the medium of radiance `le`: `∫₀ᵗ e^(−σₜ s) σₐ Lₑ ds = α' Lₑ (1 − e^(−σₜ t))` per channel,
    /// `α' = σₐ / σₜ = 1 − α` (0 where σₜ is: no absorption, no emission).
    #[inline]
    pub fn emitted(&self, le: Rgb, t: f32) -> Rgb {
        let absorbed = Rgb::ONE - self.transmittance(t);
        Rgb::from_array(std::array::from_fn(|c| {
            if self.sigma_t[c] > 0.0 {
                (1.0 - self.albedo[c]) * le[c] * absorbed[c]
            } else {
                0.0
            }
        }))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;

    /// The free-flight estimator is unbiased per channel for a medium whose channels differ:
    /// `E[weight · 1(pass)] = Tr(t_max)` and `E[weight · 1(scatter)] = ∫₀^t_max σₛ Tr(t) dt =
    /// α (1 - Tr(t_max))`.
    #[test]
    fn free_flight_is_unbiased_per_channel() {
        let m = Homogeneous { sigma_t: Rgb::new(0.5, 2.0, 4.0), albedo: Rgb::new(0.9, 0.5, 0.2) };
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
    }
}
