//! neumann's `blackbody` volume: the radiance of black bodies at the temperatures another volume
//! gives, pbrt-v4's emissive media by temperature (its `nanovdb` medium's temperature grid and
//! its `uniformgrid`'s `temperature` values).
//!
//! At a point of temperature `T` (the `temperature` volume's value there, grey) the radiance is
//! `scale · w · B̂((T − offset) · temperature_scale)` (W m⁻² sr⁻¹ per channel), `w` the `weight`
//! volume's value (1 without one: pbrt-v4's `Lescale` grid), `B̂(t)` pbrt-v4's
//! `BlackbodySpectrum`: Planck's law at `t` kelvin divided by its value at the peak wavelength,
//! reduced to linear sRGB as pbrt-v4's CIE 1931 sensor sees it (a flat spectrum of 1 has Y = 1),
//! and zero at or below 100 K, as pbrt-v4 cuts it off. `B̂` is tabulated over the temperatures
//! the volume reaches (2,048 steps, interpolated linearly).

use super::volume::Volume;
use crate::math::spectrum::{blackbody, spectrum_to_rgb, SpectrumKind};
use crate::math::{Rgb, Vec3};

/// pbrt-v4's cut-off: no emission at or below this temperature (K).
pub const MIN_KELVIN: f32 = 100.0;
/// Table entries between the cut-off and the hottest temperature.
const STEPS: usize = 2048;

/// Black-body radiance over space (module docs).
#[derive(Clone, Debug)]
pub struct Blackbody {
    temperature: Volume,
    weight: Option<Volume>,
    offset: f32,
    temperature_scale: f32,
    /// `scale · B̂` at `MIN_KELVIN + k · step` kelvin.
    table: Vec<Rgb>,
    step: f32,
}

impl Blackbody {
    /// Radiance `scale · weight · B̂((T − offset) · temperature_scale)` for the temperatures `T`
    /// of `temperature` (grey; its first channel is read).
    pub fn new(
        temperature: Volume,
        weight: Option<Volume>,
        offset: f32,
        temperature_scale: f32,
        scale: f32,
    ) -> Blackbody {
        let kelvin = |t: f32| (t - offset) * temperature_scale;
        let top = kelvin(temperature.min()).max(kelvin(temperature.max()));
        let (table, step) = if top > MIN_KELVIN && top.is_finite() {
            let step = (top - MIN_KELVIN) / (STEPS - 1) as f32;
            let table = (0..STEPS)
                .map(|k| {
                    spectrum_to_rgb(&blackbody(MIN_KELVIN + k as f32 * step, true), SpectrumKind::Illuminant) * scale
                })
                .collect();
            (table, step)
        } else {
            (vec![Rgb::ZERO], 1.0)
        };
        Blackbody { temperature, weight, offset, temperature_scale, table, step }
    }

    /// `scale · B̂(t)` at `t` kelvin (zero at or below the cut-off).
    #[inline]
    pub fn at_kelvin(&self, t: f32) -> Rgb {
        if t.is_nan() || t <= MIN_KELVIN {
            return Rgb::ZERO;
        }
        let last = self.table.len() - 1;
        let x = ((t - MIN_KELVIN) / self.step).min(last as f32);
        let k = (x as usize).min(last.saturating_sub(1));
        let f = x - k as f32;
        match self.table.get(k + 1) {
            Some(&next) => self.table[k] * (1.0 - f) + next * f,
            None => self.table[k],
        }
    }

    /// The radiance at world point `p`.
    #[inline]
    pub fn eval(&self, p: Vec3) -> Rgb {
        let t = (self.temperature.eval(p).x - self.offset) * self.temperature_scale;
        let c = self.at_kelvin(t);
        match &self.weight {
            Some(w) if c != Rgb::ZERO => c * w.eval(p).x,
            Some(_) => Rgb::ZERO,
            None => c,
        }
    }

    /// Where it can be non-zero: the temperature volume's box.
    pub fn bounds(&self) -> crate::math::Bounds3 {
        self.temperature.bounds()
    }

    /// An upper bound of every channel of [`Blackbody::eval`].
    pub fn max(&self) -> f32 {
        let b = self.table.iter().map(|c| c.max_element()).fold(0.0, f32::max);
        b * self.weight.as_ref().map_or(1.0, |w| w.max().max(0.0))
    }

    /// Whether every value it can take is finite.
    pub fn is_finite(&self) -> bool {
        self.table.iter().all(|c| c.is_finite()) && self.weight.as_ref().is_none_or(|w| w.is_finite())
    }

    /// The smallest value of any channel (negative only where the weight is).
    pub fn min(&self) -> f32 {
        self.weight.as_ref().map_or(0.0, |w| (w.min() * self.max()).min(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Transform;

    /// The table interpolates `B̂` to 0.2 % across the temperatures it spans; below the cut-off
    /// and at NaN it gives nothing; the offset, the scales and the weight apply as the docs say.
    #[test]
    fn radiance_follows_the_black_body() {
        let hot = Volume::constant(Rgb::splat(40.0), Transform::IDENTITY);
        let b = Blackbody::new(hot, None, 2.0, 150.0, 0.5);
        for t in [101.0f32, 450.0, 1000.0, 1733.3, 2999.0, 4000.0, 5700.0] {
            let want = spectrum_to_rgb(&blackbody(t, true), SpectrumKind::Illuminant) * 0.5;
            let got = b.at_kelvin(t);
            assert!((got - want).abs().max_element() <= 2e-3 * want.max_element() + 1e-9, "{t} K: {got} vs {want}");
        }
        let at_5700 = spectrum_to_rgb(&blackbody(5700.0, true), SpectrumKind::Illuminant) * 0.5;
        assert!((b.eval(Vec3::ZERO) - at_5700).abs().max_element() < 1e-4, "(40 − 2) · 150 = 5700 K");
        assert_eq!(b.at_kelvin(100.0), Rgb::ZERO);
        assert_eq!(b.at_kelvin(f32::NAN), Rgb::ZERO);
        assert!(b.max() >= at_5700.max_element() && b.max() >= b.at_kelvin(3000.0).max_element());
        // A colder medium: nothing above the cut-off, no radiance anywhere.
        let cold = Blackbody::new(Volume::constant(Rgb::splat(0.5), Transform::IDENTITY), None, 0.0, 150.0, 1.0);
        assert_eq!((cold.eval(Vec3::ZERO), cold.max()), (Rgb::ZERO, 0.0));
        // A weight multiplies.
        let hot = Volume::constant(Rgb::splat(40.0), Transform::IDENTITY);
        let w = Volume::constant(Rgb::splat(0.25), Transform::IDENTITY);
        let weighted = Blackbody::new(hot, Some(w), 2.0, 150.0, 0.5);
        assert!((weighted.eval(Vec3::ZERO) - at_5700 * 0.25).abs().max_element() < 1e-5);
        // Hotter is whiter, colder redder (the sRGB chromaticity's blue over red).
        let ratio = |t: f32| {
            let c = b.at_kelvin(t);
            c.z / c.x
        };
        assert!(
            ratio(1500.0) < ratio(3000.0) && ratio(3000.0) < ratio(5700.0),
            "{} {} {}",
            ratio(1500.0),
            ratio(3000.0),
            ratio(5700.0)
        );
    }
}
