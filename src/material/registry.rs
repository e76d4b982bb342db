//! BSDF plugins by name: the registry every scene format's loader looks BSDFs up in, and what a
//! plugin needs from the loader to build itself ([`BsdfBuilder`]). A new BSDF adds its
//! `from_props` beside itself and one line to [`BSDF_PLUGINS`].
//!
//! The wrappers, which only combine other BSDFs (Mitsuba's `twosided`, `blendbsdf`, `mask`, and
//! `null`), are built here.

use super::Bsdf;
use crate::math::Rgb;
use crate::props::{Obj, Result};
use crate::texture::TextureSource;
use std::ops::RangeInclusive;
use std::sync::Arc;

/// What a BSDF plugin needs from the loader that holds the scene's objects: its texture
/// parameters ([`TextureSource`]) and the BSDFs nested in it, built (and shared) by the loader.
pub trait BsdfBuilder: TextureSource {
    /// The BSDFs nested in `o`; an error unless their number is in `count`. A BSDF named twice
    /// (by references) is built once and shared.
    fn nested_bsdfs(&mut self, o: &Obj, count: RangeInclusive<usize>) -> Result<Vec<Arc<Bsdf>>>;

    /// The textures nested in `o` without a name (a `bumpmap`'s height field).
    fn nested_textures(&mut self, o: &Obj) -> Result<Vec<crate::texture::Texture>>;

    /// The tensor file (Mitsuba's `TensorFile`, e.g. a measured BSDF's `.bsdf`) named by the
    /// string parameter `name` of `o`, resolved against the scene's folders and shared between
    /// the plugins that name it; errors are located at the parameter.
    fn tensor_file(&mut self, o: &Obj, name: &str) -> Result<Arc<crate::tensor::TensorFile>>;
}

/// A BSDF plugin's constructor.
pub type BsdfPlugin = fn(&Obj, &mut dyn BsdfBuilder) -> Result<Bsdf>;

/// Every BSDF plugin by its (Mitsuba) name.
pub const BSDF_PLUGINS: &[(&str, BsdfPlugin)] = &[
    ("diffuse", super::Diffuse::from_props),
    ("diffusetransmission", super::DiffuseTransmission::from_props),
    ("hair", super::Hair::mitsuba_from_props),
    ("pbrt_hair", super::Hair::from_props),
    ("pbrt_subsurface", super::subsurface::Subsurface::from_props),
    ("conductor", super::Conductor::from_props),
    ("roughconductor", super::RoughConductor::from_props),
    ("dielectric", super::Dielectric::from_props),
    ("thindielectric", super::ThinDielectric::from_props),
    ("roughdielectric", super::RoughDielectric::from_props),
    ("plastic", super::Plastic::from_props),
    ("roughplastic", super::RoughPlastic::from_props),
    ("pplastic", super::PPlastic::from_props),
    ("measured", super::Measured::from_props),
    ("principled", super::Principled::from_props),
    ("principledthin", super::PrincipledThin::from_props),
    ("coateddiffuse", super::Layered::coated_diffuse_from_props),
    ("coatedconductor", super::Layered::coated_conductor_from_props),
    ("twosided", two_sided),
    ("blendbsdf", blend),
    ("mask", mask),
    ("null", null),
    ("polarizer", super::Filter::polarizer_from_props),
    ("circular", super::Filter::circular_from_props),
    ("retarder", super::Filter::retarder_from_props),
    ("normalmap", super::Perturbed::normalmap_from_props),
    ("bumpmap", super::Perturbed::bumpmap_from_props),
    ("displacement", super::Perturbed::displacement_from_props),
];

/// The constructor of the BSDF plugin `name`.
pub fn bsdf_plugin(name: &str) -> Option<BsdfPlugin> {
    BSDF_PLUGINS.iter().find(|(n, _)| *n == name).map(|(_, f)| *f)
}

/// Mitsuba's `twosided`: one nested BSDF for both sides, or two (front, back), neither with a
/// transmission or null lobe (Mitsuba 3.9.1 refuses them: a surface that transmits has no
/// separate front and back to mirror).
fn two_sided(o: &Obj, b: &mut dyn BsdfBuilder) -> Result<Bsdf> {
    let mut nested = b.nested_bsdfs(o, 1..=2)?;
    if let Some(i) = nested.iter().position(|n| n.has_transmission_lobe()) {
        let message = format!(
            "a '{}' cannot be nested in a 'twosided': only BSDFs without transmission (or a null lobe) can, as in \
             Mitsuba 3.9.1",
            nested[i].plugin_name()
        );
        return Err(match o.nested("bsdf").get(i) {
            Some(n) => n.error(message),
            None => o.error(message),
        });
    }
    let back = if nested.len() == 2 { nested.pop().expect("two") } else { nested[0].clone() };
    Ok(Bsdf::TwoSided([nested.pop().expect("one"), back]))
}

/// Mitsuba's `blendbsdf`: `weight` (texturable, required: Mitsuba 3.9.1 has no default) toward
/// the second of two nested BSDFs.
fn blend(o: &Obj, b: &mut dyn BsdfBuilder) -> Result<Bsdf> {
    if !o.has("weight") {
        return Err(o.error("a 'blendbsdf' needs its 'weight' (a float or texture; Mitsuba 3.9.1 has no default)"));
    }
    let weight = b.texture(o, "weight", Rgb::splat(0.5))?;
    let nested = b.nested_bsdfs(o, 2..=2)?;
    let bsdfs: [Arc<Bsdf>; 2] = nested.try_into().expect("two");
    Ok(Bsdf::Blend { weight, bsdfs })
}

/// Mitsuba's `mask`: `opacity` (texturable, 0.5) of one nested BSDF; the rest passes through.
fn mask(o: &Obj, b: &mut dyn BsdfBuilder) -> Result<Bsdf> {
    let opacity = b.texture(o, "opacity", Rgb::splat(0.5))?;
    let mut nested = b.nested_bsdfs(o, 1..=1)?;
    Ok(Bsdf::Mask { opacity, bsdf: nested.pop().expect("one") })
}

/// Mitsuba's `null`: an index-matched boundary (a medium's surface).
fn null(_: &Obj, _: &mut dyn BsdfBuilder) -> Result<Bsdf> {
    Ok(Bsdf::Null)
}
