//! Light tracing (Mitsuba's `ptracer`): forward ray tracing from the emitters.
//!
//! A light path starts on an emitter chosen by power: a position by area and a direction
//! (cosine-weighted for area lights, [`Light::sample_le`]), carrying power
//! `β₀ = Lₑ |cos θ| / (p_light p_A p_ω)`. Every vertex `y` it reaches is connected to the camera
//! ([`crate::camera::Camera::sample_wi`]) and adds `β f(y) |cos θ_y| Wₑ G / p` to the pixel it projects to
//! (splatting); the path then continues by BSDF sampling with Russian roulette. An area
//! emitter's own point is connected too (what the camera sees directly), unless
//! `hide_emitters`; as in Mitsuba's `ptracer`, delta lights (point, spot, projector,
//! goniometric, directional) are not: no camera ray can meet them, so neither image shows them.
//!
//! Transport mode: light tracing transports importance, so BSDF values are those of the
//! adjoint BSDF. For refraction that removes the `1/η²` radiance scaling
//! ([`crate::material::Bsdf::eval_adjoint`], lobe by lobe), and shading normals get Veach's correction
//! `|ωₚ·nₛ| |ωₙ·n_g| / (|ωₚ·n_g| |ωₙ·nₛ|)` (ωₚ toward the previous vertex, ωₙ the next one).
//!
//! As in Mitsuba, vertices on purely specular surfaces cannot be connected (their BSDF is a
//! delta), so light that reaches the camera only by specular reflection or refraction (a light
//! seen in a mirror or through glass) is missing from a ptracer image; diffuse and glossy
//! transport, caustics included, is all there. Lights at infinity emit parallel rays into the
//! scene; no connection reaches them, so the driver sees them directly through camera rays
//! that escape the scene (`render::render_light_paths`), as Mitsuba's ptracer does.
//!
//! `max_depth` counts path segments including the one to the camera, as for `path`: 1 shows
//! the emitters only, 2 adds direct light. The image estimate: with `N` paths per pixel
//! (`spp × W × H` paths in all), a pixel's value is the sum of its splats divided by `spp`
//! (see `render::render_light_paths`).

use super::trace::PathSettings;
use crate::geometry::interaction::SHADOW_EPSILON;
use crate::light::Light;
use crate::math::float::offset_ray_origin;
use crate::math::{luminance, Ray, Rgb, Vec2, Vec3};
use crate::sampling::Pcg32;
use crate::material::TextureMemo;
use crate::scene::Scene;

/// The light tracer's settings: `max_depth` counts segments with the camera connection,
/// Russian roulette applies from `rr_depth` segments on, and `hide_emitters` leaves out the
/// emitters' direct connection to the camera.
#[derive(Clone, Debug, Default)]
pub struct LightTracer {
    /// `max_depth`, `rr_depth`, `hide_emitters`.
    pub settings: PathSettings,
}

/// Veach's shading-normal correction for adjoint transport at a surface point with shading
/// normal `ns` and geometric normal `ng`, between the direction toward the previous vertex
/// `w_prev` and the next one `w_next` (world, unit).
#[inline]
fn shading_correction(ns: Vec3, ng: Vec3, w_prev: Vec3, w_next: Vec3) -> f32 {
    if ns == ng {
        return 1.0;
    }
    let den = w_prev.dot(ng).abs() * w_next.dot(ns).abs();
    if den == 0.0 {
        0.0
    } else {
        w_prev.dot(ns).abs() * w_next.dot(ng).abs() / den
    }
}

impl LightTracer {
    fn allows(&self, segments: u32) -> bool {
        self.settings.allows(segments)
    }

    /// Traces one light path with random numbers from `rng`, calling `splat(film, value)` for
    /// each contribution that reaches the camera (film position in pixels of the whole film).
    pub fn trace(&self, scene: &Scene, rng: &mut Pcg32, splat: &mut impl FnMut(Vec2, Rgb)) {
        // The path's time where shapes move (uniform over the shutter; drawn only then).
        let time = scene.motion_shutter().map_or(0.0, |(open, close)| open + (close - open) * rng.next_f32());
        let mut u2 = || Vec2::new(rng.next_f32(), rng.next_f32());
        let Some((light_index, pmf)) = scene.sample_emitting_light(u2().x) else { return };
        let light: &Light = &scene.lights()[light_index as usize];
        let camera = scene.camera();
        let shapes = scene.geometries();

        // The emitter seen directly: one segment, light to camera.
        let (u_pos, u_lens) = (u2(), u2());
        if !self.settings.hide_emitters && self.allows(1) {
            if let Some(pos) = light.sample_le_position(shapes, u_pos) {
                if let Some(cs) = camera.sample_wi_at(pos.p, u_lens, time) {
                    let cos = pos.ng.dot(cs.wi).abs();
                    let value = light.emitted_toward(&pos, cs.wi) * (cos * cs.weight * pos.inv_pdf / pmf);
                    if value.max_element() > 0.0 {
                        let o = offset_ray_origin(pos.p, pos.p_error, pos.ng, cs.wi);
                        if !scene.occluded(&Ray::bounded(o, cs.p_lens - o, 1.0 - SHADOW_EPSILON).at_time(time)) {
                            splat(cs.film, value);
                        }
                    }
                }
            }
        }
        if !self.allows(2) {
            return;
        }

        let (u_pos, u_dir) = (u2(), u2());
        let Some(es) = light.sample_le(shapes, u_pos, u_dir) else { return };
        let mut beta = es.weight / pmf;
        let beta0 = luminance(beta).max(f32::MIN_POSITIVE);
        let origin = if es.n == Vec3::ZERO { es.p } else { offset_ray_origin(es.p, es.p_error, es.n, es.d) };
        let mut ray = Ray::new(origin, es.d).at_time(time);
        // `segments`: path segments from the light to the current vertex.
        let mut segments = 1u32;
        while let Some(si) = scene.intersect(&ray) {
            let bsdf = &scene.bsdfs()[scene.shapes()[si.shape as usize].bsdf as usize];
            let frame = si.frame();
            let w_prev = -ray.d;
            let wo = frame.to_local(w_prev);
            // Textures and normal maps looked up once for this vertex's BSDF calls.
            let memo = TextureMemo::default();
            let ctx = scene.bsdf_context(&si).with_memo(&memo);
            let (u_lens, u_lobe, u_bsdf, u_rr) = (u2(), u2().x, u2(), u2().x);

            // Connect this vertex to the camera.
            if self.allows(segments + 1) && !bsdf.is_delta() {
                if let Some(cs) = camera.sample_wi_at(si.p, u_lens, time) {
                    let wi = frame.to_local(cs.wi);
                    let f = bsdf.eval_adjoint(&ctx, wo, wi) * shading_correction(si.ns, si.ng, w_prev, cs.wi);
                    let value = beta * f * cs.weight;
                    if value.max_element() > 0.0 && !scene.occluded(&si.spawn_ray_to(cs.p_lens, Vec3::ZERO, Vec3::ZERO))
                    {
                        splat(cs.film, value);
                    }
                }
            }
            if !self.allows(segments + 2) {
                break;
            }

            // Continue by sampling the adjoint BSDF.
            let Some(bs) = bsdf.sample(&ctx, wo, u_lobe, u_bsdf) else { break };
            let w_next = frame.to_world(bs.wi);
            beta = beta * bsdf.adjoint_sample_weight(&ctx, wo, &bs) * shading_correction(si.ns, si.ng, w_prev, w_next);
            if beta.max_element() <= 0.0 || !beta.is_finite() {
                break;
            }
            segments += 1;
            if segments >= self.settings.rr_depth {
                let q = (luminance(beta) / beta0).min(0.95);
                if u_rr >= q {
                    break;
                }
                beta /= q;
            }
            ray = si.spawn_ray(w_next);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Film;
    use crate::integrator::PathIntegrator;
    use crate::render::{render, render_light_paths, RenderSettings};
    use std::sync::atomic::AtomicBool;

    /// Sum over pixels of squared differences, and of the two images' variances of the mean:
    /// for unbiased independent estimates the first is close to the second.
    fn error_vs_noise(a: &Film, b: &Film) -> (f64, f64) {
        let (ia, ib) = (a.image(), b.image());
        let (va, vb) = (a.variance_of_mean(), b.variance_of_mean());
        let mut err = 0.0f64;
        let mut noise = 0.0f64;
        for i in 0..ia.len() {
            for c in 0..3 {
                err += ((ia[i][c] - ib[i][c]) as f64).powi(2);
                noise += (va[i][c] + vb[i][c]) as f64;
            }
        }
        (err, noise)
    }

    /// Forward and backward ray tracing solve the same equation: on the diffuse Cornell box
    /// (non-square film, so that the importance normalisation and the film mapping are
    /// checked along both axes) the light tracer's image is as close to a long path-traced
    /// reference as its own noise allows — relMSE(ptracer, reference) against the relMSE
    /// expected from the two estimates' variances, each measured from two independent renders
    /// — and its mean is within 0.5 %.
    /// A directly visible environment: camera rays that escape see it, so the sky's pixels equal
    /// its radiance (exactly, with the box filter) and the lit sphere agrees with the path
    /// tracer; without a light at infinity the image is bit-identical to before (no camera rays).
    #[test]
    fn sees_lights_at_infinity_through_escaping_camera_rays() {
        use crate::camera::{Camera, FovAxis};
        use crate::geometry::{Geometry, Sphere};
        use crate::material::{Bsdf, Diffuse};
        use crate::math::{Transform, Vec3};
        let never = AtomicBool::new(false);
        let mut b = crate::scene::SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::new(0.0, 0.0, 4.0), 1.0, false)), m, None);
        b.add_constant_environment(Rgb::new(0.2, 0.4, 0.8));
        b.set_camera(Camera::perspective(Transform::IDENTITY, 45.0, FovAxis::X, 16, 16).unwrap());
        let scene = b.build().unwrap();
        let settings = RenderSettings { spp: 256, seed: 5, ..Default::default() };
        let light = render_light_paths(&scene, &LightTracer::default(), &settings, &never).unwrap().film.image();
        assert_eq!(light[0], Rgb::new(0.2, 0.4, 0.8), "a corner sees only the sky");
        let path = render(&scene, &PathIntegrator::default(), &settings, &never).unwrap().film.image();
        let centre = |im: &[Rgb]| (6..10).flat_map(|y| (6..10).map(move |x| y * 16 + x)).map(|i| im[i].y).sum::<f32>() / 16.0;
        let (l, p) = (centre(&light), centre(&path));
        assert!((l - p).abs() < 0.03 * p && p > 0.1, "the lit sphere: light tracer {l}, path tracer {p}");
        let hidden = LightTracer { settings: PathSettings { hide_emitters: true, ..Default::default() } };
        let im = render_light_paths(&scene, &hidden, &settings, &never).unwrap().film.image();
        assert_eq!(im[0], Rgb::ZERO, "hide_emitters hides the sky");
    }

    /// A point light in plain view: no camera ray meets it, so the path tracer's image has no
    /// light there, and neither has the light tracer's (Mitsuba's `ptracer` connects no delta
    /// light to the camera). Connecting it would put I / (r² Ω_pixel) in the pixel it
    /// projects to (here ≈ 50), against ≈ 0.02 of lit wall (the light tracer noisier: 4×).
    #[test]
    fn point_lights_stay_invisible_as_in_the_path_tracer() {
        use crate::camera::{Camera, FovAxis};
        use crate::geometry::{Geometry, TriangleMesh};
        use crate::material::{Bsdf, Diffuse};
        use crate::math::{Transform, Vec3};
        let never = AtomicBool::new(false);
        let mut b = crate::scene::SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
        // A wall at z = 6 facing the camera, lit by a point light halfway to it.
        let mut wall = TriangleMesh::rectangle();
        let flip = Transform::rotate(Vec3::Y, 180.0).unwrap();
        wall.transform(
            &(Transform::translate(Vec3::new(0.0, 0.0, 6.0)) * Transform::scale(Vec3::splat(10.0)).unwrap() * flip),
        );
        b.add_shape(Geometry::Mesh(wall), m, None);
        b.add_point_light(Vec3::new(0.0, 0.0, 3.0), Rgb::splat(1.0));
        b.set_camera(Camera::perspective(Transform::IDENTITY, 45.0, FovAxis::X, 16, 16).unwrap());
        let scene = b.build().unwrap();
        let settings = RenderSettings { spp: 64, seed: 3, ..Default::default() };
        let light = render_light_paths(&scene, &LightTracer::default(), &settings, &never).unwrap().film.image();
        let path = render(&scene, &PathIntegrator::default(), &settings, &never).unwrap().film.image();
        let brightest = |im: &[Rgb]| im.iter().map(|c| c.max_element()).fold(0.0f32, f32::max);
        let (l, p) = (brightest(&light), brightest(&path));
        assert!(p > 0.01 && l < 4.0 * p, "brightest pixel: light tracer {l}, path tracer {p}");
    }

    #[test]
    fn agrees_with_the_path_tracer_on_the_cornell_box() {
        use crate::film::metrics::relmse;
        let scene = crate::scene::cornell::cornell_box(40, 24).unwrap();
        let never = AtomicBool::new(false);
        let path = |seed| {
            render(
                &scene,
                &PathIntegrator::default(),
                &RenderSettings { spp: 2048, seed, ..Default::default() },
                &never,
            )
            .unwrap()
            .film
        };
        let light = |seed| {
            render_light_paths(
                &scene,
                &LightTracer::default(),
                &RenderSettings { spp: 256, seed, ..Default::default() },
                &never,
            )
            .unwrap()
            .film
        };
        let (r1, r2, a, b) = (path(1), path(2), light(3), light(4));
        let (ir1, ir2) = (r1.image(), r2.image());
        let reference: Vec<Rgb> = ir1.iter().zip(&ir2).map(|(x, y)| (*x + *y) * 0.5).collect();
        let (ia, ib) = (a.image(), b.image());
        // E[relMSE(A, ref)] ≈ var(A) + var(ref); var(A) = relMSE(A, B)/2, var(ref) = relMSE(r1, r2)/4.
        let expected = relmse(&ia, &ib) / 2.0 + relmse(&ir1, &ir2) / 4.0;
        let measured = relmse(&ia, &reference);
        let mean = |f: &Film| f.mean_and_std_error();
        let (m_ref, se_ref) = {
            let (m1, s1) = mean(&r1);
            let (m2, s2) = mean(&r2);
            ((m1 + m2) / 2.0, (s1 * s1 + s2 * s2).sqrt() / 2.0)
        };
        let (m_lt, se_lt) = {
            let (m1, s1) = mean(&a);
            let (m2, s2) = mean(&b);
            ((m1 + m2) / 2.0, (s1 * s1 + s2 * s2).sqrt() / 2.0)
        };
        let rel = (m_lt - m_ref) / m_ref;
        println!(
            "mean: ptracer {m_lt:.5} ± {se_lt:.5}, path {m_ref:.5} ± {se_ref:.5} ({:+.3} %); relMSE {measured:.3e} vs {expected:.3e} expected from noise",
            100.0 * rel
        );
        assert!((se_lt * se_lt + se_ref * se_ref).sqrt() < 0.0025 * m_ref, "too noisy to test 0.5 %");
        assert!(rel.abs() < 0.005, "means differ by {:.3} %", 100.0 * rel);
        assert!(
            measured < 1.2 * expected,
            "relMSE {measured:.3e} against the reference, {expected:.3e} expected from noise"
        );
    }

    /// Depth-limited light tracing gives the same terms as depth-limited path tracing: the
    /// emitters alone (1 segment) and direct light (2 segments).
    #[test]
    fn depth_limits_match_the_path_tracer() {
        let scene = crate::scene::cornell::cornell_box(16, 16).unwrap();
        let never = AtomicBool::new(false);
        for depth in [1, 2] {
            let path = PathIntegrator::with_max_depth(depth);
            let reference =
                render(&scene, &path, &RenderSettings { spp: 1024, seed: 3, ..Default::default() }, &never).unwrap();
            let tracer = LightTracer { settings: PathSettings { max_depth: depth, ..Default::default() } };
            let light = render_light_paths(
                &scene,
                &tracer,
                &RenderSettings { spp: 1024, seed: 4, ..Default::default() },
                &never,
            )
            .unwrap();
            let (m_ref, se_ref) = reference.film.mean_and_std_error();
            let (m_lt, se_lt) = light.film.mean_and_std_error();
            let sigma = (se_lt * se_lt + se_ref * se_ref).sqrt();
            println!("max_depth {depth}: ptracer {m_lt:.5} ± {se_lt:.5}, path {m_ref:.5} ± {se_ref:.5}");
            assert!((m_lt - m_ref).abs() < 4.0 * sigma + 1e-4 * m_ref, "max_depth {depth}: {m_lt} vs {m_ref}");
        }
    }

    /// A thin-lens camera (defocus) and a box filter crop window: still the path tracer's image.
    #[test]
    fn thin_lens_agrees_with_the_path_tracer() {
        let mut scene = crate::scene::cornell::cornell_box(24, 24).unwrap();
        let cam = scene.camera().clone().with_thin_lens(0.15, 2.5).unwrap();
        scene.set_camera(cam);
        let never = AtomicBool::new(false);
        let settings = |seed| RenderSettings { spp: 512, seed, window: Some([4, 2, 16, 20]), ..Default::default() };
        let reference = render(&scene, &PathIntegrator::default(), &settings(5), &never).unwrap();
        let light = render_light_paths(&scene, &LightTracer::default(), &settings(6), &never).unwrap();
        let (m_ref, se_ref) = reference.film.mean_and_std_error();
        let (m_lt, se_lt) = light.film.mean_and_std_error();
        let (err, noise) = error_vs_noise(&light.film, &reference.film);
        println!(
            "thin lens: ptracer {m_lt:.5} ± {se_lt:.5}, path {m_ref:.5} ± {se_ref:.5}; error/noise {:.3}",
            err / noise
        );
        assert!((m_lt - m_ref).abs() < 4.0 * (se_lt * se_lt + se_ref * se_ref).sqrt());
        assert!(err / noise < 1.25, "pixel error {err:.4e} vs noise {noise:.4e}");
    }

    /// Through rough glass (seen directly and casting light on a floor) the light tracer must
    /// use the adjoint BSDF: without removing refraction's 1/η² radiance scaling the sphere
    /// would come out 1.5² times too dark or bright. Means agree with the path tracer. The same
    /// for a blend of two rough glasses of indices 1.5 and 2: each component's adjoint takes its
    /// own η² (one factor for the blend, the product of the two indices, made this image 15 %
    /// too dark; on a random scene with such a blend Mitsuba 3.9.1's `ptracer` gives 0.443,
    /// neumann's 0.442 now and 0.388 before).
    #[test]
    fn rough_glass_uses_the_adjoint_bsdf() {
        let glass = r#"<bsdf type="roughdielectric"><float name="alpha" value="0.3"/><float name="int_ior" value="1.5"/></bsdf>"#;
        let blend = r#"<bsdf type="blendbsdf"><float name="weight" value="0.5"/>
                <bsdf type="roughdielectric"><float name="alpha" value="0.3"/><float name="int_ior" value="1.5"/></bsdf>
                <bsdf type="roughdielectric"><float name="alpha" value="0.2"/><float name="int_ior" value="2"/></bsdf>
            </bsdf>"#;
        for bsdf in [glass, blend] {
            let text = format!(
                r#"<scene version="3.0.0">
            <sensor type="perspective">
                <float name="fov" value="35"/>
                <transform name="to_world"><lookat origin="0, 2, 5" target="0, 0.6, 0" up="0, 1, 0"/></transform>
                <film type="hdrfilm"><integer name="width" value="20"/><integer name="height" value="16"/><rfilter type="box"/></film>
            </sensor>
            <shape type="rectangle">
                <transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/><translate y="3"/></transform>
                <emitter type="area"><rgb name="radiance" value="20, 20, 20"/></emitter>
            </shape>
            <shape type="sphere">
                <point name="center" x="0" y="0.8" z="0"/><float name="radius" value="0.8"/>
                {bsdf}
            </shape>
            <shape type="rectangle">
                <transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/></transform>
                <bsdf type="diffuse"/>
            </shape>
        </scene>"#
            );
            let file = crate::load::mitsuba::load_scene_text(std::path::Path::new("glass.xml"), &text, &[]).unwrap();
            let scene = file.scene;
            let never = AtomicBool::new(false);
            let reference = render(
                &scene,
                &PathIntegrator::default(),
                &RenderSettings { spp: 4096, seed: 7, ..Default::default() },
                &never,
            )
            .unwrap();
            let light = render_light_paths(
                &scene,
                &LightTracer::default(),
                &RenderSettings { spp: 4096, seed: 8, ..Default::default() },
                &never,
            )
            .unwrap();
            let (m_ref, se_ref) = reference.film.mean_and_std_error();
            let (m_lt, se_lt) = light.film.mean_and_std_error();
            let sigma = (se_lt * se_lt + se_ref * se_ref).sqrt();
            println!("rough glass: ptracer {m_lt:.5} ± {se_lt:.5}, path {m_ref:.5} ± {se_ref:.5}");
            assert!(sigma < 0.01 * m_ref, "too noisy: ± {sigma}");
            assert!((m_lt - m_ref).abs() < 4.0 * sigma, "ptracer {m_lt} vs path {m_ref} (± {sigma})");
        }
    }

    /// Mitsuba's `directionalarea` emitter: a square sending radiance 2 straight down onto a
    /// white (albedo ½) floor gives the floor an irradiance of exactly 2, so the light tracer
    /// must show the lit square at ½ · 2 / π, and nothing elsewhere (the emitter's own default
    /// BSDF is black, as Mitsuba's for emitting shapes). The path tracer sees nothing at all,
    /// as Mitsuba's: no camera, BSDF or shadow ray meets a delta direction.
    #[test]
    fn directional_area_light_lights_the_floor_below_it() {
        let text = r#"<scene version="3.0.0">
            <sensor type="perspective">
                <float name="fov" value="40"/>
                <transform name="to_world"><lookat origin="0, 3, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
                <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film>
            </sensor>
            <shape type="rectangle">
                <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
                <bsdf type="diffuse"/>
            </shape>
            <shape type="rectangle">
                <transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/><translate y="1"/></transform>
                <emitter type="directionalarea"><rgb name="radiance" value="2"/></emitter>
            </shape>
        </scene>"#;
        let file = crate::load::mitsuba::load_scene_text(std::path::Path::new("da.xml"), text, &[]).unwrap();
        let never = AtomicBool::new(false);
        let settings = RenderSettings { spp: 256, seed: 3, ..Default::default() };
        let film = render_light_paths(&file.scene, &LightTracer::default(), &settings, &never).unwrap().film;
        let image = film.image();
        let at = |x: usize, y: usize| image[y * 32 + x];
        // Rows 14–17, columns 12–19 see the floor inside the lit square (the square covers
        // rows 13–18, columns 11–20, partly at its border).
        let (mut sum, mut n) = (0.0f64, 0);
        for y in 0..32 {
            for x in 0..32 {
                let v = at(x, y);
                assert!(v.x == v.y && v.y == v.z, "grey light on a grey floor");
                if (14..=17).contains(&y) && (12..=19).contains(&x) {
                    sum += f64::from(v.x);
                    n += 1;
                    let r = v.x * crate::math::PI;
                    assert!((r - 1.0).abs() < 0.06, "pixel ({x}, {y}): {r} / π");
                } else if !(12..=19).contains(&y) || !(10..=21).contains(&x) {
                    assert_eq!(v.x, 0.0, "pixel ({x}, {y}) away from the lit square");
                }
            }
        }
        let mean = sum / f64::from(n) * std::f64::consts::PI;
        assert!((mean - 1.0).abs() < 0.01, "lit floor: {mean} / π, expected 1 / π");
        let path = render(&file.scene, &PathIntegrator::default(), &settings, &never).unwrap().film.image();
        assert!(path.iter().all(|v| *v == Rgb::ZERO), "the path tracer sees no directional area light");
    }

    /// The same seed gives the same image whatever the number of threads.
    #[test]
    fn deterministic_across_thread_counts() {
        let scene = crate::scene::cornell::cornell_box(12, 10).unwrap();
        let never = AtomicBool::new(false);
        let images: Vec<Vec<Rgb>> = [1, 2, 3]
            .iter()
            .map(|&threads| {
                let s = RenderSettings { spp: 3, seed: 9, threads, ..Default::default() };
                render_light_paths(&scene, &LightTracer::default(), &s, &never).unwrap().film.image()
            })
            .collect();
        assert!(images.iter().all(|im| *im == images[0]));
    }
}
