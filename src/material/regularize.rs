//! pbrt-v4's path regularization (`"bool regularize" true` of its `path` and `volpath`; the
//! `regularize` of neumann's `path` and `volpath`): after a path's first non-specular bounce,
//! BSDFs are seen with their Trowbridge–Reitz roughness widened
//! ([`super::microfacet::regularize_alpha`]: α < 0.3 becomes clamp(2α, 0.1, 0.3)), so that
//! near-specular chains (caustics seen through a diffuse bounce) become paths light sampling
//! can find. Biased: the image is that of rougher surfaces wherever they are seen indirectly.
//!
//! As pbrt-v4's `BxDF::Regularize`: dielectrics and conductors, smooth (which become α = 0.1)
//! or rough, and the coating and conductor base of the layered BSDFs are widened; the others
//! (diffuse, diffuse transmission, hair, measured data, thin dielectrics, pbrt's subsurface exit)
//! are unchanged, as are Mitsuba's plastics and principled BSDFs, which pbrt does not have; a
//! `subsurface` material's dielectric boundary is widened, and wrappers (two-sided, blend, mask,
//! normal and bump maps) regularize what they hold.

use super::microfacet::{Microfacet, MicrofacetType};
use super::{Bsdf, RoughConductor, RoughDielectric};
use std::sync::Arc;

impl Bsdf {
    /// This BSDF as pbrt-v4's path regularization sees it (see the module's notes).
    pub fn regularized(&self) -> Bsdf {
        // A smooth interface regularized: GGX of α = regularize_alpha(0) = 0.1.
        let smooth = || Microfacet::new(MicrofacetType::Ggx, 0.1, 0.1).into();
        let inner = |b: &Arc<Bsdf>| Arc::new(b.regularized());
        match self {
            Bsdf::Conductor(c) => Bsdf::RoughConductor(RoughConductor {
                roughness: smooth(),
                ior: c.ior.clone(),
                specular_reflectance: c.specular_reflectance.clone(),
            }),
            Bsdf::RoughConductor(c) => {
                Bsdf::RoughConductor(RoughConductor { roughness: c.roughness.regularized(), ..c.clone() })
            }
            Bsdf::Dielectric(d) => Bsdf::RoughDielectric(RoughDielectric {
                roughness: smooth(),
                eta: d.eta,
                specular_reflectance: d.specular_reflectance.clone(),
                specular_transmittance: d.specular_transmittance.clone(),
            }),
            Bsdf::RoughDielectric(d) => {
                Bsdf::RoughDielectric(RoughDielectric { roughness: d.roughness.regularized(), ..d.clone() })
            }
            Bsdf::Layered(l) => Bsdf::Layered(Box::new(super::Layered { regularized: true, ..(**l).clone() })),
            Bsdf::Subsurface(s) => Bsdf::Subsurface(Box::new(super::subsurface::Subsurface {
                surface: inner(&s.surface),
                ..(**s).clone()
            })),
            Bsdf::Blend { weight, bsdfs } => {
                Bsdf::Blend { weight: weight.clone(), bsdfs: [inner(&bsdfs[0]), inner(&bsdfs[1])] }
            }
            Bsdf::Mask { opacity, bsdf } => Bsdf::Mask { opacity: opacity.clone(), bsdf: inner(bsdf) },
            Bsdf::TwoSided([front, back]) => Bsdf::TwoSided([inner(front), inner(back)]),
            Bsdf::Perturbed(p) => Bsdf::Perturbed(super::Perturbed { bsdf: inner(&p.bsdf), ..p.clone() }),
            other => other.clone(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::microfacet::{regularize_alpha, Microfacet, MicrofacetType, Roughness};
    use super::super::*;
    use crate::math::{Rgb, Vec2, Vec3};

    const CTX: BsdfContext = BsdfContext { uv: Vec2::ZERO, mesh: None, textures: None, si: None, memo: None };

    /// pbrt-v4's `TrowbridgeReitzDistribution::Regularize`.
    #[test]
    fn alpha_is_doubled_and_clamped_below_0_3() {
        for (a, want) in [
            (0.0, 0.1),
            (0.02, 0.1),
            (0.05, 0.1),
            (0.1, 0.2),
            (0.12, 0.24),
            (0.2, 0.3),
            (0.29, 0.3),
            (0.3, 0.3),
            (0.7, 0.7),
        ] {
            assert!((regularize_alpha(a) - want).abs() < 1e-6, "{a}: {}", regularize_alpha(a));
        }
    }

    fn ggx(a: f32) -> Microfacet {
        Microfacet::new(MicrofacetType::Ggx, a, a)
    }

    /// Smooth interfaces become GGX of α = 0.1 (the same values as such a rough BSDF written
    /// out), rough ones take the widened α, textured roughness is widened where it is looked
    /// up; a layered BSDF widens its coating; diffuse and wrapped diffuse are unchanged.
    #[test]
    fn bsdfs_are_widened_as_pbrt_regularizes_them() {
        let (wo, wi) = (Vec3::new(0.3, 0.1, 0.95).normalize(), Vec3::new(-0.25, 0.05, 0.97).normalize());
        let same = |a: &Bsdf, b: &Bsdf| {
            let (fa, fb) = (a.eval(&CTX, wo, wi), b.eval(&CTX, wo, wi));
            let (pa, pb) = (a.pdf(&CTX, wo, wi), b.pdf(&CTX, wo, wi));
            (fa - fb).abs().max_element() <= 1e-5 * (1.0 + fa.max_element()) && (pa - pb).abs() <= 1e-5 * (1.0 + pa)
        };
        let glass = Bsdf::Dielectric(Dielectric {
            eta: 1.5,
            specular_reflectance: Rgb::ONE.into(),
            specular_transmittance: Rgb::ONE.into(),
        });
        let rough_glass = |r: Roughness| {
            Bsdf::RoughDielectric(RoughDielectric {
                roughness: r,
                eta: 1.5,
                specular_reflectance: Rgb::ONE.into(),
                specular_transmittance: Rgb::ONE.into(),
            })
        };
        assert!(glass.is_delta() && !glass.regularized().is_delta());
        assert!(same(&glass.regularized(), &rough_glass(ggx(0.1).into())));
        assert!(same(&rough_glass(ggx(0.05).into()).regularized(), &rough_glass(ggx(0.1).into())));
        assert!(same(&rough_glass(ggx(0.12).into()).regularized(), &rough_glass(ggx(0.24).into())));
        assert!(same(&rough_glass(ggx(0.5).into()).regularized(), &rough_glass(ggx(0.5).into())));
        assert!(
            !same(&rough_glass(ggx(0.12).into()), &rough_glass(ggx(0.24).into())),
            "the test can tell the two apart"
        );
        let textured = Roughness {
            distribution: ggx(0.3),
            textures: Some(Box::new([Rgb::splat(0.12).into(), Rgb::splat(0.12).into()])),
            regularized: false,
        };
        assert!(same(&rough_glass(textured.clone()), &rough_glass(ggx(0.12).into())));
        assert!(same(&rough_glass(textured).regularized(), &rough_glass(ggx(0.24).into())));
        let gold = ConductorIor { eta: Rgb::new(0.2, 0.4, 1.4).into(), k: Rgb::new(3.6, 2.4, 1.8).into() };
        let mirror = Bsdf::Conductor(Conductor { ior: Some(gold.clone()), specular_reflectance: Rgb::ONE.into() });
        let rough_gold = Bsdf::RoughConductor(RoughConductor {
            roughness: ggx(0.1).into(),
            ior: Some(gold),
            specular_reflectance: Rgb::ONE.into(),
        });
        assert!(same(&mirror.regularized(), &rough_gold));
        let two_sided = Bsdf::TwoSided([Arc::new(mirror.clone()), Arc::new(mirror)]);
        assert!(same(&two_sided.regularized(), &Bsdf::TwoSided([Arc::new(rough_gold.clone()), Arc::new(rough_gold)])));
        let diffuse = Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5)));
        assert!(same(&diffuse.regularized(), &diffuse));
    }
}
