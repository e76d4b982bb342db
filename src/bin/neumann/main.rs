//! The `neumann` command: one module per subcommand (`render`, `merge`, `validate`, `converge`,
//! `bench`, `mc`); the library's option enums parse themselves ([`neumann::choice::Choice`]), so none is
//! mirrored here.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Parser, Subcommand};
use neumann::choice::Choice;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;

/// `println!` that ignores a closed standard output (`neumann render … | head` must not panic
/// on a broken pipe: the render goes on and its image is written).
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

mod bench;
mod converge;
mod denoise;
mod job;
mod mc;
mod merge;
mod render;
mod validate;

#[derive(Parser, Debug)]
#[command(name = "neumann", version, about = "A physically based Monte Carlo renderer", arg_required_else_help = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// A clap value parser for a library option enum: its names, each with its description in
/// `--help`, parsed into the enum.
pub fn choice<T: Choice + Clone + Send + Sync>() -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(T::CHOICES.iter().map(|&(_, name, help)| PossibleValue::new(name).help(help)))
        .map(|s| T::parse_name(&s).expect("the parser admits only the enum's names"))
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene (default: the built-in Cornell box) to an image (.png, .exr or .pfm).
    Render(Box<render::RenderArgs>),
    /// Combine the parts of a render split over machines (render --part I/N, --pixel-bounds) into
    /// the whole image, weighted by their samples; refuses parts of different renders and names
    /// what is missing.
    Merge(merge::MergeArgs),
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
    Converge(converge::ConvergeArgs),
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

pub static CANCEL: AtomicBool = AtomicBool::new(false);

/// The signal (SIGINT 2, SIGTERM 15) that asked the render to stop, 0 if none.
pub static STOPPED_BY: std::sync::atomic::AtomicI32 = std::sync::atomic::AtomicI32::new(0);

/// Listens for SIGINT and SIGTERM on a thread of its own: the first sets [`CANCEL`] (the render
/// finishes the samples in flight and its work is written) and records the signal; a second
/// exits at once with 128 + the signal's number.
pub fn handle_signals() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else { return };
    std::thread::spawn(move || {
        for sig in signals.forever() {
            if CANCEL.swap(true, std::sync::atomic::Ordering::SeqCst) {
                std::process::exit(128 + sig);
            }
            STOPPED_BY.store(sig, std::sync::atomic::Ordering::SeqCst);
            eprintln!(
                "\n{}: finishing the samples in flight and writing what has been rendered (again to abort)",
                if sig == SIGINT { "interrupted" } else { "terminated" }
            );
        }
    });
}

/// An error and the exit code it maps to (1: could not do it, 2: bad arguments).
pub struct Failure(pub u8, pub String);

/// A bad-argument failure (exit code 2).
pub fn usage(msg: String) -> Failure {
    Failure(2, msg)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render::run(*args),
        Command::Merge(args) => merge::run(args),
        Command::Bench(args) => bench::run(&args).map_err(|e| Failure(1, e.to_string())),
        Command::Converge(args) => converge::run(args),
        Command::Validate { scenes, scene_dir, reference_dir, seed } => {
            validate::run(&scenes, &scene_dir, &reference_dir, seed)
        }
        Command::Mc { runs, seed, radiance } => {
            if radiance.is_finite() && radiance >= 0.0 {
                mc::run(runs, seed, radiance);
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
