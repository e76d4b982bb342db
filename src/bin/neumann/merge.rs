//! `neumann merge`: combine the parts of a split render (`render --part`, `--pixel-bounds`) into
//! the whole image.

use crate::{usage, Failure};
use neumann::film::output::{write_image_layers, Format, ImageInfo};
use neumann::film::part::{merge_parts, read_part, write_part};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// The parts (OpenEXR files written by `neumann render --part` or `--pixel-bounds`).
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// The merged image; the extension picks the format (.exr keeps the sums, so that it can be
    /// merged again or continued).
    #[arg(short, long)]
    output: PathBuf,
    /// Merge the parts that exist when samples or tiles are missing (they are listed either way).
    #[arg(long)]
    allow_partial: bool,
    /// Exposure in stops for PNG output (× 2^EV).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    exposure: f32,
}

/// `neumann merge`.
pub fn run(a: MergeArgs) -> Result<(), Failure> {
    let format = Format::from_path(&a.output).map_err(|e| usage(e.to_string()))?;
    neumann::film::output::check_destination(&a.output).map_err(|e| Failure(1, e.to_string()))?;
    if !a.exposure.is_finite() {
        return Err(usage(format!("--exposure must be a finite number of stops, got {}", a.exposure)));
    }
    let start = std::time::Instant::now();
    let parts = a.parts.iter().map(|p| read_part(p)).collect::<Result<Vec<_>, _>>().map_err(|e| Failure(1, e.to_string()))?;
    let merged = merge_parts(&parts, a.allow_partial).map_err(|e| Failure(1, e.to_string()))?;
    for m in &merged.missing {
        say!("warning: missing {m}");
    }
    let [_, _, w, h] = merged.image;
    let (lo, hi) = merged.film.spp_range();
    let samples = if lo == hi { format!("{lo} spp") } else { format!("{lo}–{hi} spp") };
    match (&merged.info, format) {
        (Some(info), Format::Exr) => write_part(&a.output, &merged.film, info, merged.alpha),
        _ => {
            let alpha = merged.alpha.then(|| merged.film.alpha());
            let mut channels = Vec::new();
            if format == Format::Exr {
                channels = merged.film.aov_channels();
                channels.push(("spp".to_string(), merged.film.sample_counts()));
            }
            let info = ImageInfo { spp: lo, exposure: a.exposure, ..Default::default() };
            write_image_layers(&a.output, w, h, &merged.film.image(), alpha.as_deref(), &channels, &info)
        }
    }
    .map_err(|e| Failure(1, e.to_string()))?;
    say!(
        "merged {} parts of {} into {} ({w}x{h}, {samples}, {:.2} s){}",
        parts.len(),
        parts[0].info.scene,
        a.output.display(),
        start.elapsed().as_secs_f64(),
        if merged.missing.is_empty() { "" } else { " — partial: the samples listed above are missing" }
    );
    if merged.film.dropped() > 0 {
        say!("warning: {} samples were NaN or infinite and were dropped by the parts' renders", merged.film.dropped());
    }
    Ok(())
}
