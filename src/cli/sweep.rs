//! `gripopt sweep`: a parameter study on a grid (see `gripopt::sweep`).

use anyhow::Result;
use gripopt::params::{Design, Problem};
use gripopt::sweep::{self, Stage, SweepSpec, Vary};
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

/// Build the spec from the arguments (all checks that need no evaluation).
pub fn spec_of(a: &SweepArgs) -> Result<SweepSpec> {
    if a.vary.len() > 3 {
        anyhow::bail!("--vary: at most 3 names, {} given", a.vary.len());
    }
    let problem = Problem::load(&a.problem)?;
    let design = match &a.design {
        None => problem.nominal,
        Some(s) => Design::parse_assignments(s)?,
    };
    let vary = a.vary.iter().map(|s| Vary::parse(s)).collect::<Result<Vec<_>, _>>()?;
    let stage = match a.stage {
        StageArg::Kinematics => Stage::Kinematics,
        StageArg::Static => Stage::Static,
        StageArg::Dynamic => Stage::Dynamic,
    };
    let spec = SweepSpec { problem, design, vary, stage, hold_l_hand: a.hold_l_hand, psi_rule: a.psi_rule };
    spec.validate()?;
    for b in &a.bisect {
        if !spec.vary.iter().any(|v| &v.name == b) {
            anyhow::bail!(
                "--bisect {b}: not one of the varied names ({})",
                spec.vary.iter().map(|v| v.name.as_str()).collect::<Vec<_>>().join(", ")
            );
        }
    }
    if a.threads == Some(0) {
        anyhow::bail!("--threads 0: must be at least 1");
    }
    match a.bisect_steps {
        Some(n) if a.bisect.is_empty() => anyhow::bail!("--bisect-steps {n}: only with --bisect NAME"),
        Some(n) if !(1..=60).contains(&n) => anyhow::bail!("--bisect-steps {n}: 1 to 60"),
        _ => {}
    }
    // the plotted keys, before anything is evaluated: one the stage computes, and the flag
    // of the plots this grid draws (line plots for one varied name, else maps)
    sweep::out::check_plot_keys(&spec, "--y", &a.ys)?;
    sweep::out::check_plot_keys(&spec, "--color", &a.color)?;
    let line = sweep::plot::is_line(&spec);
    if line && !a.color.is_empty() {
        anyhow::bail!("--color: maps are drawn for 2 or 3 varied names; this grid draws line plots (use --y KEY)");
    }
    if !line && !a.ys.is_empty() {
        anyhow::bail!("--y: line plots are drawn for one varied name; this grid draws maps (use --color KEY)");
    }
    Ok(spec)
}

/// Run the sweep.
pub fn run(a: SweepArgs) -> Result<()> {
    let spec = spec_of(&a)?;
    // the folder is locked and checked before anything is evaluated (a run folder, a file a
    // sweep did not write: refused); an earlier sweep's files are replaced
    let (_lock, earlier) = sweep::out::open_out_folder(&a.out)?;
    if spec.problem.robust.is_some() {
        // said before anything runs: a sweep evaluates the single-object pipeline
        eprintln!(
            "note: {} has [robust]: a sweep varies and evaluates the reference [object] and [scene] only; the robust objects and scenarios are not evaluated (docs/robust.md)",
            crate::cli::out::path(&a.problem)
        );
    }
    let late = sweep::stage3_only_names(&spec);
    if spec.stage != Stage::Dynamic && !late.is_empty() {
        eprintln!(
            "warning: --vary {}: only stage 3 (the simulated grasp) uses it, and --stage {} stops before it: every point is the same in it (--stage dynamic)",
            late.join(", "),
            if spec.stage == Stage::Static { "static" } else { "kinematics" }
        );
    }
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(t) = a.threads {
        b = b.num_threads(t);
    }
    let pool = b.build()?;
    let pb = indicatif::ProgressBar::new(spec.len() as u64);
    pb.set_style(
        indicatif::ProgressStyle::with_template("sweep [{bar:30}] {pos}/{len} points, ETA {eta}").expect("template"),
    );
    let rows = pool.install(|| sweep::run(&spec, &|| pb.inc(1)))?;
    pb.finish_and_clear();
    let mut bounds = Vec::new();
    for name in &a.bisect {
        bounds.extend(pool.install(|| sweep::bisect(&spec, &rows, name, a.bisect_steps.unwrap_or(20)))?);
    }
    for (flag, v) in a.ys.iter().map(|v| ("--y", v)).chain(a.color.iter().map(|v| ("--color", v))) {
        if v.split('+').all(|k| rows.iter().all(|r| r.num(k).is_none())) {
            eprintln!("warning: {flag} {v}: no point of the sweep has a value (each was discarded before the stage that computes it, or it was not finite); its plot is empty");
        }
    }
    let ys: Vec<String> = if !a.ys.is_empty() {
        a.ys.clone()
    } else {
        match spec.stage {
            Stage::Dynamic => vec!["e_cyl+e_lim".into(), "t_stab".into()],
            Stage::Static => vec!["alpha".into(), "mean_force".into(), "max_offset".into()],
            Stage::Kinematics => vec!["min_margin_deg".into()],
        }
    };
    // sweep.csv first, listing every file this sweep writes (a sweep stopped halfway
    // leaves nothing a later one cannot attribute)
    let mut planned = sweep::plot::planned(&spec, &ys, &a.color);
    if !a.bisect.is_empty() {
        planned.push(sweep::out::BOUNDARIES_FILE.into());
    }
    sweep::write_outputs(&a.out, &spec, &rows, &earlier, &planned)?;
    if !a.bisect.is_empty() {
        sweep::write_boundaries(&a.out, &spec, &bounds)?;
    }
    let files = sweep::plot::plot_all(&a.out, &spec, &rows, &ys, &a.color, &bounds)?;
    sweep::seal(&a.out, &spec, &rows, &planned)?;
    summary(&a.out, &rows, &bounds, &files);
    Ok(())
}

fn summary(out: &Path, rows: &[sweep::Row], bounds: &[sweep::Boundary], files: &[PathBuf]) {
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
