//! pbrt-v4's procedural cloud density (its `cloud` medium, `CloudMedium::Density`): octaves of
//! Perlin noise ([`super::noise`]) at a lookup point first displaced by the noise's own
//! gradient ("wispiness"), fading out with height. The density is dimensionless, in [0, 1];
//! the medium multiplies it into its σₐ and σₛ.
//!
//! At a point `p` of the medium's space: `q = frequency · p`; where `wispiness > 0`, two
//! displacements `q += ω ∇noise(λ q)` with `(ω, λ) = (0.05 · wispiness, 10)` then halved and
//! ×1.99 (the gradient by forward differences of 0.01, as pbrt's `DNoise`); then
//! `d = Σᵢ₌₀⁴ 0.5^(i+1) noise(1.99ⁱ q)`, `d = clamp((1 − p.y) · 4.5 · density · d, 0, 1) +
//! 2 max(0, ½ − p.y)`, clamped to [0, 1]: below y = ½ the cloud thickens to solid at y = 0.

use super::noise::noise;
use crate::math::Vec3;

/// The parameters of pbrt-v4's cloud density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CloudDensity {
    /// `density` (1): the noise's weight.
    pub density: f32,
    /// `wispiness` (1): how far the lookup point is displaced (0: not at all).
    pub wispiness: f32,
    /// `frequency` (5): the noise's scale, per unit of the medium's space.
    pub frequency: f32,
}

impl Default for CloudDensity {
    fn default() -> CloudDensity {
        CloudDensity { density: 1.0, wispiness: 1.0, frequency: 5.0 }
    }
}

/// The gradient of [`noise`] at `p` by forward differences of 0.01 (pbrt-v4's `DNoise`).
pub fn noise_gradient(p: Vec3) -> Vec3 {
    const DELTA: f32 = 0.01;
    let n = noise(p);
    Vec3::new(
        noise(p + Vec3::new(DELTA, 0.0, 0.0)) - n,
        noise(p + Vec3::new(0.0, DELTA, 0.0)) - n,
        noise(p + Vec3::new(0.0, 0.0, DELTA)) - n,
    ) / DELTA
}

impl CloudDensity {
    /// The density at `p` (the medium's own space), in [0, 1] (module docs).
    pub fn at(&self, p: Vec3) -> f32 {
        let mut q = self.frequency * p;
        if self.wispiness > 0.0 {
            let (mut omega, mut lambda) = (0.05 * self.wispiness, 10.0f32);
            for _ in 0..2 {
                q += omega * noise_gradient(lambda * q);
                omega *= 0.5;
                lambda *= 1.99;
            }
        }
        let (mut d, mut omega, mut lambda) = (0.0f32, 0.5f32, 1.0f32);
        for _ in 0..5 {
            d += omega * noise(lambda * q);
            omega *= 0.5;
            lambda *= 1.99;
        }
        let d = ((1.0 - p.y) * 4.5 * self.density * d).clamp(0.0, 1.0) + 2.0 * (0.5 - p.y).max(0.0);
        // A NaN (from a point at infinity) becomes 0, where `clamp` would keep it.
        if d > 0.0 {
            d.min(1.0)
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Pcg32;

    /// Within [0, 1] everywhere; solid at and below y = 0 (the altitude term alone reaches 1);
    /// neither constant nor empty across the cloud's box; and at a density of 0 only the
    /// altitude term is left: 2 (½ − y) below y = ½, nothing above.
    #[test]
    fn density_is_bounded_solid_below_and_varied() {
        let c = CloudDensity::default();
        let empty = CloudDensity { density: 0.0, ..c };
        let mut rng = Pcg32::new(7, 1);
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for _ in 0..20_000 {
            let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let d = c.at(p);
            assert!((0.0..=1.0).contains(&d), "{p}: {d}");
            if p.y > 0.6 {
                (lo, hi) = (lo.min(d), hi.max(d));
            }
            let e = empty.at(p);
            assert!((e - (2.0 * (0.5 - p.y)).max(0.0)).abs() < 1e-6, "{p}: {e}");
            assert_eq!(c.at(Vec3::new(p.x, -p.y, p.z)), 1.0);
        }
        assert!(lo == 0.0 && hi > 0.5, "{lo} .. {hi}");
    }

    /// The gradient is the forward difference it is defined as, and close to the noise's
    /// slope (a central difference at a finer step) where the noise is smooth.
    #[test]
    fn noise_gradient_is_the_noises_slope() {
        let mut rng = Pcg32::new(3, 9);
        let mut close = 0;
        for _ in 0..200 {
            let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 20.0;
            let g = noise_gradient(p);
            let fd = (noise(p + Vec3::new(0.0, 0.01, 0.0)) - noise(p)) / 0.01;
            assert_eq!(g.y, fd);
            let h = 1e-3;
            let c = (noise(p + Vec3::new(h, 0.0, 0.0)) - noise(p - Vec3::new(h, 0.0, 0.0))) / (2.0 * h);
            close += usize::from((g.x - c).abs() < 0.15);
        }
        assert!(close > 180, "{close} of 200");
    }

    /// Wispiness displaces the lookup: with it the density differs from the same cloud
    /// without it at most points above y = ½ (below, both are solid).
    #[test]
    fn wispiness_moves_the_lookup() {
        let c = CloudDensity::default();
        let still = CloudDensity { wispiness: 0.0, ..c };
        let mut rng = Pcg32::new(5, 2);
        let mut differ = 0;
        for _ in 0..500 {
            let p = Vec3::new(rng.next_f32(), 0.55 + 0.4 * rng.next_f32(), rng.next_f32());
            differ += usize::from((c.at(p) - still.at(p)).abs() > 1e-4);
        }
        assert!(differ > 250, "{differ}");
    }
}
