//! `neumann bench`: BVH build time, ray throughput (primary, incoherent closest-hit and
//! incoherent shadow rays) with one thread and with all threads, and path-tracing samples per
//! second on the Cornell box.

use clap::Args;
use neumann::bvh::{Bvh, Kernel};
use neumann::camera::{Camera, FovAxis};
use neumann::geometry::{Geometry, TriangleMesh};
use neumann::integrator::PathIntegrator;
use neumann::material::{Bsdf, Diffuse};
use neumann::math::{Bounds3, Ray, Rgb, Transform, Vec2, Vec3};
use neumann::render::{render, RenderSettings};
use neumann::sampling::{sample_uniform_sphere, Pcg32};
use neumann::scene::{cornell, Scene, SceneBuilder};
use rayon::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// Benchmark options.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Mesh to trace (.obj or .ply); default: a generated displaced sphere.
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// Triangles in the generated mesh.
    #[arg(long, default_value_t = 1_000_000, value_parser = clap::value_parser!(u64).range(8..))]
    pub triangles: u64,
    /// Rays per ray benchmark.
    #[arg(long, default_value_t = 1 << 20, value_parser = clap::value_parser!(u64).range(1..))]
    pub rays: u64,
    /// Skip the Cornell box rendering benchmark.
    #[arg(long)]
    pub no_cbox: bool,
    /// Cornell box film size (square).
    #[arg(long, default_value_t = 512)]
    pub cbox_res: u32,
    /// Cornell box samples per pixel.
    #[arg(long, default_value_t = 64)]
    pub cbox_spp: u32,
    /// Also write the mesh (`mesh.bin`) and the incoherent rays (`rays.bin`) to this folder, for
    /// timing another ray tracer on identical data (`tools/embree/`; formats in `write_export`).
    #[arg(long, value_name = "DIR")]
    pub export: Option<PathBuf>,
    /// The BVH traversal's compiled kernel (default: the most capable one this CPU runs), to
    /// compare them on one machine.
    #[arg(long, value_enum)]
    pub kernel: Option<KernelArg>,
}

/// `--kernel` values: [`Kernel`]'s variants.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum KernelArg {
    /// Two 4-wide halves (SSE2).
    Portable,
    /// 8-wide AVX.
    Avx,
}

impl From<KernelArg> for Kernel {
    fn from(k: KernelArg) -> Kernel {
        match k {
            KernelArg::Portable => Kernel::Portable,
            KernelArg::Avx => Kernel::Avx,
        }
    }
}

/// A UV sphere with `≈ n` triangles, radially displaced so that rays see real structure.
pub fn displaced_sphere(n: usize) -> TriangleMesh {
    let nv = ((n as f64 / 4.0).sqrt().round() as u32).max(2);
    let nu = 2 * nv;
    let mut positions = Vec::with_capacity(((nu + 1) * (nv + 1)) as usize);
    for j in 0..=nv {
        let theta = std::f32::consts::PI * j as f32 / nv as f32;
        for i in 0..=nu {
            let phi = 2.0 * std::f32::consts::PI * i as f32 / nu as f32;
            let r = 1.0 + 0.08 * (12.0 * theta).sin() * (9.0 * phi).cos() + 0.03 * (40.0 * phi + 3.0 * theta).sin();
            positions.push(Vec3::new(r * theta.sin() * phi.cos(), r * theta.cos(), r * theta.sin() * phi.sin()));
        }
    }
    let mut indices = Vec::with_capacity((2 * nu * nv) as usize);
    let id = |i: u32, j: u32| j * (nu + 1) + i;
    for j in 0..nv {
        for i in 0..nu {
            indices.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            indices.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    TriangleMesh::new(positions, vec![], vec![], indices).expect("valid generated mesh")
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool")
}

/// Mrays/s of `trace` over `rays`, on `threads` threads: the best of three timed passes (this
/// VM's run-to-run noise is ±10 %; the best pass is the least disturbed one), after a warm-up.
fn throughput(threads: usize, rays: &[Ray], trace: &(dyn Fn(&Ray) -> bool + Sync)) -> (f64, usize) {
    let p = pool(threads);
    p.install(|| rays[..rays.len().min(10_000)].par_iter().filter(|r| trace(r)).count());
    let mut best = (0.0f64, 0);
    for _ in 0..3 {
        let t = Instant::now();
        let hits = p.install(|| rays.par_chunks(4096).map(|c| c.iter().filter(|r| trace(r)).count()).sum::<usize>());
        let rate = rays.len() as f64 / t.elapsed().as_secs_f64() / 1e6;
        if rate > best.0 {
            best = (rate, hits);
        }
    }
    best
}

pub fn run(args: &BenchArgs) -> Result<(), String> {
    let all = rayon::current_num_threads();
    let mesh = match &args.mesh {
        Some(path) => neumann::load::load_mesh(path).map_err(|e| e.to_string())?,
        None => displaced_sphere(args.triangles as usize),
    };
    let name = args.mesh.as_ref().map_or("generated displaced sphere".to_string(), |p| p.display().to_string());
    say!("mesh: {name}, {} triangles", mesh.len());

    // BVH build alone.
    let bounds: Vec<Bounds3> = (0..mesh.len())
        .map(|i| {
            let p = mesh.triangle(i);
            Bounds3::from_point(p[0]).union_point(p[1]).union_point(p[2])
        })
        .collect();
    for threads in [1, all] {
        let t = Instant::now();
        let bvh = pool(threads).install(|| Bvh::build(&bounds, &neumann::scene::bvh_options(bounds.len())));
        let s = bvh.stats();
        say!(
            "BVH build ({threads} thread{}): {:.3} s  ({} nodes, {} leaves, depth {}, SAH cost {:.1})",
            if threads == 1 { "" } else { "s" },
            t.elapsed().as_secs_f64(),
            s.nodes,
            s.leaves,
            s.max_depth,
            s.sah_cost
        );
    }

    let triangles = mesh.len();
    let mut scene = mesh_scene(mesh)?;
    if let Some(k) = args.kernel {
        if !scene.set_bvh_kernel(k.into()) {
            return Err(format!(
                "this CPU does not run the {:?} kernel (its best: {:?})",
                Kernel::from(k),
                Kernel::detect()
            ));
        }
    }
    say!("ray kernel: {:?} (the most capable this CPU runs: {:?})", scene.bvh().kernel(), Kernel::detect());
    say!(
        "ray-tracing structure (nodes, triangle blocks, references): {:.1} MiB, {:.0} bytes per triangle",
        scene.accel_memory_bytes() as f64 / (1 << 20) as f64,
        scene.accel_memory_bytes() as f64 / triangles as f64
    );
    let b = scene.bvh().bounds();
    let (center, radius) = b.bounding_sphere();
    let mut rng = Pcg32::new(1, 1);
    let side = ((args.rays as f64).sqrt() as u32).max(1);
    let to_world = Transform::look_at(center + Vec3::new(0.0, 0.3, 2.2) * radius, center, Vec3::Y).unwrap();
    let cam = Camera::perspective(to_world, 50.0, FovAxis::X, side, side).map_err(|e| e.to_string())?;
    let primary: Vec<Ray> = (0..side * side)
        .map(|k| cam.generate_ray(Vec2::new((k % side) as f32 + 0.5, (k / side) as f32 + 0.5), Vec2::ZERO))
        .collect();
    let incoherent: Vec<Ray> = (0..args.rays as usize)
        .map(|_| {
            let o = b.min + b.diagonal() * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            Ray::new(o, sample_uniform_sphere(Vec2::new(rng.next_f32(), rng.next_f32())).value)
        })
        .collect();
    if let Some(dir) = &args.export {
        write_export(dir, &scene, &incoherent)?;
        say!("wrote {} and {}", dir.join("mesh.bin").display(), dir.join("rays.bin").display());
    }
    say!("{:<28} {:>12} {:>12}   hit rate", "rays (Mrays/s)", "1 thread", format!("{all} threads"));
    // Closest-hit as ray-tracing kernels time it (Embree's rtcIntersect1): distance, primitive
    // and barycentrics; and with the surface interaction the renderer then computes.
    let closest = |r: &Ray| scene.intersect_hit(r).is_some();
    let interaction = |r: &Ray| scene.intersect(r).is_some();
    let shadow = |r: &Ray| scene.occluded(r);
    for (label, rays, f) in [
        ("primary closest-hit", &primary, &closest as &(dyn Fn(&Ray) -> bool + Sync)),
        ("incoherent closest-hit", &incoherent, &closest),
        ("  + surface interaction", &incoherent, &interaction),
        ("incoherent shadow (any-hit)", &incoherent, &shadow),
    ] {
        let (one, hits) = throughput(1, rays, f);
        let (many, _) = throughput(all, rays, f);
        say!("{label:<28} {one:>12.2} {many:>12.2}   {:.0} %", 100.0 * hits as f64 / rays.len() as f64);
    }

    if !args.no_cbox {
        let scene = cornell::cornell_box(args.cbox_res, args.cbox_res).map_err(|e| e.to_string())?;
        let integrator = PathIntegrator::with_max_depth(8);
        let settings = RenderSettings { spp: args.cbox_spp, seed: 0, ..Default::default() };
        let out = render(&scene, &integrator, &settings, &AtomicBool::new(false)).map_err(|e| e.to_string())?;
        say!(
            "Cornell box {r}x{r}, {} spp, max_depth 8, {all} threads: {:.2} s, {:.3} M samples/s",
            args.cbox_spp,
            out.elapsed.as_secs_f64(),
            out.samples_per_second() / 1e6,
            r = args.cbox_res
        );
    }
    Ok(())
}

/// Writes the benchmark's mesh and incoherent rays as little-endian binary files in `dir`:
/// `mesh.bin` = u32 vertex count V, u32 triangle count T, V × 3 f32 positions, T × 3 u32
/// indices; `rays.bin` = u32 ray count N, N × (3 f32 origin, 3 f32 unit direction), each ray
/// spanning (0, ∞).
fn write_export(dir: &std::path::Path, scene: &Scene, rays: &[Ray]) -> Result<(), String> {
    let Some(Geometry::Mesh(mesh)) = scene.geometries().first() else {
        return Err("bench --export: the benchmark scene has no mesh".into());
    };
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut m = Vec::with_capacity(8 + 12 * mesh.positions.len() + 12 * mesh.indices.len());
    m.extend((mesh.positions.len() as u32).to_le_bytes());
    m.extend((mesh.indices.len() as u32).to_le_bytes());
    for p in &mesh.positions {
        m.extend([p.x, p.y, p.z].iter().flat_map(|c| c.to_le_bytes()));
    }
    for t in &mesh.indices {
        m.extend(t.iter().flat_map(|i| i.to_le_bytes()));
    }
    let mut r = Vec::with_capacity(4 + 24 * rays.len());
    r.extend((rays.len() as u32).to_le_bytes());
    for ray in rays {
        let (o, d) = (ray.o, ray.d);
        r.extend([o.x, o.y, o.z, d.x, d.y, d.z].iter().flat_map(|c| c.to_le_bytes()));
    }
    for (name, bytes) in [("mesh.bin", m), ("rays.bin", r)] {
        let path = dir.join(name);
        std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}

fn mesh_scene(mesh: TriangleMesh) -> Result<Scene, String> {
    let mut b = SceneBuilder::new();
    let m = b.add_bsdf(Bsdf::Diffuse(Diffuse::new(Rgb::splat(0.5))));
    b.add_shape(Geometry::Mesh(mesh), m, None);
    b.set_camera(Camera::perspective(Transform::IDENTITY, 45.0, FovAxis::X, 1, 1).map_err(|e| e.to_string())?);
    b.build().map_err(|e| e.to_string())
}
