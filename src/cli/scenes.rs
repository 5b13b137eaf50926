//! `gripopt simulate` and `replay --scene`: `--scene centred|offset:X|free[:X]` parsing, the
//! one simulation of a design in a scene (the library's), and its report (text, JSON, CSV,
//! plot), in the same way for every scene.

use crate::cli::args::{check_output, check_rtol, MethodArg};
use crate::cli::csv_stream::CsvStream;
use crate::cli::inputs::{design_of, load_problem};
use crate::cli::report::{dec4, print_dyn, print_free, yes_no};
use crate::cli::watch::{Streamed, Watch};
use anyhow::{bail, Context, Result};
use gripopt::app::{
    Column, Design, Method, Problem, Record, ReplayInScene, SceneChoice, SimulateRequest, SimulationRecord,
    POSE_COLUMNS,
};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// `centred`, `offset:X` or `free[:X]` (metres; the library's [`SceneChoice::parse`]) applied to the `[scene]` of problem `p`, read
/// from `from` (checked by the library as a problem file's would be: the free scene needs
/// g_eq = 0; an error names `from` and the flag).
pub fn apply_scene(p: &Problem, from: &Path, arg: &str) -> Result<Problem> {
    let scene = SceneChoice::parse(arg).context("--scene")?;
    Ok(p.in_scene(scene, Path::new(&format!("{} with --scene {arg}", from.display())))?)
}

/// Arguments of `gripopt simulate`.
#[derive(clap::Args)]
pub struct SimulateArgs {
    /// Problem file (TOML).
    pub problem: PathBuf,
    /// Design as l21=..,b=..,t22=..,r=..,p=..,psi_deg=.. (default: the problem's nominal).
    #[arg(long)]
    pub design: Option<String>,
    /// Relative tolerance (default: the problem's solver.rtol).
    #[arg(long)]
    pub rtol: Option<f64>,
    /// Integration method (default: the problem's solver.method; absent there, the default
    /// solver: auto with the default's tolerance scaling). A method given here takes the
    /// tolerances as given.
    #[arg(long, value_enum)]
    pub method: Option<MethodArg>,
    /// Scene (MODEL.md §14): centred, offset:X or free[:X] (metres; default: the problem's [scene]).
    #[arg(long)]
    pub scene: Option<String>,
    /// A robust problem's object ([[robust.objects]] name) to grasp instead of the
    /// reference [object]: its cylinder and grip torque, the spring sized at [hand] tau.
    #[arg(long)]
    pub object: Option<String>,
    /// Print the evaluation record (stages 0–3, verdict, scene, method) as one JSON
    /// object (docs/outputs.md).
    #[arg(long)]
    pub json: bool,
    /// Write the trajectory (accepted steps and events) to this CSV file.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Close the finger on nothing (contacts off): shows where the linkage itself goes,
    /// e.g. into a parallel singularity.
    #[arg(long)]
    pub no_contact: bool,
    /// Print every located event to stderr.
    #[arg(long)]
    pub trace: bool,
    /// Plot the grasp (joint angles, contact forces, raw and filtered hand force) to this SVG file.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Overwrite the --csv / --plot files if they exist (refused otherwise).
    #[arg(long)]
    pub force: bool,
}

/// `gripopt simulate`: the outputs checked (never over an input: the problem file and a
/// robust problem's object files), the scene and object applied, then the simulation.
pub fn run(a: SimulateArgs) -> Result<()> {
    let (csv, plot, force) = (a.csv.as_deref(), a.plot.as_deref(), a.force);
    check_output("--csv", csv, force, &[&a.problem])?;
    check_output("--plot", plot, force, &[&a.problem])?;
    let mut p = load_problem(&a.problem)?;
    // the robust objects' files are inputs too
    let objects = p.object_files(&a.problem);
    let inputs: Vec<&Path> = objects.iter().map(|f| f.as_path()).collect();
    check_output("--csv", csv, force, &inputs)?;
    check_output("--plot", plot, force, &inputs)?;
    if let Some(sc) = &a.scene {
        p = apply_scene(&p, &a.problem, sc)?;
    }
    let without = "simulate runs without --object";
    if let Some(name) = &a.object {
        super::robust::object_index(&p, name, &a.problem.display().to_string(), without)?;
    }
    if p.robust.is_some() && a.object.is_none() {
        // as export and sweep say it; stderr, so that --json stays one JSON object
        eprintln!(
            "note: {} has [robust]: simulate runs the reference [object] only, not the robust objects or scenarios; --object NAME simulates the design on one of its objects ({}) (docs/robust.md)",
            a.problem.display(),
            super::robust::object_names(&p)
        );
    }
    let x = design_of(&p, &a.design)?;
    let o = SimulateOpts {
        rtol: check_rtol(a.rtol)?,
        method: a.method.map(MethodArg::to_method),
        object: a.object.clone(),
        contacts: !a.no_contact,
        trace: a.trace,
        json: a.json,
        csv,
        plot,
        replay: None,
    };
    simulate_on(&p, &x, &o).with_context(|| format!("simulating {}", a.problem.display()))
}

/// How `simulate` (and `replay --scene`) runs a design and reports it.
pub struct SimulateOpts<'a> {
    /// Relative tolerance (default: the problem's).
    pub rtol: Option<f64>,
    /// Integration method (None: the problem's `solver.method`).
    pub method: Option<Method>,
    /// One of a robust problem's objects by name (`--object`, checked; None: the reference
    /// `[object]`).
    pub object: Option<String>,
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

/// `gripopt simulate [--object NAME]`: the diagnostic simulation of design `x` in the
/// problem's scene, on the reference `[object]` or on one of the robust objects (its
/// cylinder and grip torque, the spring sized at `[hand] tau`, as the robust evaluation's
/// stage 2 has them): the library's simulation, reported here.
pub fn simulate_on(p: &Problem, x: &Design, o: &SimulateOpts<'_>) -> Result<()> {
    let kind = p.scene.setup.kind;
    if o.plot.is_some() && kind.is_free() {
        bail!("--plot: the free scene is not plotted (use --csv for its poses)");
    }
    if !o.contacts && !kind.runs_without_contacts() {
        bail!("--no-contact: only the centred scene runs without contacts (the {kind} scene needs the object)");
    }
    let method = o.method.unwrap_or(p.solver.method);
    if let Err(rule) = method.check_atol(p.solver.atol) {
        let atol = gripopt::app::fmt_num(p.solver.atol);
        bail!("--method {method}: the problem's solver.atol {atol}: {rule}");
    }
    // the samples kept only for a plot, streamed to the CSV; progress on stderr when it takes long
    let mut watch = Watch::new(o.plot.is_some(), o.trace);
    watch.csv = match o.csv {
        None => None,
        Some(path) if kind.is_free() => Some(Streamed::Poses(CsvStream::create(path, POSES_TITLE, &POSE_COLUMNS)?)),
        Some(path) => {
            // the offset scene's finger 2 moves on its own: its columns after finger 1's
            let finger2 = kind.has_finger2();
            let columns = gripopt::app::trajectory_columns(finger2);
            let title = if finger2 { SAMPLES_TITLE_OFFSET } else { SAMPLES_TITLE };
            Some(Streamed::Samples(CsvStream::create(path, title, &columns)?, finger2))
        }
    };
    let req =
        SimulateRequest { scene: None, object: o.object.clone(), rtol: o.rtol, method: o.method, contacts: o.contacts };
    let simulated = gripopt::app::simulate_into(p, x, &req, &mut watch);
    let (traj, csv) = (std::mem::take(&mut watch.traj), watch.csv.take());
    drop(watch);
    let s = simulated?;
    let rows = csv.map(|c| c.into_stream().finish()).transpose()?;
    if let Some(path) = o.plot {
        let title = format!("{}: grasp", p.name);
        crate::cli::out::write_file_with(path, |tmp| Ok(gripopt::app::grasp_plot(tmp, &title, &traj.samples)?))?;
    }
    if o.json {
        let v = SimulateJson { object: s.object.as_deref(), rtol: o.rtol, sim: s.record, replay: o.replay.as_ref() };
        outln!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    print_simulation(p, s.object.as_deref(), &s.record.record, s.record.method, s.rtol);
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
    if kind.is_free() {
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
        None => outln!("verdict    {}", kind.passing_words()),
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
    samples: &[gripopt::app::Sample],
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
    let choice = SceneChoice::parse(scene).context("--scene")?;
    let label = format!("{} with --scene {scene}", dir.join("problem.toml").display());
    let Some(d) = gripopt::app::design_in_scene(dir, id, choice, Path::new(&label))? else {
        return Ok(None);
    };
    if !json {
        outln!("{}", d.replay.note);
    }
    let ran = d.replay.replay.scene.clone();
    let o = SimulateOpts {
        rtol: None,
        method: None,
        object: None,
        contacts: true,
        trace: false,
        json,
        csv,
        plot,
        replay: Some(d.replay),
    };
    simulate_on(&d.problem, &d.design, &o)
        .with_context(|| format!("replaying design {id} of {} in the {ran} scene", dir.display()))?;
    Ok(Some(0))
}
