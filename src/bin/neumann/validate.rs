//! Validation against Mitsuba 3: render a scene of `scenes/` at the settings its reference was
//! measured at, and compare with the committed Mitsuba reference (`references/<scene>.exr`) and
//! Mitsuba's own error at the same sample count (`references/references.csv`, written by
//! `tools/mitsuba/references.py`).
//!
//! Metrics, over all pixels and channels: `relMSE = mean((x - r)² / (r² + 10⁻²))` (the error
//! relative to the reference value, softened near black), and the relative difference of the image
//! means. Equal-spp relMSE within a small factor of Mitsuba's says neumann's estimator is as
//! efficient per sample; the mean within 0.5 % (or three standard deviations of Mitsuba's own
//! mean at that spp, where its mean scatters more) catches a bias that noise would hide.

use crate::{usage, Failure};
use neumann::film::metrics::{image_mean, relmse};
use neumann::load::image::load_image;
use neumann::load::mitsuba::load_scene_file;
use neumann::render::{render_integrator, RenderSettings};
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// One row of `references/references.csv`.
#[derive(Clone, Debug)]
pub struct Reference {
    /// Scene name (`scenes/<name>.xml`, `references/<name>.exr`).
    pub scene: String,
    /// Square resolution.
    pub res: u32,
    /// Samples per pixel of the compared renders.
    pub test_spp: u32,
    /// Mitsuba's relMSE at `test_spp` (mean over seeds).
    pub mitsuba_relmse: f64,
    /// Mean of the reference image.
    pub reference_mean: f64,
    /// Mitsuba's samples per second at `test_spp` on the machine that made the references.
    pub mitsuba_samples_per_second: f64,
    /// Largest accepted ratio of neumann's relMSE to Mitsuba's (column `max_relmse_ratio`;
    /// 1.5 where the column is absent).
    pub max_relmse_ratio: f64,
    /// Largest accepted relative difference of the image mean from the reference's (column
    /// `max_mean_difference`: 0.5 %, or three standard deviations of Mitsuba's own means at
    /// `test_spp` where that is more; 0.5 % where the column is absent).
    pub max_mean_difference: f64,
}

/// The outcome of validating one scene.
#[derive(Clone, Debug)]
pub struct Validation {
    /// The reference row.
    pub reference: Reference,
    /// neumann's relMSE against the reference.
    pub relmse: f64,
    /// neumann's image mean.
    pub mean: f64,
    /// neumann's samples per second.
    pub samples_per_second: f64,
}

impl Validation {
    /// relMSE relative to Mitsuba's.
    pub fn relmse_ratio(&self) -> f64 {
        self.relmse / self.reference.mitsuba_relmse
    }

    /// Relative difference of the means, `(mean - ref) / ref`.
    pub fn mean_difference(&self) -> f64 {
        (self.mean - self.reference.reference_mean) / self.reference.reference_mean
    }

    /// Whether it passes: relMSE ≤ `max_relmse_ratio` × Mitsuba's (1.5 unless the scene asks
    /// for tighter) and the mean within `max_mean_difference`.
    pub fn passed(&self) -> bool {
        self.relmse_ratio() <= self.reference.max_relmse_ratio
            && self.mean_difference().abs() <= self.reference.max_mean_difference
    }
}

/// Reads `references.csv` in `dir`.
pub fn read_references(dir: &Path) -> Result<Vec<Reference>, String> {
    let path = dir.join("references.csv");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut lines = text.lines().enumerate();
    let header: Vec<&str> = lines.next().map(|(_, l)| l.split(',').collect()).unwrap_or_default();
    let col = |name: &str| {
        header.iter().position(|h| *h == name).ok_or_else(|| format!("{}: no column '{name}'", path.display()))
    };
    let (c_scene, c_res, c_spp, c_rel, c_mean, c_sps) = (
        col("scene")?,
        col("res")?,
        col("test_spp")?,
        col("mitsuba_relmse")?,
        col("reference_mean")?,
        col("mitsuba_samples_per_second")?,
    );
    let c_max = header.iter().position(|h| *h == "max_relmse_ratio");
    let c_mean_max = header.iter().position(|h| *h == "max_mean_difference");
    lines
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            let f: Vec<&str> = l.split(',').collect();
            let bad = || format!("{}:{}: malformed row", path.display(), i + 1);
            let num = |c: usize| f.get(c).and_then(|s| s.trim().parse::<f64>().ok()).ok_or_else(bad);
            Ok(Reference {
                scene: f.get(c_scene).ok_or_else(bad)?.to_string(),
                res: num(c_res)? as u32,
                test_spp: num(c_spp)? as u32,
                mitsuba_relmse: num(c_rel)?,
                reference_mean: num(c_mean)?,
                mitsuba_samples_per_second: num(c_sps)?,
                max_relmse_ratio: match c_max {
                    Some(c) => num(c)?,
                    None => 1.5,
                },
                max_mean_difference: match c_mean_max {
                    Some(c) => num(c)?,
                    None => 0.005,
                },
            })
        })
        .collect()
}

/// Renders `scenes_dir/<scene>.xml` at the reference's settings (seed `seed`) and compares it with
/// `references_dir/<scene>.exr`.
pub fn validate(scenes_dir: &Path, references_dir: &Path, r: &Reference, seed: u64) -> Result<Validation, String> {
    let defines = [("res".to_string(), r.res.to_string()), ("spp".to_string(), r.test_spp.to_string())];
    let file = load_scene_file(&scenes_dir.join(format!("{}.xml", r.scene)), &defines).map_err(|e| e.to_string())?;
    let settings = RenderSettings {
        spp: r.test_spp,
        seed,
        sampler: file.sampler,
        filter: file.filter.clone(),
        window: file.window,
        sample_border: file.sample_border,
        transform: file.transform,
        ..Default::default()
    };
    let out = render_integrator(&file.scene, &file.integrator, &settings, &AtomicBool::new(false))
        .map_err(|e| e.to_string())?;
    let image = out.film.image();
    let reference = load_image(&references_dir.join(format!("{}.exr", r.scene)), true).map_err(|e| e.to_string())?;
    if reference.pixels.len() != image.len() {
        return Err(format!(
            "reference {} is {}x{} but the render has {} pixels",
            r.scene,
            reference.width,
            reference.height,
            image.len()
        ));
    }
    Ok(Validation {
        reference: r.clone(),
        relmse: relmse(&image, &reference.pixels),
        mean: image_mean(&image),
        samples_per_second: out.samples_per_second(),
    })
}

/// `neumann validate`: the comparison table; fails if any scene fails.
pub fn run(
    scenes: &[String],
    scene_dir: &std::path::Path,
    reference_dir: &std::path::Path,
    seed: u64,
) -> Result<(), Failure> {
    let refs = read_references(reference_dir).map_err(|e| Failure(1, e.to_string()))?;
    if let Some(s) = scenes.iter().find(|s| !refs.iter().any(|r| &r.scene == *s)) {
        let names: Vec<&str> = refs.iter().map(|r| r.scene.as_str()).collect();
        return Err(usage(format!("no reference for scene '{s}' (references exist for: {})", names.join(", "))));
    }
    say!(
        "{:<16} {:>5} {:>6} {:>12} {:>12} {:>7} {:>6} {:>9} {:>6} {:>10} {:>10}  verdict",
        "scene", "res", "spp", "relMSE", "Mitsuba", "ratio", "bound", "mean diff", "bound", "Msamp/s", "Mitsuba"
    );
    let mut failed = 0;
    for r in refs.iter().filter(|r| scenes.is_empty() || scenes.contains(&r.scene)) {
        let v = validate(scene_dir, reference_dir, r, seed).map_err(|e| Failure(1, e.to_string()))?;
        let ok = v.passed();
        failed += usize::from(!ok);
        say!(
            "{:<16} {:>5} {:>6} {:>12.4e} {:>12.4e} {:>7.3} {:>6.2} {:>+8.3}% {:>5.2}% {:>10.2} {:>10.2}  {}",
            r.scene,
            r.res,
            r.test_spp,
            v.relmse,
            r.mitsuba_relmse,
            v.relmse_ratio(),
            r.max_relmse_ratio,
            100.0 * v.mean_difference(),
            100.0 * r.max_mean_difference,
            v.samples_per_second / 1e6,
            r.mitsuba_samples_per_second / 1e6,
            if ok { "ok" } else { "FAIL" }
        );
    }
    say!(
        "(pass: relMSE ≤ bound × Mitsuba's at equal spp and |mean diff| ≤ its bound: 0.5 %, or three standard \
         deviations of Mitsuba's own mean at that spp where that is more; Mitsuba's speed as recorded with the references)"
    );
    if failed > 0 {
        return Err(Failure(1, format!("{failed} scene(s) failed validation")));
    }
    Ok(())
}
