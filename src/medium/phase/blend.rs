//! Mitsuba's `blendphase`: the mixture `(1 - w) p₀ + w p₁` of two phase functions, with a
//! weight `w` that is a volume (constant, or a grid that varies in space). A volume of three
//! channels weighs by their mean, and the weight is clamped to [0, 1], as Mitsuba does.
//! Sampled by picking one of the two with probabilities `1 - w` and `w` (reusing the first
//! random number, rescaled) and reporting the mixture's density.

use super::PhaseFunction;
use crate::image::VolumeSource;
use crate::math::spectrum::SpectrumKind;
use crate::math::{Vec2, Vec3, ONE_MINUS_EPSILON};
use crate::medium::volume::{volume_param, Volume};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::Sample;

/// A mixture of two phase functions.
#[derive(Clone, Debug)]
pub struct BlendPhase {
    /// `w`: how much of the second phase function.
    weight: Volume,
    phases: [PhaseFunction; 2],
}

impl BlendPhase {
    /// `(1 - w) phases[0] + w phases[1]`, `w` from the volume `weight` (world space).
    pub fn new(weight: Volume, phases: [PhaseFunction; 2]) -> BlendPhase {
        BlendPhase { weight, phases }
    }

    /// The weight of the second phase function at the world point `p`, in [0, 1].
    #[inline]
    pub fn weight(&self, p: Vec3) -> f32 {
        let w = self.weight.eval(p);
        let mean = (w.x + w.y + w.z) / 3.0;
        // (NaN, which validated volumes never hold, would weigh nothing.)
        if mean > 0.0 {
            mean.min(1.0)
        } else {
            0.0
        }
    }

    /// The mixture's density for `w`, given the two densities.
    #[inline]
    fn mix(w: f32, p0: f32, p1: f32) -> f32 {
        if w <= 0.0 {
            p0
        } else if w >= 1.0 {
            p1
        } else {
            (1.0 - w) * p0 + w * p1
        }
    }

    /// Density of scattering from `wo` into `wi` at `p` (sr⁻¹).
    #[inline]
    pub fn eval(&self, p: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        let w = self.weight(p);
        let p0 = if w < 1.0 { self.phases[0].eval(p, wo, wi) } else { 0.0 };
        let p1 = if w > 0.0 { self.phases[1].eval(p, wo, wi) } else { 0.0 };
        BlendPhase::mix(w, p0, p1)
    }

    /// Samples one of the two by `u.x` (the second when `u.x < w`), that one's direction from
    /// `u.x` rescaled and `u.y`; the density is the mixture's.
    #[inline]
    pub fn sample(&self, p: Vec3, wo: Vec3, u: Vec2) -> Sample<Vec3> {
        let w = self.weight(p);
        let (k, ux) = if u.x < w { (1, u.x / w) } else { (0, (u.x - w) / (1.0 - w)) };
        let s = self.phases[k].sample(p, wo, Vec2::new(ux.min(ONE_MINUS_EPSILON), u.y));
        let other =
            if (k == 0 && w > 0.0) || (k == 1 && w < 1.0) { self.phases[1 - k].eval(p, wo, s.value) } else { 0.0 };
        let (p0, p1) = if k == 0 { (s.pdf, other) } else { (other, s.pdf) };
        Sample::solid_angle(s.value, BlendPhase::mix(w, p0, p1))
    }

    /// Mean cosine of the deflection at `p`.
    pub fn mean_cosine(&self, p: Vec3) -> Option<f32> {
        let w = self.weight(p);
        Some(BlendPhase::mix(w, self.phases[0].mean_cosine(p)?, self.phases[1].mean_cosine(p)?))
    }

    /// `blendphase`: `weight` (required: a `<float>`, `<rgb>`, `<spectrum>` or `<volume>`) and
    /// two nested `<phase>`s, in order.
    pub fn from_props(o: &Obj, files: &mut dyn VolumeSource) -> PropResult<BlendPhase> {
        o.check_children(&["phase"])?;
        if o.get("weight").is_none() {
            return Err(o.error("the parameter 'weight' (a <float> or a <volume>) is required"));
        }
        let weight = volume_param(o, "weight", 0.5, SpectrumKind::Unbounded, files)?;
        if !weight.is_finite() {
            return Err(o.error_at("weight", "the weight must be finite"));
        }
        let nested = o.nested("phase");
        if nested.len() != 2 {
            return Err(o.error(format!("a blendphase takes two nested <phase>s, got {}", nested.len())));
        }
        let phases = [PhaseFunction::from_props(&nested[0], files)?, PhaseFunction::from_props(&nested[1], files)?];
        // Mitsuba's blend takes the microflake flag from its parts but keeps the projected area
        // at 1, so its medium's extinction would not follow the flakes: refused.
        if let Some(k) = phases.iter().position(|ph| ph.microflakes().is_some()) {
            return Err(nested[k]
                .error("an sggx phase function cannot be blended (its medium's extinction follows its flakes)"));
        }
        Ok(BlendPhase::new(weight, phases))
    }
}
