//! `gripopt show RUN`: a run's state (running, stopped and resumable, interrupted,
//! finished), its front sorted by an objective, with units, each design with its replay
//! command (text or JSON); when no design is feasible, why; whether verify.csv checked the
//! run's current generation. Reads the run's files through the library's run folder reader,
//! typed (they are rewritten every generation, so a running run can be shown too).

use crate::cli::out::path as quoted;
use anyhow::Result;
use gripopt::app::{DesignRow, DesignView, RunInfo, RunState, RunView, ShowRequest, DESIGN_COLUMNS, OBJECTIVES};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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

fn unit(name: &str) -> &'static str {
    DESIGN_COLUMNS.iter().find(|c| c.0 == name).map(|c| c.1).or_else(|| gripopt::app::robust_unit(name)).unwrap_or("")
}

/// The replay command of design `id` of the run in `dir` (None: the run recorded nothing).
fn replay_command(dir: &Path, recorded: bool, id: u64) -> Option<String> {
    recorded.then(|| format!("gripopt replay {} --design {id}", quoted(dir)))
}

/// Said of a run that recorded nothing.
const NOT_RECORDED: &str = "not recorded (run.json: the run was started with `--record none`), nothing to replay";

/// `gripopt show`.
pub fn run(a: ShowArgs) -> Result<()> {
    let req = ShowRequest { best: a.best.clone(), archive: a.archive, limit: a.limit };
    // the objective first, whatever is shown
    gripopt::app::objective_named(&req.best)?;
    if let Some(id) = a.design {
        let d = gripopt::app::show_design(&a.run_dir, id)?;
        for w in &d.warnings {
            eprintln!("warning: {w}");
        }
        return if a.json { design_json(&a.run_dir, &d) } else { design_text(&a.run_dir, &d) };
    }
    let v = gripopt::app::show_run(&a.run_dir, &req)?;
    if a.json {
        return run_json(&a.run_dir, &v);
    }
    run_text(&a.run_dir, &v, a.archive);
    Ok(())
}

/// `show --design ID --json`: every column with its unit, the table it is in, its replay.
fn design_json(dir: &Path, d: &DesignView) -> Result<()> {
    let mut m: BTreeMap<String, serde_json::Value> = BTreeMap::new();
    if let serde_json::Value::Object(values) = serde_json::to_value(&d.row)? {
        for (k, value) in values {
            let u = unit(&k);
            m.insert(k, serde_json::to_value(WithUnit { value, unit: u })?);
        }
    }
    m.insert("file".into(), d.file.into());
    m.insert("replay".into(), replay_command(dir, d.recorded, d.row.id).into());
    outln!("{}", serde_json::to_string_pretty(&m)?);
    Ok(())
}

/// `show --design ID`: every column with its unit, and its replay.
fn design_text(dir: &Path, d: &DesignView) -> Result<()> {
    // before the first checkpoint the views themselves; then the checkpoint, which they show
    let from = if d.from_checkpoint { format!("the checkpoint, as in {}", d.file) } else { d.file.to_string() };
    outln!("design {} (from {from})", d.row.id);
    for (k, v) in &d.row.text_cells() {
        let u = unit(k);
        let u = if matches!(u, "-" | "text" | "bool") { String::new() } else { format!(" {u}") };
        outln!("  {k:<14} {}{u}", if v.is_empty() { "—" } else { v });
    }
    outln!("  replay: {}", replay_command(dir, d.recorded, d.row.id).as_deref().unwrap_or(NOT_RECORDED));
    Ok(())
}

/// `show --json`.
fn run_json(dir: &Path, v: &RunView) -> Result<()> {
    let recorded = v.info.recording.enabled;
    let j = ShowJson {
        run_dir: dir.display().to_string(),
        status: v.state.word(),
        pid: match v.state {
            RunState::Running(pid) => pid,
            _ => None,
        },
        resumable: v.resumable,
        completed_generations: v.info.completed_generations,
        generations: v.info.generations,
        evaluations: v.info.evaluations,
        no_feasible_design: v.no_feasible.clone(),
        verify: v.verified.as_ref().map(|(g, current)| VerifyJson { generation: g.generation, current: *current }),
        warnings: v.warnings.clone(),
        source: if v.checkpoint_generation.is_some() { "checkpoint.json" } else { v.file },
        file: v.file,
        sorted_by: v.best.name,
        direction: v.best.sense.word(),
        units: DESIGN_COLUMNS
            .iter()
            .map(|c| (c.0.to_string(), c.1))
            .chain(v.rows.first().map(|r| r.robust.columns()).unwrap_or_default())
            .collect(),
        designs: v.rows.iter().map(|r| Shown { row: r, replay: replay_command(dir, recorded, r.id) }).collect(),
    };
    outln!("{}", serde_json::to_string_pretty(&j)?);
    Ok(())
}

/// `show`: the run's state, what does not agree, what verify checked, then its designs.
fn run_text(dir: &Path, v: &RunView, archive: bool) {
    outln!("{}: {}", quoted(dir), state_text(v.state, &v.info, dir, v.resumable));
    for w in &v.warnings {
        outln!("warning: {w}");
    }
    if let Some((g, current)) = &v.verified {
        if *current {
            outln!("{}: generation {}'s front (the run's current state)", v.verify_file, g.generation);
        } else {
            outln!(
                "{}: generation {}'s front; the run has changed since (now {} generations): run `gripopt verify {}` again",
                v.verify_file,
                g.generation,
                v.info.completed_generations,
                quoted(dir)
            );
        }
    }
    if v.none_yet {
        outln!("no generation completed yet");
        return;
    }
    if v.rows.is_empty() {
        for l in v.no_feasible.iter().flatten() {
            outln!("{}", crate::cli::report::with_steps_hint(l, v.max_steps));
        }
    }
    let of = match (v.checkpoint_generation, v.warnings.is_empty()) {
        (Some(g), false) => format!("checkpoint.json's {} (generation {g})", if archive { "archive" } else { "front" }),
        _ => v.file.to_string(),
    };
    outln!(
        "{} of {of}, sorted by {} ({} is better), best first",
        gripopt::app::counted(v.rows.len() as u64, "design", "designs"),
        v.best.name,
        v.best.sense.better()
    );
    if !v.info.recording.enabled {
        outln!("replay: {NOT_RECORDED}");
    }
    designs_table(dir, v);
}

/// A shown column: its label, where its value is in a row (an objective or a design
/// variable, by index) and the factor to the shown unit.
struct TableColumn {
    label: String,
    objective: bool,
    index: usize,
    scale: f64,
}

impl TableColumn {
    fn value(&self, r: &DesignRow) -> Option<f64> {
        if self.objective {
            gripopt::app::row_objectives(r)[self.index]
        } else {
            Some(r.parameters()[self.index])
        }
    }
}

/// The table's columns after the id: the objectives (labels and display units of
/// [`gripopt::app::OBJECTIVES`]), then the design (lengths in mm, ψ in degrees).
fn table_columns() -> Vec<TableColumn> {
    let objectives = OBJECTIVES.iter().enumerate().map(|(index, o)| {
        let (unit, scale) = o.shown;
        let label = if unit == "-" { o.name.to_string() } else { format!("{} {unit}", o.name) };
        TableColumn { label, objective: true, index, scale }
    });
    let design = [("l21 mm", 1e3), ("b mm", 1e3), ("t22 mm", 1e3), ("r", 1.0), ("p", 1.0), ("psi deg", 1.0)];
    let design = design.into_iter().enumerate().map(|(index, (label, scale))| TableColumn {
        label: label.to_string(),
        objective: false,
        index,
        scale,
    });
    objectives.chain(design).collect()
}

/// The designs as a table: id, objectives, design, replay command, a robust run's P(stay)
/// per object.
fn designs_table(dir: &Path, v: &RunView) {
    let recorded = v.info.recording.enabled;
    let columns = table_columns();
    let head: Vec<String> =
        std::iter::once(format!(" {:>13}", "id")).chain(columns.iter().map(|c| format!(" {:>13}", c.label))).collect();
    let replay_head = if recorded { "  replay" } else { "" };
    outln!("{}{replay_head}", head.join(""));
    for r in &v.rows {
        let cells: Vec<String> = std::iter::once(format!(" {:>13}", r.id))
            .chain(columns.iter().map(|c| match c.value(r) {
                // small values (alpha near isotropy) keep their significant digits
                Some(x) if x != 0.0 && (x * c.scale).abs() < 1e-3 => format!(" {:>13.4e}", x * c.scale),
                Some(x) => format!(" {:>13.5}", x * c.scale),
                None => format!(" {:>13}", "—"),
            }))
            .collect();
        // a robust run: each object's P(stay) (docs/robust.md)
        let p_stay: String = r
            .robust
            .objects()
            .iter()
            .map(|o| format!("  {o} {}", r.robust.get(o, "p_stay").map_or("—".into(), |p| format!("{p:.3}"))))
            .collect();
        let p_stay = if p_stay.is_empty() { p_stay } else { format!("  P(stay):{p_stay}") };
        let replay = replay_command(dir, recorded, r.id).map(|c| format!("  {c}")).unwrap_or_default();
        outln!("{}{replay}{p_stay}", cells.join(""));
    }
}
