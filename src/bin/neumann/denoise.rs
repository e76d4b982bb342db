//! `render --denoise`: the guides the denoiser needs (`denoising_albedo` and `normal` AOVs, added to the
//! integrator) and the call into Open Image Denoise (`neumann::film::denoise`, cargo feature
//! `oidn`). Without the feature, `--denoise` is an error saying how to get it.

use crate::{usage, Failure};
use neumann::film::Film;
use neumann::integrator::aov::{AovIntegrator, DENOISER_AOVS};
use neumann::integrator::{AnyIntegrator, IntegratorKind};
use neumann::math::Rgb;

/// How to build neumann with the denoiser.
const HOW: &str = "this neumann was built without denoising: install Open Image Denoise (e.g. `pip install pyoidn` \
    in a virtual environment) and build with `OIDN_DIR=<…>/site-packages/pyoidn/oidn cargo build --release --features oidn` \
    (README: Denoising)";

/// Checks that denoising is built in and adds the `albedo` and `normal` AOVs the denoiser is
/// guided by to a camera-ray integrator (the light tracer and radiosity are denoised from the
/// image alone). Returns whether guides will be rendered.
pub fn add_guides(integrator: &mut AnyIntegrator) -> Result<bool, Failure> {
    if !cfg!(feature = "oidn") {
        return Err(usage(HOW.to_string()));
    }
    if integrator.camera().is_none() {
        return Ok(false);
    }
    let guides = DENOISER_AOVS;
    let current = std::mem::replace(integrator, AnyIntegrator::with_kind(IntegratorKind::Path, Default::default()));
    *integrator = match current {
        AnyIntegrator::Aov(mut existing) => {
            for (name, kind) in guides {
                match existing.aovs.iter().find(|(n, _)| n == name) {
                    Some((_, k)) if *k == kind => {}
                    Some(_) => {
                        return Err(usage(format!(
                            "--denoise needs the AOV '{name}' as a {kind}, and the scene's aov integrator has another AOV of that name"
                        )))
                    }
                    None => existing.aovs.push((name.to_string(), kind)),
                }
            }
            AnyIntegrator::Aov(existing)
        }
        other => AnyIntegrator::Aov(AovIntegrator::around(other, guides.iter().map(|(n, k)| (n.to_string(), *k)).collect())),
    };
    Ok(true)
}

/// `image` (`film`'s pixel estimates) denoised (`neumann::film::denoise::denoise_film`).
#[cfg(feature = "oidn")]
pub fn apply(film: &Film, image: &[Rgb]) -> Result<Vec<Rgb>, Failure> {
    neumann::film::denoise::denoise_film(film, image).map_err(|e| Failure(1, e))
}

/// Without the feature [`add_guides`] has refused `--denoise` already.
#[cfg(not(feature = "oidn"))]
pub fn apply(_film: &Film, _image: &[Rgb]) -> Result<Vec<Rgb>, Failure> {
    Err(usage(HOW.to_string()))
}
