//! `gripopt show RUN`: a run's state (running, stopped and resumable, interrupted,
//! finished), its front sorted by an objective, with units, each design with its replay
//! command (text or JSON); when no design is feasible, why; whether verify.csv checked the
//! run's current generation. Reads the run's files through the library's run folder reader,
//! typed (they are rewritten every generation, so a running run can be shown too).

use crate::cli::out::path as quoted;
use anyhow::{bail, Result};
use gripopt::run::{CheckpointTables, DesignRow, RunFolder, RunInfo, RunState, DESIGN_COLUMNS};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// Arguments of `gripopt show`.
#[derive(clap::Args)]
pub struct ShowArgs {
    /// Run folder.
    run_dir: PathBuf,
    /// Sort the front by this objective, best first: max_offset, alpha, mean_force, t_stab.
    #[arg(long, default_value = "max_offset")]
    best: String,
    /// Show one design (of the front, the archive or the final population) in full.
    #[arg(long)]
    design: Option<u64>,
    /// Show the archive (every feasible non-dominated design of the run) instead of the
    /// population's front.
    #[arg(long)]
    archive: bool,
    /// At most this many designs (0 = all).
    #[arg(long, default_value_t = 0)]
    limit: usize,
    /// One JSON object: the run's status and the designs, with units.
    #[arg(long)]
    pub(crate) json: bool,
}

fn unit(name: &str) -> &'static str {
    DESIGN_COLUMNS.iter().find(|c| c.0 == name).map(|c| c.1).or_else(|| gripopt::run::robust_unit(name)).unwrap_or("")
}

/// A design as `show --json` lists it: its row's columns in the file's order (`reason` as
/// JSON text, null when none, not the CSV's quoted cell) and its replay command.
struct Shown<'a> {
    row: &'a DesignRow,
    /// None: the run was not recorded (`--record none`), nothing to replay.
    replay: Option<String>,
}

impl Serialize for Shown<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::{Error, SerializeMap};
        let values = match serde_json::to_value(self.row).map_err(S::Error::custom)? {
            serde_json::Value::Object(values) => values,
            _ => return Err(S::Error::custom("a design row is a map")),
        };
        let mut m = s.serialize_map(None)?;
        for (column, _) in self.row.text_cells() {
            match column.as_str() {
                "reason" => m.serialize_entry(&column, &self.row.reason)?,
                _ => m.serialize_entry(&column, &values.get(&column))?,
            }
        }
        m.serialize_entry("replay", &self.replay)?;
        m.end()
    }
}

/// A value with its unit (`show --design ID --json`).
#[derive(Serialize)]
struct WithUnit {
    value: serde_json::Value,
    unit: &'static str,
}

/// `show --json`.
#[derive(Serialize)]
struct ShowJson<'a> {
    run_dir: String,
    /// running, stopped (killed or crashed), interrupted or finished.
    status: &'static str,
    /// The pid of the process running it (status running).
    pid: Option<u32>,
    /// `gripopt resume` can continue it now.
    resumable: bool,
    completed_generations: u64,
    generations: u64,
    evaluations: u64,
    /// Why no design is feasible (null when one is).
    no_feasible_design: Option<Vec<String>>,
    /// What verify.csv checked (null: no verify.csv).
    verify: Option<VerifyJson>,
    /// What does not agree in the folder: run.json or a CSV view against checkpoint.json
    /// (the designs shown are the checkpoint's); empty when all agree.
    warnings: Vec<String>,
    /// Where the designs come from: checkpoint.json (or the view `file` before the first
    /// checkpoint).
    source: &'static str,
    file: &'a str,
    sorted_by: &'a str,
    direction: &'a str,
    /// Every column's unit, a robust run's per-object columns included.
    units: BTreeMap<String, &'static str>,
    designs: Vec<Shown<'a>>,
}

/// `show --json`'s verify.csv.
#[derive(Serialize)]
struct VerifyJson {
    /// The run's completed generations when verify.csv was written.
    generation: u64,
    /// It checked the run's current state (the last checkpoint).
    current: bool,
}

/// The run's state in words, with what to do (text of `show`).
fn state_text(state: RunState, info: &RunInfo, dir: &std::path::Path, resumable: bool) -> String {
    let d = quoted(dir);
    let g = format!("{} of {} generations", info.completed_generations, info.generations);
    match state {
        RunState::Running(pid) => format!("running{}, {g}", pid.map(|p| format!(" (pid {p})")).unwrap_or_default()),
        RunState::Stopped if resumable => format!("stopped (killed or crashed), {g}; resumable: `gripopt resume {d}`"),
        RunState::Stopped => format!(
            "stopped (killed or crashed) before its first checkpoint; nothing to resume: `{}`",
            info.optimise_command(dir)
        ),
        RunState::Interrupted => format!("interrupted, {g}; resume with `gripopt resume {d}`"),
        RunState::Finished => format!("finished, {g}"),
    }
}

/// The objective `name` of a row.
fn objective(r: &DesignRow, name: &str) -> Option<f64> {
    match name {
        "max_offset" => r.max_offset,
        "alpha" => r.alpha,
        "mean_force" => r.mean_force,
        _ => r.t_stab,
    }
}

/// Design `id` and the table it is in: the checkpoint's front, archive or population (or,
/// before the first checkpoint, the views pareto.csv, archive.csv, population.csv).
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
        ("pareto.csv", RunFolder::front as fn(&RunFolder) -> gripopt::Result<Vec<DesignRow>>),
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

/// `gripopt show`.
pub fn run(a: ShowArgs) -> Result<()> {
    let dir = &a.run_dir;
    let Some(best) = gripopt::eval::OBJECTIVES.iter().find(|o| o.name == a.best) else {
        bail!("--best {}: expected one of {}", a.best, gripopt::eval::objective_names().join(", "));
    };
    let (obj, maximise) = (best.name, best.sense == gripopt::eval::Sense::Maximise);
    let folder = RunFolder::open(dir)?;
    let file = if a.archive { "archive.csv" } else { "pareto.csv" };
    let run = folder.info()?;
    // a run recorded nothing (`--record none`): no design can be replayed
    let replay = |id: u64| run.recording.enabled.then(|| format!("gripopt replay {} --design {id}", quoted(dir)));
    let not_recorded = "not recorded (run.json: the run was started with `--record none`), nothing to replay";
    // the designs of the run's state (its checkpoint), not the views a user may replace
    let tables = folder.checkpoint_tables()?;
    let mut warnings: Vec<String> = vec![];
    if let Some(m) = tables.as_ref().and_then(|t| t.run_json_mismatch.as_ref()) {
        warnings.push(format!("run.json {m}"));
    }
    if tables.is_none() && run.completed_generations > 0 {
        warnings.push(format!(
            "checkpoint.json is missing, but run.json records {} completed generations: the designs shown are the views' (pareto.csv, archive.csv), unchecked; restore checkpoint.json (e.g. from a backup)",
            run.completed_generations
        ));
    }
    if let Some(id) = a.design {
        let Some((row, f)) = find_design(&folder, tables.as_ref(), id)? else {
            // ids are 0, 1, … in the order of evaluation: one the run never had is no older
            // design, and replay would not find it either
            let n = run.evaluations;
            if id >= n {
                let ids = if n == 0 {
                    "it has evaluated no design yet".to_string()
                } else {
                    format!("its ids are 0 to {}", n - 1)
                };
                bail!(
                    "--design {id}: the run {} has no design {id}: {ids} (run.json: {n} evaluations at its last checkpoint)",
                    quoted(dir)
                );
            }
            let older = match replay(id) {
                Some(r) => format!("older designs: `{r}`"),
                None => "older designs are not kept: the run was not recorded".into(),
            };
            bail!("--design {id}: not in pareto.csv, archive.csv or population.csv of {} ({older})", quoted(dir))
        };
        for w in &warnings {
            eprintln!("warning: {w}");
        }
        let cells = row.text_cells();
        if a.json {
            let mut m: BTreeMap<String, serde_json::Value> = BTreeMap::new();
            if let serde_json::Value::Object(values) = serde_json::to_value(&row)? {
                for (k, value) in values {
                    let u = unit(&k);
                    m.insert(k, serde_json::to_value(WithUnit { value, unit: u })?);
                }
            }
            m.insert("file".into(), f.into());
            m.insert("replay".into(), replay(id).into());
            outln!("{}", serde_json::to_string_pretty(&m)?);
        } else {
            // before the first checkpoint the views themselves; then the checkpoint, which
            // they show
            let from = if tables.is_some() { format!("the checkpoint, as in {f}") } else { f.to_string() };
            outln!("design {id} (from {from})");
            for (k, v) in &cells {
                let u = unit(k);
                let u = if matches!(u, "-" | "text" | "bool") { String::new() } else { format!(" {u}") };
                outln!("  {k:<14} {}{u}", if v.is_empty() { "—" } else { v });
            }
            outln!("  replay: {}", replay(id).as_deref().unwrap_or(not_recorded));
        }
        return Ok(());
    }
    let state = folder.state()?;
    let resumable = folder.resumable()?;
    // a verify.csv that cannot be read (a pipe, a folder, a damaged `# run:` line) is a
    // warning: the run itself is shown
    let verified = folder.verified_generation().unwrap_or_else(|e| {
        warnings.push(format!("not read: {e}"));
        None
    });
    let verify_current =
        |v: &gripopt::run::VerifiedGeneration| run.checkpoint_sha256.as_deref() == Some(&v.checkpoint_sha256);
    let why_none = run.discards.explain();
    // a run killed in its first generation has no table yet
    let none_yet = tables.is_none() && run.completed_generations == 0 && !dir.join(file).exists();
    let mut rows = match (&tables, none_yet, a.archive) {
        (Some(t), ..) => {
            let rows = if a.archive { t.archive.clone() } else { t.front.clone() };
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
    rows.sort_by(|x, y| {
        // designs without the value go last, whichever way the objective is better
        let (a, b) = (objective(x, obj).filter(|v| !v.is_nan()), objective(y, obj).filter(|v| !v.is_nan()));
        let o = match (a, b) {
            (Some(a), Some(b)) if maximise => b.total_cmp(&a),
            (Some(a), Some(b)) => a.total_cmp(&b),
            (Some(_), None) => std::cmp::Ordering::Less,
            (None, Some(_)) => std::cmp::Ordering::Greater,
            (None, None) => std::cmp::Ordering::Equal,
        };
        o.then_with(|| x.id.cmp(&y.id))
    });
    if a.limit > 0 {
        rows.truncate(a.limit);
    }
    if a.json {
        let v = ShowJson {
            run_dir: dir.display().to_string(),
            status: state.word(),
            pid: match state {
                RunState::Running(pid) => pid,
                _ => None,
            },
            resumable,
            completed_generations: run.completed_generations,
            generations: run.generations,
            evaluations: run.evaluations,
            no_feasible_design: why_none,
            verify: verified.as_ref().map(|v| VerifyJson { generation: v.generation, current: verify_current(v) }),
            warnings,
            source: if tables.is_some() { "checkpoint.json" } else { file },
            file,
            sorted_by: obj,
            direction: if maximise { "maximise" } else { "minimise" },
            units: DESIGN_COLUMNS
                .iter()
                .map(|c| (c.0.to_string(), c.1))
                .chain(rows.first().map(|r| r.robust.columns()).unwrap_or_default())
                .collect(),
            designs: rows.iter().map(|r| Shown { row: r, replay: replay(r.id) }).collect(),
        };
        outln!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    outln!("{}: {}", quoted(dir), state_text(state, &run, dir, resumable));
    for w in &warnings {
        outln!("warning: {w}");
    }
    if let Some(v) = &verified {
        let file = folder.verify_file().unwrap_or("verify.csv");
        if verify_current(v) {
            outln!("{file}: generation {}'s front (the run's current state)", v.generation);
        } else {
            outln!(
                "{file}: generation {}'s front; the run has changed since (now {} generations): run `gripopt verify {}` again",
                v.generation,
                run.completed_generations,
                quoted(dir)
            );
        }
    }
    if none_yet {
        outln!("no generation completed yet");
        return Ok(());
    }
    if rows.is_empty() {
        // the run's step budget, for an aborted simulation's line
        let max_steps = folder.problem().ok().map(|p| p.solver.max_steps);
        for l in why_none.iter().flatten() {
            outln!("{}", crate::cli::report::with_steps_hint(l, max_steps));
        }
    }
    let of = match (&tables, warnings.is_empty()) {
        (Some(t), false) => {
            format!("checkpoint.json's {} (generation {})", if a.archive { "archive" } else { "front" }, t.generation)
        }
        _ => file.to_string(),
    };
    outln!(
        "{} of {of}, sorted by {obj} ({}), best first",
        gripopt::run::counted(rows.len() as u64, "design", "designs"),
        if maximise { "higher is better" } else { "lower is better" }
    );
    if !run.recording.enabled {
        outln!("replay: {not_recorded}");
    }
    let shown = ["id", "max_offset", "alpha", "mean_force", "t_stab", "l21", "b", "t22", "r", "p", "psi_deg"];
    let label = |n: &str| match n {
        "max_offset" => "max_offset mm".to_string(),
        "t_stab" => "t_stab ms".to_string(),
        "mean_force" => "mean_force N".to_string(),
        "psi_deg" => "psi deg".to_string(),
        "l21" | "b" | "t22" => format!("{n} mm"),
        _ => n.to_string(),
    };
    let line: Vec<String> = shown.iter().map(|n| format!(" {:>13}", label(n))).collect();
    let replay_head = if run.recording.enabled { "  replay" } else { "" };
    outln!("{}{replay_head}", line.join(""));
    for r in &rows {
        let x = r.parameters();
        let values = [None, r.max_offset, r.alpha, r.mean_force, r.t_stab, Some(x[0]), Some(x[1]), Some(x[2])];
        let values = values.into_iter().chain([Some(x[3]), Some(x[4]), Some(x[5])]);
        let cells: Vec<String> = shown
            .iter()
            .zip(values)
            .map(|(n, v)| {
                let scale = match *n {
                    "max_offset" | "t_stab" | "l21" | "b" | "t22" => 1e3,
                    _ => 1.0,
                };
                match v {
                    None if *n == "id" => format!(" {:>13}", r.id),
                    // small values (alpha near isotropy) keep their significant digits
                    Some(x) if x != 0.0 && (x * scale).abs() < 1e-3 => format!(" {:>13.4e}", x * scale),
                    Some(x) => format!(" {:>13.5}", x * scale),
                    None => format!(" {:>13}", "—"),
                }
            })
            .collect();
        // a robust run: each object's P(stay) (docs/robust.md)
        let p_stay: String = r
            .robust
            .objects()
            .iter()
            .map(|o| format!("  {o} {}", r.robust.get(o, "p_stay").map_or("—".into(), |p| format!("{p:.3}"))))
            .collect();
        let p_stay = if p_stay.is_empty() { p_stay } else { format!("  P(stay):{p_stay}") };
        let replay = replay(r.id).map(|c| format!("  {c}")).unwrap_or_default();
        outln!("{}{replay}{p_stay}", cells.join(""));
    }
    Ok(())
}
