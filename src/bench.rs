//! `neumann bench`: BVH build time, ray throughput and path-tracing speed.

use clap::Args;

/// Benchmark options.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Triangles in the generated test mesh.
    #[arg(long, default_value_t = 1_000_000)]
    pub triangles: usize,
}

pub fn run(_args: &BenchArgs) -> Result<(), String> {
    Err("not yet".into())
}
