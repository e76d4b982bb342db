//! Convergence measurements: render a scene at 1, 2, 4, … N samples per pixel with several
//! estimators, measure the error against a reference, fit the log-log slope (≈ -1 for the MSE
//! of any unbiased Monte Carlo estimator with independent samples; steeper with stratification
//! or QMC on smooth integrands) and time each render, so that estimators can be compared per
//! sample and per second (efficiency = 1 / (MSE × time)).
//!
//! Output: a CSV (one row per estimator and sample count) and a two-panel log-log plot, MSE
//! against spp and MSE against seconds, one labelled curve per estimator, as SVG and PNG
//! (plotters; the PNG's labels use the bundled DejaVu Sans subset in `assets/fonts/`).

use crate::job::{builtin_job, file_job, parse_defines, parse_res};
use crate::{choice, usage, Failure, CANCEL};
use neumann::estimators::loglog_slope;
use neumann::film::metrics::{mse, relmse};
use neumann::film::output::{write_image_alpha, ImageInfo};
use neumann::integrator::{AnyIntegrator, DirectStrategy, Integrator, PathIntegrator, PathSettings};
use neumann::math::Rgb;
use neumann::render::{render, RenderSettings};
use neumann::sampling::sampler::SamplerKind;
use neumann::scene::Scene;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

#[derive(clap::Args, Debug)]
pub struct ConvergeArgs {
    /// Scene: a Mitsuba 3 XML file or a built-in scene (cbox, the default).
    scene: Option<String>,
    /// Reference image (EXR or PFM of the same size); default: render one with MIS at 16 × the
    /// largest spp.
    #[arg(long = "ref", value_name = "REF")]
    reference: Option<PathBuf>,
    /// Direct-light strategies to compare (comma-separated).
    #[arg(long, value_parser = choice::<DirectStrategy>(), value_delimiter = ',', default_value = "mis,light,bsdf")]
    direct: Vec<DirectStrategy>,
    /// Samplers to compare (comma-separated).
    #[arg(long, value_parser = choice::<SamplerKind>(), value_delimiter = ',', default_value = "independent")]
    sampler: Vec<SamplerKind>,
    /// Largest samples per pixel (levels 1, 2, 4, … up to it).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    max_spp: u32,
    /// Film resolution, W or WxH (default: the reference's, or 64 without one: small enough for
    /// many renders).
    #[arg(long)]
    res: Option<String>,
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

/// `neumann converge`.
pub fn run(a: ConvergeArgs) -> Result<(), Failure> {
    let scene_arg = a.scene.clone().unwrap_or_else(|| "cbox".to_string());
    let defines = parse_defines(&a.define)?;
    let mut job = if scene_arg == "cbox" {
        builtin_job(&scene_arg, &defines)?
    } else {
        file_job(std::path::Path::new(&scene_arg), &defines, &Default::default(), None)?
    };
    // The reference, read first: its size is the renders' unless --res says otherwise.
    let reference_image = match &a.reference {
        Some(path) => Some(neumann::load::image::load_image(path, true).map_err(|e| Failure(1, e.to_string()))?),
        None => None,
    };
    let (w, h) = match (&a.res, &reference_image) {
        (Some(r), _) => parse_res(r).map_err(usage)?,
        (None, Some(img)) => (img.width, img.height),
        (None, None) => (64, 64),
    };
    let camera = job.file.scene.camera().with_resolution(w, h).map_err(|e| Failure(1, e.to_string()))?;
    job.file.scene.set_camera(camera);
    let base = match &job.file.integrator {
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
    let reference = match reference_image {
        Some(img) => {
            if (img.width, img.height) != (w, h) {
                return Err(usage(format!(
                    "the reference is {}x{} but --res asks for {w}x{h} renders: leave --res out to render at the reference's size",
                    img.width, img.height
                )));
            }
            img.pixels
        }
        None => {
            let spp = a.max_spp.saturating_mul(16).min(1 << 16);
            say!(
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
            let out =
                render(&job.file.scene, &integrator, &settings, &CANCEL).map_err(|e| Failure(1, e.to_string()))?;
            let image = out.film.image();
            write_image_alpha(&a.out.join("reference.exr"), w, h, &image, None, &ImageInfo { spp, exposure: 0.0, ..Default::default() })
                .map_err(|e| Failure(1, e.to_string()))?;
            image
        }
    };
    let levels = spp_levels(a.max_spp);
    let mut curves = Vec::new();
    say!("{:<24} {:>8} {:>12} {:>10} {:>12}", "estimator", "slope", "MSE (max)", "seconds", "1/(MSE·s)");
    for &d in &a.direct {
        for &s in &a.sampler {
            let name = if a.sampler.len() > 1 { format!("{d} / {s}") } else { format!("{d}") };
            let integrator =
                PathIntegrator { settings: PathSettings { max_depth, ..base.settings }, strategy: d, ..base.clone() };
            let base = RenderSettings { sampler: s, seed: a.seed, threads: a.threads, ..Default::default() };
            let curve = measure(&name, &job.file.scene, &integrator, &reference, &levels, &base)
                .map_err(|e| Failure(1, e.to_string()))?;
            let last = curve.points.last().copied().expect("at least one level");
            say!(
                "{name:<24} {:>8.3} {:>12.4e} {:>10.3} {:>12.4e}",
                curve.slope().unwrap_or(f64::NAN),
                last.mse,
                last.seconds,
                curve.efficiency().unwrap_or(0.0)
            );
            curves.push(curve);
        }
    }
    write_csv(&a.out.join("convergence.csv"), &curves).map_err(|e| Failure(1, e.to_string()))?;
    let title = format!("{} {w}x{h}, max_depth {max_depth}: MSE against a reference", job.name);
    plot(&a.out.join("convergence.svg"), &a.out.join("convergence.png"), &title, &curves)
        .map_err(|e| Failure(1, e.to_string()))?;
    say!("wrote convergence.csv, convergence.svg and convergence.png to {}", a.out.display());
    Ok(())
}

/// Parses `W` or `WxH`.
/// One measured point of a curve.
#[derive(Clone, Copy, Debug)]
pub struct Point {
    /// Samples per pixel.
    pub spp: u32,
    /// Mean squared error over pixels and channels.
    pub mse: f64,
    /// Relative MSE (`(x - r)² / (r² + 10⁻²)`, see `neumann::film::metrics::relmse`).
    pub relmse: f64,
    /// Render time in seconds.
    pub seconds: f64,
}

/// The convergence curve of one estimator.
#[derive(Clone, Debug)]
pub struct Curve {
    /// Label (estimator and sampler).
    pub name: String,
    /// Points in increasing spp.
    pub points: Vec<Point>,
}

impl Curve {
    /// Log-log slope of MSE against spp (≈ -1 for plain Monte Carlo).
    pub fn slope(&self) -> Option<f64> {
        loglog_slope(&self.points.iter().map(|p| (p.spp as f64, p.mse)).collect::<Vec<_>>())
    }

    /// Efficiency at the last point: `1 / (MSE × seconds)` (higher is better).
    pub fn efficiency(&self) -> Option<f64> {
        self.points.last().map(|p| 1.0 / (p.mse * p.seconds).max(1e-300))
    }
}

/// Sample counts 1, 2, 4, … up to `max_spp` (inclusive if a power of two).
pub fn spp_levels(max_spp: u32) -> Vec<u32> {
    (0..32).map(|k| 1u32 << k).take_while(|&s| s <= max_spp.max(1)).collect()
}

/// Measures one estimator: an independent render at each level, with `base`'s sampler, seed
/// and threads.
pub fn measure(
    name: &str,
    scene: &Scene,
    integrator: &dyn Integrator,
    reference: &[Rgb],
    levels: &[u32],
    base: &RenderSettings,
) -> Result<Curve, String> {
    let mut points = Vec::new();
    for &spp in levels {
        let settings = RenderSettings { spp, ..base.clone() };
        let out = render(scene, integrator, &settings, &AtomicBool::new(false)).map_err(|e| e.to_string())?;
        let image = out.film.image();
        if image.len() != reference.len() {
            return Err(format!("the reference has {} pixels, the render {}", reference.len(), image.len()));
        }
        points.push(Point {
            spp,
            mse: mse(&image, reference),
            relmse: relmse(&image, reference),
            seconds: out.elapsed.as_secs_f64(),
        });
    }
    Ok(Curve { name: name.to_string(), points })
}

/// Writes the curves as CSV: `estimator,spp,mse,relmse,seconds`.
pub fn write_csv(path: &Path, curves: &[Curve]) -> Result<(), String> {
    let mut s = String::from("estimator,spp,mse,relmse,seconds\n");
    for c in curves {
        for p in &c.points {
            s += &format!("{},{},{:.6e},{:.6e},{:.6}\n", c.name, p.spp, p.mse, p.relmse, p.seconds);
        }
    }
    std::fs::write(path, s).map_err(|e| format!("cannot write '{}': {e}", path.display()))
}

static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans-subset.ttf");

/// Draws the two-panel log-log plot (MSE vs spp, MSE vs seconds) to `svg` and `png`.
pub fn plot(svg: &Path, png: &Path, title: &str, curves: &[Curve]) -> Result<(), String> {
    use plotters::prelude::*;
    // The bitmap backend needs a registered font (the SVG backend only names it).
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    let (w, h) = (1100u32, 460u32);
    let svg_root = SVGBackend::new(svg, (w, h)).into_drawing_area();
    draw(&svg_root, title, curves).map_err(|e| format!("cannot draw '{}': {e}", svg.display()))?;
    svg_root.present().map_err(|e| format!("cannot write '{}': {e}", svg.display()))?;
    let png_root = BitMapBackend::new(png, (w, h)).into_drawing_area();
    draw(&png_root, title, curves).map_err(|e| format!("cannot draw '{}': {e}", png.display()))?;
    png_root.present().map_err(|e| format!("cannot write '{}': {e}", png.display()))?;
    Ok(())
}

type DrawResult<DB> =
    Result<(), plotters::drawing::DrawingAreaErrorKind<<DB as plotters::prelude::DrawingBackend>::ErrorType>>;

fn draw<DB: plotters::prelude::DrawingBackend>(
    root: &plotters::drawing::DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    curves: &[Curve],
) -> DrawResult<DB> {
    use plotters::prelude::*;
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 20))?;
    let panels = root.split_evenly((1, 2));
    let all: Vec<&Point> = curves.iter().flat_map(|c| &c.points).filter(|p| p.mse > 0.0).collect();
    if all.is_empty() {
        return Ok(());
    }
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for p in &all {
        lo = lo.min(p.mse);
        hi = hi.max(p.mse);
    }
    let (lo, hi) = (lo / 1.5, hi * 1.5);
    let max_spp = all.iter().map(|p| p.spp).max().unwrap_or(1) as f64;
    let (mut t_lo, mut t_hi) = (f64::INFINITY, 0.0f64);
    for p in &all {
        t_lo = t_lo.min(p.seconds.max(1e-4));
        t_hi = t_hi.max(p.seconds.max(1e-4));
    }
    let palette = [RED, BLUE, GREEN, MAGENTA, CYAN, BLACK, RGBColor(230, 140, 0), RGBColor(120, 60, 0)];
    for (panel, per_time) in panels.iter().zip([false, true]) {
        let mut chart =
            ChartBuilder::on(panel).margin(12).x_label_area_size(40).y_label_area_size(70).build_cartesian_2d(
                if per_time { (t_lo / 1.5..t_hi * 1.5).log_scale() } else { (0.8..max_spp * 1.25).log_scale() },
                (lo..hi).log_scale(),
            )?;
        chart
            .configure_mesh()
            .x_desc(if per_time { "render time (s)" } else { "samples per pixel" })
            .y_desc("MSE")
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .x_label_formatter(&|v| if per_time { format!("{v:.0e}") } else { format!("{v:.0}") })
            .draw()?;
        for (k, c) in curves.iter().enumerate() {
            let color = palette[k % palette.len()];
            let pts: Vec<(f64, f64)> = c
                .points
                .iter()
                .filter(|p| p.mse > 0.0)
                .map(|p| (if per_time { p.seconds.max(1e-4) } else { p.spp as f64 }, p.mse))
                .collect();
            let label = match c.slope() {
                Some(s) if !per_time => format!("{} (slope {s:.2})", c.name),
                _ => c.name.clone(),
            };
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2)));
            chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerLeft)
            .draw()?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use neumann::estimators::irradiance::{
        estimate_uniform_sky_irradiance, estimate_uniform_sky_irradiance_stratified, HemisphereStrategy,
    };
    use neumann::sampling::Pcg32;

    /// The slope fit on synthetic estimators of known order: the MSE of uniform-hemisphere
    /// irradiance falls as N⁻¹, its jittered-stratified version (smooth 2D integrand) as N⁻².
    #[test]
    fn slope_fit_recovers_known_convergence_orders() {
        let exact = std::f64::consts::PI;
        let runs = 400;
        let curve = |stratified: bool| {
            let points = [4usize, 8, 16, 32, 64]
                .iter()
                .map(|&k| {
                    let mut rng = Pcg32::new(5, k as u64);
                    let mse = (0..runs)
                        .map(|_| {
                            let e = if stratified {
                                estimate_uniform_sky_irradiance_stratified(1.0, k, &mut rng).value
                            } else {
                                estimate_uniform_sky_irradiance(1.0, k * k, HemisphereStrategy::Uniform, &mut rng).value
                            };
                            (e - exact).powi(2)
                        })
                        .sum::<f64>()
                        / runs as f64;
                    Point { spp: (k * k) as u32, mse, relmse: mse, seconds: 1.0 }
                })
                .collect();
            Curve { name: "synthetic".into(), points }
        };
        let independent = curve(false).slope().unwrap();
        let stratified = curve(true).slope().unwrap();
        assert!((independent + 1.0).abs() < 0.1, "independent slope {independent}");
        assert!((stratified + 2.0).abs() < 0.2, "stratified slope {stratified}");
    }

    /// End to end on a small Cornell box: the MSE of the path tracer falls with slope ≈ -1, and
    /// the CSV and both plots are written.
    #[test]
    fn cornell_box_convergence_and_outputs() {
        let scene = neumann::scene::cornell::cornell_box(16, 16).unwrap();
        let integrator = PathIntegrator::with_max_depth(4);
        let reference = render(
            &scene,
            &integrator,
            &RenderSettings { spp: 4096, seed: 999, ..Default::default() },
            &AtomicBool::new(false),
        )
        .unwrap()
        .film
        .image();
        let base = RenderSettings { seed: 1, ..Default::default() };
        let curve = measure("path", &scene, &integrator, &reference, &spp_levels(64), &base).unwrap();
        assert_eq!(curve.points.len(), 7);
        let slope = curve.slope().unwrap();
        assert!((-1.3..-0.7).contains(&slope), "slope {slope}");
        let dir = std::env::temp_dir().join(format!("neumann-converge-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        write_csv(&dir.join("c.csv"), std::slice::from_ref(&curve)).unwrap();
        plot(&dir.join("c.svg"), &dir.join("c.png"), "test", &[curve]).unwrap();
        let csv = std::fs::read_to_string(dir.join("c.csv")).unwrap();
        assert_eq!(csv.lines().count(), 8);
        assert!(std::fs::read_to_string(dir.join("c.svg")).unwrap().contains("samples per pixel"));
        assert!(std::fs::metadata(dir.join("c.png")).unwrap().len() > 1000);
        std::fs::remove_dir_all(&dir).ok();
    }
}
