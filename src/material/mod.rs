//! Materials: BSDFs as a closed enum with `sample` / `eval` / `pdf`.
//!
//! Conventions (Mitsuba 3): directions are in the local shading frame (normal = +z), `wo`
//! points away from the surface toward the viewer, `wi` toward the light. [`Bsdf::eval`]
//! returns the BSDF *times the cosine* `f(wo, wi) |cos θᵢ|`; [`Bsdf::pdf`] is per unit solid
//! angle; [`Bsdf::sample`] returns the sampled `wi`, its pdf and the weight
//! `f |cos θᵢ| / pdf`. BSDFs are one-sided unless stated: seen from the back (`wo.z ≤ 0`) they
//! are black, as in Mitsuba.

mod diffuse;
pub mod fresnel;
pub mod microfacet;

pub use diffuse::Diffuse;

use crate::math::{Rgb, Vec2, Vec3};

/// The outcome of sampling a BSDF.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    /// Sampled incident direction (local frame, unit).
    pub wi: Vec3,
    /// Its density per unit solid angle (ignored for delta lobes).
    pub pdf: f32,
    /// `f(wo, wi) |cos θᵢ| / pdf`: the factor the path throughput is multiplied by.
    pub weight: Rgb,
    /// Whether `wi` was chosen by a delta (specular) lobe, which light sampling cannot reach.
    pub delta: bool,
}

/// The BSDFs (closed set, dispatched by `match`).
#[derive(Clone, Debug)]
pub enum Bsdf {
    /// Lambertian reflection `ρ / π`.
    Diffuse(Diffuse),
}

impl Bsdf {
    /// `f(wo, wi) |cos θᵢ|` (local frame).
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        match self {
            Bsdf::Diffuse(b) => b.eval(wo, wi),
        }
    }

    /// Density of [`Bsdf::sample`] choosing `wi`, per unit solid angle.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Bsdf::Diffuse(b) => b.pdf(wo, wi),
        }
    }

    /// Samples `wi` for `wo` from one number `u1` (lobe choice) and two `u` (direction).
    #[inline]
    pub fn sample(&self, wo: Vec3, u1: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            Bsdf::Diffuse(b) => b.sample(wo, u1, u),
        }
    }

    /// Whether the BSDF has only delta lobes (light sampling is useless on it).
    #[inline]
    pub fn is_delta(&self) -> bool {
        match self {
            Bsdf::Diffuse(_) => false,
        }
    }
}
