//! Argument parsing and dispatch.

use anyhow::Result;
use args::{check_threads, with_hooks};
use clap::{Parser, Subcommand};
use inputs::{design_of, load_problem};
use std::path::PathBuf;

#[macro_use]
pub(crate) mod out;
mod args;
mod bench;
mod csv_stream;
mod export;
mod inputs;
mod optcmd;
mod progress;
mod report;
mod robust;
mod scenes;
mod show;
mod sweep;
mod verify;
mod watch;

/// Design optimisation of underactuated two-finger grippers for high-speed grasping.
#[derive(Parser)]
#[command(name = "gripopt", version, about)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Staged evaluation (stages 0–3) of one design, with a report of every computed value.
    Evaluate {
        /// Problem file (TOML).
        problem: PathBuf,
        /// Design as l21=..,b=..,t22=..,r=..,p=..,psi_deg=.. (default: the problem's nominal).
        #[arg(long)]
        design: Option<String>,
        /// Print the MODEL.md §10 record as one JSON object.
        #[arg(long)]
        json: bool,
        /// Stages 0–2 only (no grasp simulation).
        #[arg(long)]
        static_only: bool,
    },
    /// Diagnostic grasp simulation: runs to t_stab (or t_max) and reports every criterion.
    Simulate(scenes::SimulateArgs),
    /// NSGA-II over the staged pipeline; checkpoints every generation into RUN_DIR.
    Optimise(optcmd::OptimiseArgs),
    /// Print a recorded design, re-simulate it and verify its trajectory (a single-object
    /// free-kind run: also record its free scene to RUN_DIR/free-ID.mcap).
    Replay(optcmd::ReplayArgs),
    /// Continue a stopped, killed or finished run.
    Resume {
        /// Run folder.
        run_dir: PathBuf,
        /// New total number of generations (default: the run's).
        #[arg(long)]
        generations: Option<u64>,
        /// Resume even if the problem file changed or the checkpoint's content checksum does
        /// not match (recorded in run.json).
        #[arg(long)]
        force: bool,
        /// Worker threads.
        #[arg(long)]
        threads: Option<usize>,
        /// Print the summary as one JSON object (for scripts).
        #[arg(long)]
        json: bool,
    },
    /// A run's front sorted by an objective, with units and each design's replay command.
    Show(show::ShowArgs),
    /// Validate the optimiser's NSGA-II (crowding survival, SBX: the reference
    /// implementation's algorithm, not the default) on standard problems (ZDT1-3, DTLZ2,
    /// BNH, TNK, OSY, C2DTLZ2): hypervolume and IGD of the final feasible non-dominated set;
    /// exit 3 when a problem's hypervolume median lies outside the reference band.
    MooTest {
        /// Problem name, or `all`.
        name: String,
        /// Seed of one run.
        #[arg(long)]
        seed: Option<u64>,
        /// A range of seeds, e.g. 1-11 (prints the median against the reference band).
        #[arg(long)]
        seeds: Option<String>,
        /// One JSON object per run: problem, seed, hv, igd, evaluations, wall_s.
        #[arg(long)]
        json: bool,
        /// Population size.
        #[arg(long, default_value_t = 100)]
        pop: usize,
        /// Generations (default: 250 for ZDT and DTLZ2, 200 otherwise; 1 = initial population).
        #[arg(long)]
        generations: Option<u64>,
    },
    /// Parameter study: evaluate a grid of 1-3 varied names, write DIR/sweep.csv and plots.
    Sweep(sweep::SweepArgs),
    /// Re-simulate a run's designs in the free scene and compare with the criteria's prediction (RUN_DIR/verify.csv); a robust run's front on fresh scenarios (RUN_DIR/verify_robust.csv).
    Verify(verify::VerifyArgs),
    /// A design to MuJoCo (MJCF) or to a build sheet (JSON/CSV) for CAD (docs/export.md).
    Export(export::ExportArgs),
    /// Benchmarks (speed figures for docs/benchmarks.md; not tests).
    Bench {
        /// Print the figures as one JSON object on stdout (the text report goes to stderr).
        #[arg(long, global = true)]
        json: bool,
        #[command(subcommand)]
        which: bench::BenchCmd,
    },
}

impl Cmd {
    /// Whether the command was asked for `--json` (its failure is then a JSON object on
    /// stdout too, [`out::report_error`]).
    fn json(&self) -> bool {
        match self {
            Cmd::Evaluate { json, .. }
            | Cmd::Resume { json, .. }
            | Cmd::MooTest { json, .. }
            | Cmd::Bench { json, .. } => *json,
            Cmd::Simulate(a) => a.json,
            Cmd::Optimise(a) => a.json,
            Cmd::Replay(a) => a.json,
            Cmd::Show(a) => a.json,
            Cmd::Sweep(_) | Cmd::Verify(_) | Cmd::Export(_) => false,
        }
    }
}

/// Whether `--json` is among the arguments (before a `--`): a usage error clap reports
/// before the command is known is then a JSON object on stdout too.
fn json_asked() -> bool {
    // `--json`, or `--json=VALUE` (a flag takes no value: clap refuses it, and the refusal
    // is then a JSON object too)
    std::env::args_os()
        .skip(1)
        .take_while(|a| a != "--")
        .any(|a| a == "--json" || a.to_str().is_some_and(|a| a.starts_with("--json=")))
}

/// Entry point: the process exit code (0 done, 3 a check did not pass, 130 interrupted;
/// an error's code, [`out::report_error`]), with stdout flushed.
pub fn run() -> i32 {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // a usage error (not --help or --version) with --json: its message as JSON
            if e.use_stderr() && json_asked() {
                out::error_json(&out::usage_message(&e.to_string()), e.exit_code());
            }
            e.exit()
        }
    };
    let json = cli.cmd.json();
    let result = dispatch(cli.cmd);
    // what is still buffered (a last line without its line break) is written before the exit
    if let Err(e) = std::io::Write::flush(&mut std::io::stdout()) {
        out::failed(&e);
    }
    match result {
        Ok(code) => code,
        Err(e) => out::report_error(&e, json),
    }
}

/// Run the command: its exit code, or its error.
fn dispatch(cmd: Cmd) -> Result<i32> {
    match cmd {
        Cmd::Evaluate { problem, design, json, static_only } => {
            let p = load_problem(&problem)?;
            let x = design_of(&p, &design)?;
            report::evaluate(&p, &x, json, static_only).map(|_| 0)
        }
        Cmd::Simulate(a) => scenes::run(a).map(|_| 0),
        Cmd::Optimise(a) => optcmd::optimise(a),
        Cmd::Replay(a) => optcmd::replay_cmd(a),
        Cmd::Resume { run_dir, generations, force, threads, json } => {
            let mut run = gripopt::app::Optimiser::resume(&run_dir).force(force).threads(threads);
            if let Some(g) = generations {
                run = run.generations(g);
            }
            let s = with_hooks(run).run()?;
            optcmd::summary(&s, json)
        }
        Cmd::Show(a) => show::run(a).map(|_| 0),
        Cmd::MooTest { name, seed, seeds, json, pop, generations } => {
            optcmd::moo_test(&name, seed, seeds, json, pop, generations)
        }
        Cmd::Bench { which, json } => bench::run(which, json).map(|_| 0),
        Cmd::Sweep(a) => sweep::run(a).map(|_| 0),
        Cmd::Export(a) => export::run(a).map(|_| 0),
        Cmd::Verify(a) => {
            check_threads(a.threads)?;
            verify::run(a).map(|_| 0)
        }
    }
}
