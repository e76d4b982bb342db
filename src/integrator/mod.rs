//! Integrators: estimators of the radiance arriving at the camera.
//!
//! An integrator implements [`Integrator::li`], one unbiased sample of the radiance along a
//! camera ray; the render driver averages them per pixel. The path tracer samples the Neumann
//! series `L = Σₖ Tᵏ Lₑ` term by term along one path per sample.

pub mod direct;
pub mod path;

pub use direct::DirectIntegrator;
pub use path::{DirectStrategy, MisHeuristic, PathIntegrator};

use crate::math::{Ray, Rgb};
use crate::sampling::Sampler;
use crate::scene::Scene;

/// An estimator of incident radiance along camera rays.
pub trait Integrator: Sync {
    /// Name (Mitsuba's plugin name where one exists).
    fn name(&self) -> &'static str;
    /// One sample of the radiance arriving along `ray` (toward its origin). The sampler is
    /// positioned at the pixel sample; the integrator draws its dimensions in a fixed order.
    fn li(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler) -> Rgb;

    /// Whether [`Integrator::li_terms`] separates the Neumann-series terms.
    fn has_terms(&self) -> bool {
        false
    }

    /// [`Integrator::li`], also adding each contribution to `terms[k - 1]` where k is the
    /// number of path segments it took (`terms[0]`: `Lₑ` seen directly, `terms[1]`: `T Lₑ`,
    /// …; the last entry collects all longer paths). Returns the same value, bit for bit, as
    /// `li` with the same sampler state.
    fn li_terms(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, terms: &mut [Rgb]) -> Rgb {
        let _ = terms;
        self.li(scene, ray, sampler)
    }
}

/// One of neumann's integrators, chosen at run time (by the scene file or the command line).
#[derive(Clone, Debug)]
pub enum AnyIntegrator {
    /// Mitsuba's `path`.
    Path(PathIntegrator),
    /// Mitsuba's `direct`.
    Direct(DirectIntegrator),
}

impl Default for AnyIntegrator {
    fn default() -> Self {
        AnyIntegrator::Path(PathIntegrator::default())
    }
}

impl Integrator for AnyIntegrator {
    fn name(&self) -> &'static str {
        match self {
            AnyIntegrator::Path(i) => i.name(),
            AnyIntegrator::Direct(i) => i.name(),
        }
    }

    #[inline]
    fn li(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler) -> Rgb {
        match self {
            AnyIntegrator::Path(i) => i.li(scene, ray, sampler),
            AnyIntegrator::Direct(i) => i.li(scene, ray, sampler),
        }
    }

    fn has_terms(&self) -> bool {
        matches!(self, AnyIntegrator::Path(_))
    }

    fn li_terms(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, terms: &mut [Rgb]) -> Rgb {
        match self {
            AnyIntegrator::Path(i) => i.li_terms(scene, ray, sampler, terms),
            AnyIntegrator::Direct(i) => i.li_terms(scene, ray, sampler, terms),
        }
    }
}
