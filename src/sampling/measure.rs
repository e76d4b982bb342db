//! Samples carry their pdf *and* the measure it is expressed in.
//!
//! Mixing measures is the classic bug of light sampling: a light's position pdf is per unit
//! **area**, a BSDF's direction pdf per unit **solid angle**; MIS must compare them in one
//! measure. [`area_to_solid_angle`] is the Jacobian `dA = r² / |cos θ_l| dω` that converts.

/// The measure a pdf is a density with respect to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Measure {
    /// Lebesgue measure on the real line (1D densities: distances, powers).
    Length,
    /// Area on a surface or in the plane (m⁻² for positions).
    Area,
    /// Solid angle on the unit sphere of directions (sr⁻¹).
    SolidAngle,
    /// Counting measure: the pdf is a probability mass (discrete choices, delta distributions).
    Discrete,
}

/// A sampled value with its probability density `pdf` in `measure`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample<T> {
    /// The sampled value.
    pub value: T,
    /// Density of `value` with respect to `measure` (mass for [`Measure::Discrete`]).
    pub pdf: f32,
    /// What `pdf` is a density of.
    pub measure: Measure,
}

impl<T> Sample<T> {
    /// A sample with a density per unit length.
    #[inline]
    pub fn length(value: T, pdf: f32) -> Self {
        Sample { value, pdf, measure: Measure::Length }
    }
    /// A sample with a density per unit area.
    #[inline]
    pub fn area(value: T, pdf: f32) -> Self {
        Sample { value, pdf, measure: Measure::Area }
    }
    /// A sample with a density per unit solid angle.
    #[inline]
    pub fn solid_angle(value: T, pdf: f32) -> Self {
        Sample { value, pdf, measure: Measure::SolidAngle }
    }
    /// A sample with a probability mass.
    #[inline]
    pub fn discrete(value: T, pmf: f32) -> Self {
        Sample { value, pdf: pmf, measure: Measure::Discrete }
    }
}

/// Converts a density per unit area at a point `dist` away (squared: `dist2`), seen under
/// `|cos θ|` = `abs_cos` between the surface normal there and the connecting direction, into a
/// density per unit solid angle: `p_ω = p_A r² / |cos θ|`. Returns 0 for grazing points
/// (`abs_cos = 0`), which cannot be sampled.
#[inline]
pub fn area_to_solid_angle(pdf_area: f32, dist2: f32, abs_cos: f32) -> f32 {
    if abs_cos <= 0.0 {
        0.0
    } else {
        pdf_area * dist2 / abs_cos
    }
}

/// Inverse of [`area_to_solid_angle`]: `p_A = p_ω |cos θ| / r²`.
#[inline]
pub fn solid_angle_to_area(pdf_solid_angle: f32, dist2: f32, abs_cos: f32) -> f32 {
    if dist2 <= 0.0 {
        0.0
    } else {
        pdf_solid_angle * abs_cos / dist2
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::PI;

    #[test]
    fn sphere_area_density_seen_from_centre_is_uniform_in_solid_angle() {
        // Uniform area sampling of a sphere of radius R seen from its centre: every point is at
        // distance R, normal along the ray (cos = 1): p_ω = (1 / 4πR²) R² = 1 / 4π.
        for r in [0.5f32, 2.0, 10.0] {
            let p_a = 1.0 / (4.0 * PI * r * r);
            let p_w = area_to_solid_angle(p_a, r * r, 1.0);
            assert!((p_w - 1.0 / (4.0 * PI)).abs() < 1e-6);
            assert!((solid_angle_to_area(p_w, r * r, 1.0) - p_a).abs() < 1e-9);
        }
        assert_eq!(area_to_solid_angle(1.0, 1.0, 0.0), 0.0);
        let s = Sample::solid_angle(1u8, 0.5);
        assert_eq!(s.measure, Measure::SolidAngle);
    }
}
