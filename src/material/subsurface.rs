//! pbrt-v4's `subsurface` material (neumann's `pbrt_subsurface` plugin): a dielectric boundary,
//! smooth or rough, over a translucent medium whose light leaves the surface elsewhere, by the
//! tabulated BSSRDF of [`super::bssrdf`].
//!
//! As a BSDF it is its boundary ([`Subsurface::surface`]): reflection, and transmission into
//! the object. Where a path transmits into it, the `volpath` integrator samples where the light
//! comes out again (a probe segment meeting a surface of the same material) and goes on from
//! there by the BSSRDF's exit lobe, pbrt-v4's `VolPathIntegrator` semantics; the other
//! integrators see the boundary only (pbrt-v4's `PathIntegrator` ignores BSSRDFs too).
//!
//! Parameters (pbrt-v4's, one of three ways): `sigma_a` and `sigma_s` (m⁻¹ per channel,
//! texturable; pbrt's default RGB (0.0011, 0.0024, 0.014) and (2.55, 3.21, 3.77)); or
//! `reflectance` (the effective albedo, texturable) with `mfp` (the mean free path, texturable,
//! 1), inverted through the table; both times `scale` (1). `g` (0) is the phase asymmetry the
//! table is computed for. The boundary takes `dielectric`'s parameters (`int_ior`, `ext_ior`) or,
//! with a `distribution` or `alpha`, `roughdielectric`'s; its relative index is the BSSRDF's `η`.

use super::bssrdf::{BssrdfTable, TabulatedBssrdf};
use super::{Bsdf, BsdfBuilder, BsdfContext};
use crate::math::spectrum::SpectrumKind;
use crate::math::{Rgb, Vec3};
use crate::props::{Obj, Result as PropResult};
use crate::texture::Texture;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// How the medium's coefficients are given.
#[derive(Clone, Debug)]
pub enum Coefficients {
    /// Absorption and scattering coefficients (m⁻¹, before `scale`).
    Sigma {
        /// σₐ.
        sigma_a: Texture,
        /// σₛ.
        sigma_s: Texture,
    },
    /// The effective albedo and the mean free path (m, before `scale`).
    Reflectance {
        /// The diffuse reflectance the medium should have.
        reflectance: Texture,
        /// Mean free path `1/σₜ`.
        mfp: Texture,
    },
}

/// A dielectric boundary over a BSSRDF.
#[derive(Clone, Debug)]
pub struct Subsurface {
    /// The boundary (a `dielectric` or `roughdielectric`).
    pub surface: Arc<Bsdf>,
    /// The medium's coefficients.
    pub coefficients: Coefficients,
    /// Factor on σₐ and σₛ, or on the mean free path.
    pub scale: f32,
    /// Relative index of the interior (the boundary's).
    pub eta: f32,
    /// The profile table for `g` and `eta`.
    pub table: Arc<BssrdfTable>,
}

/// The tables computed so far, by the bits of `(g, eta)`.
type Tables = Mutex<HashMap<(u32, u32), Arc<BssrdfTable>>>;

/// The table for `(g, eta)`, computed once per process and shared.
fn table_for(g: f32, eta: f32) -> Arc<BssrdfTable> {
    static TABLES: OnceLock<Tables> = OnceLock::new();
    let tables = TABLES.get_or_init(Default::default);
    let key = (g.to_bits(), eta.to_bits());
    if let Some(t) = tables.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
        return t.clone();
    }
    let t = Arc::new(BssrdfTable::beam_diffusion(g, eta));
    tables.lock().unwrap_or_else(|e| e.into_inner()).entry(key).or_insert(t).clone()
}

impl Subsurface {
    /// `(σₐ, σₛ)` (m⁻¹) at the point of `ctx`.
    pub fn sigma(&self, ctx: &BsdfContext) -> (Rgb, Rgb) {
        match &self.coefficients {
            Coefficients::Sigma { sigma_a, sigma_s } => {
                ((ctx.eval(sigma_a) * self.scale).max(Rgb::ZERO), (ctx.eval(sigma_s) * self.scale).max(Rgb::ZERO))
            }
            Coefficients::Reflectance { reflectance, mfp } => {
                let r = ctx.eval(reflectance).clamp(Rgb::ZERO, Rgb::ONE);
                let mfp = (ctx.eval(mfp) * self.scale).max(Rgb::ZERO);
                self.table.from_diffuse(r, mfp)
            }
        }
    }

    /// The BSSRDF entered at `po` (shading normal `ns`) with the coefficients at `ctx`.
    pub fn bssrdf<'a>(&'a self, ctx: &BsdfContext, po: Vec3, ns: Vec3) -> TabulatedBssrdf<'a> {
        let (sigma_a, sigma_s) = self.sigma(ctx);
        TabulatedBssrdf::new(po, ns, sigma_a, sigma_s, &self.table)
    }

    /// The coefficient textures.
    pub fn textures(&self) -> Vec<&Texture> {
        match &self.coefficients {
            Coefficients::Sigma { sigma_a, sigma_s } => vec![sigma_a, sigma_s],
            Coefficients::Reflectance { reflectance, mfp } => vec![reflectance, mfp],
        }
    }

    /// neumann's `pbrt_subsurface` (module docs).
    pub fn from_props(o: &Obj, b: &mut dyn BsdfBuilder) -> PropResult<Bsdf> {
        let g = o.float_checked("g", 0.0, |g| g > -1.0 && g < 1.0, "a number in (-1, 1)")?;
        let scale = o.float_checked("scale", 1.0, |s| s >= 0.0 && s.is_finite(), "a non-negative number")?;
        let coefficients = if o.has("sigma_a") || o.has("sigma_s") {
            if !(o.has("sigma_a") && o.has("sigma_s")) {
                let missing = if o.has("sigma_a") { "sigma_s" } else { "sigma_a" };
                return Err(o.error(format!("sigma_a and sigma_s go together: {missing} is missing")));
            }
            if o.has("reflectance") || o.has("mfp") {
                return Err(o.error("give either sigma_a and sigma_s or reflectance (and mfp), not both"));
            }
            Coefficients::Sigma {
                sigma_a: b.texture_of(o, "sigma_a", Rgb::ONE, SpectrumKind::Unbounded)?,
                sigma_s: b.texture_of(o, "sigma_s", Rgb::ONE, SpectrumKind::Unbounded)?,
            }
        } else if o.has("reflectance") {
            Coefficients::Reflectance {
                reflectance: b.texture(o, "reflectance", Rgb::ONE)?,
                mfp: b.texture_of(o, "mfp", Rgb::ONE, SpectrumKind::Unbounded)?,
            }
        } else if o.has("mfp") {
            return Err(o.error("mfp needs a reflectance"));
        } else {
            Coefficients::Sigma {
                sigma_a: Texture::Constant(Rgb::new(0.0011, 0.0024, 0.014)),
                sigma_s: Texture::Constant(Rgb::new(2.55, 3.21, 3.77)),
            }
        };
        let rough = ["distribution", "alpha", "alpha_u", "alpha_v"].iter().any(|n| o.has(n));
        let surface =
            if rough { super::RoughDielectric::from_props(o, b)? } else { super::Dielectric::from_props(o, b)? };
        let eta = match &surface {
            Bsdf::Dielectric(d) => d.eta,
            Bsdf::RoughDielectric(d) => d.eta,
            _ => unreachable!("a dielectric boundary"),
        };
        if eta == 1.0 {
            return Err(o.error("the boundary's relative index is 1: the BSSRDF needs a refracting surface"));
        }
        Ok(Bsdf::Subsurface(Box::new(Subsurface {
            surface: Arc::new(surface),
            coefficients,
            scale,
            eta,
            table: table_for(g, eta),
        })))
    }
}
