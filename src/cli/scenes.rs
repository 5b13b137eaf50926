//! `gripopt simulate` and `replay --scene`: `--scene centred|offset:X|free[:X]` parsing, the
//! one simulation of a design in a scene (the library's), and its report (text, JSON, CSV,
//! plot), in the same way for every scene.

use crate::cli::csv_stream::CsvStream;
use crate::cli::report::{dec4, print_dyn, print_free, yes_no};
use crate::cli::watch::{Streamed, Watch};
use anyhow::{bail, Context, Result};
use gripopt::eval::{Record, RobustSetup, SimulationRecord};
use gripopt::params::{Design, Problem, SceneKind};
use gripopt::sim::{Controls, Integration, Method, SceneSpec};
use gripopt::{Column, POSE_COLUMNS};
use serde::Serialize;
use std::path::Path;

/// `centred`, `offset:X` or `free[:X]` (metres; the library's [`gripopt::parse_scene`]) applied to the `[scene]` of problem `p`, read
/// from `from` (checked by the library as a problem file's would be: the free scene needs
/// g_eq = 0; an error names `from` and the flag).
pub fn apply_scene(p: &Problem, from: &Path, arg: &str) -> Result<Problem> {
    let (kind, x_off) = gripopt::parse_scene(arg).context("--scene")?;
    Ok(p.in_scene(kind, x_off, Path::new(&format!("{} with --scene {arg}", from.display())))?)
}

/// How `simulate` (and `replay --scene`) runs a design and reports it.
pub struct SimulateOpts<'a> {
    /// Relative tolerance (default: the problem's).
    pub rtol: Option<f64>,
    /// Integration method (None: the problem's `solver.method`).
    pub method: Option<Method>,
    /// Contacts with the object (centred scene; false: the linkage alone).
    pub contacts: bool,
    /// Print every located event to stderr.
    pub trace: bool,
    /// One JSON object instead of the text report.
    pub json: bool,
    /// Write the trajectory to this CSV file.
    pub csv: Option<&'a Path>,
    /// Plot the grasp to this SVG file (centred and offset scenes).
    pub plot: Option<&'a Path>,
    /// What `replay --scene` adds to the JSON object.
    pub replay: Option<ReplayInScene>,
}

/// One of a robust problem's objects, picked by `simulate --object NAME`: the problem's
/// robust setup and the object's index in it.
pub struct PickedObject {
    /// The problem's robust setup (the object's nominal scene, the spring's sizing scene).
    pub setup: RobustSetup,
    /// The object's index.
    pub index: usize,
}

impl PickedObject {
    /// `--object NAME` of problem `p` (from `source`): an input error naming the flag when `p`
    /// has no [robust] or no object of that name.
    pub fn of(p: &Problem, name: &str, source: &Path) -> Result<Self> {
        let without = "simulate runs without --object";
        let index = super::robust::object_index(p, name, &source.display().to_string(), without)?;
        let setup = RobustSetup::of(p).ok_or_else(|| anyhow::anyhow!("--object {name}: no robust setup"))?;
        Ok(PickedObject { setup, index })
    }

    /// The object's name.
    pub fn name(&self) -> &str {
        &self.setup.spec.objects[self.index].name
    }
}

/// `gripopt simulate`: the diagnostic simulation of design `x` in the problem's scene.
pub fn simulate_in_scene(p: &Problem, x: &Design, o: &SimulateOpts<'_>) -> Result<()> {
    simulate_on(p, x, None, o)
}

/// `gripopt simulate [--object NAME]`: the diagnostic simulation of design `x` in the
/// problem's scene, on the reference `[object]` or on one of the robust objects (`object`:
/// its cylinder and grip torque, the spring sized at `[hand] tau`, as the robust evaluation's
/// stage 2 has them).
pub fn simulate_on(p: &Problem, x: &Design, object: Option<&PickedObject>, o: &SimulateOpts<'_>) -> Result<()> {
    let kind = p.scene.setup.kind;
    if o.plot.is_some() && kind == SceneKind::Free {
        bail!("--plot: the free scene is not plotted (use --csv for its poses)");
    }
    if !o.contacts && kind != SceneKind::Centred {
        bail!("--no-contact: only the centred scene runs without contacts (the {kind} scene needs the object)");
    }
    let method = o.method.unwrap_or(p.solver.method);
    if let Err(rule) = method.check_atol(p.solver.atol) {
        let atol = gripopt::params::fmt_num(p.solver.atol);
        bail!("--method {method}: the problem's solver.atol {atol}: {rule}");
    }
    // the problem's own settings (the default's scaling included) unless a method is named
    let integ = Integration::overridden(&p.solver, o.method, o.rtol);
    let ctl = Controls { contacts: o.contacts, ..Controls::DIAGNOSTIC };
    let spec = SceneSpec::of(&p.scene.setup);
    // the samples kept only for a plot, streamed to the CSV; progress on stderr when it takes long
    let mut watch = Watch::new(o.plot.is_some(), o.trace);
    watch.csv = match (o.csv, kind) {
        (None, _) => None,
        (Some(path), SceneKind::Free) => Some(Streamed::Poses(CsvStream::create(path, POSES_TITLE, &POSE_COLUMNS)?)),
        (Some(path), _) => {
            // the offset scene's finger 2 moves on its own: its columns after finger 1's
            let finger2 = kind == SceneKind::Offset;
            let columns = gripopt::trajectory_columns(finger2);
            let title = if finger2 { SAMPLES_TITLE_OFFSET } else { SAMPLES_TITLE };
            Some(Streamed::Samples(CsvStream::create(path, title, &columns)?, finger2))
        }
    };
    let ev = match object {
        Some(ob) => gripopt::eval::simulate_object(x, &ob.setup, ob.index, &spec, &integ, &ctl, &mut watch),
        None => gripopt::eval::simulate(x, &p.scene, &spec, &integ, &ctl, &mut watch),
    };
    let (traj, csv) = (std::mem::take(&mut watch.traj), watch.csv.take());
    drop(watch);
    if ev.scene.is_none() {
        let d = ev.discard.expect("a design without statics was discarded");
        bail!("the design is discarded at stage {} ({}); the grasp needs stages 0–2", d.stage, d.reason);
    }
    let record = Record::from_eval(&ev);
    let rows = csv.map(|c| c.into_stream().finish()).transpose()?;
    if let Some(path) = o.plot {
        let title = format!("{}: grasp", p.name);
        crate::cli::out::write_file_with(path, |tmp| Ok(gripopt::run::grasp_plot(tmp, &title, &traj.samples)?))?;
    }
    if o.json {
        let object = object.map(PickedObject::name);
        let v =
            SimulateJson { object, rtol: o.rtol, sim: SimulationRecord { record, method }, replay: o.replay.as_ref() };
        outln!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    print_simulation(p, object.map(PickedObject::name), &record, method, integ.rtol);
    if let (Some(n), Some(path)) = (rows, o.csv) {
        outln!("trajectory: {n} samples written to {}", crate::cli::out::path(path));
    }
    Ok(())
}

/// `simulate --json`: the simulation's record, and for `replay --scene` where it came from.
#[derive(Serialize)]
struct SimulateJson<'a> {
    /// `--object NAME`: the robust object simulated (absent: the reference `[object]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    object: Option<&'a str>,
    /// `--rtol R`: the relative tolerance it ran with (absent: the problem's `solver.rtol`).
    #[serde(skip_serializing_if = "Option::is_none")]
    rtol: Option<f64>,
    #[serde(flatten)]
    sim: SimulationRecord,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    replay: Option<&'a ReplayInScene>,
}

/// The text report of a simulation.
fn print_simulation(p: &Problem, object: Option<&str>, r: &Record, method: Method, rtol: f64) {
    let kind = r.scene.unwrap_or_default();
    let x_off = r.x_off.unwrap_or(0.0);
    let object = object.map_or(String::new(), |o| format!("  object {}", crate::cli::out::shown(o)));
    outln!(
        "problem {}{object}  scene {kind}  x_off {x_off} m  method {}  rtol {rtol:e}",
        crate::cli::out::shown(&p.name),
        method.as_str()
    );
    let g = &r.grasp;
    if kind == SceneKind::Free {
        outln!("centred grasp (the criteria's prediction):");
    }
    print_dyn(g);
    outln!("  f0 (rigid statics) {} / {} N", dec4(r.statics.f0_1), dec4(r.statics.f0_2));
    let ok = |v: Option<bool>| match v {
        Some(true) => "ok",
        Some(false) => "VIOLATED",
        None => "not reached",
    };
    outln!("  criteria: impact {}  fold {}  force {}", ok(g.impact_ok), ok(g.fold_ok), ok(g.force_ok));
    if let Some(h) = &r.offset_scene {
        outln!(
            "  hand force at the end ({}, {}) N (static ({}, {}) N); recentres {}",
            dec4(h.hand_x_end),
            dec4(h.hand_y_end),
            dec4(h.hand0_x),
            dec4(h.hand0_y),
            yes_no(h.recentres)
        );
    }
    if let Some(f) = &r.free_scene {
        print_free(f, r.x_off);
    }
    match &r.verdict.reason {
        None => outln!("verdict    {}", if kind == SceneKind::Free { "the object barely moves" } else { "stable" }),
        Some(why) => outln!("verdict    DISCARDED at stage 3: {}", crate::cli::report::with_hint(why, p)),
    }
}

const SAMPLES_TITLE: &str = "trajectory: finger 1 at every accepted step and event (docs/outputs.md)";
const SAMPLES_TITLE_OFFSET: &str =
    "trajectory: finger 1, then finger 2 (finger2_), at every accepted step and event (docs/outputs.md)";
const POSES_TITLE: &str =
    "free scene: the object's pose and both fingers at every accepted step and event (docs/outputs.md)";

/// The `#` title and units lines and the header of a CSV with `columns`.
fn csv_head(title: &str, columns: &[Column]) -> String {
    let units: Vec<String> = columns.iter().map(|(n, u, _)| format!("{n} [{u}]")).collect();
    let names: Vec<&str> = columns.iter().map(|c| c.0).collect();
    format!("# gripopt {title}\n# units: {}\n{}", units.join(" "), names.join(","))
}

/// Recorded grasp samples as CSV under the `#` line `title` (`fmt` formats each number), written atomically (errors name
/// `path`).
pub fn write_samples_csv(
    path: &Path,
    title: &str,
    samples: &[gripopt::sim::Sample],
    fmt: fn(f64) -> String,
) -> Result<()> {
    // finger 2's columns where recorded (an offset run's; NaN where an older gripopt left some out)
    let finger2 = samples.iter().any(|s| s.finger2.is_some());
    let mut w = csv_head(title, &gripopt::trajectory_columns(finger2));
    for s in samples {
        let v: Vec<String> = gripopt::trajectory_row(s, finger2).into_iter().map(fmt).collect();
        w.push('\n');
        w.push_str(&v.join(","));
    }
    w.push('\n');
    crate::cli::out::write_file(path, w.as_bytes())
}

/// A scene as `--scene` spells it (`centred`, `offset:X`, `free:X`).
fn scene_name(p: &Problem) -> String {
    match p.scene.setup.kind {
        SceneKind::Centred => "centred".into(),
        k => format!("{k}:{}", p.scene.setup.x_off),
    }
}

/// What `replay --scene` adds to `simulate --json`: where the design came from, and that a
/// different scene cannot be verified.
#[derive(Debug, Serialize)]
pub struct ReplayInScene {
    /// The run, design and shard.
    pub replay: ReplaySource,
    /// Always null: nothing was compared.
    pub verified: Option<bool>,
    /// Why.
    pub note: String,
}

/// Where a replayed design came from.
#[derive(Debug, Serialize)]
pub struct ReplaySource {
    /// The run folder.
    pub run_dir: String,
    /// The design id.
    pub design: u64,
    /// The shard it was read from.
    pub file: String,
    /// The run's scene.
    pub recorded_scene: String,
    /// The scene simulated.
    pub scene: String,
}

/// `gripopt replay RUN_DIR --design ID --scene S`. When S is the run's own scene (its
/// `problem.toml`: kind, and x_off for offset/free) this returns `None` and the caller
/// replays and verifies as usual. Otherwise it re-simulates the recorded design in S with
/// the run's problem and reports it like `simulate --scene S` (text, `--json`, `--csv`),
/// saying that a different scene cannot be verified against the recording; `Some(0)`.
pub fn replay_in_scene(
    dir: &Path,
    id: u64,
    scene: &str,
    json: bool,
    csv: Option<&Path>,
    plot: Option<&Path>,
) -> Result<Option<i32>> {
    let folder = gripopt::run::RunFolder::open(dir)?;
    let run_problem = folder.problem()?;
    let p = apply_scene(&run_problem, &dir.join("problem.toml"), scene)?;
    let (ran, recorded) = (scene_name(&p), scene_name(&run_problem));
    let (a, b) = (&p.scene.setup, &run_problem.scene.setup);
    // numerically: free:-0 is the run's free:0
    if a.kind == b.kind && (a.kind == SceneKind::Centred || a.x_off == b.x_off) {
        return Ok(None);
    }
    let rec = folder.design(id)?;
    let x = rec.design();
    let note = format!(
        "design {id} of {} re-simulated in the {ran} scene; the run recorded the {recorded} scene, so a different scene cannot be verified against the recording (nothing compared)",
        crate::cli::out::path(dir)
    );
    if !json {
        outln!("{note}");
    }
    let replay = ReplayInScene {
        replay: ReplaySource {
            run_dir: dir.display().to_string(),
            design: id,
            file: rec.file.display().to_string(),
            recorded_scene: recorded,
            scene: ran.clone(),
        },
        verified: None,
        note,
    };
    let o =
        SimulateOpts { rtol: None, method: None, contacts: true, trace: false, json, csv, plot, replay: Some(replay) };
    simulate_in_scene(&p, &x, &o)
        .with_context(|| format!("replaying design {id} of {} in the {ran} scene", dir.display()))?;
    Ok(Some(0))
}
