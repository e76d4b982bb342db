//! Mitsuba's `moment` integrator: renders with one or more nested camera-ray integrators and
//! records, per nested integrator, the mean and the second moment of its samples as AOVs. The
//! image itself is the first nested integrator's.
//!
//! Channels (Mitsuba 3's names and order): for each nested integrator `n` (its `name`
//! attribute, else `_arg_0`, `_arg_1`, … for unnamed ones in document order), its own AOVs
//! `n.<aov>`, then `n.X`, `n.Y`, `n.Z` (the sample's CIE XYZ, from linear sRGB); then the same
//! list again with the prefix `m2_`, holding the per-sample square of each value. A pixel's
//! `m2_` channel is thus the filter-weighted mean of `v²`, and `m2 − mean²` the sample variance.
//! Each nested integrator draws its random numbers after the previous one's, so they are
//! independent samples.

use super::{nested_integrators, AnyIntegrator, Integrator, RadianceSample};
use crate::camera::RayDifferentials;
use crate::math::color::srgb_to_xyz;
use crate::math::{Ray, Rgb};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::Sampler;
use crate::scene::Scene;

/// The moment integrator: nested integrators with their names.
#[derive(Clone, Debug)]
pub struct MomentIntegrator {
    /// The nested camera-ray integrators and their names.
    pub nested: Vec<(String, AnyIntegrator)>,
}

impl MomentIntegrator {
    /// Mitsuba's `moment`: one or more nested `<integrator>`s (camera-ray integrators only).
    pub fn from_props(o: &Obj) -> PropResult<MomentIntegrator> {
        let nested = nested_integrators(o)?;
        if nested.is_empty() {
            return Err(o.error("the moment integrator needs a nested <integrator> whose samples it records"));
        }
        Ok(MomentIntegrator { nested })
    }

    /// The channel names of the first moments (the `m2_` ones follow with the same order).
    fn first_moment_names(&self) -> Vec<String> {
        let mut names = Vec::new();
        for (name, i) in &self.nested {
            names.extend(inner(i).aov_names().into_iter().map(|a| format!("{name}.{a}")));
            names.extend(["X", "Y", "Z"].map(|c| format!("{name}.{c}")));
        }
        names
    }
}

impl Integrator for MomentIntegrator {
    fn name(&self) -> &'static str {
        "moment"
    }

    fn sample(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, terms: &mut [Rgb]) -> RadianceSample {
        super::sample_without_aovs(self, scene, ray, sampler, terms)
    }

    fn has_terms(&self) -> bool {
        inner(&self.nested[0].1).has_terms()
    }

    fn aov_names(&self) -> Vec<String> {
        let first = self.first_moment_names();
        let second = first.iter().map(|n| format!("m2_{n}"));
        first.iter().cloned().chain(second).collect()
    }

    fn aov_count(&self) -> usize {
        2 * self.nested.iter().map(|(_, i)| inner(i).aov_count() + 3).sum::<usize>()
    }

    fn wants_differentials(&self) -> bool {
        self.nested.iter().any(|(_, i)| inner(i).wants_differentials())
    }

    fn sample_aovs(
        &self,
        scene: &Scene,
        ray: &Ray,
        differentials: Option<&RayDifferentials>,
        sampler: &mut Sampler,
        terms: &mut [Rgb],
        aovs: &mut [f32],
    ) -> RadianceSample {
        let (first, second) = aovs.split_at_mut(aovs.len() / 2);
        let mut at = 0;
        let mut result = RadianceSample { l: Rgb::ZERO, alpha: 0.0 };
        for (k, (_, nested)) in self.nested.iter().enumerate() {
            let inner = inner(nested);
            let n = inner.aov_count();
            // Only the first (the image) keeps the Neumann-series terms.
            let terms: &mut [Rgb] = if k == 0 { terms } else { &mut [] };
            let s = inner.sample_aovs(scene, ray, differentials, sampler, terms, &mut first[at..at + n]);
            let xyz = srgb_to_xyz(s.l);
            first[at + n..at + n + 3].copy_from_slice(&[xyz.x, xyz.y, xyz.z]);
            at += n + 3;
            if k == 0 {
                result = s;
            }
        }
        for (m2, v) in second.iter_mut().zip(first.iter()) {
            *m2 = v * v;
        }
        result
    }
}

/// A nested integrator as the camera-ray integrator it is (checked when it was nested).
fn inner(i: &AnyIntegrator) -> &dyn Integrator {
    i.camera().expect("nested integrators trace camera rays")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choice::Choice;
    use crate::film::filter::Filter;
    use crate::integrator::{IntegratorKind, PathIntegrator, PathSettings};
    use crate::render::{render, RenderSettings};
    use crate::scene::cornell::cornell_box;
    use std::sync::atomic::AtomicBool;

    /// The image is the nested integrator's, bit for bit (it draws the same numbers); the first
    /// moments are the XYZ of the image; the second moments are the per-pixel mean of the
    /// squared samples, which for the box filter is `Var + mean²` with the film's own sample
    /// variance of the radiance (so the difference is a real variance: never negative).
    #[test]
    fn mean_and_second_moment_of_the_nested_integrator() {
        let scene = cornell_box(12, 12).unwrap();
        let path = PathIntegrator { settings: PathSettings::default(), ..Default::default() };
        let moment = AnyIntegrator::with_kind(IntegratorKind::Moment, PathSettings::default());
        assert_eq!(moment.name(), IntegratorKind::Moment.name());
        let settings = RenderSettings { spp: 64, seed: 3, filter: Filter::BOX, ..Default::default() };
        let never = AtomicBool::new(false);
        let plain = render(&scene, &path, &settings, &never).unwrap();
        let with = render(&scene, moment.camera().unwrap(), &settings, &never).unwrap();
        assert_eq!(plain.film.image(), with.film.image());
        let channels = with.film.aov_channels();
        let names: Vec<&str> = channels.iter().map(|c| c.0.as_str()).collect();
        assert_eq!(names, ["_arg_0.X", "_arg_0.Y", "_arg_0.Z", "m2__arg_0.X", "m2__arg_0.Y", "m2__arg_0.Z"]);
        let image = with.film.image();
        let var = with.film.variance_of_mean();
        let mut excess = 0.0f64;
        for (i, c) in image.iter().enumerate() {
            let xyz = srgb_to_xyz(*c);
            for k in 0..3 {
                let mean = channels[k].1[i];
                assert!((mean - xyz[k]).abs() <= 1e-4 * xyz[k].max(1.0), "pixel {i} channel {k}: {mean} vs {}", xyz[k]);
                let m2 = channels[3 + k].1[i];
                assert!(m2 >= mean * mean * (1.0 - 1e-4), "pixel {i}: second moment {m2} < mean² {}", mean * mean);
            }
            // Y is a fixed linear combination of R, G, B, so its sample variance is at most
            // (Σ coefficient · σ)² of the channels' and at least 0; m2 − Y² is n−1/n of it.
            let sigma: f32 = (0..3).map(|k| [0.212671, 0.715160, 0.072169][k] * (var[i][k] * 64.0).sqrt()).sum();
            let y_var = channels[4].1[i] - channels[1].1[i].powi(2);
            assert!(y_var <= sigma * sigma * 1.001 + 1e-6, "pixel {i}: {y_var} > {}", sigma * sigma);
            excess += y_var as f64;
        }
        assert!(excess > 0.0, "a noisy render has a positive variance somewhere");
    }
}
