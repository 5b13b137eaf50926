//! The step-count experiment of issue 23 (item 2): Radau IIA of order 9 (5 stages) against the
//! default order 5 (RADAU5) on the work-precision ensemble's centred grasps, through gripopt's
//! own scene and driver (`gripopt::bench::radau_order`; docs/benchmarks.md).
//!
//! `cargo bench -p gripopt-diffsol-bench --bench radau_order [-- PROBLEM --sample N --rtols … --order 5|9]`

use anyhow::Result;
use clap::Parser;
use gripopt::bench::{radau_order, Order};
use gripopt::params::Problem;
use std::path::PathBuf;

/// Radau IIA order 9 against order 5 over the ensemble.
#[derive(Parser)]
#[command(name = "radau-order")]
struct Args {
    /// Problem file (relative: from the repository root).
    #[arg(default_value = "problems/bottle-1l.toml")]
    problem: PathBuf,
    /// Designs of the ensemble (as `gripopt bench work-precision --sample`).
    #[arg(long, default_value_t = 40)]
    sample: usize,
    /// Seed of the ensemble.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Relative tolerances (atol 1e-3·rtol), comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1e-5, 1e-6, 1e-7])]
    rtols: Vec<f64>,
    /// Only this order (5 or 9; default both), e.g. to count one method's instructions.
    #[arg(long)]
    order: Option<u32>,
    /// Passed by `cargo bench`; ignored.
    #[arg(long, hide = true)]
    bench: bool,
}

fn main() -> Result<()> {
    let mut a = Args::parse();
    if a.problem.is_relative() {
        a.problem = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(&a.problem);
    }
    let p = Problem::load(&a.problem)?;
    let orders = match a.order {
        None => vec![Order::Five, Order::Nine],
        Some(5) => vec![Order::Five],
        Some(9) => vec![Order::Nine],
        Some(o) => anyhow::bail!("--order {o}: 5 or 9"),
    };
    radau_order(&p, a.sample, a.seed, &a.rtols, &orders, &mut std::io::stdout())?;
    Ok(())
}
