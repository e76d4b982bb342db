//! `neumann render`: render a scene to an image, with command-line flags overriding the scene's
//! settings.

use crate::job::{builtin_job, file_job, parse_defines, parse_res};
use crate::{choice, usage, Failure, CANCEL};
use neumann::film::part::PartInfo;
use neumann::film::output::{write_image_alpha, write_image_layers, Channel, Format, ImageInfo, WriteError};
use neumann::integrator::radiosity::Method;
use neumann::integrator::{AnyIntegrator, DirectStrategy, IntegratorKind, MisHeuristic, PathSettings};
use neumann::load::overrides::Overrides;
use neumann::light::LightSamplerKind;
use neumann::render::{render_integrator_with, RenderSettings};
use neumann::sampling::sampler::SamplerKind;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::time::Duration;

#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scene to render: a Mitsuba 3 XML file, a pbrt-v4 file (.pbrt), a glTF 2.0 file (.gltf, .glb), or a built-in
    /// scene name (cbox, the default).
    scene: Option<String>,
    /// glTF: the camera to render, by name or index in the file's cameras (or the name of the
    /// node holding it); default: the first, or one framing the scene if the file has none.
    #[arg(long, value_name = "NAME|INDEX")]
    camera: Option<String>,
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
    /// The most memory the film may take, e.g. 8G or 512M (default: half of this machine's
    /// memory). A larger render is refused before it starts.
    #[arg(long)]
    max_memory: Option<String>,
    /// Save the render's state to OUTPUT.state every this many seconds (at the end of a pass)
    /// and when it finishes, so that --resume can continue it.
    #[arg(long)]
    checkpoint: Option<f64>,
    /// Continue the render saved in this state file (written by --checkpoint) up to --spp: the
    /// same scene and settings are required; the result equals a render that never stopped.
    #[arg(long)]
    resume: Option<PathBuf>,
    /// Worker threads (default: one per core; at most 1024).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u64).range(0..=1024))]
    threads: u64,
    /// Render for this many seconds (whole passes), instead of a sample count.
    #[arg(long)]
    time: Option<f64>,
    /// Scene parameter name=value: overrides the scene file's <default> of that name ($name);
    /// the built-in Cornell box has res, spp, max_depth.
    #[arg(short = 'D', value_name = "NAME=VALUE")]
    define: Vec<String>,
    /// Sampler (default: the scene's; independent for the built-in scene).
    #[arg(long, value_parser = choice::<SamplerKind>())]
    sampler: Option<SamplerKind>,
    /// Direct-light strategy of the path tracer (default: mis).
    #[arg(long, value_parser = choice::<DirectStrategy>())]
    direct: Option<DirectStrategy>,
    /// MIS heuristic of the mis strategy (default: power).
    #[arg(long, value_parser = choice::<MisHeuristic>())]
    mis: Option<MisHeuristic>,
    /// How next-event estimation chooses a light (path, volpath, volpathmis, direct). Default: the scene
    /// integrator's `light_sampler`, else bvh.
    #[arg(long, value_parser = choice::<LightSamplerKind>())]
    light_sampler: Option<LightSamplerKind>,
    /// Exposure in stops for PNG output (× 2^EV).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Integrator (default: the scene's; path for the built-in scene). Settings it shares with
    /// the scene's integrator (max_depth, rr_depth, hide_emitters) are kept.
    #[arg(long, value_parser = choice::<IntegratorKind>())]
    integrator: Option<IntegratorKind>,
    /// Radiosity: longest patch edge in world units (default 0.1; the Cornell box is 2 wide).
    #[arg(long, value_name = "SIZE")]
    patch_size: Option<f32>,
    /// Radiosity: Monte Carlo form-factor rays per patch (default 512).
    #[arg(long, value_name = "N")]
    ff_rays: Option<u32>,
    /// Radiosity: linear solver (default gauss-seidel).
    #[arg(long, value_parser = choice::<Method>())]
    radiosity_method: Option<Method>,
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
    /// Adaptive sampling with Cycles' noise threshold T (Cycles' default 0.01): a pixel stops
    /// taking samples once its relative error estimate, from a separate half of its samples, is
    /// below 5·T as in Cycles (and its neighbours' too), after --min-spp samples; --spp (or
    /// --time) bounds the render.
    #[arg(long, value_name = "T")]
    noise_threshold: Option<f32>,
    /// With --noise-threshold: the image averages the even-numbered samples only, which the
    /// stopping rule (judged on the odd-numbered ones) does not see: unbiased, at twice the
    /// variance per sample. Without it the image averages all samples (Cycles' rule, slightly
    /// biased toward the pixels' typical values).
    #[arg(long)]
    unbiased_adaptive: bool,
    /// Samples every pixel takes before adaptive sampling may stop it (at least 4); default or
    /// 0: Cycles' automatic count, max(4, ⌈16 / T^0.3⌉) (T = 0.01: 64).
    #[arg(long, value_name = "N")]
    min_spp: Option<u32>,
    /// Show the render live in the tev image viewer listening at HOST:PORT (tev's default:
    /// 127.0.0.1:14158), updated after each pass (at most once a second) and at the end.
    #[arg(long, value_name = "HOST:PORT")]
    display: Option<String>,
    /// Denoise the image with Intel Open Image Denoise, guided by albedo and normal AOVs (needs
    /// the `oidn` build feature): the output is the denoised image, with the noisy one as the
    /// `noisy` layer of an EXR, or beside a PNG/PFM as OUTPUT.noisy.png.
    #[arg(long)]
    denoise: bool,
    /// Arbitrary output variables written as layers of the EXR beside the image, comma-separated:
    /// albedo, normal (shading normal), depth, position, uv, geo_normal, sh_normal, prim_index,
    /// shape_index (of the first surface the camera ray hits), and variance (each pixel's
    /// estimated variance of its mean, with its sample count `spp`).
    #[arg(long, value_name = "LIST")]
    aov: Option<String>,
    /// Render part I of N of the samples of every pixel (a render split over machines; the parts
    /// take the samples a single render takes) and write it as an OpenEXR part for `neumann merge`.
    #[arg(long, value_name = "I/N")]
    part: Option<String>,
    /// Render only the pixels x0 ≤ x < x1, y0 ≤ y < y1 of the image (a tile of a render split over
    /// machines) and write it as an OpenEXR part for `neumann merge`, which assembles the tiles.
    #[arg(long, value_name = "X0,X1,Y0,Y1")]
    pixel_bounds: Option<String>,
}

/// What part of a split render to render: `--part I/N` and `--pixel-bounds`.
struct Split {
    /// `(I, N)`, 1-based.
    part_of: Option<(u32, u32)>,
    /// The tile `[x, y, width, height]`.
    tile: Option<[u32; 4]>,
}

/// Parses `--part I/N` and `--pixel-bounds X0,X1,Y0,Y1`, the latter checked against `image` (the
/// film or its crop window).
fn parse_split(a: &RenderArgs, spp: u32, image: [u32; 4]) -> Result<Option<Split>, Failure> {
    if a.part.is_none() && a.pixel_bounds.is_none() {
        return Ok(None);
    }
    let part_of = match &a.part {
        None => None,
        Some(t) => {
            let bad = || usage(format!("--part expects I/N with 1 ≤ I ≤ N, e.g. 3/8, got '{t}'"));
            let (i, n) = t.split_once('/').ok_or_else(bad)?;
            let (i, n): (u32, u32) = (i.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
            if i == 0 || i > n {
                return Err(bad());
            }
            if n > spp {
                return Err(usage(format!(
                    "--part {i}/{n}: {spp} samples per pixel do not split into {n} parts (raise --spp, or split by tiles with --pixel-bounds)"
                )));
            }
            Some((i, n))
        }
    };
    let tile = match &a.pixel_bounds {
        None => None,
        Some(t) => {
            let bad = || usage(format!("--pixel-bounds expects X0,X1,Y0,Y1 with X0 < X1 and Y0 < Y1, e.g. 0,256,0,128, got '{t}'"));
            let v: Vec<u32> = t.split(',').map(|x| x.trim().parse()).collect::<Result<_, _>>().map_err(|_| bad())?;
            let [x0, x1, y0, y1] = v[..] else { return Err(bad()) };
            if x0 >= x1 || y0 >= y1 {
                return Err(bad());
            }
            let [ix, iy, iw, ih] = image;
            if x0 < ix || y0 < iy || x1 > ix + iw || y1 > iy + ih {
                return Err(usage(format!(
                    "--pixel-bounds {t} reach outside the image, pixels x {ix}–{}, y {iy}–{}",
                    ix + iw,
                    iy + ih
                )));
            }
            Some([x0, y0, x1 - x0, y1 - y0])
        }
    };
    Ok(Some(Split { part_of, tile }))
}

/// `neumann render`.
pub fn run(a: RenderArgs) -> Result<(), Failure> {
    let scene_arg = a.scene.clone().unwrap_or_else(|| "cbox".to_string());
    let defines = parse_defines(&a.define)?;
    let builtin = scene_arg == "cbox";
    if let Some(0) = a.spp {
        return Err(usage("--spp must be at least 1".into()));
    }
    let mut job = if builtin {
        if let Some(c) = &a.camera {
            return Err(usage(format!("--camera {c}: choosing a camera is for glTF files (the built-in scene has one)")));
        }
        let mut job = builtin_job(&scene_arg, &defines)?;
        apply_builtin_flags(&mut job, &a)?;
        job
    } else if scene_arg.to_ascii_lowercase().ends_with(".xml")
        || scene_arg.ends_with(".pbrt")
        || neumann::load::is_gltf(std::path::Path::new(&scene_arg))
        || std::path::Path::new(&scene_arg).exists()
    {
        // A scene file: the flags become parameters of its objects, validated by the plugins.
        let path = std::path::Path::new(&scene_arg);
        let mut job = file_job(path, &defines, &flag_overrides(&a)?, a.camera.as_deref())?;
        select_integrator(&mut job.file.integrator, &a)?;
        if a.res.is_some() {
            job.file.window = None;
        }
        job
    } else {
        return Err(Failure(
            1,
            format!("unknown scene '{scene_arg}': give a Mitsuba 3 .xml, pbrt-v4 .pbrt or glTF (.gltf, .glb) scene file or a built-in scene name (cbox)"),
        ));
    };
    if job.file.scene.has_media() && !job.file.integrator.kind().renders_media() {
        eprintln!(
            "warning: the scene has participating media, which the {} integrator ignores (as Mitsuba's): use --integrator volpath",
            job.file.integrator.name()
        );
    }
    if let Some(s) = a.sampler {
        job.file.sampler = s;
    }
    if let Some(direct) = a.direct {
        match &mut job.file.integrator {
            AnyIntegrator::Path(p) => {
                p.strategy = direct;
                if matches!(direct, DirectStrategy::Uniform | DirectStrategy::Cosine)
                    && job.file.scene.lights().iter().any(|l| l.is_delta())
                {
                    eprintln!(
                        "warning: --direct {direct} samples directions, which never hit point, spot or directional lights: \
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
        match &mut job.file.integrator {
            AnyIntegrator::Path(p) => p.heuristic = m,
            other => return Err(usage(format!("--mis applies to the path integrator, not '{}'", other.name()))),
        }
    }
    let time_budget = match a.time {
        // The scene's own limit (Mitsuba's integrator timeout) keeps its sample count.
        None => job.file.time_limit,
        Some(t) => match Duration::try_from_secs_f64(t) {
            Ok(d) if t > 0.0 => Some(d),
            _ => return Err(usage(format!("--time must be a positive number of seconds, got {t:?}"))),
        },
    };
    if !a.exposure.is_finite() {
        return Err(usage(format!("--exposure must be a finite number of stops, got {}", a.exposure)));
    }
    let image = job.file.window.unwrap_or([0, 0, job.file.scene.camera().width(), job.file.scene.camera().height()]);
    if (a.part.is_some() || a.pixel_bounds.is_some()) && a.time.is_some() && a.spp.is_none() {
        return Err(usage(
            "--part and --pixel-bounds split a render of a sample count: give --spp (with --time each part stops early, and merge names what is missing)".into(),
        ));
    }
    let split = parse_split(&a, job.file.spp, image)?;
    if split.is_some() {
        if job.file.colors != neumann::film::output::ColorChannels::Rgb {
            return Err(usage(
                "a render split into parts keeps R, G, B in its parts (they merge into RGB): give the film pixel_format rgb or rgba, or render in one piece".into(),
            ));
        }
        if a.bounces_out.is_some() {
            return Err(usage("--bounces-out cannot be split into parts: render the terms in one piece".into()));
        }
        if let AnyIntegrator::Radiosity(_) = job.file.integrator {
            return Err(usage("radiosity renders are not split into parts: its solve is the cost, and every part would repeat it".into()));
        }
    }
    let output = a.output.clone().unwrap_or_else(|| match &split {
        None => PathBuf::from(format!("{}.png", job.name)),
        Some(s) => {
            let mut name = job.name.clone();
            if let Some((i, n)) = s.part_of {
                name += &format!("-part{i}of{n}");
            }
            if let Some([x, y, w, h]) = s.tile {
                name += &format!("-tile{x}-{}x{y}-{}", x + w, y + h);
            }
            PathBuf::from(format!("{name}.exr"))
        }
    });
    // The default name in the current folder: say so when it replaces an earlier image.
    let replaces_default = a.output.is_none() && output.exists();
    if split.is_some() && Format::from_path(&output).ok() != Some(Format::Exr) {
        return Err(usage(format!("a part of a split render is written as OpenEXR: name the output .exr, not '{}'", output.display())));
    }
    // Before rendering: a render must not be lost to a missing or read-only folder.
    Format::from_path(&output).map_err(|e| usage(e.to_string()))?;
    neumann::film::output::check_destination(&output).map_err(|e| Failure(1, e.to_string()))?;
    if Format::from_path(&output).map_err(|e| usage(e.to_string()))? == Format::Pfm && job.file.alpha {
        return Err(usage(format!(
            "the scene asks for an alpha channel (pixel_format rgba), which PFM cannot hold: write {}.exr or .png",
            job.name
        )));
    }

    let want_variance = add_aovs(&mut job, &a, &output)?;
    if a.denoise && split.is_some() {
        return Err(usage("--denoise applies to whole images: merge the parts, then denoise the merged render".into()));
    }
    // The denoiser's guides are AOVs the user did not ask for unless --aov named them.
    let guides_only = a.denoise && crate::denoise::add_guides(&mut job.file.integrator)? && a.aov.is_none();
    let term_count = match (&a.bounces_out, &job.file.integrator) {
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
    // The film's memory, checked before anything is allocated for it.
    let budget = match &a.max_memory {
        Some(m) => parse_bytes(m).ok_or_else(|| usage(format!("--max-memory expects a size such as 8G or 512M, got '{m}'")))?,
        None => default_memory_budget(),
    };
    let [_, _, fw, fh] = split.as_ref().and_then(|s| s.tile).unwrap_or(image);
    let aov_count = job.file.integrator.camera().map_or(0, |i| i.aov_names().len());
    let need = u64::from(fw) * u64::from(fh) * neumann::film::Film::bytes_per_pixel(term_count, aov_count);
    if need > budget {
        return Err(Failure(
            1,
            format!(
                "the film needs {:.1} GiB ({fw}×{fh} pixels), more than the memory budget of {:.1} GiB: \
                 render smaller, or raise --max-memory",
                need as f64 / (1u64 << 30) as f64,
                budget as f64 / (1u64 << 30) as f64
            ),
        ));
    }
    if let Some(t) = a.noise_threshold {
        if !(t > 0.0 && t.is_finite()) {
            return Err(usage(format!("--noise-threshold must be a positive number, e.g. 0.01, got {t}")));
        }
        if job.file.integrator.camera().is_none() {
            return Err(usage(format!(
                "--noise-threshold stops pixels that camera rays sample: the {} integrator has none (use path, volpath, volpathmis or direct)",
                job.file.integrator.name()
            )));
        }
        if split.is_some() || a.checkpoint.is_some() || a.resume.is_some() {
            return Err(usage("--noise-threshold applies to a whole render in one go (not with --part, --pixel-bounds, --checkpoint or --resume)".into()));
        }
    } else if a.min_spp.is_some() || a.unbiased_adaptive {
        return Err(usage("--min-spp and --unbiased-adaptive apply to adaptive sampling: give --noise-threshold too".into()));
    }
    let settings = RenderSettings {
        noise_threshold: a.noise_threshold,
        min_spp: match (a.min_spp, a.noise_threshold) {
            (Some(n), _) if n > 0 => n.max(4),
            (_, Some(t)) => neumann::render::auto_min_spp(t),
            _ => 16,
        },
        spp: if a.time.is_some() && a.spp.is_none() { u32::MAX } else { job.file.spp },
        time_budget,
        seed: job.file.seed,
        threads: a.threads as usize,
        sampler: job.file.sampler,
        progress: !a.quiet,
        filter: job.file.filter.clone(),
        alpha: job.file.alpha,
        transform: job.file.transform,
        terms: term_count,
        sample_range: split.as_ref().and_then(|s| s.part_of).map(|(i, n)| PartInfo::split(job.file.spp, i, n)),
        window: split.as_ref().and_then(|s| s.tile).or(job.file.window),
        tile_of: split.as_ref().and_then(|s| s.tile).map(|_| image),
        sample_border: job.file.sample_border,
        ..Default::default()
    };
    crate::handle_signals();
    let cam = job.file.scene.camera();
    let [_, _, width, height] = settings.window.unwrap_or([0, 0, cam.width(), cam.height()]);
    let (first, end) = settings.sample_range.unwrap_or((0, job.file.spp));
    say!(
        "rendering {}{} at {width}x{height}, {}, {}, {} threads, film {:.1} MiB",
        job.name,
        match &split {
            None => String::new(),
            Some(s) => format!(
                " ({}{})",
                s.part_of.map_or(String::new(), |(i, n)| format!("part {i}/{n}: samples {first}–{end} of {}", job.file.spp)),
                s.tile.map_or(String::new(), |[x, y, w, h]| format!(
                    "{}tile x {x}–{}, y {y}–{}",
                    if s.part_of.is_some() { ", " } else { "" },
                    x + w,
                    y + h
                ))
            ),
        },
        match a.time {
            Some(t) if a.spp.is_some() => format!("{} spp or {t} s, whichever comes first", end - first),
            Some(t) => format!("for {t} s"),
            None if split.is_some() => format!("{} spp", end - first),
            None => format!("{} spp", job.file.spp),
        },
        job.file.integrator.describe(),
        if a.threads == 0 { rayon::current_num_threads() } else { a.threads as usize },
        need as f64 / (1u64 << 20) as f64
    );
    let mut preview = a.display.as_ref().map(|address| Preview::new(address, &job.name, job.file.alpha));
    let mut on_pass = |film: &neumann::film::Film, _done: u32| {
        if let Some(p) = &mut preview {
            p.show(film, false);
        }
    };
    let out = if a.checkpoint.is_some() || a.resume.is_some() {
        resumable_render(&job, &a, &scene_arg, &defines, &settings, &output, &mut on_pass)?
    } else {
        render_integrator_with(&job.file.scene, &job.file.integrator, &settings, &CANCEL, &mut on_pass)
            .map_err(|e| Failure(1, e.to_string()))?
    };
    if let Some(p) = &mut preview {
        p.show(&out.film, true);
    }
    for line in &out.report {
        say!("{line}");
    }
    if let Some(split) = &split {
        return write_split_part(&job, &scene_arg, &defines, &settings, split, image, &out, &output);
    }
    let (lo, hi) = out.film.spp_range();
    let alpha = job.file.alpha.then(|| out.film.alpha());
    let info = ImageInfo { spp: lo, exposure: a.exposure, colors: job.file.colors, component: job.file.component };
    let mut image = match (a.unbiased_adaptive, out.film.even_image()) {
        (true, Some(even)) => even,
        _ => out.film.image(),
    };
    let mut noisy = None;
    if a.denoise {
        let start = std::time::Instant::now();
        let denoised = crate::denoise::apply(&out.film, &image)?;
        noisy = Some(std::mem::replace(&mut image, denoised));
        say!("denoised with Open Image Denoise in {:.2} s", start.elapsed().as_secs_f64());
    }
    let is_exr = Format::from_path(&output).ok() == Some(Format::Exr);
    if job.file.component != neumann::film::output::ComponentFormat::Float32 && !is_exr {
        say!("warning: the film's component_format applies to .exr output; {} has its own", output.display());
    }
    let mut channels = if guides_only && !is_exr { Vec::new() } else { out.film.aov_channels() };
    if let (Some(noisy), true) = (&noisy, is_exr) {
        for (c, name) in ["noisy.R", "noisy.G", "noisy.B"].into_iter().enumerate() {
            channels.push((name.to_string(), noisy.iter().map(|v| v[c]).collect()));
        }
    }
    if want_variance {
        let variance = out.film.variance_of_mean();
        for (c, name) in ["variance.R", "variance.G", "variance.B"].into_iter().enumerate() {
            channels.push((name.to_string(), variance.iter().map(|v| v[c]).collect()));
        }
    }
    if (want_variance || lo != hi || a.noise_threshold.is_some()) && Format::from_path(&output).ok() == Some(Format::Exr) {
        // An interrupted render: the pixels hold different sample counts; say which.
        channels.push(("spp".to_string(), out.film.sample_counts()));
    }
    if !channels.is_empty() && Format::from_path(&output).ok() != Some(Format::Exr) {
        say!(
            "warning: the {} AOV channels of the {} integrator are not written: only .exr holds them",
            channels.len(),
            job.file.integrator.name()
        );
        channels.clear();
    }
    write_image_layers(&output, width, height, &image, alpha.as_deref(), &channels, &info)
        .map_err(|e| Failure(1, e.to_string()))?;
    if let (Some(noisy), false) = (&noisy, is_exr) {
        let beside = output.with_extension(format!("noisy.{}", output.extension().and_then(|e| e.to_str()).unwrap_or("png")));
        write_image_alpha(&beside, width, height, noisy, alpha.as_deref(), &info).map_err(|e| Failure(1, e.to_string()))?;
        say!("wrote the image before denoising to {}", beside.display());
    }
    if !channels.is_empty() {
        say!("wrote {} AOV channels beside R, G, B: {}", channels.len(), aov_summary(&channels));
    }
    if let Some(dir) = &a.bounces_out {
        write_terms(dir, &out.film, width, height, &info).map_err(|e| Failure(1, e.to_string()))?;
        say!("wrote {} Neumann-series terms, their sum and a contact sheet to {}", term_count, dir.display());
    }
    let spp_text = match (lo == hi, a.noise_threshold.is_some()) {
        (true, _) => format!("{lo} spp"),
        (false, true) => format!("{lo}–{hi} spp, adaptive"),
        (false, false) => format!("{lo}–{hi} spp (interrupted mid-pass)"),
    };
    say!(
        "wrote {} ({spp_text}, {:.2} s, {:.3} M samples/s)",
        output.display(),
        out.elapsed.as_secs_f64(),
        out.samples_per_second() / 1e6
    );
    if let Some(t) = a.noise_threshold {
        let counts = out.film.sample_counts();
        let mean = counts.iter().map(|&c| c as f64).sum::<f64>() / counts.len().max(1) as f64;
        let stopped = counts.iter().filter(|&&c| (c as u32) < hi).count();
        say!(
            "adaptive sampling (noise threshold {t}): mean {mean:.1} spp, {:.1} % of pixels stopped before {hi} spp (each pixel's count is the EXR's spp channel)",
            100.0 * stopped as f64 / counts.len().max(1) as f64
        );
    }
    if out.interrupted {
        say!("render interrupted: the image holds {spp_text}");
    } else if let (Some(budget), Some(target)) = (settings.time_budget, a.spp.or((a.time.is_none()).then_some(job.file.spp))) {
        // Both limits were set: say which one ended the render.
        if lo >= target {
            say!("the render stopped at its sample target ({target} spp) before the time budget ({:.3} s) was used", budget.as_secs_f64());
        } else {
            say!("the render stopped when its time budget ({:.3} s) was used, at {lo} of {target} spp", budget.as_secs_f64());
        }
    } else if settings.time_budget.is_some() {
        say!("the render stopped when its time budget was used");
    }
    if a.exposure != 0.0 && Format::from_path(&output).ok() != Some(Format::Png) {
        say!("note: --exposure applies to PNG output; {} holds linear radiance, unscaled", output.display());
    }
    if replaces_default {
        say!("note: replaced the earlier {} (name the output with -o to keep both)", output.display());
    }
    let stopped_by = crate::STOPPED_BY.load(Ordering::SeqCst);
    if out.film.dropped() > 0 {
        say!("warning: {} samples were NaN or infinite and were dropped", out.film.dropped());
    }
    if stopped_by != 0 {
        // Interrupted by a signal: the image is written; the exit status says it is partial.
        return Err(Failure((128 + stopped_by) as u8, format!("stopped by signal {stopped_by}; wrote {}", output.display())));
    }
    Ok(())
}

/// The flags that set scene parameters (`--res`, `--spp`, `--integrator`, `--max-depth`,
/// `--seed`, `--light-sampler`), for the built-in scene, which has no scene file whose objects
/// they could override.
fn apply_builtin_flags(job: &mut crate::job::Job, a: &RenderArgs) -> Result<(), Failure> {
    if let Some(r) = &a.res {
        let (w, h) = parse_res(r).map_err(usage)?;
        let camera = job.file.scene.camera().with_resolution(w, h).map_err(|e| Failure(1, e.to_string()))?;
        job.file.scene.set_camera(camera);
        job.file.window = None;
    }
    if let Some(s) = a.spp {
        job.file.spp = s;
    }
    select_integrator(&mut job.file.integrator, a)?;
    if let Some(d) = a.max_depth {
        if d < -1 {
            return Err(usage(format!("--max-depth must be -1 (unlimited) or ≥ 0, got {d}")));
        }
        let name = job.file.integrator.name();
        match job.file.integrator.path_settings_mut() {
            Some(settings) => settings.max_depth = d,
            None => {
                return Err(usage(format!(
                    "--max-depth applies to the path, volpath, volpathmis and ptracer integrators, not '{name}'"
                )))
            }
        }
    }
    if let Some(s) = a.seed {
        job.file.seed = s;
    }
    if let Some(kind) = a.light_sampler {
        if !job.file.integrator.kind().samples_lights() {
            return Err(usage(format!(
                "--light-sampler applies to the path, volpath, volpathmis and direct integrators, not '{}'",
                job.file.integrator.name()
            )));
        }
        job.file.scene.set_light_sampler(kind).map_err(|e| Failure(1, e.to_string()))?
    }
    Ok(())
}

/// The flags that set scene parameters, as overrides of a scene file's objects: `--spp` and
/// `--seed` (the sampler's `sample_count`, `seed`), `--res` (the film's `width`, `height`, and a
/// crop window of the whole frame), `--max-depth` and `--light-sampler` (the integrator's
/// `max_depth`, `light_sampler`), `--integrator` (the integrator's type).
fn flag_overrides(a: &RenderArgs) -> Result<Overrides, Failure> {
    use neumann::load::overrides::{Override, Target};
    use neumann::props::Value;
    let mut o = Overrides::default();
    if let Some(k) = a.integrator {
        o.integrator = Some((k, format!("--integrator {}", neumann::choice::Choice::name(k))));
    }
    if let Some(s) = a.spp {
        o.settings.push(Override::new(Target::Sampler, "sample_count", Value::Integer(s.into()), format!("--spp {s}")));
    }
    if let Some(s) = a.seed {
        let v = i64::try_from(s).map_err(|_| usage(format!("--seed must be at most {}, got {s}", i64::MAX)))?;
        o.settings.push(Override::new(Target::Sampler, "seed", Value::Integer(v), format!("--seed {s}")));
    }
    if let Some(r) = &a.res {
        let (w, h) = parse_res(r).map_err(usage)?;
        let source = format!("--res {r}");
        for (name, v) in [("width", w), ("height", h), ("crop_width", w), ("crop_height", h), ("crop_offset_x", 0), ("crop_offset_y", 0)]
        {
            o.settings.push(Override::new(Target::Film, name, Value::Integer(v.into()), source.clone()));
        }
    }
    if let Some(d) = a.max_depth {
        o.settings.push(Override::new(Target::Integrator, "max_depth", Value::Integer(d.into()), format!("--max-depth {d}")));
    }
    if let Some(k) = a.light_sampler {
        let name = neumann::choice::Choice::name(k);
        o.settings.push(Override::new(
            Target::Integrator,
            "light_sampler",
            Value::String(name.to_string()),
            format!("--light-sampler {name}"),
        ));
    }
    Ok(o)
}

/// Applies `--integrator` and the radiosity flags to the scene's integrator. Settings the old
/// and new integrator share (max_depth, rr_depth, hide_emitters) carry over.
fn select_integrator(current: &mut AnyIntegrator, a: &RenderArgs) -> Result<(), Failure> {
    let settings = match &*current {
        AnyIntegrator::Direct(d) => PathSettings { hide_emitters: d.hide_emitters, ..Default::default() },
        other => other.path_settings().copied().unwrap_or_default(),
    };
    if let Some(kind) = a.integrator {
        if current.kind() != kind {
            *current = AnyIntegrator::with_kind(kind, settings);
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
                o.method = m;
            }
            o.smooth |= a.smooth;
            if let Some(p) = &a.patches_out {
                o.patches_out = Some(p.clone());
            }
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

/// Writes each Neumann-series term, the sum and a contact sheet (terms then sum, left to right).
fn write_terms(
    dir: &std::path::Path,
    film: &neumann::film::Film,
    w: u32,
    h: u32,
    info: &ImageInfo,
) -> Result<(), WriteError> {
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

/// The AOV layers of `channels` (`albedo.R`, `albedo.G`, … → `albedo`), in order.
fn aov_summary(channels: &[Channel]) -> String {
    let mut layers: Vec<&str> = Vec::new();
    for (name, _) in channels {
        let layer = name.rsplit_once('.').map_or(name.as_str(), |(l, _)| l);
        if layers.last() != Some(&layer) {
            layers.push(layer);
        }
    }
    layers.join(", ")
}

/// A size in bytes: a number with an optional K, M, G or T suffix (powers of 1024).
fn parse_bytes(s: &str) -> Option<u64> {
    let s = s.trim();
    let (digits, shift) = match s.chars().last()?.to_ascii_uppercase() {
        'K' => (&s[..s.len() - 1], 10),
        'M' => (&s[..s.len() - 1], 20),
        'G' => (&s[..s.len() - 1], 30),
        'T' => (&s[..s.len() - 1], 40),
        _ => (s, 0),
    };
    let v: f64 = digits.trim().parse().ok()?;
    (v.is_finite() && v > 0.0).then(|| (v * (1u64 << shift) as f64).min(u64::MAX as f64) as u64)
}

/// Half of the machine's memory (`MemTotal` of `/proc/meminfo`), or 8 GiB where that is unknown.
fn default_memory_budget() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| t.lines().find(|l| l.starts_with("MemTotal:")).and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok()))
        .map_or(8 << 30, |kib| kib * 1024 / 2)
}

/// A render with `--checkpoint` and/or `--resume`: camera-ray integrators only. The state file
/// holds the film's sums after a whole pass and a fingerprint of the scene file, the `-D`
/// parameters and every setting that changes the samples (all but the sample target and the
/// time), which a resumed render must match.
fn resumable_render(
    job: &crate::job::Job,
    a: &RenderArgs,
    scene_arg: &str,
    defines: &[(String, String)],
    settings: &RenderSettings,
    output: &std::path::Path,
    on_pass: &mut dyn FnMut(&neumann::film::Film, u32),
) -> Result<neumann::render::RenderOutcome, Failure> {
    use neumann::film::state::StateInfo;
    use neumann::film::Film;
    let integrator = job.file.integrator.camera().ok_or_else(|| {
        usage(format!("--checkpoint and --resume apply to camera-ray integrators, not '{}'", job.file.integrator.name()))
    })?;
    let interval = match a.checkpoint {
        Some(t) if t.is_finite() && t > 0.0 => Some(Duration::from_secs_f64(t)),
        Some(t) => return Err(usage(format!("--checkpoint must be a positive number of seconds, got {t}"))),
        None => None,
    };
    let (base, _) = render_fingerprint(job, scene_arg, defines, settings);
    // A resumed render also continues the same samples of the same pixels.
    let fingerprint = fnv1a(base, format!("{:?}|{:?}|{:?}", settings.sample_range, settings.window, settings.tile_of).as_bytes());
    let start = match &a.resume {
        None => None,
        Some(path) => {
            let bytes = neumann::load::limits::read_bounded(path, neumann::load::limits::MAX_FILE_BYTES)
                .map_err(|e| Failure(1, e.to_string()))?;
            let (film, info) =
                Film::from_state_bytes(&bytes).map_err(|e| Failure(1, format!("{}: {e}", path.display())))?;
            if info.fingerprint != fingerprint {
                return Err(Failure(
                    1,
                    format!(
                        "{}: saved from another scene or other settings (resume with the same scene file, -D parameters, \
                         integrator, seed, sampler, resolution and filter)",
                        path.display()
                    ),
                ));
            }
            if info.spp_done >= settings.sample_range.map_or(settings.spp, |r| r.1) {
                return Err(usage(format!(
                    "{} already holds {} spp: ask for more with --spp",
                    path.display(),
                    info.spp_done
                )));
            }
            say!("resuming {} from {} spp", path.display(), info.spp_done);
            Some((film, info.spp_done))
        }
    };
    let state_path = {
        let mut name = output.as_os_str().to_owned();
        name.push(".state");
        PathBuf::from(name)
    };
    let mut last = std::time::Instant::now();
    let mut write_error = None;
    let mut save = |film: &Film, done: u32, force: bool| {
        if interval.is_none() || write_error.is_some() || !(force || last.elapsed() >= interval.unwrap_or_default()) {
            return;
        }
        let bytes = film.state_bytes(&StateInfo { fingerprint, spp_done: done, seed: settings.seed });
        if let Err(e) = neumann::film::output::write_atomically(&state_path, |tmp| {
            std::fs::write(tmp, &bytes).map_err(|e| e.to_string())
        }) {
            write_error = Some(e);
        }
        last = std::time::Instant::now();
    };
    let target = settings.sample_range.map_or(settings.spp, |r| r.1);
    let out = neumann::render::render_from(&job.file.scene, integrator, settings, &CANCEL, start, &mut |film, done| {
        save(film, done, done == target);
        on_pass(film, done);
    })
    .map_err(|e| Failure(1, e.to_string()))?;
    if let Some(e) = write_error {
        return Err(Failure(1, format!("cannot write the checkpoint {}: {e}", state_path.display())));
    }
    if interval.is_some() {
        say!("checkpoint: {} (continue with --resume {0} --spp N)", state_path.display());
    }
    Ok(out)
}

/// FNV-1a of `bytes`, continuing from `h` (stable across runs and builds).
fn fnv1a(h: u64, bytes: &[u8]) -> u64 {
    bytes.iter().fold(h, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3))
}

/// A fingerprint of what makes a render's samples (the scene file's bytes, the `-D` parameters
/// and every setting but the sample count, time and which part of a split), and those settings
/// in words.
fn render_fingerprint(
    job: &crate::job::Job,
    scene_arg: &str,
    defines: &[(String, String)],
    settings: &RenderSettings,
) -> (u64, String) {
    let scene_bytes = if scene_arg == "cbox" { Vec::new() } else { std::fs::read(scene_arg).unwrap_or_default() };
    let cam = job.file.scene.camera();
    let settings_text = format!(
        "{}, sampler {}, filter {}, film {}x{}, crop {:?}{}{}{}",
        job.file.integrator.describe(),
        settings.sampler,
        settings.filter,
        cam.width(),
        cam.height(),
        job.file.window,
        if settings.alpha { ", alpha" } else { "" },
        if settings.terms > 0 { format!(", {} terms", settings.terms) } else { String::new() },
        if defines.is_empty() { String::new() } else { format!(", -D {defines:?}") },
    );
    let hashed = format!("{scene_arg}|{settings_text}|{}", settings.seed);
    (fnv1a(fnv1a(0xcbf2_9ce4_8422_2325, &scene_bytes), hashed.as_bytes()), settings_text)
}

/// Writes a part of a split render (`--part`, `--pixel-bounds`): the samples of whole passes
/// it finished, with what `neumann merge` needs to know.
#[allow(clippy::too_many_arguments)]
fn write_split_part(
    job: &crate::job::Job,
    scene_arg: &str,
    defines: &[(String, String)],
    settings: &RenderSettings,
    split: &Split,
    image: [u32; 4],
    out: &neumann::render::RenderOutcome,
    output: &std::path::Path,
) -> Result<(), Failure> {
    let (first, end) = settings.sample_range.unwrap_or((0, settings.spp));
    let (done, _) = out.film.spp_range();
    let stopped_by = crate::STOPPED_BY.load(Ordering::SeqCst);
    if done == 0 {
        let code = if stopped_by != 0 { (128 + stopped_by) as u8 } else { 1 };
        return Err(Failure(code, format!("the part finished no pass of samples: nothing written to {}", output.display())));
    }
    let (fingerprint, settings_text) = render_fingerprint(job, scene_arg, defines, settings);
    let info = PartInfo {
        fingerprint,
        scene: job.name.clone(),
        settings: settings_text,
        seed: settings.seed,
        spp: settings.spp,
        samples: (first, first + done),
        window: settings.window.unwrap_or(image),
        image,
        part_of: split.part_of,
    };
    neumann::film::part::write_part(output, &out.film, &info, settings.alpha).map_err(|e| Failure(1, e.to_string()))?;
    say!(
        "wrote {} ({info}; {:.2} s, {:.3} M samples/s): combine the parts with neumann merge",
        output.display(),
        out.elapsed.as_secs_f64(),
        out.samples_per_second() / 1e6
    );
    if first + done < end {
        say!("the part stopped early: it holds samples {first}–{} of its {first}–{end}", first + done);
    }
    if out.film.dropped() > 0 {
        say!("warning: {} samples were NaN or infinite and were dropped", out.film.dropped());
    }
    if stopped_by != 0 {
        return Err(Failure((128 + stopped_by) as u8, format!("stopped by signal {stopped_by}; wrote {}", output.display())));
    }
    Ok(())
}

/// `--aov LIST`: wraps the scene's integrator to record the listed AOVs (or adds them to its
/// `aov` integrator), and says whether the variance is asked for (the film computes it).
fn add_aovs(job: &mut crate::job::Job, a: &RenderArgs, output: &std::path::Path) -> Result<bool, Failure> {
    use neumann::choice::Choice;
    use neumann::integrator::aov::{AovIntegrator, AovKind};
    let Some(list) = &a.aov else { return Ok(false) };
    let mut variance = false;
    let mut kinds: Vec<(String, AovKind)> = Vec::new();
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let kind = match item {
            "variance" => {
                variance = true;
                continue;
            }
            "normal" => AovKind::ShNormal,
            other => AovKind::parse_name(other).map_err(|_| {
                let names: Vec<&str> = AovKind::CHOICES.iter().map(|c| c.1).collect();
                usage(format!("--aov: unknown AOV '{other}' (expected normal, variance, {})", names.join(", ")))
            })?,
        };
        if kinds.iter().any(|(n, _)| n == item) {
            return Err(usage(format!("--aov names '{item}' twice")));
        }
        kinds.push((item.to_string(), kind));
    }
    if kinds.is_empty() && !variance {
        return Err(usage("--aov expects a list such as albedo,normal,depth,variance".into()));
    }
    if Format::from_path(output).ok() != Some(Format::Exr) {
        return Err(usage(format!("--aov writes layers of an OpenEXR image: name the output .exr, not '{}'", output.display())));
    }
    if job.file.integrator.camera().is_none() {
        return Err(usage(format!(
            "--aov records what camera rays see: the {} integrator traces none (use path, volpath, volpathmis or direct)",
            job.file.integrator.name()
        )));
    }
    if kinds.is_empty() {
        return Ok(variance);
    }
    let current = std::mem::replace(&mut job.file.integrator, AnyIntegrator::with_kind(IntegratorKind::Path, Default::default()));
    job.file.integrator = match current {
        // The scene's own aov integrator gets the new AOVs beside its own.
        AnyIntegrator::Aov(mut existing) => {
            for (name, kind) in kinds {
                if existing.aovs.iter().any(|(n, _)| *n == name) {
                    return Err(usage(format!("--aov {name}: the scene's aov integrator already records an AOV of that name")));
                }
                existing.aovs.push((name, kind));
            }
            AnyIntegrator::Aov(existing)
        }
        other => AnyIntegrator::Aov(AovIntegrator::around(other, kinds)),
    };
    Ok(variance)
}

/// The live preview of `--display`: the film's image sent to tev after a pass, at most once a
/// second, and at the end. A tev that cannot be reached, or goes away, is reported once; the
/// render goes on.
struct Preview {
    address: String,
    name: String,
    alpha: bool,
    display: Option<(neumann::film::tev::TevDisplay, [u32; 2])>,
    last: Option<std::time::Instant>,
    failed: bool,
}

impl Preview {
    fn new(address: &str, name: &str, alpha: bool) -> Preview {
        Preview { address: address.to_string(), name: name.to_string(), alpha, display: None, last: None, failed: false }
    }

    fn show(&mut self, film: &neumann::film::Film, force: bool) {
        use neumann::film::tev::TevDisplay;
        if self.failed || (!force && self.last.is_some_and(|t| t.elapsed() < Duration::from_secs(1))) {
            return;
        }
        let size = [film.width(), film.height()];
        if self.display.as_ref().is_none_or(|(_, s)| *s != size) {
            let channels: Vec<String> =
                ["R", "G", "B", "A"].iter().take(if self.alpha { 4 } else { 3 }).map(|c| c.to_string()).collect();
            match TevDisplay::connect(&self.address, &self.name, size[0], size[1], channels) {
                Ok(d) => self.display = Some((d, size)),
                Err(e) => {
                    eprintln!("warning: {e}; rendering without the live preview");
                    self.failed = true;
                    return;
                }
            }
        }
        let image = film.image();
        let alpha = self.alpha.then(|| film.alpha());
        let pixels: Vec<f32> = image
            .iter()
            .enumerate()
            .flat_map(|(i, c)| [c.x, c.y, c.z].into_iter().chain(alpha.as_ref().map(|a| a[i])))
            .collect();
        if let Some((d, _)) = &mut self.display {
            if let Err(e) = d.update(&pixels) {
                eprintln!("warning: {e}; the live preview stops (the render goes on)");
                self.failed = true;
            }
        }
        self.last = Some(std::time::Instant::now());
    }
}
