//! Mitsuba's `depth` integrator: the distance to the first surface along each camera ray.
//!
//! Every channel of a sample holds the distance (world units) from the camera ray's origin
//! (on the near-clip plane for a perspective camera, as in Mitsuba) to the first surface it
//! meets, whatever that surface is (an emitter, a `null` BSDF, a medium's boundary); a ray that
//! meets none gives 0 and coverage 0. The film averages samples as it averages radiance, so a
//! pixel on a silhouette holds the mean distance weighted by coverage. No random numbers are
//! drawn. Mitsuba's parameters of every sampling integrator (`hide_emitters`, `timeout`,
//! `samples_per_pass`) are read; `hide_emitters` changes nothing here, as in Mitsuba.

use super::{Integrator, RadianceSample};
use crate::math::{Ray, Rgb};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::Sampler;
use crate::scene::{HitSlot, Scene};

/// The distance to the first surface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DepthIntegrator;

impl DepthIntegrator {
    /// From Mitsuba's parameters (none of its own).
    pub fn from_props(o: &Obj) -> PropResult<DepthIntegrator> {
        o.bool("hide_emitters", false)?;
        Ok(DepthIntegrator)
    }
}

impl Integrator for DepthIntegrator {
    fn name(&self) -> &'static str {
        "depth"
    }

    fn sample(&self, scene: &Scene, ray: &Ray, _: &mut Sampler, _: &mut [Rgb]) -> RadianceSample {
        match scene.intersect_deferred(ray, &mut HitSlot::default()) {
            Some(hit) => RadianceSample { l: Rgb::splat(hit.t() * ray.d.length()), alpha: 1.0 },
            None => RadianceSample { l: Rgb::ZERO, alpha: 0.0 },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::aov::AovKind;
    use crate::integrator::{AnyIntegrator, AovIntegrator};
    use crate::render::{render, RenderSettings};
    use std::sync::atomic::AtomicBool;

    /// The distances of a Cornell box equal those the `aov` integrator records (`depth.T`), bit
    /// for bit with the same samples; most pixels see the box (at more than 1 from the
    /// camera), and a pixel is covered where its distance is not 0.
    #[test]
    fn equals_the_depth_aov() {
        let scene = crate::scene::cornell::cornell_box(16, 12).unwrap();
        let settings = RenderSettings { spp: 4, seed: 1, alpha: true, ..Default::default() };
        let never = AtomicBool::new(false);
        let depth = render(&scene, &DepthIntegrator, &settings, &never).unwrap().film;
        let aov = AovIntegrator::around(AnyIntegrator::default(), vec![("d".into(), AovKind::Depth)]);
        let reference = render(&scene, &aov, &settings, &never).unwrap().film;
        let channels = reference.aov_channels();
        let d = &channels.iter().find(|c| c.0 == "d.T").expect("the aov film has d.T").1;
        let (image, alpha) = (depth.image(), depth.alpha());
        assert_eq!(image.len(), d.len());
        for (k, (px, &want)) in image.iter().zip(d.iter()).enumerate() {
            assert_eq!(px.x, want, "pixel {k}");
            assert!(px.x == px.y && px.y == px.z, "pixel {k}: {px:?}");
            assert_eq!(px.x > 0.0, alpha[k] > 0.0, "pixel {k}: coverage {}", alpha[k]);
        }
        let inside = image.iter().filter(|px| px.x > 1.0).count();
        assert!(inside > image.len() * 2 / 3, "{inside} of {} pixels see the box", image.len());
    }

    /// A unit sphere 4 from the camera, nothing else: the centre pixel holds the distance from
    /// the near-clip plane to the pole, a corner pixel 0 with coverage 0.
    #[test]
    fn misses_are_zero_and_uncovered() {
        use crate::camera::{Camera, FovAxis};
        use crate::geometry::{Geometry, Sphere};
        use crate::material::{Bsdf, Diffuse};
        use crate::math::{Transform, Vec3};
        let mut b = crate::scene::SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 1.0, false)), m, None);
        b.add_constant_environment(Rgb::splat(1.0));
        let to_world = Transform::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y).unwrap();
        b.set_camera(Camera::perspective(to_world, 40.0, FovAxis::X, 9, 9).unwrap());
        let scene = b.build().unwrap();
        let settings =
            RenderSettings { spp: 16, filter: crate::film::filter::Filter::BOX, alpha: true, ..Default::default() };
        let film = render(&scene, &DepthIntegrator, &settings, &AtomicBool::new(false)).unwrap().film;
        let centre = 4 * 9 + 4;
        assert!((film.image()[centre].x - 2.99).abs() < 0.01, "{:?}", film.image()[centre]);
        assert_eq!((film.image()[0], film.alpha()[0]), (Rgb::ZERO, 0.0));
    }
}
