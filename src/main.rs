//! The `neumann` command.

use clap::{Parser, Subcommand};
use neumann::estimators::irradiance::{estimate_uniform_sky_irradiance, HemisphereStrategy};
use neumann::sampling::Pcg32;
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(name = "neumann", version, about = "A physically based Monte Carlo renderer", arg_required_else_help = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
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

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Mc { runs, seed, radiance } => {
            if !(radiance.is_finite() && radiance >= 0.0) {
                eprintln!("error: --radiance must be a finite non-negative number, got {radiance}");
                return ExitCode::from(2);
            }
            mc_irradiance(runs, seed, radiance);
            ExitCode::SUCCESS
        }
    }
}

/// Irradiance under a uniform sky, `E = L π`, by uniform and cosine-weighted hemisphere sampling.
fn mc_irradiance(runs: u32, seed: u64, radiance: f64) {
    let exact = radiance * std::f64::consts::PI;
    println!("Irradiance under a uniform sky of radiance L = {radiance}: E = ∫ L cos θ dω = L π = {exact:.6}");
    println!("{:<22} {:>8} {:>12} {:>12} {:>12}", "estimator", "N", "estimate", "exact", "RMSE");
    for (name, strategy) in
        [("uniform hemisphere", HemisphereStrategy::Uniform), ("cosine-weighted", HemisphereStrategy::Cosine)]
    {
        for n in [16usize, 256, 4096, 65536] {
            let mut rng = Pcg32::new(seed, n as u64);
            let estimates: Vec<f64> =
                (0..runs).map(|_| estimate_uniform_sky_irradiance(radiance, n, strategy, &mut rng).value).collect();
            let mean = estimates.iter().sum::<f64>() / runs as f64;
            let rmse = (estimates.iter().map(|e| (e - exact) * (e - exact)).sum::<f64>() / runs as f64).sqrt();
            println!("{name:<22} {n:>8} {mean:>12.6} {exact:>12.6} {rmse:>12.3e}");
        }
    }
}
