//! What to render: a scene (the built-in Cornell box or a Mitsuba XML file) with its settings,
//! and the parsing of `-D` and `--res`.

use crate::{usage, Failure};
use neumann::film::filter::Filter;
use neumann::integrator::{AnyIntegrator, PathIntegrator};
use neumann::load::load_scene;
use neumann::load::overrides::Overrides;
use neumann::load::SceneFile;
use neumann::sampling::sampler::SamplerKind;
use neumann::scene::cornell;

/// Parses `W` or `WxH`.
pub fn parse_res(s: &str) -> Result<(u32, u32), String> {
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

/// A scene ready to render with its settings (from the built-in Cornell box or a file), and the
/// name outputs are named after.
pub struct Job {
    pub name: String,
    pub file: SceneFile,
}

/// Parses the `-D name=value` list.
pub fn parse_defines(defines: &[String]) -> Result<Vec<(String, String)>, Failure> {
    defines
        .iter()
        .map(|d| match d.split_once('=') {
            Some((k, v)) if !k.trim().is_empty() => Ok((k.trim().to_string(), v.to_string())),
            _ => Err(usage(format!("-D expects NAME=VALUE, got '{d}'"))),
        })
        .collect()
}

/// The built-in Cornell box with cbox.xml's parameters (res, spp, max_depth) from `-D`.
pub fn builtin_job(name: &str, defines: &[(String, String)]) -> Result<Job, Failure> {
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
    let file = SceneFile {
        scene: cornell::cornell_box(res.0, res.1).map_err(|e| Failure(1, e.to_string()))?,
        integrator: AnyIntegrator::Path(PathIntegrator::with_max_depth(max_depth)),
        spp,
        sampler: SamplerKind::Independent,
        seed: 0,
        filter: Filter::BOX,
        window: None,
        alpha: false,
        colors: Default::default(),
        component: Default::default(),
        sample_border: false,
        transform: Default::default(),
        time_limit: None,
        warnings: Vec::new(),
    };
    Ok(Job { name: name.to_string(), file })
}

/// A scene file (Mitsuba XML or glTF), with command-line flags as `overrides` of its objects and
/// the glTF `camera` to render. A problem with a flag is a usage error (exit 2), one in the
/// file exit 1.
pub fn file_job(
    path: &std::path::Path,
    defines: &[(String, String)],
    overrides: &Overrides,
    camera: Option<&str>,
) -> Result<Job, Failure> {
    let file = load_scene(path, defines, overrides, camera).map_err(|e| {
        let flag_problem = e.loc.is_none() && (e.message.starts_with("--camera") || e.message.starts_with("-D "));
        let from_flag = flag_problem || e.loc.as_ref().is_some_and(|l| l.file.path.as_os_str() == "command line");
        Failure(if from_flag { 2 } else { 1 }, e.to_string())
    })?;
    for w in &file.warnings {
        eprintln!("{w}");
    }
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene").to_string();
    Ok(Job { name, file })
}
