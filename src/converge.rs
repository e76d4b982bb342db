//! Convergence measurements: render a scene at 1, 2, 4, … N samples per pixel with several
//! estimators, measure the error against a reference, fit the log-log slope (≈ -1 for the MSE
//! of any unbiased Monte Carlo estimator with independent samples; steeper with stratification
//! or QMC on smooth integrands) and time each render, so that estimators can be compared per
//! sample and per second (efficiency = 1 / (MSE × time)).
//!
//! Output: a CSV (one row per estimator and sample count) and a two-panel log-log plot, MSE
//! against spp and MSE against seconds, one labelled curve per estimator, as SVG and PNG
//! (plotters; the PNG's labels use the bundled DejaVu Sans subset in `assets/fonts/`).

use crate::estimators::loglog_slope;
use crate::integrator::Integrator;
use crate::math::Rgb;
use crate::render::{render, RenderSettings};
use crate::scene::Scene;
use crate::validate::relmse;
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// One measured point of a curve.
#[derive(Clone, Copy, Debug)]
pub struct Point {
    /// Samples per pixel.
    pub spp: u32,
    /// Mean squared error over pixels and channels.
    pub mse: f64,
    /// Relative MSE (`(x - r)² / (r² + 10⁻²)`, see [`crate::validate::relmse`]).
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

/// Mean squared error over pixels and channels.
pub fn mse(image: &[Rgb], reference: &[Rgb]) -> f64 {
    let sum: f64 = image
        .iter()
        .zip(reference)
        .map(|(a, b)| {
            let d = (*a - *b).as_dvec3();
            d.length_squared()
        })
        .sum();
    sum / (3 * image.len().max(1)) as f64
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
        let out = render(scene, integrator, &settings, &AtomicBool::new(false))?;
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

static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans-subset.ttf");

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
    use crate::estimators::irradiance::{
        estimate_uniform_sky_irradiance, estimate_uniform_sky_irradiance_stratified, HemisphereStrategy,
    };
    use crate::sampling::Pcg32;

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
        let scene = crate::scene::cornell::cornell_box(16, 16).unwrap();
        let integrator = crate::integrator::PathIntegrator::with_max_depth(4);
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
