//! pbrt-v4's goniometric light (neumann's `goniometric` emitter): a point light whose intensity
//! varies with direction as a goniophotometric diagram says — a square image in pbrt-v4's
//! equal-area octahedral layout, read as one channel (the average of its RGB, as pbrt does)
//! times the light's intensity colour.
//!
//! In the light's frame (`to_world`) the diagram's pole is +y: the direction `d` reads the
//! texel nearest to `equal_area_sphere_to_square(d.x, d.z, d.y)` (pbrt's y/z swap). The
//! intensity is `I(d) = intensity · image(d)` (W sr⁻¹); the power `4π · intensity · mean(image)`.
//! Emitted rays for light tracing leave uniformly over the sphere, weighted by `4π I(d)`.

use super::{EmissionSample, LightSample};
use crate::image::Image;
use crate::math::{luminance, Rgb, Transform, Vec2, Vec3, PI};
use crate::sampling::equal_area::equal_area_sphere_to_square;
use crate::sampling::sample_uniform_sphere;
use std::sync::Arc;

/// A goniometric light.
#[derive(Clone, Debug)]
pub struct Goniometric {
    /// World → light frame.
    to_local: Transform,
    /// Position (world).
    position: Vec3,
    /// Intensity colour (W sr⁻¹ where the diagram is 1).
    intensity: Rgb,
    /// The diagram: one value per texel of a square equal-area image.
    diagram: Arc<Vec<f32>>,
    /// Its side in texels.
    side: usize,
    /// Its mean value.
    mean: f32,
}

/// Why a goniometric light cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GoniometricError {
    /// The image is not square.
    #[error("a goniometric diagram is a square equal-area image, this one is {0}×{1}")]
    NotSquare(u32, u32),
    /// A texel is negative or not finite.
    #[error("the goniometric diagram has a negative or non-finite texel")]
    BadTexel,
}

impl Goniometric {
    /// A goniometric light placed by `to_world` (its position is the frame's origin), with the
    /// diagram `image` (square; each texel's RGB average is its value) times `intensity`.
    pub fn new(to_world: Transform, image: &Image, intensity: Rgb) -> Result<Goniometric, GoniometricError> {
        if image.width != image.height || image.width == 0 {
            return Err(GoniometricError::NotSquare(image.width, image.height));
        }
        let diagram: Vec<f32> = image.pixels.iter().map(|c| (c.x + c.y + c.z) / 3.0).collect();
        if diagram.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(GoniometricError::BadTexel);
        }
        let mean = diagram.iter().map(|v| *v as f64).sum::<f64>() as f32 / diagram.len() as f32;
        Ok(Goniometric {
            to_local: to_world.inverse(),
            position: to_world.apply_point(Vec3::ZERO),
            intensity,
            diagram: Arc::new(diagram),
            side: image.width as usize,
            mean,
        })
    }

    /// Intensity (W sr⁻¹) toward the unit world direction `d`.
    pub fn intensity_toward(&self, d: Vec3) -> Rgb {
        let Some(local) = self.to_local.apply_vector(d).try_normalize() else { return Rgb::ZERO };
        let uv = equal_area_sphere_to_square(Vec3::new(local.x, local.z, local.y));
        let texel = |t: f32| ((t * self.side as f32) as usize).min(self.side - 1);
        self.intensity * self.diagram[texel(uv.y) * self.side + texel(uv.x)]
    }

    /// Light arriving at `p_ref` (a delta light: `pdf` 1).
    pub fn sample_li(&self, p_ref: Vec3) -> Option<LightSample> {
        let d = self.position - p_ref;
        let dist2 = d.length_squared();
        if dist2 == 0.0 {
            return None;
        }
        let wi = d / dist2.sqrt();
        let li = self.intensity_toward(-wi) / dist2;
        (li.max_element() > 0.0 && li.is_finite()).then(|| LightSample::from_point(self.position, wi, li))
    }

    /// A ray leaving the light: its direction uniform over the sphere, weight `4π I(d)` (whose
    /// mean is the power).
    pub fn sample_le(&self, u_dir: Vec2) -> Option<EmissionSample> {
        let d = sample_uniform_sphere(u_dir).value;
        let weight = self.intensity_toward(d) * (4.0 * PI);
        (weight.max_element() > 0.0).then_some(EmissionSample {
            p: self.position,
            p_error: Vec3::ZERO,
            n: Vec3::ZERO,
            d,
            weight,
        })
    }

    /// Emitted power (luminance, W): `4π · luminance(intensity) · mean(diagram)` (each texel an
    /// equal solid angle).
    pub fn power(&self) -> f32 {
        4.0 * PI * luminance(self.intensity) * self.mean
    }

    /// Position (world).
    pub fn position(&self) -> Vec3 {
        self.position
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::equal_area::equal_area_square_to_sphere;

    /// A diagram bright in one texel: the intensity there (pbrt's +y pole at the square's
    /// centre), zero elsewhere; the emitted rays' weights average to the power, which is
    /// 4π × the mean.
    #[test]
    fn diagram_lookup_power_and_emission() {
        let n = 4u32;
        let mut pixels = vec![Rgb::splat(0.5); 16];
        pixels[5] = Rgb::new(3.0, 6.0, 9.0); // texel (1, 1): average 6
        let image = Image { width: n, height: n, pixels };
        let to_world = Transform::translate(Vec3::new(1.0, 2.0, 3.0));
        let g = Goniometric::new(to_world, &image, Rgb::new(1.0, 2.0, 1.0)).unwrap();
        // The centre of texel (1, 1) in the square, as a direction with pbrt's axes swapped back.
        let s = equal_area_square_to_sphere(Vec2::new(1.5 / 4.0, 1.5 / 4.0));
        let d = Vec3::new(s.x, s.z, s.y);
        assert!((g.intensity_toward(d) - Rgb::new(6.0, 12.0, 6.0)).abs().max_element() < 1e-5);
        let sample = g.sample_li(Vec3::new(1.0, 2.0, 3.0) + 2.0 * d).unwrap();
        assert!((sample.li - Rgb::new(6.0, 12.0, 6.0) / 4.0).abs().max_element() < 1e-4, "{}", sample.li);
        // The centre of the square is the +y pole.
        let s = equal_area_square_to_sphere(Vec2::splat(0.5));
        assert!((Vec3::new(s.x, s.z, s.y) - Vec3::Y).length() < 1e-5);
        let mean = (15.0 * 0.5 + 6.0) / 16.0;
        assert!((g.power() - 4.0 * PI * luminance(Rgb::new(1.0, 2.0, 1.0)) * mean).abs() < 1e-3);
        let mut rng = crate::sampling::Pcg32::new(3, 1);
        let n_rays = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n_rays {
            if let Some(e) = g.sample_le(crate::testkit::u2(&mut rng)) {
                sum += luminance(e.weight) as f64;
            }
        }
        let estimate = sum / n_rays as f64;
        assert!((estimate / g.power() as f64 - 1.0).abs() < 0.03, "{estimate} vs {}", g.power());
        let wide = Image { width: 4, height: 2, pixels: vec![Rgb::ONE; 8] };
        assert_eq!(Goniometric::new(Transform::IDENTITY, &wide, Rgb::ONE).unwrap_err(), GoniometricError::NotSquare(4, 2));
    }
}
