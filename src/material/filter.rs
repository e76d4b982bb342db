//! Mitsuba's polarizing elements — `polarizer` (linear), `circular` and `retarder` — as its
//! unpolarized (RGB) variants render them: null surfaces that pass light straight through,
//! scaled by a factor: a polarizer keeps half of unpolarized light, `0.5 × transmittance`
//! (`transmittance` texturable, 1 by default), a circular polarizer the same, a retarder all of
//! it. Their polarizing parameters (`theta`, `delta`, `polarizing`, `left_handed`) change only
//! the polarization state, which RGB rendering does not carry: read and checked, not used.
//!
//! Like `null`, they are a delta lobe `wi = −wo` for the path tracers; the volumetric path
//! tracers cross them, with shadow rays, as index-matched boundaries that attenuate.

use super::{Bsdf, BsdfBuilder, BsdfContext};
use crate::math::Rgb;
use crate::props::{Obj, Result as PropResult};
use crate::texture::Texture;

/// Which element.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilterKind {
    /// Mitsuba's `polarizer`.
    LinearPolarizer,
    /// Mitsuba's `circular`.
    CircularPolarizer,
    /// Mitsuba's `retarder`.
    Retarder,
}

impl FilterKind {
    /// The plugin's name.
    pub fn name(self) -> &'static str {
        match self {
            FilterKind::LinearPolarizer => "polarizer",
            FilterKind::CircularPolarizer => "circular",
            FilterKind::Retarder => "retarder",
        }
    }
}

/// A polarizing element seen by unpolarized light.
#[derive(Clone, Debug)]
pub struct Filter {
    /// Which element.
    pub kind: FilterKind,
    /// The share of unpolarized light it passes before `transmittance`: ½ for polarizers, 1
    /// for a retarder.
    pub scale: f32,
    /// Its `transmittance` (a retarder has none: 1).
    pub transmittance: Texture,
}

impl Filter {
    /// The factor light passing through at `ctx` is multiplied by, per channel.
    #[inline]
    pub fn transmission(&self, ctx: &BsdfContext) -> Rgb {
        ctx.eval(&self.transmittance) * self.scale
    }

    /// Mitsuba's `polarizer`: `theta` (degrees, texturable, 0), `transmittance` (texturable,
    /// 1), `polarizing` (true).
    pub fn polarizer_from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        b.texture(o, "theta", Rgb::ZERO)?;
        o.bool("polarizing", true)?;
        Self::build(o, b, FilterKind::LinearPolarizer, 0.5)
    }

    /// Mitsuba's `circular`: `transmittance` (texturable, 1), `left_handed` (false).
    pub fn circular_from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        o.bool("left_handed", false)?;
        Self::build(o, b, FilterKind::CircularPolarizer, 0.5)
    }

    /// Mitsuba's `retarder`: `theta` (degrees, 0) and `delta` (degrees, 90), both texturable.
    pub fn retarder_from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        b.texture(o, "theta", Rgb::ZERO)?;
        b.texture(o, "delta", Rgb::splat(90.0))?;
        let transmittance = Texture::Constant(Rgb::ONE);
        Ok(Bsdf::Filter(Filter { kind: FilterKind::Retarder, scale: 1.0, transmittance }))
    }

    fn build(o: &Obj, b: &mut dyn BsdfBuilder, kind: FilterKind, scale: f32) -> PropResult<Bsdf> {
        let transmittance = b.texture(o, "transmittance", Rgb::ONE)?;
        Ok(Bsdf::Filter(Filter { kind, scale, transmittance }))
    }
}
