//! Radiosity: the finite-element solution of the rendering equation for diffuse scenes.
//!
//! The surfaces are cut into small triangular patches `i` of area `Aᵢ`, reflectance `ρᵢ` and
//! emitted radiosity `Eᵢ = π Lₑ` (W/m², one-sided), on each of which radiosity `Bᵢ` (W/m²) is
//! assumed constant. Energy balance gives `Bᵢ = Eᵢ + ρᵢ Σⱼ Fᵢⱼ Bⱼ`, i.e. `B = E + ρ F B`, where
//! the form factor `Fᵢⱼ` is the fraction of the light leaving patch i (diffusely) that arrives at
//! patch j. Its Neumann series `B = Σₖ (ρF)ᵏ E` is the same series the path tracer samples.
//!
//! - **Form factors** by Monte Carlo: from uniform points on patch i, cosine-weighted directions
//!   (the diffuse emission distribution) are traced; `Fᵢⱼ ≈` the fraction that first hits the
//!   front of patch j. Rows sum to at most 1 (the rest escapes or hits back faces).
//! - **Solvers**: Jacobi (`B ← E + ρ F B`, the Neumann series term by term), Gauss–Seidel (the same
//!   sweep using updated values at once) and progressive refinement (shooting: the patch with the
//!   most unshot power `ΔBᵢ Aᵢ` shoots it to every patch j that sees it, `ΔBⱼ += ρⱼ Fⱼᵢ ΔBᵢ`,
//!   using column i of F; with exact form factors `Fⱼᵢ = Fᵢⱼ Aᵢ/Aⱼ` (reciprocity), but the
//!   column keeps the three solvers on the same Monte Carlo matrix, hence the same solution). All
//!   stop when the relative residual (change, or unshot power) falls below the tolerance.
//! - **Display**: a camera ray sees radiance `B/π` of the patch it hits (flat), or the barycentric
//!   interpolation of vertex radiosities averaged over the patches sharing each vertex (smooth).
//!
//! Only diffuse, untextured materials and area emitters are allowed; anything else is an error
//! naming the shape.

use crate::camera::Camera;
use crate::geometry::{Geometry, TriangleMesh};
use crate::integrator::{Integrator, RadianceSample};
use crate::light::Light;
use crate::material::Bsdf;
use crate::math::float::{gamma, offset_ray_origin};
use crate::math::{luminance, Frame, Ray, Rgb, Vec2, Vec3, PI};
use crate::props::{Obj, Result as PropResult};
use crate::sampling::{sample_cosine_hemisphere_malley, sample_uniform_triangle, Pcg32, Sampler};
use crate::scene::{Scene, SceneBuilder};
use crate::texture::Texture;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, Ordering};

/// Which linear solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// `B ← E + ρ F B` with the previous iterate (the Neumann series).
    Jacobi,
    /// The same sweep, using each updated `Bⱼ` immediately.
    GaussSeidel,
    /// Progressive refinement: shoot the largest unshot power first.
    Shooting,
}

crate::choices!(Method, "radiosity solver", {
    Method::Jacobi => "jacobi", "Jacobi iteration, B ← E + ρ F B (the Neumann series term by term)";
    Method::GaussSeidel => "gauss-seidel", "Gauss–Seidel iteration (updated values used at once)";
    Method::Shooting => "shooting", "progressive refinement: shoot the largest unshot power first";
});

/// Radiosity settings.
#[derive(Clone, Debug)]
pub struct Options {
    /// Longest patch edge (world units); triangles are split at their edge midpoints until
    /// every edge is at most this long.
    pub patch_size: f32,
    /// Rays per patch for the form factors.
    pub rays_per_patch: u32,
    /// Solver.
    pub method: Method,
    /// Stop when the relative residual is below this.
    pub tolerance: f64,
    /// Iteration limit (sweeps for Jacobi/Gauss–Seidel, shots / patch count for shooting).
    pub max_iterations: usize,
    /// Smooth (vertex-interpolated) display instead of flat patches.
    pub smooth: bool,
    /// Seed of the form-factor rays.
    pub seed: u64,
    /// Where to write the per-patch solution as CSV after the solve (none by default).
    pub patches_out: Option<std::path::PathBuf>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            patch_size: 0.1,
            rays_per_patch: 512,
            method: Method::GaussSeidel,
            tolerance: 1e-4,
            max_iterations: 1000,
            smooth: false,
            seed: 0,
            patches_out: None,
        }
    }
}

impl Radiosity {
    /// What the solve did, for the render's report: patches, form factors, iterations and
    /// residuals, emitted and reflected power.
    pub fn report_lines(&self) -> Vec<String> {
        let last = self.history.last().copied().unwrap_or((0, 0.0));
        let shown: Vec<String> = self
            .history
            .iter()
            .filter(|(k, _)| k.is_power_of_two() || *k == last.0)
            .map(|(k, r)| format!("{k}: {r:.2e}"))
            .collect();
        vec![
            format!(
                "radiosity: {} patches, {} non-zero form factors, {} iterations, residual {:.2e}; emitted {:.4} W, reflected {:.4} W (luminance)",
                self.b.len(),
                self.form_factor_entries,
                last.0,
                last.1,
                self.emitted_power(),
                self.reflected_power()
            ),
            format!("  residual by iteration: {}", shown.join(", ")),
        ]
    }
}

/// The solved radiosity of a scene's patches, ready to display.
#[derive(Debug)]
pub struct Radiosity {
    /// The scene cut into patches (one triangle per patch), with the original camera.
    pub scene: Scene,
    /// Index of the first patch of each shape.
    first_patch: Vec<u32>,
    /// Patch areas.
    pub area: Vec<f32>,
    /// Patch reflectances.
    pub rho: Vec<Rgb>,
    /// Emitted radiosity `π Lₑ`.
    pub emission: Vec<Rgb>,
    /// Solved radiosity.
    pub b: Vec<Rgb>,
    /// `(iteration, relative residual)` after each iteration.
    pub history: Vec<(usize, f64)>,
    /// Per-patch vertex radiosities for smooth display (empty when flat).
    vertex_b: Vec<[Rgb; 3]>,
    /// Number of form-factor entries (non-zero `Fᵢⱼ`).
    pub form_factor_entries: usize,
}

/// Splits a triangle at its edge midpoints until every edge is at most `max_edge`.
fn subdivide(p: [Vec3; 3], max_edge: f32, depth: u32, out: &mut Vec<[Vec3; 3]>) {
    let longest = (p[1] - p[0]).length().max((p[2] - p[1]).length()).max((p[0] - p[2]).length());
    if longest <= max_edge || depth >= 12 {
        out.push(p);
        return;
    }
    let (m01, m12, m20) = ((p[0] + p[1]) * 0.5, (p[1] + p[2]) * 0.5, (p[2] + p[0]) * 0.5);
    for t in [[p[0], m01, m20], [m01, p[1], m12], [m20, m12, p[2]], [m01, m12, m20]] {
        subdivide(t, max_edge, depth + 1, out);
    }
}

/// The most patches a solve takes.
const MAX_PATCHES: usize = 200_000;

/// How many patches [`subdivide`] makes of `p`: midpoint subdivision halves every edge, so
/// `4^L` with `L` the levels until the longest edge fits (at most 12).
fn patch_count(p: [Vec3; 3], max_edge: f32) -> u64 {
    let longest = (p[1] - p[0]).length().max((p[2] - p[1]).length()).max((p[0] - p[2]).length());
    let mut levels = 0u32;
    let mut edge = longest;
    while edge > max_edge && levels < 12 {
        edge *= 0.5;
        levels += 1;
    }
    4u64.pow(levels)
}

/// Radiance of an area light attached to a shape, if any.
fn shape_emission(scene: &Scene, shape: usize) -> Rgb {
    match scene.shapes()[shape].light.map(|i| &scene.lights()[i as usize]) {
        Some(Light::Area { radiance, .. }) => radiance.mean(),
        _ => Rgb::ZERO,
    }
}

/// What the radiosity method cannot handle in a scene.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RadiosityError {
    /// The patch size is not a positive number.
    #[error("patch size must be positive, got {0}")]
    PatchSize(f32),

    /// A shape moves (radiosity solves a scene at rest).
    #[error("{0}: radiosity solves a scene at rest; this shape moves")]
    Moving(String),
    /// An area emitter's radiance varies over its surface.
    #[error("radiosity needs constant emission: an area emitter's radiance is a texture")]
    TexturedEmission,
    /// A light other than an area emitter.
    #[error("radiosity handles one-sided area emitters only; the scene has a {0} light")]
    Light(&'static str),
    /// A shape's reflectance varies over its surface.
    #[error("{0}: radiosity needs constant reflectances (this one is textured)")]
    TexturedReflectance(String),
    /// A shape whose BSDF is not diffuse.
    #[error("{shape}: radiosity handles diffuse surfaces only, not the {bsdf} BSDF")]
    NotDiffuse {
        /// The shape (its label, [`Scene::shape_label`]).
        shape: String,
        /// Its BSDF's plugin name.
        bsdf: &'static str,
    },
    /// A shape that is no triangle mesh.
    #[error("{0}: radiosity patches triangle meshes (rectangles, cubes, OBJ/PLY); spheres, disks, cylinders and SDF grids are not meshed")]
    NotAMesh(String),
    /// Patching a mesh failed.
    #[error("{0}: {1}")]
    Mesh(String, crate::geometry::MeshError),
    /// The patched scene could not be built.
    #[error("{0}")]
    Build(#[from] crate::scene::BuildError),
    /// Nothing to patch.
    #[error("the scene has no surfaces to patch")]
    NoSurfaces,
    /// More patches than the dense solve handles.
    #[error("{0} patches is too many (at most 200 000): use a larger patch size")]
    TooManyPatches(usize),
    /// The solve was interrupted (its form factors or iterations unfinished: nothing to show).
    #[error("interrupted before the radiosity solve finished (no image to keep)")]
    Interrupted,
}

impl Radiosity {
    /// Meshes `scene` into patches, computes form factors and solves. Errors name what the
    /// method cannot handle. `cancel` becoming true stops it between patches (form factors)
    /// and between iterations or shots ([`RadiosityError::Interrupted`]).
    pub fn solve(scene: &Scene, opts: &Options, cancel: &AtomicBool) -> Result<Radiosity, RadiosityError> {
        if !(opts.patch_size > 0.0 && opts.patch_size.is_finite()) {
            return Err(RadiosityError::PatchSize(opts.patch_size));
        }
        if let Some(s) = (0..scene.shapes().len() as u32).find(|&s| scene.shape_motion(s).is_some()) {
            return Err(RadiosityError::Moving(scene.shape_label(s as usize)));
        }
        if scene.lights().iter().any(|l| matches!(l, Light::Area { radiance, .. } if !matches!(radiance, crate::texture::Texture::Constant(_)))) {
            return Err(RadiosityError::TexturedEmission);
        }
        if let Some(l) = scene.lights().iter().find(|l| !matches!(l, Light::Area { two_sided: false, .. })) {
            return Err(RadiosityError::Light(match l {
                Light::Point { .. } => "point",
                Light::Spot { .. } => "spot",
                Light::Directional { .. } => "directional",
                Light::Projector(_) => "projector",
                Light::Goniometric(_) => "goniometric",
                Light::Constant { .. } => "constant environment",
                Light::Area { .. } => "two-sided area",
                Light::DirectionalArea { .. } => "directional area",
                Light::EnvMap { .. } => "environment map",
                Light::SunSky { .. } => "sun and sky",
            }));
        }
        // Count the patches before making them: a tiny patch size must be an error, not an
        // allocation of gigabytes.
        let planned: u64 = scene
            .geometries()
            .iter()
            .filter_map(|g| if let Geometry::Mesh(m) = g { Some(m) } else { None })
            .flat_map(|m| (0..m.len()).map(move |i| patch_count(m.triangle(i), opts.patch_size)))
            .sum();
        if planned > MAX_PATCHES as u64 {
            return Err(RadiosityError::TooManyPatches(planned.min(usize::MAX as u64) as usize));
        }
        let mut b = SceneBuilder::new();
        let mut first_patch = Vec::new();
        let (mut area, mut rho, mut emission) = (Vec::new(), Vec::new(), Vec::new());
        let black = b.add_bsdf(Bsdf::Diffuse(crate::material::Diffuse::new(Rgb::ZERO)));
        for (s, geometry) in scene.geometries().iter().enumerate() {
            let reflectance = match &scene.bsdfs()[scene.shapes()[s].bsdf as usize] {
                Bsdf::Diffuse(d) => match &d.reflectance {
                    Texture::Constant(c) => *c,
                    _ => return Err(RadiosityError::TexturedReflectance(scene.shape_label(s))),
                },
                other => return Err(RadiosityError::NotDiffuse { shape: scene.shape_label(s), bsdf: other.plugin_name() }),
            };
            let Geometry::Mesh(mesh) = geometry else { return Err(RadiosityError::NotAMesh(scene.shape_label(s))) };
            let le = shape_emission(scene, s);
            let mut tris = Vec::new();
            for i in 0..mesh.len() {
                subdivide(mesh.triangle(i), opts.patch_size, 0, &mut tris);
            }
            first_patch.push(area.len() as u32);
            let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
            let indices: Vec<[u32; 3]> = (0..tris.len() as u32).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
            let mut patches =
                TriangleMesh::new(positions, vec![], vec![], indices).map_err(|e| RadiosityError::Mesh(scene.shape_label(s), e))?;
            patches.flip_normals = mesh.flip_normals;
            for t in &tris {
                area.push(0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length());
                rho.push(reflectance);
                emission.push(le * PI);
            }
            // The display scene needs no materials: its patches carry the solution.
            b.add_shape(Geometry::Mesh(patches), black, None);
        }
        let camera: Camera = scene.camera().clone();
        b.set_camera(camera);
        let patched = b.build()?;
        let n = area.len();
        if n == 0 {
            return Err(RadiosityError::NoSurfaces);
        }
        if n > MAX_PATCHES {
            return Err(RadiosityError::TooManyPatches(n));
        }

        // Form factors, one row per patch, deterministic per row.
        let patch_of = |shape: u32, prim: u32| first_patch[shape as usize] + prim;
        let rows: Vec<Vec<(u32, f32)>> = (0..n)
            .into_par_iter()
            .map(|i| {
                if cancel.load(Ordering::Relaxed) {
                    return Vec::new();
                }
                let (s, k) = locate(&first_patch, i as u32);
                let Geometry::Mesh(m) = &patched.geometries()[s as usize] else { unreachable!("patches are meshes") };
                let p = m.triangle(k as usize);
                let normal = m.normal_of(&p);
                let frame = Frame::from_z(normal);
                let mut rng = Pcg32::new(opts.seed, i as u64);
                let mut hits = Vec::with_capacity(opts.rays_per_patch as usize);
                for _ in 0..opts.rays_per_patch {
                    let bary = sample_uniform_triangle(Vec2::new(rng.next_f32(), rng.next_f32())).value;
                    let x = p[0] * bary.x + p[1] * bary.y + p[2] * bary.z;
                    let err = gamma(7) * ((p[0] * bary.x).abs() + (p[1] * bary.y).abs() + (p[2] * bary.z).abs());
                    let d = frame
                        .to_world(sample_cosine_hemisphere_malley(Vec2::new(rng.next_f32(), rng.next_f32())).value);
                    let ray = Ray::new(offset_ray_origin(x, err, normal, d), d);
                    if let Some(si) = patched.intersect(&ray) {
                        if si.ng.dot(d) < 0.0 {
                            hits.push(patch_of(si.shape, si.prim));
                        }
                    }
                }
                hits.sort_unstable();
                let mut row: Vec<(u32, f32)> = Vec::new();
                let w = 1.0 / opts.rays_per_patch as f32;
                for j in hits {
                    match row.last_mut() {
                        Some((last, f)) if *last == j => *f += w,
                        _ => row.push((j, w)),
                    }
                }
                row
            })
            .collect();
        if cancel.load(Ordering::Relaxed) {
            return Err(RadiosityError::Interrupted);
        }
        let form_factor_entries = rows.iter().map(Vec::len).sum();

        let (bsol, history) = match opts.method {
            Method::Jacobi | Method::GaussSeidel => iterate(&rows, &rho, &emission, opts, cancel),
            Method::Shooting => shoot(&rows, &rho, &emission, &area, opts, cancel),
        }
        .ok_or(RadiosityError::Interrupted)?;
        let mut r = Radiosity {
            scene: patched,
            first_patch,
            area,
            rho,
            emission,
            b: bsol,
            history,
            vertex_b: Vec::new(),
            form_factor_entries,
        };
        if opts.smooth {
            r.vertex_b = r.vertex_radiosities();
        }
        Ok(r)
    }

    /// Total power leaving the surfaces, `Σ Bᵢ Aᵢ` (luminance, W).
    pub fn total_power(&self) -> f64 {
        self.b.iter().zip(&self.area).map(|(b, a)| luminance(*b) as f64 * *a as f64).sum()
    }

    /// Power emitted, `Σ Eᵢ Aᵢ` (luminance, W).
    pub fn emitted_power(&self) -> f64 {
        self.emission.iter().zip(&self.area).map(|(e, a)| luminance(*e) as f64 * *a as f64).sum()
    }

    /// Power reflected by the surfaces, `Σ (Bᵢ - Eᵢ) Aᵢ` (luminance, W).
    pub fn reflected_power(&self) -> f64 {
        self.b.iter().zip(&self.emission).zip(&self.area).map(|((b, e), a)| luminance(*b - *e) as f64 * *a as f64).sum()
    }

    /// Per-patch data as CSV: patch, shape, area, centroid, reflectance, emission, radiosity.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("patch,shape,area,cx,cy,cz,rho_r,rho_g,rho_b,e_r,e_g,e_b,b_r,b_g,b_b\n");
        for i in 0..self.b.len() {
            let (shape, k) = locate(&self.first_patch, i as u32);
            let Geometry::Mesh(m) = &self.scene.geometries()[shape as usize] else { continue };
            let p = m.triangle(k as usize);
            let c = (p[0] + p[1] + p[2]) / 3.0;
            let (r, e, b) = (self.rho[i], self.emission[i], self.b[i]);
            s += &format!(
                "{i},{shape},{:.6e},{:.6},{:.6},{:.6},{:.4},{:.4},{:.4},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e}\n",
                self.area[i], c.x, c.y, c.z, r.x, r.y, r.z, e.x, e.y, e.z, b.x, b.y, b.z
            );
        }
        s
    }

    /// Area-weighted average radiosity at each vertex position (per shape), per patch corner.
    fn vertex_radiosities(&self) -> Vec<[Rgb; 3]> {
        let key = |s: u32, p: Vec3| (s, (p * 1e5).round().as_ivec3().to_array());
        let mut acc: HashMap<(u32, [i32; 3]), (Rgb, f32)> = HashMap::new();
        let corners = |i: usize| {
            let (s, k) = locate(&self.first_patch, i as u32);
            let Geometry::Mesh(m) = &self.scene.geometries()[s as usize] else { unreachable!("patches are meshes") };
            (s, m.triangle(k as usize))
        };
        for i in 0..self.b.len() {
            let (s, p) = corners(i);
            for v in p {
                let e = acc.entry(key(s, v)).or_insert((Rgb::ZERO, 0.0));
                e.0 += self.b[i] * self.area[i];
                e.1 += self.area[i];
            }
        }
        (0..self.b.len())
            .map(|i| {
                let (s, p) = corners(i);
                p.map(|v| {
                    let (sum, w) = acc[&key(s, v)];
                    sum / w.max(f32::MIN_POSITIVE)
                })
            })
            .collect()
    }
}

/// (shape, patch index within the shape) of global patch `i`.
fn locate(first_patch: &[u32], i: u32) -> (u32, u32) {
    let s = first_patch.partition_point(|&f| f <= i) - 1;
    (s as u32, i - first_patch[s])
}

/// A solver's radiosities (per patch) and its convergence history (iteration, residual).
type Solved = (Vec<Rgb>, Vec<(usize, f64)>);

/// Jacobi or Gauss–Seidel sweeps of `B = E + ρ F B`; `None` if `cancel` became true.
fn iterate(rows: &[Vec<(u32, f32)>], rho: &[Rgb], e: &[Rgb], opts: &Options, cancel: &AtomicBool) -> Option<Solved> {
    let mut b = e.to_vec();
    let mut history = Vec::new();
    for it in 1..=opts.max_iterations {
        if cancel.load(Ordering::Relaxed) {
            return None;
        }
        let gather = |b: &[Rgb], i: usize| e[i] + rho[i] * rows[i].iter().map(|&(j, f)| b[j as usize] * f).sum::<Rgb>();
        let (mut change, mut norm) = (0.0f64, 0.0f64);
        if opts.method == Method::Jacobi {
            let next: Vec<Rgb> = (0..b.len()).map(|i| gather(&b, i)).collect();
            for (old, new) in b.iter().zip(&next) {
                change += luminance((*new - *old).abs()) as f64;
                norm += luminance(*new) as f64;
            }
            b = next;
        } else {
            for i in 0..b.len() {
                let new = gather(&b, i);
                change += luminance((new - b[i]).abs()) as f64;
                norm += luminance(new) as f64;
                b[i] = new;
            }
        }
        let residual = if norm > 0.0 { change / norm } else { 0.0 };
        history.push((it, residual));
        if residual < opts.tolerance {
            break;
        }
    }
    Some((b, history))
}

/// Progressive refinement (shooting); `None` if `cancel` became true.
fn shoot(
    rows: &[Vec<(u32, f32)>],
    rho: &[Rgb],
    e: &[Rgb],
    area: &[f32],
    opts: &Options,
    cancel: &AtomicBool,
) -> Option<Solved> {
    let n = e.len();
    // Columns of F: cols[i] lists (j, Fⱼᵢ), the patches that receive from i.
    let mut cols: Vec<Vec<(u32, f32)>> = vec![Vec::new(); n];
    for (j, row) in rows.iter().enumerate() {
        for &(i, f) in row {
            cols[i as usize].push((j as u32, f));
        }
    }
    let mut b = e.to_vec();
    let mut unshot = e.to_vec();
    let total_emitted: f64 = e.iter().zip(area).map(|(e, a)| luminance(*e) as f64 * *a as f64).sum();
    let mut history = Vec::new();
    let max_shots = opts.max_iterations.saturating_mul(n).max(1);
    for shot in 1..=max_shots {
        if cancel.load(Ordering::Relaxed) {
            return None;
        }
        let (i, power) = (0..n)
            .map(|i| (i, luminance(unshot[i]) as f64 * area[i] as f64))
            .fold((0, -1.0), |best, x| if x.1 > best.1 { x } else { best });
        let residual = if total_emitted > 0.0 { power * n as f64 / total_emitted } else { 0.0 };
        if shot % n == 0 || residual < opts.tolerance {
            // Report per sweep-equivalent (n shots): the largest unshot power relative to the
            // average emitted power per patch.
            history.push((shot / n.max(1), residual));
        }
        if residual < opts.tolerance || power <= 0.0 {
            break;
        }
        let db = unshot[i];
        unshot[i] = Rgb::ZERO;
        for &(j, f) in &cols[i] {
            let j = j as usize;
            let d = rho[j] * db * f;
            b[j] += d;
            unshot[j] += d;
        }
    }
    Some((b, history))
}

/// Displays a solved radiosity: the radiance `B/π` of the patch a camera ray hits.
#[derive(Debug)]
pub struct RadiosityIntegrator {
    /// The solution.
    pub solution: Radiosity,
}

impl Integrator for RadiosityIntegrator {
    fn name(&self) -> &'static str {
        "radiosity"
    }

    fn sample(&self, _scene: &Scene, ray: &Ray, _sampler: &mut Sampler, _terms: &mut [Rgb]) -> RadianceSample {
        let r = &self.solution;
        let Some(si) = r.scene.intersect(ray) else { return RadianceSample { l: Rgb::ZERO, alpha: 0.0 } };
        RadianceSample { l: self.radiance(&si, ray), alpha: 1.0 }
    }
}

impl RadiosityIntegrator {
    /// The displayed radiance at the camera ray's hit `si`: the patch's (or, smooth, the
    /// interpolated vertices') radiosity over π.
    fn radiance(&self, si: &crate::geometry::SurfaceInteraction, ray: &Ray) -> Rgb {
        let r = &self.solution;
        if si.ng.dot(ray.d) >= 0.0 {
            return Rgb::ZERO; // back faces do not reflect (one-sided diffuse)
        }
        let i = (r.first_patch[si.shape as usize] + si.prim) as usize;
        if r.vertex_b.is_empty() {
            return r.b[i] / PI;
        }
        let Geometry::Mesh(m) = &r.scene.geometries()[si.shape as usize] else { return r.b[i] / PI };
        let p = m.triangle(si.prim as usize);
        let total = (p[1] - p[0]).cross(p[2] - p[0]).length().max(f32::MIN_POSITIVE);
        let w1 = (p[2] - p[0]).cross(si.p - p[0]).length() / total;
        let w2 = (si.p - p[0]).cross(p[1] - p[0]).length() / total;
        let w0 = (1.0 - w1 - w2).max(0.0);
        let v = r.vertex_b[i];
        (v[0] * w0 + v[1] * w1 + v[2] * w2) / PI
    }
}

impl Options {
    /// neumann's `radiosity` integrator: `patch_size` (0.1), `rays_per_patch` (512, up to 2²⁴),
    /// `method` (`gauss_seidel`, `jacobi`, `shooting`), `tolerance` (1e-4, in (0, 1)),
    /// `max_iterations` (1000, up to 10⁶), `smooth` (false), `seed` (0).
    pub fn from_props(o: &Obj) -> PropResult<Options> {
        let d = Options::default();
        let patch_size =
            o.float_checked("patch_size", d.patch_size, |v| v > 0.0 && v.is_finite(), "a positive length")?;
        let rays = o.int("rays_per_patch", d.rays_per_patch as i64)?;
        if !(1..=1 << 24).contains(&rays) {
            return Err(o.error_at("rays_per_patch", format!("rays_per_patch must be between 1 and 2^24, got {rays}")));
        }
        let tolerance =
            o.float_checked("tolerance", d.tolerance as f32, |v| v > 0.0 && v < 1.0, "a number in (0, 1)")?;
        let max_iterations = o.int("max_iterations", d.max_iterations as i64)?;
        if !(1..=1_000_000).contains(&max_iterations) {
            return Err(o.error_at(
                "max_iterations",
                format!("max_iterations must be between 1 and 10⁶, got {max_iterations}"),
            ));
        }
        let method = o
            .choice("method", &["gauss_seidel", "jacobi", "shooting"])?
            .parse()
            .map_err(|e: String| o.error_at("method", e))?;
        Ok(Options {
            patch_size,
            rays_per_patch: rays as u32,
            method,
            tolerance: tolerance as f64,
            max_iterations: max_iterations as usize,
            smooth: o.bool("smooth", false)?,
            seed: o.int("seed", 0)?.max(0) as u64,
            patches_out: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::FovAxis;
    use crate::material::Diffuse;
    use crate::math::Transform;

    /// A closed box whose walls all emit `Lₑ` and reflect `ρ`: by symmetry `B = E + ρ B`, so
    /// `B = π Lₑ / (1 - ρ)` on every patch, whatever the meshing (rows of F sum to 1 in a closed
    /// box). Every solver must find it.
    #[test]
    fn uniform_enclosure_matches_the_geometric_series() {
        let (le, rho) = (2.0f32, 0.6f32);
        let mut b = SceneBuilder::new();
        let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(rho))));
        let mut cube = TriangleMesh::cube();
        cube.flip_normals = true; // walls face inward
        b.add_shape(Geometry::Mesh(cube), m, Some(Rgb::splat(le)));
        b.set_camera(Camera::perspective(Transform::IDENTITY, 60.0, FovAxis::X, 8, 8).unwrap());
        let scene = b.build().unwrap();
        let expected = PI * le / (1.0 - rho);
        for method in [Method::Jacobi, Method::GaussSeidel, Method::Shooting] {
            let opts = Options { patch_size: 0.8, rays_per_patch: 256, method, tolerance: 1e-6, ..Default::default() };
            let r = Radiosity::solve(&scene, &opts, &AtomicBool::new(false)).unwrap();
            for bi in &r.b {
                assert!((bi.x - expected).abs() < 2e-3 * expected, "{method:?}: {} vs {expected}", bi.x);
            }
            assert!(r.history.last().unwrap().1 < 1e-5, "{method:?} did not converge: {:?}", r.history.last());
        }
    }

    /// The Cornell box: the radiosity image approaches the path tracer's as patches shrink
    /// (the piecewise-constant error falls), and the finest agrees on the image mean.
    #[test]
    fn cornell_box_converges_to_the_path_tracer() {
        use crate::render::{render, RenderSettings};
        use std::sync::atomic::AtomicBool;
        let scene = crate::scene::cornell::cornell_box(32, 32).unwrap();
        let never = AtomicBool::new(false);
        let path = crate::integrator::PathIntegrator::default();
        let reference =
            render(&scene, &path, &RenderSettings { spp: 1024, seed: 5, ..Default::default() }, &never).unwrap();
        let (ref_mean, ref_se) = reference.film.mean_and_std_error();
        let ref_img = reference.film.image();
        let mut errors = Vec::new();
        for size in [0.5f32, 0.25, 0.1] {
            let opts = Options { patch_size: size, rays_per_patch: 1024, smooth: true, ..Default::default() };
            let r = Radiosity::solve(&scene, &opts, &AtomicBool::new(false)).unwrap();
            let integrator = RadiosityIntegrator { solution: r };
            let out = render(&scene, &integrator, &RenderSettings { spp: 1024, seed: 5, ..Default::default() }, &never)
                .unwrap();
            let img = out.film.image();
            let (mean, _) = out.film.mean_and_std_error();
            let rmse = crate::film::metrics::mse(&img, &ref_img).sqrt();
            println!(
                "patch {size}: {} patches, mean {mean:.5} vs {ref_mean:.5} ± {ref_se:.5}, RMSE {rmse:.4}",
                integrator.solution.b.len()
            );
            errors.push(((mean - ref_mean) / ref_mean, rmse));
        }
        assert!(errors[1].1 < errors[0].1 && errors[2].1 < errors[1].1, "RMSE must fall with patch size: {errors:?}");
        assert!(errors[2].0.abs() < 0.02, "finest mean off by {:.2} %", 100.0 * errors[2].0);
    }

    /// Total reflected power `Σ (Bᵢ - Eᵢ) Aᵢ` against an independent estimate of the same
    /// quantity by forward (analog) light tracing in the original scene: particles leave the
    /// emitters with power `Φ/N` (position by area, direction cosine-weighted); each surface hit
    /// reflects `ρ` of the particle's power, which is tallied and carried on along a cosine
    /// direction. Patch discretisation moves light between patches but conserves energy, so
    /// the totals agree within 1 %.
    #[test]
    fn reflected_power_matches_light_tracing() {
        let scene = crate::scene::cornell::cornell_box(8, 8).unwrap();
        let opts = Options { patch_size: 0.25, rays_per_patch: 4096, ..Default::default() };
        let r = Radiosity::solve(&scene, &opts, &AtomicBool::new(false)).unwrap();
        let power: Vec<f64> = (0..r.b.len()).map(|i| luminance(r.emission[i]) as f64 * r.area[i] as f64).collect();
        let emitted: f64 = power.iter().sum();
        let cdf: Vec<f64> = power
            .iter()
            .scan(0.0, |acc, p| {
                *acc += p / emitted;
                Some(*acc)
            })
            .collect();
        let reflectance = |shape: u32| match &scene.bsdfs()[scene.shapes()[shape as usize].bsdf as usize] {
            Bsdf::Diffuse(d) => match &d.reflectance {
                Texture::Constant(c) => *c,
                _ => unreachable!(),
            },
            _ => unreachable!(),
        };
        let particles = 400_000u32;
        let mut rng = Pcg32::new(3, 0);
        let (mut sum, mut sum_sq) = (0.0f64, 0.0f64);
        for _ in 0..particles {
            let u = rng.next_f32() as f64;
            let i = cdf.partition_point(|&c| c < u).min(cdf.len() - 1);
            let (s, k) = locate(&r.first_patch, i as u32);
            let Geometry::Mesh(m) = &r.scene.geometries()[s as usize] else { unreachable!() };
            let p = m.triangle(k as usize);
            let bary = sample_uniform_triangle(Vec2::new(rng.next_f32(), rng.next_f32())).value;
            let mut x = p[0] * bary.x + p[1] * bary.y + p[2] * bary.z;
            let mut n = m.normal_of(&p);
            let mut err = Vec3::splat(1e-4);
            // Power in units of the emitted power, per colour channel relative to luminance.
            let mut beta = r.emission[i] / luminance(r.emission[i]);
            let mut tally = 0.0f64;
            for _ in 0..64 {
                let d = Frame::from_z(n)
                    .to_world(sample_cosine_hemisphere_malley(Vec2::new(rng.next_f32(), rng.next_f32())).value);
                let Some(si) = scene.intersect(&Ray::new(offset_ray_origin(x, err, n, d), d)) else { break };
                if si.ng.dot(d) >= 0.0 {
                    break; // back faces absorb, as in the radiosity model
                }
                beta *= reflectance(si.shape);
                tally += luminance(beta) as f64;
                if beta.max_element() < 1e-6 {
                    break;
                }
                (x, n, err) = (si.p, si.ng, si.p_error);
            }
            sum += tally;
            sum_sq += tally * tally;
        }
        let n = particles as f64;
        let traced = emitted * sum / n;
        let se = emitted * ((sum_sq / n - (sum / n).powi(2)) / (n - 1.0)).sqrt();
        let radiosity = r.reflected_power();
        let rel = (radiosity - traced) / traced;
        println!(
            "reflected power: radiosity {radiosity:.4} W, light traced {traced:.4} ± {se:.4} W ({:+.2} %)",
            100.0 * rel
        );
        assert!(se < 0.002 * traced, "the light-traced estimate is too noisy to test 1 %: ± {se}");
        assert!(rel.abs() < 0.01, "reflected power differs by {:.2} %", 100.0 * rel);
    }

    #[test]
    fn refuses_what_it_cannot_solve() {
        let never = AtomicBool::new(false);
        let scene_with = |bsdf: Bsdf| {
            let mut b = SceneBuilder::new();
            let m = b.add_bsdf(bsdf);
            b.add_shape(Geometry::Mesh(TriangleMesh::rectangle()), m, None);
            b.add_point_light(Vec3::Z, Rgb::ONE);
            b.set_camera(Camera::perspective(Transform::IDENTITY, 60.0, FovAxis::X, 4, 4).unwrap());
            b.build().unwrap()
        };
        let e = Radiosity::solve(&scene_with(Bsdf::Diffuse(Diffuse::new(Rgb::ONE))), &Options::default(), &never)
            .unwrap_err();
        assert_eq!(e, RadiosityError::Light("point"));
        let mirror = Bsdf::Conductor(crate::material::Conductor { ior: None, specular_reflectance: Rgb::ONE.into() });
        let mut b = SceneBuilder::new();
        let m = b.add_bsdf(mirror);
        b.add_shape(Geometry::Mesh(TriangleMesh::rectangle()), m, Some(Rgb::ONE));
        b.set_camera(Camera::perspective(Transform::IDENTITY, 60.0, FovAxis::X, 4, 4).unwrap());
        let e = Radiosity::solve(&b.build().unwrap(), &Options::default(), &never).unwrap_err();
        assert!(matches!(&e, RadiosityError::NotDiffuse { shape, bsdf: "conductor" } if shape == "shape 0"), "{e}");
        assert_eq!(e.to_string(), "shape 0: radiosity handles diffuse surfaces only, not the conductor BSDF");
        // A tiny patch size is refused before the patches are made (it once took gigabytes).
        let cornell = crate::scene::cornell::cornell_box(4, 4).unwrap();
        let start = std::time::Instant::now();
        let e = Radiosity::solve(&cornell, &Options { patch_size: 1e-4, ..Default::default() }, &never).unwrap_err();
        assert!(matches!(e, RadiosityError::TooManyPatches(n) if n > 1_000_000), "{e}");
        assert!(start.elapsed().as_secs_f32() < 1.0);
        // An interrupt stops even a solve that would take hours (2²⁴ rays for each of the
        // Cornell box's patches: 10¹⁰ rays), with either solver. (The bound on its time is loose
        // so that a loaded machine passes; an uninterrupted solve would not come near it.)
        let cancelled = AtomicBool::new(true);
        for method in [Method::GaussSeidel, Method::Shooting] {
            let start = std::time::Instant::now();
            let opts = Options { rays_per_patch: 1 << 24, method, ..Default::default() };
            let e = Radiosity::solve(&cornell, &opts, &cancelled).unwrap_err();
            assert_eq!(e, RadiosityError::Interrupted);
            assert!(start.elapsed().as_secs_f32() < 30.0, "{:?}", start.elapsed());
        }
    }
}
