//! Linear RGB radiometric quantities.
//!
//! neumann renders in linear sRGB/Rec.709 primaries (as Mitsuba 3's `*_rgb` variants do):
//! radiance, irradiance, reflectance and intensity are RGB triples stored in a `Vec3`.

use glam::Vec3;

/// A linear RGB triple (radiance W m⁻² sr⁻¹, reflectance, intensity W sr⁻¹, …, per channel).
pub type Rgb = Vec3;

/// CIE XYZ of a linear sRGB (Rec. 709 primaries, D65 white) triple: Mitsuba's `srgb_to_xyz`.
#[inline]
pub fn srgb_to_xyz(c: Rgb) -> Rgb {
    Rgb::new(
        0.412453 * c.x + 0.357580 * c.y + 0.180423 * c.z,
        0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z,
        0.019334 * c.x + 0.119193 * c.y + 0.950227 * c.z,
    )
}

/// Luminance (relative, Y of CIE XYZ) of a linear Rec.709 RGB triple.
#[inline]
pub fn luminance(c: Rgb) -> f32 {
    0.212_671 * c.x + 0.715_160 * c.y + 0.072_169 * c.z
}

/// The sRGB transfer function (linear → encoded), for values in [0, 1].
#[inline]
pub fn srgb_encode(x: f32) -> f32 {
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// Inverse sRGB transfer function (encoded → linear), for values in [0, 1].
#[inline]
pub fn srgb_decode(x: f32) -> f32 {
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trip_and_luminance_of_white() {
        for i in 0..=100 {
            let x = i as f32 / 100.0;
            assert!((srgb_decode(srgb_encode(x)) - x).abs() < 1e-5);
        }
        assert!((luminance(Vec3::ONE) - 1.0).abs() < 1e-5);
        assert!((srgb_encode(0.5) - 0.735_357).abs() < 1e-4);
    }
}
