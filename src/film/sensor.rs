//! What a radiance sample becomes before it reaches the film: pbrt-v4's pixel-sensor steps that
//! neumann's RGB films can take — white balance and the clamp of a sample's largest component.
//!
//! **White balance** (pbrt-v4's `whitebalance` of its `cie1931` sensor): the image is adapted
//! from a source white — CIE daylight (the D series) of the given correlated colour
//! temperature, or a black body below 4000 K where the D series is not defined, as pbrt
//! chooses — to the output colour space's white (sRGB's D65) by the von Kries transform in
//! Bradford's cone space: `RGB ← RGB_from_XYZ · B⁻¹ diag(L_dst/L_src) B · XYZ_from_RGB`.
//! **Clamp** (pbrt-v4's `maxcomponentvalue`): a sample whose largest RGB component exceeds the
//! bound is scaled down to it (biased, as pbrt's is; off by default).

use crate::math::{Mat3, Rgb, Vec3};

/// The per-sample transform (identity by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleTransform {
    /// A colour matrix applied to every sample (white balance), if any.
    pub matrix: Option<Mat3>,
    /// The largest value a sample's largest component may take (∞: no clamp).
    pub max_component: f32,
}

impl Default for SampleTransform {
    fn default() -> Self {
        SampleTransform { matrix: None, max_component: f32::INFINITY }
    }
}

/// Bradford's cone-response matrix (XYZ → LMS), rows as published.
fn bradford() -> Mat3 {
    Mat3::from_cols(
        Vec3::new(0.8951, -0.7502, 0.0389),
        Vec3::new(0.2664, 1.7135, -0.0685),
        Vec3::new(-0.1614, 0.0367, 1.0296),
    )
}

/// Linear sRGB → CIE XYZ (D65).
fn xyz_from_rgb() -> Mat3 {
    Mat3::from_cols(
        Vec3::new(0.412_456_4, 0.212_672_9, 0.019_333_9),
        Vec3::new(0.357_576_1, 0.715_152_2, 0.119_192),
        Vec3::new(0.180_437_5, 0.072_175, 0.950_304_1),
    )
}

/// sRGB's white point (D65) chromaticity.
pub const D65_XY: [f32; 2] = [0.3127, 0.3290];

/// XYZ of chromaticity `xy` at Y = 1.
fn xyz_of(xy: [f32; 2]) -> Vec3 {
    Vec3::new(xy[0] / xy[1], 1.0, (1.0 - xy[0] - xy[1]) / xy[1])
}

/// The chromaticity of pbrt-v4's white for a colour temperature of `kelvin`: CIE daylight of
/// that correlated colour temperature (on the 1968 Planck constant, T · 1.4388/1.4380), by the
/// CIE's closed form for its x and `y = −3x² + 2.870x − 0.275`; below 4000 K, where the D series
/// is not defined, a black body's.
pub fn white_chromaticity(kelvin: f32) -> [f32; 2] {
    let cct = kelvin as f64 * 1.4388 / 1.4380;
    if cct < 4000.0 {
        let samples: Vec<(f32, f32)> = (0..=94)
            .map(|i| {
                let nm = 360.0 + 5.0 * i as f64;
                (nm as f32, planck(nm * 1e-9, kelvin as f64) as f32)
            })
            .collect();
        let xyz = crate::math::spectrum::spectrum_to_xyz(&samples);
        let s = xyz.x + xyz.y + xyz.z;
        return [xyz.x / s, xyz.y / s];
    }
    let x = if cct <= 7000.0 {
        -4.607e9 / cct.powi(3) + 2.9678e6 / (cct * cct) + 0.09911e3 / cct + 0.244063
    } else {
        -2.0064e9 / cct.powi(3) + 1.9018e6 / (cct * cct) + 0.24748e3 / cct + 0.23704
    };
    let y = -3.0 * x * x + 2.870 * x - 0.275;
    [x as f32, y as f32]
}

/// Planck's spectral radiance at wavelength `l` (m) and temperature `t` (K), up to a constant.
fn planck(l: f64, t: f64) -> f64 {
    const H: f64 = 6.626_070_15e-34;
    const C: f64 = 299_792_458.0;
    const K: f64 = 1.380_649e-23;
    2.0 * H * C * C / l.powi(5) / ((H * C / (l * K * t)).exp() - 1.0) * 1e-13
}

impl SampleTransform {
    /// pbrt-v4's white balance from the white of `kelvin` to sRGB's D65, as a matrix on linear
    /// sRGB.
    pub fn white_balance(kelvin: f32) -> Mat3 {
        let b = bradford();
        let src = b * xyz_of(white_chromaticity(kelvin));
        let dst = b * xyz_of(D65_XY);
        let adapt = b.inverse() * Mat3::from_diagonal(dst / src) * b;
        let m = xyz_from_rgb();
        m.inverse() * adapt * m
    }

    /// Whether every sample passes unchanged.
    pub fn is_identity(&self) -> bool {
        self.matrix.is_none() && self.max_component == f32::INFINITY
    }

    /// The sample `l` after the colour matrix and the clamp.
    #[inline]
    pub fn apply(&self, l: Rgb) -> Rgb {
        let l = self.matrix.map_or(l, |m| m * l);
        let max = l.max_element();
        if max > self.max_component {
            l * (self.max_component / max)
        } else {
            l
        }
    }

    /// A Neumann-series term of the sample: the colour matrix only (the clamp is of the whole
    /// sample).
    #[inline]
    pub fn apply_linear(&self, l: Rgb) -> Rgb {
        self.matrix.map_or(l, |m| m * l)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The adaptation takes the source white to D65's white (sRGB (1, 1, 1)), is near the
    /// identity at 6500 K (D65's temperature), and warms a scene lit by a cooler white (a higher
    /// temperature leaves more blue to remove).
    #[test]
    fn white_balance_maps_the_source_white_to_d65() {
        let m_rgb_xyz = xyz_from_rgb().inverse();
        for kelvin in [2700.0, 3500.0, 5000.0, 6500.0, 9000.0] {
            let wb = SampleTransform::white_balance(kelvin);
            let src_white_rgb = m_rgb_xyz * xyz_of(white_chromaticity(kelvin));
            let out = wb * src_white_rgb;
            assert!((out - Vec3::ONE).abs().max_element() < 2e-3, "{kelvin} K: {out}");
        }
        let d65 = SampleTransform::white_balance(6504.0);
        assert!((d65 - Mat3::IDENTITY).abs_diff_eq(Mat3::ZERO, 5e-3), "{d65}");
        let cool = SampleTransform::white_balance(9000.0) * Vec3::ONE;
        assert!(cool.z < cool.x, "balancing for a bluish white takes blue out: {cool}");
        // Daylight's x: 0.3457 near 5000 K (D50), 0.3127 near 6500 K (D65).
        let d50 = white_chromaticity(5000.0 * 1.4380 / 1.4388);
        assert!((d50[0] - 0.3457).abs() < 1e-3 && (d50[1] - 0.3586).abs() < 1e-3, "{d50:?}");
        // A black body below 4000 K: 2856 K is CIE illuminant A, (0.4476, 0.4074).
        let a = white_chromaticity(2856.0);
        assert!((a[0] - 0.4476).abs() < 2e-3 && (a[1] - 0.4074).abs() < 2e-3, "{a:?}");
    }

    #[test]
    fn clamp_scales_the_largest_component_down() {
        let t = SampleTransform { matrix: None, max_component: 2.0 };
        assert_eq!(t.apply(Rgb::new(4.0, 1.0, 0.0)), Rgb::new(2.0, 0.5, 0.0));
        assert_eq!(t.apply(Rgb::new(1.0, 1.0, 0.0)), Rgb::new(1.0, 1.0, 0.0));
        assert!(SampleTransform::default().is_identity() && !t.is_identity());
    }
}
