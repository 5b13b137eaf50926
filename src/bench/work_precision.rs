//! `gripopt bench work-precision`: CPU time against error for each integrator on one design,
//! against a tight reference run. The reference, the error measures and the table are also
//! what the diffsol comparison (`benches/diffsol.rs`) uses.

use super::table::{plot, print_table, print_targets, write_csv, Row};
use super::{say, Out};
use super::{time_it, BenchProgress};
use crate::eval::{evaluate, stage_kinematics, stage_statics, Discard, EvalOptions, StaticsResult};
use crate::model::Finger;
use crate::params::{Design, Problem, SceneKind, SceneParams};
use crate::sim::{diagnostic_grasp, DynamicsResult, Integration, Method};
use crate::{Error, Result};
use std::path::PathBuf;
use std::time::Instant;

/// The rtols of the table (atol 1e-3·rtol unless fixed).
pub const RTOLS: [f64; 8] = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10];

/// Settings of a work-precision table.
#[derive(Debug, Clone)]
pub struct WorkPrecision {
    /// Output folder.
    pub out_dir: PathBuf,
    /// Maximum repetitions per point (each point stops after ~1 s once min(3, reps) ran).
    pub reps: usize,
    /// Absolute tolerance on angles and rates at every rtol (`None`: 1e-3·rtol).
    pub atol: Option<f64>,
    /// Relative tolerances, one row per method and rtol.
    pub rtols: Vec<f64>,
}

impl Default for WorkPrecision {
    fn default() -> Self {
        WorkPrecision { out_dir: PathBuf::from("results/bench"), reps: 200, atol: None, rtols: RTOLS.to_vec() }
    }
}

impl WorkPrecision {
    /// The absolute tolerance used at `rtol`.
    pub fn atol_at(&self, rtol: f64) -> f64 {
        self.atol.unwrap_or(rtol * 1e-3)
    }
}

/// Checks a fixed absolute tolerance (`--atol`): positive and finite.
pub fn check_atol(atol: Option<f64>) -> Result<()> {
    match atol {
        Some(a) if !(a > 0.0 && a.is_finite()) => Err(Error::Input(format!("--atol {a}: must be a positive number"))),
        _ => Ok(()),
    }
}

/// Checks a list of relative tolerances (`--rtols`): non-empty, each in (0, 1).
fn check_rtols(rtols: &[f64]) -> Result<()> {
    if rtols.is_empty() {
        return Err(Error::Input("--rtols: at least one is needed".into()));
    }
    match rtols.iter().find(|r| !(**r > 0.0 && **r < 1.0)) {
        Some(r) => Err(Error::Input(format!("--rtols {r}: must lie in (0, 1)"))),
        None => Ok(()),
    }
}

/// Relative error |a − b| / |b|; NaN where either is missing or b is 0.
pub(super) fn rel(a: Option<f64>, b: Option<f64>) -> f64 {
    match (a, b) {
        (Some(a), Some(b)) if b != 0.0 => ((a - b) / b).abs(),
        _ => f64::NAN,
    }
}

/// The problem's own scene, as the bench names it: `centred`, `offset (x_off 3.000 mm)`.
pub(super) fn problem_scene_name(problem: &Problem) -> String {
    let setup = &problem.scene.setup;
    match setup.kind {
        SceneKind::Centred => "centred".into(),
        k => format!("{} (x_off {:.3} mm)", k.as_str(), setup.x_off * 1e3),
    }
}

/// Says which scene a work-precision table simulates: always the centred grasp (its
/// reference, t_first, E_cyl, t_stab and f_stab are that scene's), and plainly so when
/// the problem's own scene is another one.
pub(super) fn say_scene(problem: &Problem, out: Out) -> Result<()> {
    say!(out, "scene: centred (the work-precision table always simulates the centred grasp)");
    if problem.scene.setup.kind != SceneKind::Centred {
        let other = match problem.scene.setup.kind {
            SceneKind::Free => "`gripopt bench free` times the free scene",
            _ => "`gripopt simulate` runs it",
        };
        say!(
            out,
            "note: this problem's scene is {}, which the table does NOT simulate ({other}); only the whole \
             staged evaluation line runs the problem's own scene",
            problem_scene_name(problem)
        );
    }
    Ok(())
}

fn discarded(d: Discard) -> Error {
    Error::bench(format!("design discarded at stage {}: {}", d.stage, d.reason))
}

/// What one run of some integrator gives, for one row of the table.
#[derive(Debug, Clone, Copy)]
pub struct Measured {
    /// Time of the first contact onset.
    pub t_first: Option<f64>,
    /// E_cyl of the first impact.
    pub e_cyl: Option<f64>,
    /// Time to stability.
    pub t_stab: Option<f64>,
    /// Normal forces at t_stab.
    pub f_end: [f64; 2],
    /// Accepted steps.
    pub steps: u64,
    /// Right-hand-side evaluations (Jacobian ones included).
    pub rhs: u64,
    /// The run's verdict is the reference's.
    pub same_verdict: bool,
}

impl Measured {
    /// A run of gripopt's own simulator, its verdict compared with the reference's outcome.
    pub fn of(r: &DynamicsResult, reference: &DynamicsResult) -> Self {
        Measured {
            t_first: r.first.map(|x| x.t),
            e_cyl: r.first.map(|x| x.impact.e_cyl),
            t_stab: r.t_stab,
            f_end: r.f_end,
            steps: r.stats.steps,
            rhs: r.rhs_evals,
            same_verdict: r.outcome == reference.outcome,
        }
    }
}

/// The grasp a work-precision table is about: one design that passes stage 2, and its
/// reference run (Radau IIA, rtol 1e-12, atol 1e-15, diagnostic mode, whatever atol the
/// table uses).
#[derive(Debug, Clone)]
pub struct Reference {
    /// The problem's scene.
    pub scene: SceneParams,
    /// The design's finger (stage 1).
    pub finger: Finger,
    /// The design's statics (stage 2).
    pub statics: StaticsResult,
    /// The reference run.
    pub run: DynamicsResult,
}

impl Reference {
    /// Stages 1–2 of `design` and its reference run; an error if the design is discarded or
    /// the reference does not reach stability.
    pub fn new(problem: &Problem, design: &Design) -> Result<Self> {
        let s = &problem.scene;
        let k = stage_kinematics(design, s).map_err(discarded)?;
        let st = stage_statics(&k.finger, s).map_err(discarded)?;
        let run = diagnostic_grasp(&k.finger, s, &st, &Self::options(Method::Radau5));
        if run.t_stab.is_none() {
            return Err(Error::bench("the reference run did not reach stability"));
        }
        Ok(Reference { scene: s.clone(), finger: k.finger, statics: st, run })
    }

    /// The reference's tight settings, for `method`.
    pub fn options(method: Method) -> Integration {
        Integration::new(1e-12, 1e-15, 5_000_000).with_method(method)
    }

    /// Writes the atol used and the reference's values to `out`.
    pub fn print(&self, atol: Option<f64>, out: Out) -> Result<()> {
        let r = &self.run;
        say!(out, "atol: {}", atol.map_or("1e-3·rtol".to_string(), |a| format!("{a:e} at every rtol")));
        say!(out,
            "reference: Radau IIA rtol 1e-12: t_first {:.12e} s, E_cyl {:.12e} J, t_stab {:.12e} s, f_stab ({:.9}, {:.9}) N",
            r.first.map(|x| x.t).unwrap_or(f64::NAN),
            r.first.map(|x| x.impact.e_cyl).unwrap_or(f64::NAN),
            r.t_stab.unwrap_or(f64::NAN),
            r.f_end[0],
            r.f_end[1]
        );
        Ok(())
    }

    /// The row of a run measured as `m`, at `rtol`, with CPU times `cpu_min`, `cpu_med`.
    pub fn row(&self, method: &'static str, rtol: f64, cpu_min: f64, cpu_med: f64, m: &Measured) -> Row {
        let reference = &self.run;
        let ef = m.f_end.iter().zip(reference.f_end.iter()).map(|(a, b)| ((a - b) / b).abs()).fold(0.0, f64::max);
        Row {
            method,
            rtol,
            cpu_min,
            cpu_med,
            steps: m.steps,
            rhs: m.rhs,
            err_t_first: rel(m.t_first, reference.first.map(|x| x.t)),
            err_e_cyl: rel(m.e_cyl, reference.first.map(|x| x.impact.e_cyl)),
            err_t_stab: rel(m.t_stab, reference.t_stab),
            err_force: if m.t_stab.is_some() { ef } else { f64::NAN },
            verdict_same: m.same_verdict,
        }
    }

    /// Rows of gripopt's own integrators (Radau IIA, TR-BDF2, Dormand–Prince) at each rtol
    /// of `wp`, each point timed for ~1 s or `wp.reps` runs; no progress shown.
    pub fn own_rows(&self, wp: &WorkPrecision) -> Vec<Row> {
        self.own_rows_showing(wp, &())
    }

    /// [`own_rows`](Self::own_rows), telling `progress` each point as it goes.
    pub fn own_rows_showing(&self, wp: &WorkPrecision, progress: &dyn BenchProgress) -> Vec<Row> {
        let (f, s, st) = (&self.finger, &self.scene, &self.statics);
        let methods = [Method::Radau5, Method::TrBdf2, Method::Dopri5, Method::Auto];
        progress.begin("work-precision", (methods.len() * wp.rtols.len()) as u64, "");
        let mut rows = vec![];
        for m in methods {
            for &rtol in &wp.rtols {
                progress.message(&format!("{m:?} rtol {rtol:e}"));
                let o = Integration::new(rtol, wp.atol_at(rtol), 5_000_000).with_method(m);
                let (r, tmin, tmed) = time_it(|| diagnostic_grasp(f, s, st, &o), 1.0, wp.reps);
                rows.push(self.row(label(m), rtol, tmin, tmed, &Measured::of(&r, &self.run)));
                progress.step();
            }
        }
        progress.end();
        rows
    }
}

/// Label of one of gripopt's own methods in the table.
fn label(m: Method) -> &'static str {
    match m {
        Method::Radau5 => "Radau5",
        Method::TrBdf2 => "TrBdf2",
        Method::Dopri5 => "Dopri5",
        Method::Auto => "Auto",
    }
}

/// The work-precision table of `design`: the reference (checked against Dormand–Prince at
/// the same tight tolerance), gripopt's integrators at each rtol, the cheapest run per
/// method within 1e-5 on t_stab, and the whole staged evaluation's time. Writes
/// work_precision.csv and work_precision.svg into `wp.out_dir`; the text goes to `out`, the
/// figures come back as JSON.
pub fn work_precision(
    problem: &Problem,
    design: &Design,
    wp: &WorkPrecision,
    out: Out,
    progress: &dyn BenchProgress,
) -> Result<serde_json::Value> {
    check_atol(wp.atol)?;
    check_rtols(&wp.rtols)?;
    let reference = Reference::new(problem, design)?;
    let check =
        diagnostic_grasp(&reference.finger, &reference.scene, &reference.statics, &Reference::options(Method::Dopri5));
    say_scene(problem, out)?;
    reference.print(wp.atol, out)?;
    say!(
        out,
        "           Dormand–Prince rtol 1e-12 differs by {:.1e} relative in t_stab",
        rel(check.t_stab, reference.run.t_stab)
    );
    let rows = reference.own_rows_showing(wp, progress);
    say!(out, "(diffsol rows: `cargo bench -p gripopt-diffsol-bench --bench diffsol`, as `make bench` does)");
    let csv = wp.out_dir.join("work_precision.csv");
    let svg = wp.out_dir.join("work_precision.svg");
    let existed = csv.exists() || svg.exists();
    write_csv(&rows, &csv)?;
    print_table(&rows, out)?;
    print_targets(&rows, out)?;
    // whole staged evaluation (stages 0–3, pipeline mode, max_offset scan included)
    let s = &problem.scene;
    let opts = EvalOptions::full(problem);
    let mut ts = vec![];
    for _ in 0..wp.reps.max(20) {
        let t0 = Instant::now();
        std::hint::black_box(evaluate(design, s, &opts));
        ts.push(t0.elapsed().as_secs_f64());
    }
    let (t_min, t_med) = super::min_med(ts);
    let ev = evaluate(design, s, &opts);
    say!(
        out,
        "whole staged evaluation (stages 0-3, pipeline mode, method {}, rtol {:e}) in the problem's scene {}: min {:.3} ms, median {:.3} ms; verdict: {}",
        problem.solver.method,
        problem.solver.rtol,
        problem_scene_name(problem),
        t_min * 1e3,
        t_med * 1e3,
        ev.discard.map(|d| format!("stage {} {}", d.stage, d.reason)).unwrap_or("feasible".into())
    );
    plot(&rows, &svg)?;
    say!(out, "wrote {} and {}{}", csv.display(), svg.display(), super::replaced_note(existed));
    Ok(serde_json::json!({
        "bench": "work-precision", "scene": "centred", "problem_scene": problem.scene.setup.kind, "rows": rows, "csv": csv.display().to_string(), "svg": svg.display().to_string(),
        "whole_evaluation_ms": {
            "min": t_min * 1e3, "median": t_med * 1e3, "rtol": problem.solver.rtol, "method": problem.solver.method,
            "scene": problem.scene.setup.kind, "x_off": problem.scene.setup.x_off,
        },
    }))
}
