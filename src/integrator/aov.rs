//! Mitsuba's `aov` integrator: arbitrary output variables of the surface the camera ray hits
//! first (depth, position, normals, uv, albedo, primitive and shape index), beside the image of
//! one or more nested camera-ray integrators.
//!
//! Parameters: `aovs`, a comma-separated list of `name:type` pairs, with the types `albedo`
//! (channels `name.R/G/B`: the BSDF's diffuse reflectance), `depth` (`name.T`: distance along
//! the camera ray from its near-clip origin), `position` (`name.X/Y/Z`, world space),
//! `uv` (`name.U/V`), `geo_normal` and `sh_normal` (`name.X/Y/Z`, unit, world space),
//! `prim_index` (`name.I`: the triangle's index in its mesh — an `ellipsoidsmesh`'s ellipsoid, as
//! Mitsuba counts its shells —, the ellipsoid's in `ellipsoids`, 0 for other analytic shapes) and
//! `shape_index` (`name.I`: 1 + the shape's index in the scene, Mitsuba's shape id). Rays that
//! hit nothing give 0 in every channel. Nested integrators (named by their `name` attribute,
//! else `_arg_0`, `_arg_1`, …) come first as `n.R/G/B/A` (their radiance and coverage), then
//! their own AOVs `n.<aov>`; the image is the first nested integrator's (black without one).
//! `dp_du` and `dp_dv` (`name.X/Y/Z`) are the tangents `∂p/∂u`, `∂p/∂v` of the surface's
//! parameterization (world space, not normalized), as Mitsuba's shapes define them; `duv_dx`
//! and `duv_dy` (`name.U/V`) the change of (u, v) per pixel right and down, from the camera
//! ray's differentials ([`crate::camera::Camera::ray_differentials`]) scaled by 1/√spp as
//! Mitsuba scales them, and solved in the tangent plane as Mitsuba's `compute_uv_partials`
//! solves it (zero where Mitsuba's solve gives NaN: on misses, degenerate parameterizations).
//! `boundary_test` (projective differentiable rendering) is an error.

use super::{nested_integrators, AnyIntegrator, Integrator, RadianceSample};
use crate::camera::RayDifferentials;
use crate::geometry::SurfaceInteraction;
use crate::math::{Ray, Rgb, Vec2, Vec3};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::Sampler;
use crate::scene::Scene;

/// What one AOV records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AovKind {
    /// Diffuse reflectance (RGB).
    Albedo,
    /// Hit distance.
    Depth,
    /// Hit point.
    Position,
    /// Texture coordinates.
    Uv,
    /// Geometric normal.
    GeoNormal,
    /// Shading normal.
    ShNormal,
    /// Primitive index within the shape.
    PrimIndex,
    /// Shape id (1-based).
    ShapeIndex,
    /// `∂p/∂u`, the surface's tangent along its first texture coordinate (world space, not
    /// normalized).
    DpDu,
    /// `∂p/∂v` (world space, not normalized).
    DpDv,
    /// `∂(u, v)/∂x`: the change of the texture coordinates per pixel to the right, from the
    /// camera ray's differentials (Mitsuba's `duv_dx`).
    DuvDx,
    /// `∂(u, v)/∂y`: per pixel down (Mitsuba's `duv_dy`).
    DuvDy,
    /// Radiance emitted toward the camera by the first surface (an area emitter's side facing
    /// it), or by the lights at infinity for a ray that escapes: the part of the image a
    /// denoiser leaves alone.
    Emission,
    /// The denoiser's albedo guide: the diffuse reflectance, except on an emitter seen from its
    /// emitting side, where it is the emitted radiance scaled to a largest channel of 1 (so that
    /// a light and the surface around it differ in the guide as they do in the image).
    DenoisingAlbedo,
}

crate::choices!(AovKind, "AOV type", {
    AovKind::Albedo => "albedo", "diffuse reflectance of the BSDF (R, G, B)";
    AovKind::Depth => "depth", "distance to the first hit along the camera ray (T)";
    AovKind::Position => "position", "world-space hit point (X, Y, Z)";
    AovKind::Uv => "uv", "texture coordinates (U, V)";
    AovKind::GeoNormal => "geo_normal", "geometric normal (X, Y, Z)";
    AovKind::ShNormal => "sh_normal", "shading normal (X, Y, Z)";
    AovKind::PrimIndex => "prim_index", "primitive index within its shape (I)";
    AovKind::ShapeIndex => "shape_index", "1 + the shape's index in the scene (I)";
    AovKind::DpDu => "dp_du", "world-space tangent ∂p/∂u of the surface's parameterization (X, Y, Z)";
    AovKind::DpDv => "dp_dv", "world-space tangent ∂p/∂v (X, Y, Z)";
    AovKind::DuvDx => "duv_dx", "change of (u, v) per pixel to the right, from ray differentials (U, V)";
    AovKind::DuvDy => "duv_dy", "change of (u, v) per pixel down, from ray differentials (U, V)";
    AovKind::Emission => "emission", "radiance emitted toward the camera by the first surface or the sky (R, G, B)";
    AovKind::DenoisingAlbedo => "denoising_albedo", "albedo, or an emitter's normalised radiance: the denoiser's guide (R, G, B)";
});

impl AovKind {
    /// Channel suffixes.
    fn channels(self) -> &'static [&'static str] {
        match self {
            AovKind::Albedo | AovKind::DenoisingAlbedo | AovKind::Emission => &["R", "G", "B"],
            AovKind::Depth => &["T"],
            AovKind::Position | AovKind::GeoNormal | AovKind::ShNormal | AovKind::DpDu | AovKind::DpDv => {
                &["X", "Y", "Z"]
            }
            AovKind::Uv | AovKind::DuvDx | AovKind::DuvDy => &["U", "V"],
            AovKind::PrimIndex | AovKind::ShapeIndex => &["I"],
        }
    }
}

/// The AOVs a denoiser is guided by (name and kind): the albedo guide, the normal guide, and
/// the emission seen directly, which it leaves alone (`film::denoise::denoise_film`, `--denoise`).
pub const DENOISER_AOVS: [(&str, AovKind); 3] =
    [("denoising_albedo", AovKind::DenoisingAlbedo), ("normal", AovKind::ShNormal), ("emission", AovKind::Emission)];

/// The AOV integrator.
#[derive(Clone, Debug)]
pub struct AovIntegrator {
    /// The requested AOVs: name and kind, in order.
    pub aovs: Vec<(String, AovKind)>,
    /// Nested camera-ray integrators and their names.
    pub nested: Vec<(String, AnyIntegrator)>,
    /// Whether each nested integrator's image is also a layer `name.R/G/B/A` (Mitsuba's `aov`
    /// integrator); off for the AOVs the command line adds to an integrator (`--aov`), whose
    /// image is the render itself.
    pub image_layers: bool,
}

impl AovIntegrator {
    /// Mitsuba's `aov`: `aovs` (required) and nested `<integrator>`s.
    pub fn from_props(o: &Obj) -> PropResult<AovIntegrator> {
        let spec = o.string("aovs")?;
        let mut aovs = Vec::new();
        for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (name, ty) = item.split_once(':').unwrap_or((item, ""));
            if name.is_empty() || ty.is_empty() {
                return Err(o.error_at("aovs", format!("AOV '{item}' is not a <name>:<type> pair")));
            }
            let kind = match ty {
                "boundary_test" => {
                    return Err(o.error_at(
                        "aovs",
                        "AOV type 'boundary_test' (the distance to a silhouette, for projective differentiable rendering) is not implemented by neumann",
                    ))
                }
                _ => ty.parse::<AovKind>().map_err(|e| o.error_at("aovs", e))?,
            };
            aovs.push((name.to_string(), kind));
        }
        let nested = nested_integrators(o)?;
        if aovs.is_empty() && nested.is_empty() {
            return Err(o.error_at("aovs", "the aov integrator has no AOVs and no nested integrator"));
        }
        Ok(AovIntegrator { aovs, nested, image_layers: true })
    }

    /// The AOVs `aovs` (name and kind) recorded beside `integrator`'s image (a camera-ray
    /// integrator), its own AOV channels kept under their names: what `--aov` makes of the
    /// scene's integrator.
    pub fn around(integrator: AnyIntegrator, aovs: Vec<(String, AovKind)>) -> AovIntegrator {
        AovIntegrator { aovs, nested: vec![("image".into(), integrator)], image_layers: false }
    }

    /// Channels per nested integrator's image layer (R, G, B, A, or none).
    fn image_channels(&self) -> usize {
        if self.image_layers {
            4
        } else {
            0
        }
    }

    /// Whether an AOV reads `∂p/∂v`, which hits compute only where asked to.
    fn reads_dpdv(&self) -> bool {
        self.aovs.iter().any(|(_, kind)| matches!(kind, AovKind::DpDv | AovKind::DuvDx | AovKind::DuvDy))
    }

    fn inner(&self, k: usize) -> &dyn Integrator {
        self.nested[k].1.camera().expect("nested integrators trace camera rays")
    }
}

impl Integrator for AovIntegrator {
    fn name(&self) -> &'static str {
        "aov"
    }

    fn sample(&self, scene: &Scene, ray: &Ray, sampler: &mut Sampler, terms: &mut [Rgb]) -> RadianceSample {
        super::sample_without_aovs(self, scene, ray, sampler, terms)
    }

    fn has_terms(&self) -> bool {
        !self.nested.is_empty() && self.inner(0).has_terms()
    }

    fn aov_names(&self) -> Vec<String> {
        let mut names = Vec::new();
        if self.image_layers {
            for (name, _) in &self.nested {
                names.extend(["R", "G", "B", "A"].map(|c| format!("{name}.{c}")));
            }
        }
        for (k, (name, _)) in self.nested.iter().enumerate() {
            let own = self.inner(k).aov_names().into_iter();
            names.extend(own.map(|a| if self.image_layers { format!("{name}.{a}") } else { a }));
        }
        for (name, kind) in &self.aovs {
            names.extend(kind.channels().iter().map(|c| format!("{name}.{c}")));
        }
        names
    }

    fn aov_count(&self) -> usize {
        let nested: usize = (0..self.nested.len()).map(|k| self.image_channels() + self.inner(k).aov_count()).sum();
        nested + self.aovs.iter().map(|(_, kind)| kind.channels().len()).sum::<usize>()
    }

    fn wants_differentials(&self) -> bool {
        self.aovs.iter().any(|(_, kind)| matches!(kind, AovKind::DuvDx | AovKind::DuvDy))
            || (0..self.nested.len()).any(|k| self.inner(k).wants_differentials())
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
        let per_image = self.image_channels();
        let (rgba, mut rest) = aovs.split_at_mut(per_image * self.nested.len());
        let mut result = RadianceSample { l: Rgb::ZERO, alpha: 0.0 };
        for k in 0..self.nested.len() {
            let inner = self.inner(k);
            let (own, tail) = rest.split_at_mut(inner.aov_count());
            rest = tail;
            let terms: &mut [Rgb] = if k == 0 { terms } else { &mut [] };
            let s = inner.sample_aovs(scene, ray, differentials, sampler, terms, own);
            if self.image_layers {
                rgba[4 * k..4 * k + 4].copy_from_slice(&[s.l.x, s.l.y, s.l.z, s.alpha]);
            }
            if k == 0 {
                result = s;
            }
        }
        let Some(si) = (if self.reads_dpdv() { scene.intersect_complete(ray) } else { scene.intersect(ray) }) else {
            rest.fill(0.0);
            // Only the emission AOV sees anything of an escaping ray: the sky.
            let mut at = 0;
            for &(_, kind) in &self.aovs {
                if kind == AovKind::Emission {
                    let d = ray.d.normalize();
                    let sky: Rgb = scene.infinite_lights().iter().map(|&i| scene.lights()[i as usize].le_escaped(ray.o, d)).sum();
                    rest[at..at + 3].copy_from_slice(&[sky.x, sky.y, sky.z]);
                }
                at += kind.channels().len();
            }
            return result;
        };
        let mut out = rest.iter_mut();
        let mut put = |values: &[f32]| {
            for &v in values {
                *out.next().expect("one slot per AOV channel") = v;
            }
        };
        let mut partials: Option<(Vec2, Vec2)> = None;
        for &(_, kind) in &self.aovs {
            match kind {
                AovKind::Albedo | AovKind::DenoisingAlbedo => {
                    let shape = &scene.shapes()[si.shape as usize];
                    let le = match (kind, shape.light) {
                        (AovKind::DenoisingAlbedo, Some(l)) => scene.lights()[l as usize].le(si.ns, -ray.d.normalize(), si.uv),
                        _ => Rgb::ZERO,
                    };
                    let a = if le.max_element() > 0.0 && le.is_finite() {
                        le / le.max_element()
                    } else {
                        let bsdf = &scene.bsdfs()[shape.bsdf as usize];
                        let wo = si.frame().to_local(-ray.d.normalize());
                        bsdf.diffuse_reflectance(&scene.bsdf_context(&si), wo)
                    };
                    put(&[a.x, a.y, a.z]);
                }
                AovKind::Emission => {
                    let le = match scene.shapes()[si.shape as usize].light {
                        Some(l) => scene.lights()[l as usize].le(si.ns, -ray.d.normalize(), si.uv),
                        None => Rgb::ZERO,
                    };
                    put(&[le.x, le.y, le.z]);
                }
                AovKind::Depth => put(&[si.t * ray.d.length()]),
                AovKind::Position => put(&[si.p.x, si.p.y, si.p.z]),
                AovKind::Uv => {
                    let uv = scene.uv_at(ray, &si);
                    put(&[uv.x, uv.y])
                }
                AovKind::GeoNormal => put(&[si.ng.x, si.ng.y, si.ng.z]),
                AovKind::ShNormal => put(&[si.ns.x, si.ns.y, si.ns.z]),
                AovKind::PrimIndex => {
                    let per = match &scene.geometries()[si.shape as usize] {
                        crate::geometry::Geometry::Mesh(m) => m.faces_per_primitive.max(1),
                        _ => 1,
                    };
                    put(&[(si.prim / per) as f32])
                }
                AovKind::ShapeIndex => put(&[(si.shape + 1) as f32]),
                AovKind::DpDu => put(&[si.dpdu.x, si.dpdu.y, si.dpdu.z]),
                AovKind::DpDv => put(&[si.dpdv.x, si.dpdv.y, si.dpdv.z]),
                AovKind::DuvDx | AovKind::DuvDy => {
                    // Solved once for both.
                    let (dx, dy) = *partials
                        .get_or_insert_with(|| differentials.map_or((Vec2::ZERO, Vec2::ZERO), |d| uv_partials(&si, d)));
                    let duv = if kind == AovKind::DuvDx { dx } else { dy };
                    put(&[duv.x, duv.y])
                }
            }
        }
        result
    }
}

/// Mitsuba's `SurfaceInteraction::compute_uv_partials`: where the two offset rays of
/// `differentials` meet the tangent plane of `si` (through `si.p`, normal `si.ng`), and the
/// least-squares (u, v) of those offsets in the basis `∂p/∂u`, `∂p/∂v`: `(∂(u, v)/∂x,
/// ∂(u, v)/∂y)`. Zero where the parameterization is degenerate or an offset ray runs parallel
/// to the plane (Mitsuba gives NaN there; no NaN reaches neumann's images).
pub fn uv_partials(si: &SurfaceInteraction, differentials: &RayDifferentials) -> (Vec2, Vec2) {
    let (n, p) = (si.ng, si.p);
    let plane = n.dot(p);
    let offset = |o: Vec3, d: Vec3| d * ((plane - n.dot(o)) / n.dot(d)) - p + o;
    let (dp_dx, dp_dy) = (offset(differentials.o_x, differentials.d_x), offset(differentials.o_y, differentials.d_y));
    let (a00, a01, a11) = (si.dpdu.dot(si.dpdu), si.dpdu.dot(si.dpdv), si.dpdv.dot(si.dpdv));
    let inv_det = 1.0 / (a00 * a11 - a01 * a01);
    let inv_det = if inv_det.is_finite() { inv_det } else { 0.0 };
    let solve = |dp: Vec3| {
        let (b0, b1) = (si.dpdu.dot(dp), si.dpdv.dot(dp));
        let duv = Vec2::new(a11 * b0 - a01 * b1, a00 * b1 - a01 * b0) * inv_det;
        if duv.is_finite() {
            duv
        } else {
            Vec2::ZERO
        }
    };
    (solve(dp_dx), solve(dp_dy))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, FovAxis};
    use crate::film::filter::Filter;
    use crate::geometry::{Geometry, Sphere};
    use crate::material::{Bsdf, Diffuse};
    use crate::math::{Transform, Vec3};
    use crate::render::{render, RenderSettings};
    use crate::scene::SceneBuilder;
    use std::sync::atomic::AtomicBool;

    /// A unit sphere of albedo (0.2, 0.4, 0.6) seen from z = 4 along −z, in a constant
    /// environment: the centre pixel sees the sphere's pole (depth 3, position and normals
    /// (0, 0, 1), shape id 1), the corner pixel sees nothing (every AOV 0) but the environment
    /// (coverage 1, Mitsuba's rule).
    /// The AOVs `--aov` adds around an integrator leave its image bit-identical (they draw no
    /// random numbers) and are named after their types, without image layers.
    #[test]
    fn aovs_around_an_integrator_keep_its_image() {
        let scene = crate::scene::cornell::cornell_box(12, 10).unwrap();
        let plain = AnyIntegrator::with_kind(crate::integrator::IntegratorKind::Path, Default::default());
        let wrapped = AovIntegrator::around(plain.clone(), vec![("albedo".into(), AovKind::Albedo), ("normal".into(), AovKind::ShNormal)]);
        assert_eq!(wrapped.aov_names(), ["albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z"]);
        let settings = RenderSettings { spp: 4, seed: 2, ..Default::default() };
        let never = AtomicBool::new(false);
        let a = render(&scene, plain.camera().unwrap(), &settings, &never).unwrap().film;
        let b = render(&scene, &wrapped, &settings, &never).unwrap().film;
        assert!(a.image() == b.image(), "the image changed");
        let channels = b.aov_channels();
        let albedo = &channels[0].1;
        assert!(albedo.iter().all(|v| (0.0..=1.0).contains(v)) && albedo.iter().any(|&v| v > 0.3));
        // Emission and the denoiser's albedo: the light's pixel sees its radiance (18.4, 14, 6.75)
        // and, in the albedo guide, that radiance scaled to a largest channel of 1.
        let kinds = vec![("emission".into(), AovKind::Emission), ("denoising_albedo".into(), AovKind::DenoisingAlbedo)];
        let big = crate::scene::cornell::cornell_box(48, 48).unwrap();
        let lit = render(&big, &AovIntegrator::around(plain, kinds), &RenderSettings { spp: 4, ..settings }, &never).unwrap().film;
        let ch = lit.aov_channels();
        let (er, eb, ar, ab) = (&ch[0].1, &ch[2].1, &ch[3].1, &ch[5].1);
        let i = (0..er.len()).max_by(|&a, &b| er[a].total_cmp(&er[b])).unwrap();
        assert!((er[i] - 18.387).abs() < 0.01 && (eb[i] - 6.7536).abs() < 0.01, "emission {} {}", er[i], eb[i]);
        assert!((ar[i] - 1.0).abs() < 1e-5 && (ab[i] - 6.7536 / 18.387).abs() < 1e-3, "albedo guide {} {}", ar[i], ab[i]);
        assert!(er.iter().filter(|&&v| v == 0.0).count() > er.len() / 2, "most pixels see no emitter");
    }

    #[test]
    fn geometric_aovs_of_a_sphere() {
        let mut b = SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::new(0.2, 0.4, 0.6))));
        b.add_shape(Geometry::Sphere(Sphere::new(Vec3::ZERO, 1.0, false)), m, None);
        b.add_constant_environment(Rgb::splat(1.0));
        let to_world = Transform::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y).unwrap();
        b.set_camera(Camera::perspective(to_world, 40.0, FovAxis::X, 9, 9).unwrap());
        let scene = b.build().unwrap();
        let aov = AnyIntegrator::with_kind(crate::integrator::IntegratorKind::Aov, Default::default());
        let settings = RenderSettings { spp: 16, filter: Filter::BOX, ..Default::default() };
        let out = render(&scene, aov.camera().unwrap(), &settings, &AtomicBool::new(false)).unwrap();
        let channels = out.film.aov_channels();
        let get = |name: &str, pixel: usize| channels.iter().find(|c| c.0 == name).unwrap().1[pixel];
        let names: Vec<&str> = channels.iter().map(|c| c.0.as_str()).collect();
        assert_eq!(&names[..4], ["_arg_0.R", "_arg_0.G", "_arg_0.B", "_arg_0.A"]);
        let centre = 4 * 9 + 4;
        // From the near-clip plane (0.01 in front of the camera) to the pole.
        assert!((get("depth.T", centre) - 2.99).abs() < 0.01, "{}", get("depth.T", centre));
        for n in ["position", "geo_normal", "sh_normal"] {
            assert!((get(&format!("{n}.Z"), centre) - 1.0).abs() < 0.02, "{n}");
            assert!(get(&format!("{n}.X"), centre).abs() < 0.1, "{n}");
        }
        assert_eq!([get("albedo.R", centre), get("albedo.G", centre), get("albedo.B", centre)], [0.2, 0.4, 0.6]);
        assert_eq!(get("shape_index.I", centre), 1.0);
        assert_eq!(get("prim_index.I", centre), 0.0);
        assert!(get("uv.U", centre) > 0.0 && get("uv.V", centre) > 0.0);
        for c in &channels[4..] {
            // An escaping ray sees nothing but the sky, which only `emission` records.
            let expected = if c.0.starts_with("emission.") { 1.0 } else { 0.0 };
            assert_eq!(c.1[0], expected, "{} at the corner", c.0);
        }
        assert_eq!(get("emission.G", centre), 0.0, "the sphere emits nothing");
        assert_eq!(get("denoising_albedo.B", centre), 0.6, "the albedo where nothing emits");
        assert_eq!(get("_arg_0.A", 0), 1.0, "the environment covers the corner");
        assert_eq!(out.film.image()[0], Rgb::splat(1.0));
        assert_eq!(get("_arg_0.R", centre), out.film.image()[centre].x);
    }
}
