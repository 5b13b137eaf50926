//! `gripopt sweep`: a parameter study on a grid (see `gripopt::app::sweep_spec`).

use anyhow::Result;
use gripopt::app::sweeps::{Boundary, Row, Stage};
use gripopt::app::SweepRequest;
use std::path::{Path, PathBuf};

/// The `sweep` subcommand's arguments.
#[derive(clap::Args)]
pub struct SweepArgs {
    /// Problem file (TOML).
    pub problem: PathBuf,
    /// A varied name and its grid, NAME=LO:HI:N (1 to 3 times; the first varies fastest).
    /// NAME: a design variable (l21, b, t22, r, p, psi_deg), a derived one (l11: p = l11/l21
    /// and psi = 140 - 25.6 p; l22: r = l22/l11; l_hand: t22 = (l_hand - b - 2 l21)/2), or a
    /// numeric problem-file field (tau, density, grasp_height, radius, restitution, hand.w, scene.x_off …),
    /// or mu_scale (the phalanx friction coefficients scaled; stage 3 only). A [scene] field
    /// the problem's scene kind does not simulate is refused (scene.x_off: offset or free;
    /// scene.t_obs, scene.ground_*: free).
    #[arg(long = "vary", required = true)]
    pub vary: Vec<String>,
    /// Base design as l21=..,b=..,t22=..,r=..,p=..,psi_deg=.. (default: the problem's nominal).
    #[arg(long)]
    pub design: Option<String>,
    /// Stages to run: kinematics (0-1), static (0-2) or dynamic (0-3).
    #[arg(long, value_enum, default_value = "dynamic")]
    pub stage: StageArg,
    /// Keep the base design's l_hand when l21 or b vary (t22 derived), as the thesis does.
    #[arg(long)]
    pub hold_l_hand: bool,
    /// Apply psi = 140 - 25.6 p (thesis eq. 4.15) at every point (implied by --vary l11); not
    /// with --vary psi_deg.
    #[arg(long)]
    pub psi_rule: bool,
    /// Maps: also colour by this record key (e.g. max_offset, alpha, t_stab, e_cyl); repeatable.
    #[arg(long)]
    pub color: Vec<String>,
    /// Line plots (one varied name): record keys to plot, `+` joins keys in one plot
    /// (default: e_cyl+e_lim and t_stab for dynamic, alpha, mean_force and max_offset for static,
    /// min_margin_deg for kinematics).
    #[arg(long = "y")]
    pub ys: Vec<String>,
    /// Refine the boundaries where the verdict flips along this varied name by bisection
    /// (written to DIR/boundaries.csv).
    #[arg(long)]
    pub bisect: Vec<String>,
    /// Bisection steps per boundary, 1 to 60 (default 20; only with --bisect).
    #[arg(long)]
    pub bisect_steps: Option<u32>,
    /// Worker threads (default: all cores; results do not depend on it).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Output folder (created): sweep.csv, plots, boundaries.csv.
    #[arg(long)]
    pub out: PathBuf,
}

/// `--stage`.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum StageArg {
    /// Stages 0-1.
    Kinematics,
    /// Stages 0-2.
    Static,
    /// Stages 0-3.
    Dynamic,
}

/// The request of the arguments.
fn request(a: &SweepArgs) -> SweepRequest {
    let stage = match a.stage {
        StageArg::Kinematics => Stage::Kinematics,
        StageArg::Static => Stage::Static,
        StageArg::Dynamic => Stage::Dynamic,
    };
    SweepRequest {
        problem: a.problem.clone(),
        vary: a.vary.clone(),
        design: a.design.clone(),
        stage,
        hold_l_hand: a.hold_l_hand,
        psi_rule: a.psi_rule,
        color: a.color.clone(),
        ys: a.ys.clone(),
        bisect: a.bisect.clone(),
        bisect_steps: a.bisect_steps,
        threads: a.threads,
        out: a.out.clone(),
    }
}

/// Run the sweep.
pub fn run(a: SweepArgs) -> Result<()> {
    let req = request(&a);
    // every check that needs no evaluation, then the folder, locked, before anything is
    // evaluated (a run folder, a file a sweep did not write: refused); an earlier sweep's
    // files are replaced
    let spec = gripopt::app::sweep_spec(&req)?;
    let (_lock, earlier) = gripopt::app::open_sweep_folder(&a.out)?;
    if spec.problem.robust.is_some() {
        // said before anything runs: a sweep evaluates the single-object pipeline
        eprintln!(
            "note: {} has [robust]: a sweep varies and evaluates the reference [object] and [scene] only; the robust objects and scenarios are not evaluated (docs/robust.md)",
            crate::cli::out::path(&a.problem)
        );
    }
    let late = gripopt::app::unused_names(&spec);
    if !late.is_empty() {
        eprintln!(
            "warning: --vary {}: only stage 3 (the simulated grasp) uses it, and --stage {} stops before it: every point is the same in it (--stage dynamic)",
            late.join(", "),
            if spec.stage == Stage::Static { "static" } else { "kinematics" }
        );
    }
    let pb = indicatif::ProgressBar::new(spec.len() as u64);
    pb.set_style(
        indicatif::ProgressStyle::with_template("sweep [{bar:30}] {pos}/{len} points, ETA {eta}").expect("template"),
    );
    let swept = gripopt::app::run_sweep(&spec, &req, &|| pb.inc(1))?;
    pb.finish_and_clear();
    for (flag, v) in gripopt::app::empty_plots(&req, &swept.rows) {
        eprintln!("warning: {flag} {v}: no point of the sweep has a value (each was discarded before the stage that computes it, or it was not finite); its plot is empty");
    }
    let files = gripopt::app::write_sweep(&spec, &req, &swept, &earlier)?;
    summary(&a.out, &swept.rows, &swept.bounds, &files);
    Ok(())
}

fn summary(out: &Path, rows: &[Row], bounds: &[Boundary], files: &[PathBuf]) {
    let mut counts: Vec<(&str, usize)> = Vec::new();
    for r in rows {
        match counts.iter_mut().find(|c| c.0 == r.verdict) {
            Some(c) => c.1 += 1,
            None => counts.push((r.verdict, 1)),
        }
    }
    outln!(
        "{} point{}: {}",
        rows.len(),
        if rows.len() == 1 { "" } else { "s" },
        counts.iter().map(|(v, n)| format!("{v} {n}")).collect::<Vec<_>>().join(", ")
    );
    for b in bounds {
        let o = if b.others.is_empty() { String::new() } else { format!(" at {:?}", b.others) };
        outln!("boundary {}{}: {} at {} | {} at {}", b.name, o, b.verdict_lo, b.lo, b.verdict_hi, b.hi);
    }
    outln!("wrote {}", crate::cli::out::path(&out.join("sweep.csv")));
    for f in files {
        outln!("wrote {}", crate::cli::out::path(f));
    }
}
