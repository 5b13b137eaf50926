//! `gripopt sweep`: a parameter study on a grid — the spec checked before anything is
//! evaluated (the varied names, the bisections, the plotted keys against the plots this grid
//! draws), the grid evaluated (and the verdict's boundaries bisected) on a pool of its own,
//! then sweep.csv, boundaries.csv and the plots written (the sweep layer does each step).

use super::evaluate::in_pool;
use crate::error::{Error, Result};
use crate::fsutil::lock::RunLock;
use crate::params::{Design, Problem};
use crate::sweep::out::EarlierFile;
use crate::sweep::{self, Boundary, Row, Stage, SweepSpec, Vary};
use std::path::{Path, PathBuf};

/// What a sweep is asked for (the flags of `gripopt sweep`).
#[derive(Debug, Clone)]
pub struct SweepRequest {
    /// The problem file.
    pub problem: PathBuf,
    /// The varied names and their grids, `NAME=LO:HI:N` (1 to 3).
    pub vary: Vec<String>,
    /// The base design as `l21=..,b=..` (None: the problem's nominal).
    pub design: Option<String>,
    /// The stages to run.
    pub stage: Stage,
    /// Keep the base design's l_hand when l21 or b vary.
    pub hold_l_hand: bool,
    /// Apply ψ = 140 − 25.6 p at every point.
    pub psi_rule: bool,
    /// Maps: also colour by these record keys.
    pub color: Vec<String>,
    /// Line plots: these record keys (`+` joins keys in one plot; empty: the stage's own).
    pub ys: Vec<String>,
    /// Bisect the verdict's boundaries along these varied names.
    pub bisect: Vec<String>,
    /// Bisection steps per boundary (None: 20).
    pub bisect_steps: Option<u32>,
    /// Worker threads (None: all cores).
    pub threads: Option<usize>,
    /// The output folder.
    pub out: PathBuf,
}

/// A sweep's grid evaluated: its points and the verdict's boundaries.
#[derive(Debug, Clone)]
pub struct Swept {
    /// The points, in grid order.
    pub rows: Vec<Row>,
    /// The boundaries found by bisection.
    pub bounds: Vec<Boundary>,
}

/// The spec of `req`, with every check that needs no evaluation: an input error naming the
/// flag otherwise.
pub fn sweep_spec(req: &SweepRequest) -> Result<SweepSpec> {
    let bad = |m: String| Err(Error::Input(m));
    if req.vary.len() > 3 {
        return bad(format!("--vary: at most 3 names, {} given", req.vary.len()));
    }
    let problem = Problem::load(&req.problem)?;
    let design = match &req.design {
        None => problem.nominal,
        Some(s) => Design::parse_assignments(s)?,
    };
    let vary = req.vary.iter().map(|s| Vary::parse(s)).collect::<Result<Vec<_>>>()?;
    let spec =
        SweepSpec { problem, design, vary, stage: req.stage, hold_l_hand: req.hold_l_hand, psi_rule: req.psi_rule };
    spec.validate()?;
    for b in &req.bisect {
        if !spec.vary.iter().any(|v| &v.name == b) {
            let names: Vec<&str> = spec.vary.iter().map(|v| v.name.as_str()).collect();
            return bad(format!("--bisect {b}: not one of the varied names ({})", names.join(", ")));
        }
    }
    if req.threads == Some(0) {
        return bad("--threads 0: must be at least 1".into());
    }
    match req.bisect_steps {
        Some(n) if req.bisect.is_empty() => return bad(format!("--bisect-steps {n}: only with --bisect NAME")),
        Some(n) if !(1..=60).contains(&n) => return bad(format!("--bisect-steps {n}: 1 to 60")),
        _ => {}
    }
    // the plotted keys, before anything is evaluated: one the stage computes, and the flag
    // of the plots this grid draws (line plots for one varied name, else maps)
    sweep::out::check_plot_keys(&spec, "--y", &req.ys)?;
    sweep::out::check_plot_keys(&spec, "--color", &req.color)?;
    let line = sweep::plot::is_line(&spec);
    if line && !req.color.is_empty() {
        return bad("--color: maps are drawn for 2 or 3 varied names; this grid draws line plots (use --y KEY)".into());
    }
    if !line && !req.ys.is_empty() {
        return bad("--y: line plots are drawn for one varied name; this grid draws maps (use --color KEY)".into());
    }
    Ok(spec)
}

/// The output folder, locked, and its earlier sweep files, checked before anything is
/// evaluated (a run folder, a file a sweep did not write: refused); an earlier sweep's files
/// are replaced. The lock is held while the returned guard lives.
pub fn open_sweep_folder(dir: &Path) -> Result<(RunLock, Vec<EarlierFile>)> {
    sweep::out::open_out_folder(dir)
}

/// The varied names only stage 3 uses, where `spec`'s stage stops before it (every point is
/// the same in them).
pub fn unused_names(spec: &SweepSpec) -> Vec<String> {
    if spec.stage == Stage::Dynamic {
        return vec![];
    }
    sweep::stage3_only_names(spec).into_iter().map(String::from).collect()
}

/// Evaluate the grid of `spec` (`tick`: one more point) and bisect the boundaries `req`
/// asks for, on `req.threads` threads.
pub fn run_sweep(spec: &SweepSpec, req: &SweepRequest, tick: &(dyn Fn() + Sync)) -> Result<Swept> {
    in_pool(req.threads, || {
        let rows = sweep::run(spec, tick)?;
        let mut bounds = Vec::new();
        for name in &req.bisect {
            bounds.extend(sweep::bisect(spec, &rows, name, req.bisect_steps.unwrap_or(20))?);
        }
        Ok(Swept { rows, bounds })
    })?
}

/// The plotted keys (`--y`, `--color`) no point has a value of: (flag, keys).
pub fn empty_plots<'a>(req: &'a SweepRequest, rows: &[Row]) -> Vec<(&'static str, &'a str)> {
    let asked = req.ys.iter().map(|v| ("--y", v.as_str())).chain(req.color.iter().map(|v| ("--color", v.as_str())));
    asked.filter(|(_, v)| v.split('+').all(|k| rows.iter().all(|r| r.num(k).is_none()))).collect()
}

/// Write sweep.csv (first, listing every file this sweep writes: a sweep stopped halfway
/// leaves nothing a later one cannot attribute), boundaries.csv and the plots into
/// `req.out` (`earlier`: [`open_sweep_folder`]'s), then seal sweep.csv with each file's
/// SHA-256: the plots written.
pub fn write_sweep(
    spec: &SweepSpec,
    req: &SweepRequest,
    swept: &Swept,
    earlier: &[EarlierFile],
) -> Result<Vec<PathBuf>> {
    let ys: Vec<String> = if !req.ys.is_empty() {
        req.ys.clone()
    } else {
        match spec.stage {
            Stage::Dynamic => vec!["e_cyl+e_lim".into(), "t_stab".into()],
            Stage::Static => vec!["alpha".into(), "mean_force".into(), "max_offset".into()],
            Stage::Kinematics => vec!["min_margin_deg".into()],
        }
    };
    let mut planned = sweep::plot::planned(spec, &ys, &req.color);
    if !req.bisect.is_empty() {
        planned.push(sweep::out::BOUNDARIES_FILE.into());
    }
    sweep::write_outputs(&req.out, spec, &swept.rows, earlier, &planned)?;
    if !req.bisect.is_empty() {
        sweep::write_boundaries(&req.out, spec, &swept.bounds)?;
    }
    let files = sweep::plot::plot_all(&req.out, spec, &swept.rows, &ys, &req.color, &swept.bounds)?;
    sweep::seal(&req.out, spec, &swept.rows, &planned)?;
    Ok(files)
}
