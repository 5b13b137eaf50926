//! `gripopt show`: what a run folder says of its run, typed — its state (running, stopped
//! and resumable, interrupted, finished), its front or archive sorted by an objective (the
//! designs of its checkpoint, or of the views before the first one), what does not agree in
//! the folder, whether verify.csv checked the run's current state; or one design in full.
//! The CLI renders it (text or JSON).

use crate::error::{Error, Result};
use crate::eval::{objective_names, Objective, Sense, OBJECTIVES};
use crate::run::{CheckpointTables, DesignRow, RunFolder, RunInfo, RunState, VerifiedGeneration};
use std::path::Path;

/// What `show` is asked for.
#[derive(Debug, Clone)]
pub struct ShowRequest {
    /// Sort by this objective (its name), best first.
    pub best: String,
    /// The archive (every feasible non-dominated design of the run) instead of the front.
    pub archive: bool,
    /// At most this many designs (0: all).
    pub limit: usize,
}

/// A run as `show` shows it.
#[derive(Debug, Clone)]
pub struct RunView {
    /// run.json.
    pub info: RunInfo,
    /// What the run is doing.
    pub state: RunState,
    /// `gripopt resume` can continue it now.
    pub resumable: bool,
    /// What does not agree in the folder (run.json or a view against checkpoint.json, a
    /// verify.csv that cannot be read); the designs shown are the checkpoint's.
    pub warnings: Vec<String>,
    /// What verify.csv checked (None: no verify.csv), and whether that is the run's current
    /// state (its last checkpoint).
    pub verified: Option<(VerifiedGeneration, bool)>,
    /// The verify table's file name (verify.csv or verify_robust.csv).
    pub verify_file: &'static str,
    /// The generation of the checkpoint the designs come from (None: the views, before the
    /// first checkpoint).
    pub checkpoint_generation: Option<u64>,
    /// The view the designs are: pareto.csv or archive.csv.
    pub file: &'static str,
    /// No generation completed yet: nothing to show.
    pub none_yet: bool,
    /// The objective sorted by.
    pub best: &'static Objective,
    /// The designs, best first (those without the value last), at most the limit.
    pub rows: Vec<DesignRow>,
    /// Why no design is feasible (None when one is).
    pub no_feasible: Option<Vec<String>>,
    /// The run's step budget (its problem's `solver.max_steps`), for the discard lines.
    pub max_steps: Option<u64>,
}

/// One design as `show --design ID` shows it.
#[derive(Debug, Clone)]
pub struct DesignView {
    /// Its row.
    pub row: DesignRow,
    /// The table it is in: pareto.csv, archive.csv or population.csv.
    pub file: &'static str,
    /// It was found in the checkpoint (else in the views, before the first checkpoint).
    pub from_checkpoint: bool,
    /// What does not agree in the folder.
    pub warnings: Vec<String>,
    /// The run recorded its designs (a design can be replayed).
    pub recorded: bool,
}

/// The objective named `name`: an input error naming `--best` otherwise.
pub fn objective_named(name: &str) -> Result<&'static Objective> {
    OBJECTIVES
        .iter()
        .find(|o| o.name == name)
        .ok_or_else(|| Error::Input(format!("--best {name}: expected one of {}", objective_names().join(", "))))
}

/// The objectives of a design row, in the order of [`OBJECTIVES`].
pub fn row_objectives(r: &DesignRow) -> [Option<f64>; 4] {
    [r.max_offset, r.alpha, r.mean_force, r.t_stab]
}

/// The folder's warnings about its state: run.json against the checkpoint, a missing
/// checkpoint of a run that completed generations.
fn folder_warnings(tables: Option<&CheckpointTables>, info: &RunInfo) -> Vec<String> {
    let mut warnings: Vec<String> = vec![];
    if let Some(m) = tables.and_then(|t| t.run_json_mismatch.as_ref()) {
        warnings.push(format!("run.json {m}"));
    }
    if tables.is_none() && info.completed_generations > 0 {
        warnings.push(format!(
            "checkpoint.json is missing, but run.json records {} completed generations: the designs shown are the views' (pareto.csv, archive.csv), unchecked; restore checkpoint.json (e.g. from a backup)",
            info.completed_generations
        ));
    }
    warnings
}

/// The run in `dir` as `show` shows it.
pub fn show_run(dir: &Path, req: &ShowRequest) -> Result<RunView> {
    let best = objective_named(&req.best)?;
    let folder = RunFolder::open(dir)?;
    let file = if req.archive { "archive.csv" } else { "pareto.csv" };
    let info = folder.info()?;
    // the designs of the run's state (its checkpoint), not the views a user may replace
    let tables = folder.checkpoint_tables()?;
    let mut warnings = folder_warnings(tables.as_ref(), &info);
    let state = folder.state()?;
    let resumable = folder.resumable()?;
    // a verify.csv that cannot be read (a pipe, a folder, a damaged `# run:` line) is a
    // warning: the run itself is shown
    let verified = folder.verified_generation().unwrap_or_else(|e| {
        warnings.push(format!("not read: {e}"));
        None
    });
    let current = |v: &VerifiedGeneration| info.checkpoint_sha256.as_deref() == Some(&v.checkpoint_sha256);
    let verified = verified.map(|v| {
        let now = current(&v);
        (v, now)
    });
    // a run killed in its first generation has no table yet
    let none_yet = tables.is_none() && info.completed_generations == 0 && !dir.join(file).exists();
    let mut rows = match (&tables, none_yet, req.archive) {
        (Some(t), ..) => {
            let rows = if req.archive { t.archive.clone() } else { t.front.clone() };
            // a running run's views follow its checkpoints at their own pace
            if !matches!(state, RunState::Running(_)) {
                warnings.extend(folder.view_differs(file, &rows, t.generation)?);
            }
            rows
        }
        (None, true, _) => vec![],
        (None, false, true) => folder.archive()?,
        (None, false, false) => folder.front()?,
    };
    sort_best_first(&mut rows, best);
    if req.limit > 0 {
        rows.truncate(req.limit);
    }
    let max_steps = if rows.is_empty() { folder.problem().ok().map(|p| p.solver.max_steps) } else { None };
    Ok(RunView {
        no_feasible: info.discards.explain(),
        verify_file: folder.verify_file().unwrap_or("verify.csv"),
        checkpoint_generation: tables.as_ref().map(|t| t.generation),
        info,
        state,
        resumable,
        warnings,
        verified,
        file,
        none_yet,
        best,
        rows,
        max_steps,
    })
}

/// Sort `rows` by objective `best`, best first; designs without the value last, whichever
/// way the objective is better; ties by id.
fn sort_best_first(rows: &mut [DesignRow], best: &Objective) {
    let k = OBJECTIVES.iter().position(|o| o.name == best.name).expect("one of the objectives");
    let maximise = best.sense == Sense::Maximise;
    rows.sort_by(|x, y| {
        let (a, b) = (row_objectives(x)[k].filter(|v| !v.is_nan()), row_objectives(y)[k].filter(|v| !v.is_nan()));
        let o = match (a, b) {
            (Some(a), Some(b)) if maximise => b.total_cmp(&a),
            (Some(a), Some(b)) => a.total_cmp(&b),
            (Some(_), None) => std::cmp::Ordering::Less,
            (None, Some(_)) => std::cmp::Ordering::Greater,
            (None, None) => std::cmp::Ordering::Equal,
        };
        o.then_with(|| x.id.cmp(&y.id))
    });
}

/// Design `id` of the run in `dir` and the table it is in: the checkpoint's front, archive or
/// population (or, before the first checkpoint, the views pareto.csv, archive.csv,
/// population.csv). An input error when the run has no such design, or no longer holds it.
pub fn show_design(dir: &Path, id: u64) -> Result<DesignView> {
    let folder = RunFolder::open(dir)?;
    let info = folder.info()?;
    let tables = folder.checkpoint_tables()?;
    let warnings = folder_warnings(tables.as_ref(), &info);
    let recorded = info.recording.enabled;
    let Some((row, file)) = find_design(&folder, tables.as_ref(), id)? else {
        return Err(Error::Input(not_found(dir, id, &info)));
    };
    Ok(DesignView { row, file, from_checkpoint: tables.is_some(), warnings, recorded })
}

/// Why design `id` is not shown: ids are 0, 1, … in the order of evaluation, so one the
/// run never had is no older design (and replay would not find it either); an older one
/// is replayed where the run was recorded.
fn not_found(dir: &Path, id: u64, info: &RunInfo) -> String {
    let d = crate::error::shell_quote(&dir.to_string_lossy());
    let n = info.evaluations;
    if id >= n {
        let ids =
            if n == 0 { "it has evaluated no design yet".to_string() } else { format!("its ids are 0 to {}", n - 1) };
        return format!(
            "--design {id}: the run {d} has no design {id}: {ids} (run.json: {n} evaluations at its last checkpoint)"
        );
    }
    let older = if info.recording.enabled {
        format!("older designs: `gripopt replay {d} --design {id}`")
    } else {
        "older designs are not kept: the run was not recorded".into()
    };
    format!("--design {id}: not in pareto.csv, archive.csv or population.csv of {d} ({older})")
}

/// Design `id` and the table it is in.
fn find_design(
    folder: &RunFolder,
    tables: Option<&CheckpointTables>,
    id: u64,
) -> Result<Option<(DesignRow, &'static str)>> {
    if let Some(t) = tables {
        let found = [("pareto.csv", &t.front), ("archive.csv", &t.archive), ("population.csv", &t.population)]
            .into_iter()
            .find_map(|(f, rows)| rows.iter().find(|r| r.id == id).map(|r| (r.clone(), f)));
        return Ok(found);
    }
    for (f, read) in [
        ("pareto.csv", RunFolder::front as fn(&RunFolder) -> Result<Vec<DesignRow>>),
        ("archive.csv", RunFolder::archive),
        ("population.csv", RunFolder::population),
    ] {
        // a file not written (yet) is skipped; a damaged one is an error
        if !folder.dir().join(f).exists() {
            continue;
        }
        if let Some(row) = read(folder)?.into_iter().find(|r| r.id == id) {
            return Ok(Some((row, f)));
        }
    }
    Ok(None)
}
