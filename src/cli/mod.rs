//! Argument parsing and dispatch.

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use inputs::{design_of, load_problem};
use std::path::PathBuf;

#[macro_use]
pub(crate) mod out;
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
    Simulate {
        /// Problem file (TOML).
        problem: PathBuf,
        /// Design as l21=..,b=..,t22=..,r=..,p=..,psi_deg=.. (default: the problem's nominal).
        #[arg(long)]
        design: Option<String>,
        /// Relative tolerance (default: the problem's solver.rtol).
        #[arg(long)]
        rtol: Option<f64>,
        /// Integration method (default: the problem's solver.method; absent there, the default
        /// solver: auto with the default's tolerance scaling). A method given here takes the
        /// tolerances as given.
        #[arg(long, value_enum)]
        method: Option<MethodArg>,
        /// Scene (MODEL.md §14): centred, offset:X or free[:X] (metres; default: the problem's [scene]).
        #[arg(long)]
        scene: Option<String>,
        /// A robust problem's object ([[robust.objects]] name) to grasp instead of the
        /// reference [object]: its cylinder and grip torque, the spring sized at [hand] tau.
        #[arg(long)]
        object: Option<String>,
        /// Print the evaluation record (stages 0–3, verdict, scene, method) as one JSON
        /// object (docs/outputs.md).
        #[arg(long)]
        json: bool,
        /// Write the trajectory (accepted steps and events) to this CSV file.
        #[arg(long)]
        csv: Option<PathBuf>,
        /// Close the finger on nothing (contacts off): shows where the linkage itself goes,
        /// e.g. into a parallel singularity.
        #[arg(long)]
        no_contact: bool,
        /// Print every located event to stderr.
        #[arg(long)]
        trace: bool,
        /// Plot the grasp (joint angles, contact forces, raw and filtered hand force) to this SVG file.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Overwrite the --csv / --plot files if they exist (refused otherwise).
        #[arg(long)]
        force: bool,
    },
    /// NSGA-II over the staged pipeline; checkpoints every generation into RUN_DIR.
    Optimise {
        /// Problem file (TOML).
        problem: PathBuf,
        /// Run folder (created; must not hold a run already).
        #[arg(long)]
        out: PathBuf,
        /// Population size.
        #[arg(long, default_value_t = 100)]
        pop: usize,
        /// Generations (1 = the random initial population).
        #[arg(long, default_value_t = 50)]
        generations: u64,
        /// Seed (fixes the run).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Worker threads (default: all cores; results do not depend on it).
        #[arg(long)]
        threads: Option<usize>,
        /// What to record to MCAP in RUN_DIR/recording: every design with its grasp
        /// (all), trajectories of feasible designs only (feasible), design records only
        /// (designs), or nothing (none).
        #[arg(long, value_enum, default_value = "all")]
        record: RecordArg,
        /// Keep every n-th trajectory sample (1 = every accepted step).
        #[arg(long, default_value_t = 1)]
        record_every: u32,
        /// Interval of the 3D scene updates in milliseconds of simulated time (0 = none).
        #[arg(long, default_value_t = gripopt::record::DEFAULT_SCENE_DT * 1e3)]
        scene_ms: f64,
        /// Record every trajectory sample in full f64 (default: the compact subset).
        #[arg(long)]
        record_full: bool,
        /// zstd compression level of the recording (changes file sizes, never content).
        #[arg(long, default_value_t = gripopt::record::DEFAULT_ZSTD_LEVEL)]
        zstd_level: u32,
        /// zstd worker threads per recording shard (0 = compress on the writing thread).
        #[arg(long, default_value_t = gripopt::record::DEFAULT_ZSTD_THREADS)]
        zstd_threads: u32,
        /// Print the summary as one JSON object (for scripts).
        #[arg(long)]
        json: bool,
    },
    /// Print a recorded design, re-simulate it and verify its trajectory (a single-object
    /// free-kind run: also record its free scene to RUN_DIR/free-ID.mcap).
    Replay {
        /// Run folder.
        run_dir: PathBuf,
        /// Design id (see pareto.csv / population.csv).
        #[arg(long)]
        design: u64,
        /// Print the record plus `verified` and `max_difference` as JSON.
        #[arg(long)]
        json: bool,
        /// Write the recorded trajectory to this CSV file.
        #[arg(long)]
        csv: Option<PathBuf>,
        /// Plot the recorded trajectory to this SVG file.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Replay in this scene: centred, offset:X or free[:X] (metres). The run's own scene
        /// (default) verifies the recording; another one re-simulates the design there and
        /// reports it like `simulate --scene` (it cannot be verified against the recording).
        #[arg(long)]
        scene: Option<String>,
        /// A robust run: replay scenario K of OBJECT (e.g. can:3) of the design, compare it
        /// with the recording and record it to RUN_DIR/scenario-ID-OBJECT-K.mcap.
        #[arg(long, conflicts_with_all = ["scene", "plot"])]
        scenario: Option<String>,
        /// Overwrite the --csv / --plot files if they exist (refused otherwise).
        #[arg(long)]
        force: bool,
    },
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
    /// Validate the optimiser on standard problems (ZDT1-3, DTLZ2, BNH, TNK, OSY, C2DTLZ2):
    /// hypervolume and IGD of the final feasible non-dominated set; exit 3 when a problem's
    /// hypervolume median lies outside the reference band.
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

/// Recording choice.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum RecordArg {
    /// Every design and the trajectory of every grasp simulated.
    All,
    /// Every design; trajectories of feasible designs only.
    Feasible,
    /// Design records only.
    Designs,
    /// Nothing.
    None,
}

/// Integration method choice, spelled as in a problem file's `solver.method`.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum MethodArg {
    /// Radau IIA order 5 (stiff; a problem's default).
    Radau5,
    /// TR-BDF2 (stiff, order 2).
    #[value(name = "trbdf2", alias = "tr-bdf2")]
    TrBdf2,
    /// Dormand–Prince 5(4) (explicit; comparison only).
    Dopri5,
    /// Dormand–Prince 5(4), switching to RADAU5 where stiff (automatic).
    Auto,
}

impl MethodArg {
    fn to_method(self) -> gripopt::sim::Method {
        match self {
            MethodArg::Radau5 => gripopt::sim::Method::Radau5,
            MethodArg::TrBdf2 => gripopt::sim::Method::TrBdf2,
            MethodArg::Dopri5 => gripopt::sim::Method::Dopri5,
            MethodArg::Auto => gripopt::sim::Method::Auto,
        }
    }
}

fn check_rtol(r: Option<f64>) -> Result<Option<f64>> {
    if let Some(v) = r {
        // the same range as the problem file's solver.rtol
        gripopt::params::limit("solver.rtol")
            .check(v)
            .map_err(|rule| anyhow::anyhow!("--rtol {}: {rule}", gripopt::params::fmt_num(v)))?;
    }
    Ok(r)
}

fn check_threads(t: Option<usize>) -> Result<()> {
    Ok(gripopt::run::check_threads(t)?)
}

/// What an optimise or resume run gets from the CLI: the progress bar and ctrl-c.
fn hooks() -> gripopt::run::RunHooks {
    gripopt::run::RunHooks {
        progress: Some(Box::new(progress::Bar::new())),
        stop: Some(progress::ctrl_c_flag()),
        evaluator: None,
    }
}

/// Refuse an output file (`--csv`, `--plot`) that exists unless `force`, or a folder, a
/// pipe or device, one of the command's `inputs` or an existing file inside an input folder
/// even with `force` ([`gripopt::check_output_file`], as `export --out`); `-` (standard output carries the
/// report), a file in a folder that does not exist, and a `--plot` not named `.svg` (the
/// plot is SVG): exit 2 before anything runs.
fn check_output(flag: &str, path: Option<&std::path::Path>, force: bool, inputs: &[&std::path::Path]) -> Result<()> {
    let Some(p) = path else { return Ok(()) };
    let refuse =
        |why: String| -> Result<()> { Err(gripopt::Error::Input(format!("{flag} {}: {why}", p.display())).into()) };
    if p.as_os_str() == "-" {
        return refuse("standard output carries the report; give a file name".into());
    }
    if let Some(d) = p.parent().filter(|d| !d.as_os_str().is_empty() && !d.is_dir()) {
        return refuse(format!("the folder {} does not exist", d.display()));
    }
    gripopt::check_output_file(flag, p, force, inputs)?;
    let svg = p.extension().is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if flag == "--plot" && !svg {
        return refuse("the plot is written as SVG; give a file name ending in .svg".into());
    }
    Ok(())
}

impl Cmd {
    /// Whether the command was asked for `--json` (its failure is then a JSON object on
    /// stdout too, [`out::report_error`]).
    fn json(&self) -> bool {
        match self {
            Cmd::Evaluate { json, .. }
            | Cmd::Simulate { json, .. }
            | Cmd::Optimise { json, .. }
            | Cmd::Replay { json, .. }
            | Cmd::Resume { json, .. }
            | Cmd::MooTest { json, .. }
            | Cmd::Bench { json, .. } => *json,
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
        Cmd::Simulate { problem, design, rtol, scene, object, method, json, csv, no_contact, trace, plot, force } => {
            check_output("--csv", csv.as_deref(), force, &[&problem])?;
            check_output("--plot", plot.as_deref(), force, &[&problem])?;
            let mut p = load_problem(&problem)?;
            // the robust objects' files are inputs too
            let objects = p.object_files(&problem);
            let inputs: Vec<&std::path::Path> = objects.iter().map(|f| f.as_path()).collect();
            check_output("--csv", csv.as_deref(), force, &inputs)?;
            check_output("--plot", plot.as_deref(), force, &inputs)?;
            if let Some(sc) = &scene {
                p = scenes::apply_scene(&p, &problem, sc)?;
            }
            let object = object.as_deref().map(|name| scenes::PickedObject::of(&p, name, &problem)).transpose()?;
            if p.robust.is_some() && object.is_none() {
                // as export and sweep say it; stderr, so that --json stays one JSON object
                eprintln!(
                    "note: {} has [robust]: simulate runs the reference [object] only, not the robust objects or scenarios; --object NAME simulates the design on one of its objects ({}) (docs/robust.md)",
                    problem.display(),
                    robust::object_names(&p)
                );
            }
            let x = design_of(&p, &design)?;
            let rtol = check_rtol(rtol)?;
            let o = scenes::SimulateOpts {
                rtol,
                method: method.map(MethodArg::to_method),
                contacts: !no_contact,
                trace,
                json,
                csv: csv.as_deref(),
                plot: plot.as_deref(),
                replay: None,
            };
            scenes::simulate_on(&p, &x, object.as_ref(), &o)
                .with_context(|| format!("simulating {}", problem.display()))
                .map(|_| 0)
        }
        Cmd::Optimise {
            problem,
            out,
            pop,
            generations,
            seed,
            threads,
            record,
            record_every,
            scene_ms,
            zstd_level,
            zstd_threads,
            record_full,
            json,
        } => {
            use gripopt::record::TrajectoryKeep;
            let (enabled, trajectories) = match record {
                RecordArg::All => (true, TrajectoryKeep::All),
                RecordArg::Feasible => (true, TrajectoryKeep::Feasible),
                RecordArg::Designs => (true, TrajectoryKeep::None),
                RecordArg::None => (false, TrajectoryKeep::None),
            };
            let rec = gripopt::record::RecordOptions {
                enabled,
                trajectories,
                every: record_every,
                scene_dt: scene_ms * 1e-3,
                zstd_level,
                zstd_threads,
                resolution: if record_full {
                    gripopt::record::Resolution::Full
                } else {
                    gripopt::record::Resolution::Compact
                },
                epoch_s: 0,
            };
            let spec =
                gripopt::run::RunSpec { problem_path: problem, out, pop, generations, seed, threads, record: rec };
            let s = gripopt::run::optimise_with(&spec, hooks())?;
            optcmd::summary(&s, json)
        }
        Cmd::Replay { run_dir, design, json, csv, plot, scene, scenario, force } => {
            check_output("--csv", csv.as_deref(), force, &[&run_dir])?;
            check_output("--plot", plot.as_deref(), force, &[&run_dir])?;
            if let Some(sc) = &scenario {
                return robust::replay_scenario(&run_dir, design, sc, json, csv.as_deref());
            }
            if let Some(sc) = &scene {
                if let Some(code) =
                    scenes::replay_in_scene(&run_dir, design, sc, json, csv.as_deref(), plot.as_deref())?
                {
                    return Ok(code);
                }
            }
            optcmd::replay(&run_dir, design, json, csv.as_deref(), plot.as_deref())
        }
        Cmd::Resume { run_dir, generations, force, threads, json } => {
            let s = gripopt::run::resume_with(&run_dir, generations, force, threads, hooks())?;
            optcmd::summary(&s, json)
        }
        Cmd::Show(a) => show::run(a).map(|_| 0),
        Cmd::MooTest { name, seed, seeds, json, pop, generations } => {
            if pop < 2 {
                anyhow::bail!("--pop {pop}: must be at least 2");
            }
            if generations == Some(0) {
                anyhow::bail!("--generations 0: must be at least 1");
            }
            gripopt::run::check_population(pop.max(4), generations.unwrap_or(250), false)?;
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
