//! The `neumann` command.

use clap::{Parser, Subcommand, ValueEnum};
use neumann::estimators::irradiance::{estimate_uniform_sky_irradiance, HemisphereStrategy};
use neumann::film::output::{write_image_alpha, Format, ImageInfo};
use neumann::integrator::radiosity::{self, Method};
use neumann::integrator::{
    AnyIntegrator, DirectIntegrator, DirectStrategy, LightTracer, PathIntegrator, PathSettings, VolPathIntegrator,
};
use neumann::render::{render, render_integrator, RenderSettings, SamplerKind};
use neumann::sampling::Pcg32;
use neumann::scene::cornell;
use neumann::scene::xml::load_scene_file;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

mod bench;

#[derive(Parser, Debug)]
#[command(name = "neumann", version, about = "A physically based Monte Carlo renderer", arg_required_else_help = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum SamplerArg {
    Independent,
    Stratified,
    Sobol,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum DirectArg {
    /// Light sampling and BSDF sampling, combined by the power heuristic.
    Mis,
    /// Light (emitter area) sampling only.
    Light,
    /// BSDF sampling only.
    Bsdf,
    /// Uniform hemisphere sampling of directions, traced to emitters.
    Uniform,
    /// Cosine-weighted hemisphere sampling of directions, traced to emitters.
    Cosine,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum IntegratorArg {
    /// Path tracing with next-event estimation and MIS (backward, from the camera).
    Path,
    /// Direct lighting only (Mitsuba's `direct`).
    Direct,
    /// Light tracing (forward, from the emitters; Mitsuba's `ptracer`).
    Ptracer,
    /// Radiosity: finite elements for diffuse scenes, solved then displayed.
    Radiosity,
    /// Volumetric path tracing: participating media (Mitsuba's `volpath`).
    Volpath,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum RadiosityMethodArg {
    /// Jacobi iteration, B ← E + ρ F B (the Neumann series term by term).
    Jacobi,
    /// Gauss–Seidel iteration (updated values used at once).
    GaussSeidel,
    /// Progressive refinement: shoot the largest unshot power first.
    Shooting,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum MisArg {
    /// Balance heuristic.
    Balance,
    /// Power heuristic (exponent 2).
    Power,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene (default: the built-in Cornell box) to an image (.png, .exr or .pfm).
    Render(RenderArgs),
    /// Benchmarks: BVH build, ray throughput (primary, incoherent closest-hit and shadow rays) and
    /// path-tracing samples per second on the Cornell box.
    Bench(bench::BenchArgs),
    /// Validate against Mitsuba 3: render the scenes of scenes/ at their references' settings and
    /// compare with references/ (relMSE and mean against Mitsuba's own at equal spp).
    Validate {
        /// Scenes to validate (default: every scene in references.csv).
        scenes: Vec<String>,
        /// Folder of the scene files.
        #[arg(long, default_value = "scenes")]
        scene_dir: PathBuf,
        /// Folder of the references (EXR images and references.csv).
        #[arg(long, default_value = "references")]
        reference_dir: PathBuf,
        /// Seed of neumann's renders.
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// Convergence of estimators: render at 1, 2, 4, … spp with each direct-light strategy and
    /// sampler, measure MSE against a reference, fit the log-log slope, time it, and write a CSV
    /// and log-log plots (MSE vs spp and vs seconds; SVG and PNG).
    Converge(ConvergeArgs),
    /// Monte Carlo estimator demos: estimate, exact value and RMSE over independent runs.
    Mc {
        /// Independent runs per row (for the RMSE).
        #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(2..))]
        runs: u32,
        /// Seed of the first run.
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Sky radiance L (W m⁻² sr⁻¹).
        #[arg(long, default_value_t = 1.0)]
        radiance: f64,
    },
}

static CANCEL: AtomicBool = AtomicBool::new(false);

/// An error and the exit code it maps to (1: could not do it, 2: bad arguments).
struct Failure(u8, String);

fn usage(msg: String) -> Failure {
    Failure(2, msg)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => run_render(args),
        Command::Bench(args) => bench::run(&args).map_err(|e| Failure(1, e)),
        Command::Converge(args) => run_converge(args),
        Command::Validate { scenes, scene_dir, reference_dir, seed } => {
            run_validate(&scenes, &scene_dir, &reference_dir, seed)
        }
        Command::Mc { runs, seed, radiance } => {
            if radiance.is_finite() && radiance >= 0.0 {
                mc_irradiance(runs, seed, radiance);
                Ok(())
            } else {
                Err(usage(format!("--radiance must be a finite non-negative number, got {radiance}")))
            }
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure(code, msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(code)
        }
    }
}

#[derive(clap::Args, Debug)]
struct RenderArgs {
    /// Scene to render: a Mitsuba 3 XML file, or a built-in scene name (cbox, the default).
    scene: Option<String>,
    /// Output image; the extension picks the format (default: <scene>.png).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Samples per pixel.
    #[arg(long)]
    spp: Option<u32>,
    /// Longest path in segments (1: emitters only, 2: direct light, -1: unlimited).
    #[arg(long, allow_negative_numbers = true)]
    max_depth: Option<i32>,
    /// Film resolution, W or WxH.
    #[arg(long)]
    res: Option<String>,
    /// Seed of all random numbers (default: the scene's sampler seed, 0).
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads (default: one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Render for this many seconds (whole passes), instead of a sample count.
    #[arg(long)]
    time: Option<f64>,
    /// Scene parameter name=value: overrides the scene file's <default> of that name ($name);
    /// the built-in Cornell box has res, spp, max_depth.
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    define: Vec<String>,
    /// Sampler (default: the scene's; independent for the built-in scene).
    #[arg(long, value_enum)]
    sampler: Option<SamplerArg>,
    /// Direct-light strategy of the path tracer (default: mis).
    #[arg(long, value_enum)]
    direct: Option<DirectArg>,
    /// MIS heuristic of the mis strategy (default: power).
    #[arg(long, value_enum)]
    mis: Option<MisArg>,
    /// How next-event estimation chooses a light: bvh (default; the light BVH, by a bound on
    /// each light's contribution at the shading point), power (by emitted power) or uniform
    /// (Mitsuba's rule). Default: the scene integrator's `light_sampler`, else bvh.
    #[arg(long, value_name = "bvh|power|uniform")]
    light_sampler: Option<neumann::light::LightSamplerKind>,
    /// Exposure in stops for PNG output (× 2^EV).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Integrator (default: the scene's; path for the built-in scene). Settings it shares with
    /// the scene's integrator (max_depth, rr_depth, hide_emitters) are kept.
    #[arg(long, value_enum)]
    integrator: Option<IntegratorArg>,
    /// Radiosity: longest patch edge in world units (default 0.1; the Cornell box is 2 wide).
    #[arg(long, value_name = "SIZE")]
    patch_size: Option<f32>,
    /// Radiosity: Monte Carlo form-factor rays per patch (default 512).
    #[arg(long, value_name = "N")]
    ff_rays: Option<u32>,
    /// Radiosity: linear solver (default gauss-seidel).
    #[arg(long, value_enum)]
    radiosity_method: Option<RadiosityMethodArg>,
    /// Radiosity: stop when the relative residual falls below this (default 1e-4).
    #[arg(long)]
    tolerance: Option<f64>,
    /// Radiosity: smooth shading (vertex radiosities interpolated) instead of flat patches.
    #[arg(long)]
    smooth: bool,
    /// Radiosity: write the per-patch solution (area, centroid, ρ, emission, radiosity) as CSV.
    #[arg(long, value_name = "FILE.csv")]
    patches_out: Option<PathBuf>,
    /// Also write the terms of the Neumann series to this folder: term0.exr = Lₑ seen directly,
    /// term1.exr = T Lₑ (direct light), term2.exr = T² Lₑ, …, up to max_depth (8 terms when
    /// unlimited, the last holding all longer paths), sum.exr (= the render) and terms.png, a
    /// contact sheet of the terms and their sum side by side.
    #[arg(long, value_name = "DIR")]
    bounces_out: Option<PathBuf>,
}

#[derive(clap::Args, Debug)]
struct ConvergeArgs {
    /// Scene: a Mitsuba 3 XML file or a built-in scene (cbox, the default).
    scene: Option<String>,
    /// Reference image (EXR or PFM of the same size); default: render one with MIS at 16 × the
    /// largest spp.
    #[arg(long = "ref", value_name = "REF")]
    reference: Option<PathBuf>,
    /// Direct-light strategies to compare (comma-separated).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "mis,light,bsdf")]
    direct: Vec<DirectArg>,
    /// Samplers to compare (comma-separated).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "independent")]
    sampler: Vec<SamplerArg>,
    /// Largest samples per pixel (levels 1, 2, 4, … up to it).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    max_spp: u32,
    /// Film resolution, W or WxH (default: 64, small enough for many renders).
    #[arg(long, default_value = "64")]
    res: String,
    /// Longest path in segments (2: direct light only).
    #[arg(long, allow_negative_numbers = true)]
    max_depth: Option<i32>,
    /// Scene parameter name=value.
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    define: Vec<String>,
    /// Output folder for convergence.csv, convergence.svg, convergence.png (and reference.exr).
    #[arg(long, default_value = "converge")]
    out: PathBuf,
    /// Seed of the measured renders.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: one per core).
    #[arg(long, default_value_t = 0)]
    threads: usize,
}

fn sampler_kind(s: SamplerArg) -> SamplerKind {
    match s {
        SamplerArg::Independent => SamplerKind::Independent,
        SamplerArg::Stratified => SamplerKind::Stratified,
        SamplerArg::Sobol => SamplerKind::Sobol,
    }
}

fn direct_strategy(d: DirectArg) -> DirectStrategy {
    match d {
        DirectArg::Mis => DirectStrategy::Mis,
        DirectArg::Light => DirectStrategy::Light,
        DirectArg::Bsdf => DirectStrategy::Bsdf,
        DirectArg::Uniform => DirectStrategy::Uniform,
        DirectArg::Cosine => DirectStrategy::Cosine,
    }
}

fn run_converge(a: ConvergeArgs) -> Result<(), Failure> {
    use neumann::converge::{measure, plot, spp_levels, write_csv};
    let scene_arg = a.scene.clone().unwrap_or_else(|| "cbox".to_string());
    let defines = parse_defines(&a.define)?;
    let mut job = if scene_arg == "cbox" {
        builtin_job(&scene_arg, &defines)?
    } else {
        file_job(std::path::Path::new(&scene_arg), &defines)?
    };
    let (w, h) = parse_res(&a.res).map_err(usage)?;
    let camera = job.scene.camera().with_resolution(w, h).map_err(|e| Failure(1, e))?;
    job.scene.set_camera(camera);
    let base = match &job.integrator {
        AnyIntegrator::Path(p) => p.clone(),
        other => {
            return Err(usage(format!(
                "converge compares the path tracer's strategies; this scene uses '{}'",
                other.name()
            )))
        }
    };
    let max_depth = a.max_depth.unwrap_or(base.settings.max_depth);
    if max_depth < -1 {
        return Err(usage(format!("--max-depth must be -1 (unlimited) or ≥ 0, got {max_depth}")));
    }
    std::fs::create_dir_all(&a.out).map_err(|e| Failure(1, format!("cannot create '{}': {e}", a.out.display())))?;
    let reference = match &a.reference {
        Some(path) => {
            let img = neumann::load::image::load_image(path, true).map_err(|e| Failure(1, e))?;
            if (img.width, img.height) != (w, h) {
                return Err(Failure(
                    1,
                    format!("the reference is {}x{} but the renders are {w}x{h} (use --res)", img.width, img.height),
                ));
            }
            img.pixels
        }
        None => {
            let spp = a.max_spp.saturating_mul(16).min(1 << 16);
            println!(
                "no --ref: rendering a reference with MIS at {spp} spp (seed {}), written to reference.exr",
                a.seed + 1_000_003
            );
            let integrator = PathIntegrator {
                settings: PathSettings { max_depth, ..base.settings },
                strategy: DirectStrategy::Mis,
                ..base.clone()
            };
            let settings = RenderSettings {
                spp,
                seed: a.seed + 1_000_003,
                threads: a.threads,
                progress: true,
                ..Default::default()
            };
            let out = render(&job.scene, &integrator, &settings, &CANCEL).map_err(|e| Failure(1, e))?;
            let image = out.film.image();
            write_image_alpha(&a.out.join("reference.exr"), w, h, &image, None, &ImageInfo { spp, exposure: 0.0 })
                .map_err(|e| Failure(1, e))?;
            image
        }
    };
    let levels = spp_levels(a.max_spp);
    let mut curves = Vec::new();
    println!("{:<24} {:>8} {:>12} {:>10} {:>12}", "estimator", "slope", "MSE (max)", "seconds", "1/(MSE·s)");
    for &d in &a.direct {
        for &s in &a.sampler {
            let name = if a.sampler.len() > 1 { format!("{d:?} / {s:?}") } else { format!("{d:?}") }.to_lowercase();
            let integrator = PathIntegrator {
                settings: PathSettings { max_depth, ..base.settings },
                strategy: direct_strategy(d),
                ..base.clone()
            };
            let base =
                RenderSettings { sampler: sampler_kind(s), seed: a.seed, threads: a.threads, ..Default::default() };
            let curve =
                measure(&name, &job.scene, &integrator, &reference, &levels, &base).map_err(|e| Failure(1, e))?;
            let last = curve.points.last().copied().expect("at least one level");
            println!(
                "{name:<24} {:>8.3} {:>12.4e} {:>10.3} {:>12.4e}",
                curve.slope().unwrap_or(f64::NAN),
                last.mse,
                last.seconds,
                curve.efficiency().unwrap_or(0.0)
            );
            curves.push(curve);
        }
    }
    write_csv(&a.out.join("convergence.csv"), &curves).map_err(|e| Failure(1, e))?;
    let title = format!("{} {w}x{h}, max_depth {max_depth}: MSE against a reference", job.name);
    plot(&a.out.join("convergence.svg"), &a.out.join("convergence.png"), &title, &curves).map_err(|e| Failure(1, e))?;
    println!("wrote convergence.csv, convergence.svg and convergence.png to {}", a.out.display());
    Ok(())
}

/// Parses `W` or `WxH`.
fn parse_res(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("invalid resolution '{s}': expected W or WxH with positive integers, e.g. 512 or 640x480");
    let (w, h) = match s.split_once(['x', 'X']) {
        Some((w, h)) => (w.trim().parse().map_err(|_| bad())?, h.trim().parse().map_err(|_| bad())?),
        None => {
            let w = s.trim().parse().map_err(|_| bad())?;
            (w, w)
        }
    };
    if w == 0 || h == 0 {
        return Err(bad());
    }
    // The film keeps ~52 bytes per pixel: cap it well below this machine's memory.
    if w > 16384 || h > 16384 || (w as u64) * (h as u64) > 1 << 26 {
        return Err(format!("resolution {w}x{h} is too large (at most 16384 per side and 67 million pixels)"));
    }
    Ok((w, h))
}

/// A scene ready to render with its settings (from the built-in Cornell box or a file).
struct Job {
    name: String,
    scene: neumann::scene::Scene,
    integrator: AnyIntegrator,
    spp: u32,
    sampler: SamplerKind,
    seed: u64,
    filter: neumann::film::filter::Filter,
    window: Option<[u32; 4]>,
    alpha: bool,
}

/// Parses the `-D name=value` list.
fn parse_defines(defines: &[String]) -> Result<Vec<(String, String)>, Failure> {
    defines
        .iter()
        .map(|d| match d.split_once('=') {
            Some((k, v)) if !k.trim().is_empty() => Ok((k.trim().to_string(), v.to_string())),
            _ => Err(usage(format!("-D expects NAME=VALUE, got '{d}'"))),
        })
        .collect()
}

/// The built-in Cornell box with cbox.xml's parameters (res, spp, max_depth) from `-D`.
fn builtin_job(name: &str, defines: &[(String, String)]) -> Result<Job, Failure> {
    let (mut res, mut spp, mut max_depth) =
        ((cornell::DEFAULT_RES, cornell::DEFAULT_RES), cornell::DEFAULT_SPP, cornell::DEFAULT_MAX_DEPTH);
    for (k, v) in defines {
        let bad = |what: &str| usage(format!("-D {k}: expected {what}, got '{v}'"));
        match k.as_str() {
            "res" => res = parse_res(v).map_err(usage)?,
            "spp" => spp = v.trim().parse().ok().filter(|&s: &u32| s > 0).ok_or_else(|| bad("a positive integer"))?,
            "max_depth" => {
                max_depth = v.trim().parse().ok().filter(|&d: &i32| d >= -1).ok_or_else(|| bad("an integer ≥ -1"))?
            }
            other => {
                return Err(usage(format!(
                    "-D {other}: the scene '{name}' has no parameter '{other}' (it has res, spp, max_depth)"
                )))
            }
        }
    }
    Ok(Job {
        name: name.to_string(),
        scene: cornell::cornell_box(res.0, res.1).map_err(|e| Failure(1, e))?,
        integrator: AnyIntegrator::Path(PathIntegrator::with_max_depth(max_depth)),
        spp,
        sampler: SamplerKind::Independent,
        seed: 0,
        filter: neumann::film::filter::Filter::Box,
        window: None,
        alpha: false,
    })
}

/// A Mitsuba XML scene file.
fn file_job(path: &std::path::Path, defines: &[(String, String)]) -> Result<Job, Failure> {
    let file = load_scene_file(path, defines).map_err(|e| Failure(1, e.to_string()))?;
    for w in &file.warnings {
        eprintln!("{w}");
    }
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene").to_string();
    Ok(Job {
        name,
        scene: file.scene,
        integrator: file.integrator,
        spp: file.spp,
        sampler: file.sampler,
        seed: file.seed,
        filter: file.filter,
        window: file.window,
        alpha: file.alpha,
    })
}

fn run_render(a: RenderArgs) -> Result<(), Failure> {
    let scene_arg = a.scene.clone().unwrap_or_else(|| "cbox".to_string());
    let defines = parse_defines(&a.define)?;
    let mut job = if scene_arg == "cbox" {
        builtin_job(&scene_arg, &defines)?
    } else if scene_arg.to_ascii_lowercase().ends_with(".xml") || std::path::Path::new(&scene_arg).exists() {
        file_job(std::path::Path::new(&scene_arg), &defines)?
    } else {
        return Err(Failure(
            1,
            format!("unknown scene '{scene_arg}': give a Mitsuba 3 .xml scene file or a built-in scene name (cbox)"),
        ));
    };
    // Command-line flags override the scene's settings.
    if let Some(r) = &a.res {
        let (w, h) = parse_res(r).map_err(usage)?;
        let camera = job.scene.camera().with_resolution(w, h).map_err(|e| Failure(1, e))?;
        job.scene.set_camera(camera);
        job.window = None;
    }
    if let Some(s) = a.spp {
        if s == 0 {
            return Err(usage("--spp must be at least 1".into()));
        }
        job.spp = s;
    }
    select_integrator(&mut job.integrator, &a)?;
    if job.scene.has_media() && !matches!(job.integrator, AnyIntegrator::VolPath(_)) {
        eprintln!(
            "warning: the scene has participating media, which the {} integrator ignores (as Mitsuba's): use --integrator volpath",
            job.integrator.name()
        );
    }
    if let Some(d) = a.max_depth {
        if d < -1 {
            return Err(usage(format!("--max-depth must be -1 (unlimited) or ≥ 0, got {d}")));
        }
        match &mut job.integrator {
            AnyIntegrator::Path(PathIntegrator { settings, .. })
            | AnyIntegrator::Ptracer(LightTracer { settings })
            | AnyIntegrator::VolPath(VolPathIntegrator { settings }) => settings.max_depth = d,
            other => {
                return Err(usage(format!(
                    "--max-depth applies to the path, volpath and ptracer integrators, not '{}'",
                    other.name()
                )))
            }
        }
    }
    if let Some(s) = a.seed {
        job.seed = s;
    }
    if let Some(s) = a.sampler {
        job.sampler = match s {
            SamplerArg::Independent => SamplerKind::Independent,
            SamplerArg::Stratified => SamplerKind::Stratified,
            SamplerArg::Sobol => SamplerKind::Sobol,
        };
    }
    if let Some(kind) = a.light_sampler {
        match &job.integrator {
            AnyIntegrator::Path(_) | AnyIntegrator::VolPath(_) | AnyIntegrator::Direct(_) => {
                job.scene.set_light_sampler(kind).map_err(|e| Failure(1, e))?
            }
            other => {
                return Err(usage(format!(
                    "--light-sampler applies to the path, volpath and direct integrators, not '{}'",
                    other.name()
                )))
            }
        }
    }
    if let Some(direct) = a.direct {
        match &mut job.integrator {
            AnyIntegrator::Path(p) => {
                p.strategy = match direct {
                    DirectArg::Mis => DirectStrategy::Mis,
                    DirectArg::Light => DirectStrategy::Light,
                    DirectArg::Bsdf => DirectStrategy::Bsdf,
                    DirectArg::Uniform => DirectStrategy::Uniform,
                    DirectArg::Cosine => DirectStrategy::Cosine,
                };
                if matches!(direct, DirectArg::Uniform | DirectArg::Cosine)
                    && job.scene.lights().iter().any(|l| l.is_delta())
                {
                    eprintln!(
                        "warning: --direct {direct:?} samples directions, which never hit point, spot or directional lights: \
                         they contribute nothing with this strategy"
                    );
                }
            }
            other => {
                return Err(usage(format!(
                    "--direct applies to the path integrator, not '{}' (the direct integrator sets emitter_samples / bsdf_samples)",
                    other.name()
                )))
            }
        }
    }
    if let Some(m) = a.mis {
        match &mut job.integrator {
            AnyIntegrator::Path(p) => {
                p.heuristic = match m {
                    MisArg::Balance => neumann::integrator::MisHeuristic::Balance,
                    MisArg::Power => neumann::integrator::MisHeuristic::Power,
                }
            }
            other => return Err(usage(format!("--mis applies to the path integrator, not '{}'", other.name()))),
        }
    }
    let time_budget = match a.time {
        None => None,
        Some(t) => match Duration::try_from_secs_f64(t) {
            Ok(d) if t > 0.0 => Some(d),
            _ => return Err(usage(format!("--time must be a positive number of seconds, got {t:?}"))),
        },
    };
    if !a.exposure.is_finite() {
        return Err(usage(format!("--exposure must be a finite number of stops, got {}", a.exposure)));
    }
    let output = a.output.clone().unwrap_or_else(|| PathBuf::from(format!("{}.png", job.name)));
    if Format::from_path(&output).map_err(usage)? == Format::Pfm && job.alpha {
        return Err(usage(format!(
            "the scene asks for an alpha channel (pixel_format rgba), which PFM cannot hold: write {}.exr or .png",
            job.name
        )));
    }

    let term_count = match (&a.bounces_out, &job.integrator) {
        (None, _) => 0,
        (Some(_), AnyIntegrator::Path(p)) if (1..=16).contains(&p.settings.max_depth) => p.settings.max_depth as usize,
        (Some(_), AnyIntegrator::Path(_)) => 8,
        (Some(_), other) => {
            return Err(usage(format!("--bounces-out needs the path integrator, not '{}'", other.name())))
        }
    };
    if let Some(dir) = &a.bounces_out {
        std::fs::create_dir_all(dir).map_err(|e| Failure(1, format!("cannot create '{}': {e}", dir.display())))?;
    }
    let settings = RenderSettings {
        spp: if time_budget.is_some() && a.spp.is_none() { u32::MAX } else { job.spp },
        time_budget,
        seed: job.seed,
        threads: a.threads,
        sampler: job.sampler,
        progress: !a.quiet,
        filter: job.filter.clone(),
        window: job.window,
        alpha: job.alpha,
        terms: term_count,
        ..Default::default()
    };
    let _ = ctrlc::set_handler(|| {
        if CANCEL.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!(
            "\ninterrupted: finishing the tiles in flight and writing what has been rendered (Ctrl-C again to abort)"
        );
    });
    let cam = job.scene.camera();
    let [_, _, width, height] = job.window.unwrap_or([0, 0, cam.width(), cam.height()]);
    println!(
        "rendering {} at {width}x{height}, {}, {}, {} threads",
        job.name,
        match a.time {
            Some(t) => format!("for {t} s"),
            None => format!("{} spp", job.spp),
        },
        job.integrator.describe(),
        if a.threads == 0 { rayon::current_num_threads() } else { a.threads }
    );
    let out = render_integrator(&job.scene, &job.integrator, &settings, &CANCEL).map_err(|e| Failure(1, e))?;
    if let Some(sol) = &out.radiosity {
        report_radiosity(sol, a.patches_out.as_deref())?;
    }
    let (lo, hi) = out.film.spp_range();
    let alpha = job.alpha.then(|| out.film.alpha());
    let info = ImageInfo { spp: lo, exposure: a.exposure };
    write_image_alpha(&output, width, height, &out.film.image(), alpha.as_deref(), &info).map_err(|e| Failure(1, e))?;
    if let Some(dir) = &a.bounces_out {
        write_terms(dir, &out.film, width, height, &info).map_err(|e| Failure(1, e))?;
        println!("wrote {} Neumann-series terms, their sum and a contact sheet to {}", term_count, dir.display());
    }
    let spp_text = if lo == hi { format!("{lo} spp") } else { format!("{lo}–{hi} spp (interrupted mid-pass)") };
    println!(
        "wrote {} ({spp_text}, {:.2} s, {:.3} M samples/s)",
        output.display(),
        out.elapsed.as_secs_f64(),
        out.samples_per_second() / 1e6
    );
    if out.interrupted {
        println!("render interrupted: the image holds {spp_text}");
    }
    if out.film.dropped() > 0 {
        println!("warning: {} samples were NaN or infinite and were dropped", out.film.dropped());
    }
    Ok(())
}

/// Applies `--integrator` and the radiosity flags to the scene's integrator. Settings the old
/// and new integrator share (max_depth, rr_depth, hide_emitters) carry over.
fn select_integrator(current: &mut AnyIntegrator, a: &RenderArgs) -> Result<(), Failure> {
    let settings = match &*current {
        AnyIntegrator::Direct(d) => PathSettings { hide_emitters: d.hide_emitters, ..Default::default() },
        other => other.path_settings().copied().unwrap_or_default(),
    };
    if let Some(kind) = a.integrator {
        let same = current.name() == format!("{kind:?}").to_ascii_lowercase();
        if !same {
            *current = match kind {
                IntegratorArg::Path => AnyIntegrator::Path(PathIntegrator { settings, ..Default::default() }),
                IntegratorArg::Direct => AnyIntegrator::Direct(DirectIntegrator {
                    hide_emitters: settings.hide_emitters,
                    ..Default::default()
                }),
                IntegratorArg::Ptracer => AnyIntegrator::Ptracer(LightTracer { settings }),
                IntegratorArg::Radiosity => AnyIntegrator::Radiosity(radiosity::Options::default()),
                IntegratorArg::Volpath => AnyIntegrator::VolPath(VolPathIntegrator { settings }),
            };
        }
    }
    let radiosity_flags = a.patch_size.is_some()
        || a.ff_rays.is_some()
        || a.radiosity_method.is_some()
        || a.tolerance.is_some()
        || a.smooth
        || a.patches_out.is_some();
    match current {
        AnyIntegrator::Radiosity(o) => {
            if let Some(s) = a.patch_size {
                if !(s > 0.0 && s.is_finite()) {
                    return Err(usage(format!("--patch-size must be a positive length, got {s}")));
                }
                o.patch_size = s;
            }
            if let Some(n) = a.ff_rays {
                if n == 0 {
                    return Err(usage("--ff-rays must be at least 1".into()));
                }
                o.rays_per_patch = n;
            }
            if let Some(t) = a.tolerance {
                if !(t > 0.0 && t < 1.0) {
                    return Err(usage(format!("--tolerance must be in (0, 1), got {t}")));
                }
                o.tolerance = t;
            }
            if let Some(m) = a.radiosity_method {
                o.method = match m {
                    RadiosityMethodArg::Jacobi => Method::Jacobi,
                    RadiosityMethodArg::GaussSeidel => Method::GaussSeidel,
                    RadiosityMethodArg::Shooting => Method::Shooting,
                };
            }
            o.smooth |= a.smooth;
        }
        other if radiosity_flags => {
            return Err(usage(format!(
                "--patch-size, --ff-rays, --radiosity-method, --tolerance, --smooth and --patches-out apply to the radiosity integrator, not '{}' (add --integrator radiosity)",
                other.name()
            )))
        }
        _ => {}
    }
    Ok(())
}

/// Prints the radiosity solve (patches, form factors, iterations and residuals, power) and
/// writes the per-patch CSV if asked.
fn report_radiosity(sol: &radiosity::Radiosity, csv: Option<&std::path::Path>) -> Result<(), Failure> {
    println!(
        "radiosity: {} patches, {} non-zero form factors, {} iterations, residual {:.2e}; emitted {:.4} W, reflected {:.4} W (luminance)",
        sol.b.len(),
        sol.form_factor_entries,
        sol.history.last().map_or(0, |h| h.0),
        sol.history.last().map_or(0.0, |h| h.1),
        sol.emitted_power(),
        sol.reflected_power()
    );
    let shown: Vec<String> = sol
        .history
        .iter()
        .filter(|(k, _)| k.is_power_of_two() || *k == sol.history.last().map_or(0, |h| h.0))
        .map(|(k, r)| format!("{k}: {r:.2e}"))
        .collect();
    println!("  residual by iteration: {}", shown.join(", "));
    if let Some(path) = csv {
        std::fs::write(path, sol.to_csv())
            .map_err(|e| Failure(1, format!("cannot write '{}': {e}", path.display())))?;
        println!("wrote the per-patch solution to {}", path.display());
    }
    Ok(())
}

/// Writes each Neumann-series term, the sum and a contact sheet (terms then sum, left to right).
fn write_terms(
    dir: &std::path::Path,
    film: &neumann::film::Film,
    w: u32,
    h: u32,
    info: &ImageInfo,
) -> Result<(), String> {
    let mut panels = Vec::new();
    for k in 0..film.term_count() {
        let image = film.term_image(k);
        write_image_alpha(&dir.join(format!("term{k}.exr")), w, h, &image, None, info)?;
        panels.push(image);
    }
    let sum = film.image();
    write_image_alpha(&dir.join("sum.exr"), w, h, &sum, None, info)?;
    panels.push(sum);
    // Contact sheet: panels separated by 2-pixel white gaps.
    let gap = 2u32;
    let sheet_w = panels.len() as u32 * (w + gap) - gap;
    let mut sheet = vec![neumann::math::Rgb::ONE; (sheet_w * h) as usize];
    for (p, panel) in panels.iter().enumerate() {
        let x0 = p as u32 * (w + gap);
        for y in 0..h {
            for x in 0..w {
                sheet[(y * sheet_w + x0 + x) as usize] = panel[(y * w + x) as usize];
            }
        }
    }
    write_image_alpha(&dir.join("terms.png"), sheet_w, h, &sheet, None, info)
}

fn run_validate(
    scenes: &[String],
    scene_dir: &std::path::Path,
    reference_dir: &std::path::Path,
    seed: u64,
) -> Result<(), Failure> {
    use neumann::validate::{read_references, validate};
    let refs = read_references(reference_dir).map_err(|e| Failure(1, e))?;
    if let Some(s) = scenes.iter().find(|s| !refs.iter().any(|r| &r.scene == *s)) {
        let names: Vec<&str> = refs.iter().map(|r| r.scene.as_str()).collect();
        return Err(usage(format!("no reference for scene '{s}' (references exist for: {})", names.join(", "))));
    }
    println!(
        "{:<16} {:>5} {:>6} {:>12} {:>12} {:>7} {:>6} {:>9} {:>10} {:>10}  verdict",
        "scene", "res", "spp", "relMSE", "Mitsuba", "ratio", "bound", "mean diff", "Msamp/s", "Mitsuba"
    );
    let mut failed = 0;
    for r in refs.iter().filter(|r| scenes.is_empty() || scenes.contains(&r.scene)) {
        let v = validate(scene_dir, reference_dir, r, seed).map_err(|e| Failure(1, e))?;
        let ok = v.passed();
        failed += usize::from(!ok);
        println!(
            "{:<16} {:>5} {:>6} {:>12.4e} {:>12.4e} {:>7.3} {:>6.2} {:>+8.3}% {:>10.2} {:>10.2}  {}",
            r.scene,
            r.res,
            r.test_spp,
            v.relmse,
            r.mitsuba_relmse,
            v.relmse_ratio(),
            r.max_relmse_ratio,
            100.0 * v.mean_difference(),
            v.samples_per_second / 1e6,
            r.mitsuba_samples_per_second / 1e6,
            if ok { "ok" } else { "FAIL" }
        );
    }
    println!("(pass: relMSE ≤ bound × Mitsuba's at equal spp and |mean diff| ≤ 0.5 %; Mitsuba's speed as recorded with the references)");
    if failed > 0 {
        return Err(Failure(1, format!("{failed} scene(s) failed validation")));
    }
    Ok(())
}

/// Prints one table row per sample count: mean of the estimates over `runs` runs, exact value,
/// RMSE over the runs.
fn mc_rows(
    name: &str,
    exact: f64,
    runs: u32,
    seed: u64,
    counts: &[usize],
    mut run: impl FnMut(usize, &mut Pcg32) -> f64,
) {
    for &n in counts {
        let mut rng = Pcg32::new(seed, n as u64);
        let estimates: Vec<f64> = (0..runs).map(|_| run(n, &mut rng)).collect();
        let mean = estimates.iter().sum::<f64>() / runs as f64;
        let rmse = (estimates.iter().map(|e| (e - exact) * (e - exact)).sum::<f64>() / runs as f64).sqrt();
        println!("{name:<28} {n:>8} {mean:>12.6} {exact:>12.6} {rmse:>12.3e}");
    }
}

/// The estimator demos: irradiance under a uniform sky (uniform vs cosine vs stratified),
/// irradiance from a spherical light (hemisphere vs area vs cone sampling), and the uniformity
/// of the triangle and disk warps as χ² statistics.
fn mc_irradiance(runs: u32, seed: u64, radiance: f64) {
    use neumann::estimators::irradiance::{
        estimate_sphere_light_irradiance, estimate_uniform_sky_irradiance_stratified, SphereLightStrategy,
    };
    let header = || println!("{:<28} {:>8} {:>12} {:>12} {:>12}", "estimator", "N", "estimate", "exact", "RMSE");
    let exact = radiance * std::f64::consts::PI;
    println!("Irradiance under a uniform sky of radiance L = {radiance}: E = ∫ L cos θ dω = L π = {exact:.6}");
    header();
    let counts = [16usize, 256, 4096, 65536];
    for (name, strategy) in
        [("uniform hemisphere", HemisphereStrategy::Uniform), ("cosine-weighted", HemisphereStrategy::Cosine)]
    {
        mc_rows(name, exact, runs, seed, &counts, |n, rng| {
            estimate_uniform_sky_irradiance(radiance, n, strategy, rng).value
        });
    }
    mc_rows("uniform, stratified k×k", exact, runs, seed, &counts, |n, rng| {
        let k = (n as f64).sqrt().round() as usize;
        estimate_uniform_sky_irradiance_stratified(radiance, k, rng).value
    });

    let (r, h) = (0.25, 2.0);
    let exact = std::f64::consts::PI * radiance * (r / h) * (r / h);
    println!();
    println!(
        "Irradiance from a sphere of radiance L = {radiance}, radius {r}, at height {h}: E = π L (r/h)² = {exact:.6}"
    );
    header();
    for (name, strategy) in [
        ("uniform hemisphere", SphereLightStrategy::Uniform),
        ("cosine-weighted", SphereLightStrategy::Cosine),
        ("light area (whole sphere)", SphereLightStrategy::Area),
        ("light cone (solid angle)", SphereLightStrategy::Cone),
    ] {
        mc_rows(name, exact, runs, seed, &counts[..3], |n, rng| {
            estimate_sphere_light_irradiance(radiance, r, h, n, strategy, rng).value
        });
    }

    println!();
    println!("Uniformity of warps: Pearson χ² of 200 000 samples against the uniform density (20×20 cells)");
    println!("{:<36} {:>12} {:>6} {:>10}", "warp", "χ²", "dof", "p-value");
    use neumann::testkit::{chi2_2d, Chi2Config, Disk, Triangle};
    let cfg = Chi2Config::default().with_seed(seed);
    let u2 = |r: &mut Pcg32| neumann::math::Vec2::new(r.next_f32(), r.next_f32());
    let tri = Triangle { p: [neumann::math::Vec3::ZERO, neumann::math::Vec3::X, neumann::math::Vec3::Y] };
    let rows = [
        (
            "triangle u=1-√(1-ξ₁), v=ξ₂√(1-ξ₁)",
            chi2_2d(
                &tri,
                [20, 20],
                200_000,
                |r| {
                    let b = neumann::sampling::sample_uniform_triangle(u2(r)).value;
                    Some(neumann::math::Vec3::new(b.y, b.z, 0.0))
                },
                |_| 2.0,
                &cfg,
            ),
        ),
        (
            "triangle, naive u=ξ₁, v=ξ₂(1-ξ₁)",
            chi2_2d(
                &tri,
                [20, 20],
                200_000,
                |r| {
                    let (a, b) = (r.next_f32(), r.next_f32());
                    Some(neumann::math::Vec3::new(a, b * (1.0 - a), 0.0))
                },
                |_| 2.0,
                &cfg,
            ),
        ),
        (
            "disk r=√ξ₁, φ=2πξ₂",
            chi2_2d(
                &Disk,
                [20, 20],
                200_000,
                |r| Some(neumann::sampling::sample_uniform_disk_polar(u2(r)).value),
                |_| 1.0 / std::f64::consts::PI,
                &cfg,
            ),
        ),
        (
            "disk, concentric",
            chi2_2d(
                &Disk,
                [20, 20],
                200_000,
                |r| Some(neumann::sampling::sample_uniform_disk_concentric(u2(r)).value),
                |_| 1.0 / std::f64::consts::PI,
                &cfg,
            ),
        ),
        (
            "disk, naive r=ξ₁, φ=2πξ₂",
            chi2_2d(
                &Disk,
                [20, 20],
                200_000,
                |r| {
                    let (a, b) = (r.next_f32(), r.next_f32());
                    let phi = 2.0 * std::f32::consts::PI * b;
                    Some(neumann::math::Vec2::new(a * phi.cos(), a * phi.sin()))
                },
                |_| 1.0 / std::f64::consts::PI,
                &cfg,
            ),
        ),
    ];
    for (name, out) in rows {
        println!("{name:<36} {:>12.1} {:>6} {:>10.3e}", out.statistic, out.dof, out.p_value);
    }
    println!("(a uniform warp gives χ² ≈ dof; the naive warps are rejected with p ≈ 0)");
}
