//! `gripopt bench free`: the free scene's cost against its accuracy (issue 13, item 6). The
//! nominal design's free-scene simulation (MODEL.md §14, to t_obs) at several rtol, with the
//! integrator's Jacobian by blocks (the default) and by dense forward differences, against
//! a reference at rtol 1e-10: CPU time (min / median), steps, evaluations, and the relative
//! errors of the §14.4 outputs.

use super::work_precision::{check_atol, rel, WorkPrecision};
use super::{say, time_it, BenchProgress, Out};
use crate::eval::StaticsResult;
use crate::eval::{stage_kinematics, stage_statics};
use crate::model::Finger;
use crate::params::{Design, Problem, SceneParams};
use crate::sim::{simulate, Controls, FreeEnd, FreeResult, FreeSetup, Integration, Method, SceneSpec};
use crate::{Error, Result};
use std::path::Path;

/// The rtols of the table by default (atol 1e-3·rtol unless fixed).
pub const FREE_RTOLS: [f64; 5] = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8];

/// The reference's relative tolerance.
pub const FREE_REFERENCE_RTOL: f64 = 1e-10;

/// Settings of the free-scene table.
#[derive(Debug, Clone)]
pub struct FreeBench {
    /// The table's output folder (free_work_precision.csv and .svg), repetitions and
    /// tolerances (one row per Jacobian and rtol).
    pub table: WorkPrecision,
    /// Also the rows with the dense finite-difference Jacobian.
    pub dense: bool,
}

impl Default for FreeBench {
    fn default() -> Self {
        let table = WorkPrecision { reps: 100, rtols: FREE_RTOLS.to_vec(), ..WorkPrecision::default() };
        FreeBench { table, dense: true }
    }
}

/// One row of the free-scene table.
#[derive(Debug, Clone, serde::Serialize)]
pub struct FreeRow {
    /// "blocks" or "dense".
    pub jacobian: &'static str,
    /// The integration method ("radau5", or "auto": the stiffness-switching method).
    pub method: &'static str,
    /// Relative tolerance.
    pub rtol: f64,
    /// Minimum CPU time per simulation, s.
    pub cpu_min: f64,
    /// Median CPU time per simulation, s.
    pub cpu_med: f64,
    /// Simulations timed.
    pub reps: usize,
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps.
    pub rejected: u64,
    /// Full right-hand-side evaluations (Newton, dense Jacobians, event location).
    pub rhs: u64,
    /// Jacobians.
    pub jac: u64,
    /// Partial evaluations of the block Jacobians (one per column).
    pub jac_block_evals: u64,
    /// LU factorisations (each a real and a complex one).
    pub lu: u64,
    /// Events located.
    pub events: u32,
    /// Relative error of the largest horizontal displacement of G.
    pub err_max_disp: f64,
    /// Relative error of the largest tilt.
    pub err_max_tilt: f64,
    /// Relative error of the displacement at t_obs.
    pub err_final_disp: f64,
    /// Relative error of the peak translational kinetic energy in the first contact.
    pub err_peak_e_trans: f64,
    /// Relative error of the peak rotational kinetic energy in the first contact.
    pub err_peak_e_rot: f64,
    /// Relative error of the first-contact time.
    pub err_t_first: f64,
    /// The largest of the errors above.
    pub err_max: f64,
    /// Same verdict (moved, toppled, escaped, rim contact) as the reference.
    pub verdict_same: bool,
}

/// The errors of a run against the reference: (max displacement, max tilt, final
/// displacement, peak E_trans, peak E_rot, first contact time).
fn errors(r: &FreeResult, reference: &FreeResult) -> [f64; 6] {
    [
        rel(Some(r.object_max_displacement), Some(reference.object_max_displacement)),
        rel(Some(r.object_max_tilt_deg), Some(reference.object_max_tilt_deg)),
        rel(Some(r.object_final_displacement), Some(reference.object_final_displacement)),
        rel(Some(r.object_peak_e_trans), Some(reference.object_peak_e_trans)),
        rel(Some(r.object_peak_e_rot), Some(reference.object_peak_e_rot)),
        rel(r.first_contact_t, reference.first_contact_t),
    ]
}

/// Same verdict flags.
fn same_verdict(a: &FreeResult, b: &FreeResult) -> bool {
    (a.moved, a.toppled, a.escaped, a.rim_contact, &a.end) == (b.moved, b.toppled, b.escaped, b.rim_contact, &b.end)
}

/// The design's finger and spring preload (stages 1–2).
fn finger_of(problem: &Problem, design: &Design) -> Result<(Finger, StaticsResult)> {
    let s = &problem.scene;
    let discarded =
        |d: crate::eval::Discard| Error::bench(format!("design discarded at stage {}: {}", d.stage, d.reason));
    let k = stage_kinematics(design, s).map_err(discarded)?;
    let st = stage_statics(&k.finger, s).map_err(discarded)?;
    Ok((k.finger, st))
}

/// One free-scene simulation of `finger` at the problem's x_off.
fn run(f: &Finger, s: &SceneParams, st: &StaticsResult, dense: bool, o: &Integration) -> FreeResult {
    let setup = FreeSetup { dense_jacobian: dense, ..FreeSetup::default() };
    let spec = SceneSpec::Free { x_off: s.setup.x_off, setup, t_end: None };
    *simulate(f, s, st, &spec, o, &Controls::DIAGNOSTIC, &mut ()).free().expect("the free scene")
}

/// The free-scene work-precision table of `design`: the reference (rtol 1e-10 with the
/// block Jacobian, checked against the dense Jacobian at the same tolerance), then each
/// rtol of `free.table` with each Jacobian. Writes free_work_precision.csv and .svg into
/// `free.table.out_dir`; the text goes to `out`, the figures come back as JSON.
pub fn free_scene(
    problem: &Problem,
    design: &Design,
    free: &FreeBench,
    out: Out,
    progress: &dyn BenchProgress,
) -> Result<serde_json::Value> {
    let b = &free.table;
    check_atol(b.atol)?;
    if b.rtols.is_empty() || b.rtols.iter().any(|r| !(*r > 0.0 && *r < 1.0)) {
        return Err(Error::Input("--rtols: one or more values in (0, 1) are needed".into()));
    }
    let s = &problem.scene;
    if s.env.g_eq != 0.0 {
        return Err(Error::Input(
            "bench free: environment.g_eq must be 0 for the free scene (hand horizontal, MODEL.md §14.1)".into(),
        ));
    }
    let (f, st) = finger_of(problem, design)?;
    let opts = |rtol: f64| Integration::new(rtol, b.atol_at(rtol), 50_000_000);
    let tight = opts(FREE_REFERENCE_RTOL);
    let reference = run(&f, s, &st, false, &tight);
    if reference.end != FreeEnd::Observed {
        return Err(Error::bench(format!("the reference run ended early: {}", reference.end)));
    }
    let check = run(&f, s, &st, true, &tight);
    let r = &reference;
    say!(
        out,
        "free scene, x_off {} m, to t_obs {} s; atol {}",
        s.setup.x_off,
        r.t_end,
        b.atol.map_or("1e-3·rtol".to_string(), |a| format!("{a:e} at every rtol"))
    );
    say!(out, "reference (rtol {FREE_REFERENCE_RTOL:e}, block Jacobian): max displacement {:.9e} m, max tilt {:.9e}°, final {:.9e} m, peak E_trans {:.9e} J, E_rot {:.9e} J, first contact {:.12e} s", r.object_max_displacement, r.object_max_tilt_deg, r.object_final_displacement, r.object_peak_e_trans, r.object_peak_e_rot, r.first_contact_t.unwrap_or(f64::NAN));
    let e = errors(&check, r);
    say!(
        out,
        "           dense Jacobian at the same rtol differs by {:.1e} (largest relative difference of the six outputs)",
        e.iter().cloned().fold(0.0, f64::max)
    );
    // (Jacobian, dense, method): RADAU5 with each Jacobian, and the stiffness-switching
    // method with the block Jacobian
    let all: &[(&'static str, bool, Method)] =
        &[("blocks", false, Method::Radau5), ("blocks", false, Method::Auto), ("dense", true, Method::Radau5)];
    let jacs = if free.dense { all } else { &all[..2] };
    progress.begin("bench free", (jacs.len() * b.rtols.len()) as u64, "");
    let mut rows = vec![];
    for &(label, dense, method) in jacs {
        for &rtol in &b.rtols {
            progress.message(&format!("{} {label} rtol {rtol:e}", method.as_str()));
            let o = opts(rtol).with_method(method);
            let mut reps = 0;
            let (x, tmin, tmed) = time_it(
                || {
                    reps += 1;
                    run(&f, s, &st, dense, &o)
                },
                1.0,
                b.reps,
            );
            let e = errors(&x, r);
            rows.push(FreeRow {
                jacobian: label,
                method: method.as_str(),
                rtol,
                cpu_min: tmin,
                cpu_med: tmed,
                reps,
                steps: x.stats.steps,
                rejected: x.stats.rejected,
                rhs: x.rhs_evals,
                jac: x.stats.jac,
                jac_block_evals: x.jac_block_evals,
                lu: x.stats.lu,
                events: x.events,
                err_max_disp: e[0],
                err_max_tilt: e[1],
                err_final_disp: e[2],
                err_peak_e_trans: e[3],
                err_peak_e_rot: e[4],
                err_t_first: e[5],
                err_max: e.iter().cloned().fold(0.0, f64::max),
                verdict_same: same_verdict(&x, r),
            });
            progress.step();
        }
    }
    progress.end();
    print_rows(&rows, out)?;
    let csv = b.out_dir.join("free_work_precision.csv");
    let svg = b.out_dir.join("free_work_precision.svg");
    let existed = csv.exists() || svg.exists();
    write_rows(&rows, &csv)?;
    plot_rows(&rows, &svg)?;
    say!(out, "wrote {} and {}{}", csv.display(), svg.display(), super::replaced_note(existed));
    Ok(serde_json::json!({
        "bench": "free", "rows": rows, "csv": csv.display().to_string(), "svg": svg.display().to_string(),
        "reference": {
            "rtol": FREE_REFERENCE_RTOL, "object_max_displacement": r.object_max_displacement, "object_max_tilt_deg": r.object_max_tilt_deg,
            "object_final_displacement": r.object_final_displacement, "object_peak_e_trans": r.object_peak_e_trans,
            "object_peak_e_rot": r.object_peak_e_rot, "first_contact_t": r.first_contact_t, "steps": r.stats.steps,
            "dense_jacobian_difference": e.iter().cloned().fold(0.0, f64::max),
        },
    }))
}

/// Writes the table to `out`.
fn print_rows(rows: &[FreeRow], out: Out) -> Result<()> {
    say!(out, "{:<7} {:<7} {:>6} {:>10} {:>10} {:>6} {:>5} {:>7} {:>5} {:>7} {:>5} {:>4} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} verdict", "method", "jac", "rtol", "cpu min", "cpu med", "steps", "rej", "rhs", "jac", "blk ev", "lu", "ev", "e(disp)", "e(tilt)", "e(final)", "e(Etr)", "e(Erot)", "e(t_fc)");
    for r in rows {
        say!(out, "{:<7} {:<7} {:>6.0e} {:>8.2}ms {:>8.2}ms {:>6} {:>5} {:>7} {:>5} {:>7} {:>5} {:>4} {:>9.1e} {:>9.1e} {:>9.1e} {:>9.1e} {:>9.1e} {:>9.1e} {}", r.method, r.jacobian, r.rtol, r.cpu_min * 1e3, r.cpu_med * 1e3, r.steps, r.rejected, r.rhs, r.jac, r.jac_block_evals, r.lu, r.events, r.err_max_disp, r.err_max_tilt, r.err_final_disp, r.err_peak_e_trans, r.err_peak_e_rot, r.err_t_first, if r.verdict_same { "same" } else { "DIFFERS" });
    }
    Ok(())
}

/// Writes the rows as CSV to `path` (its folder created if need be).
fn write_rows(rows: &[FreeRow], path: &Path) -> Result<()> {
    let header = "jacobian,rtol,cpu_min_s,cpu_median_s,reps,steps,rejected,rhs_evals,jacobians,jac_block_evals,lu,events,err_max_displacement,err_max_tilt,err_final_displacement,err_peak_e_trans,err_peak_e_rot,err_t_first_contact,err_max,same_verdict,method";
    let lines = rows.iter().map(|r| {
        format!(
            "{},{:e},{:e},{:e},{},{},{},{},{},{},{},{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{},{}",
            r.jacobian,
            r.rtol,
            r.cpu_min,
            r.cpu_med,
            r.reps,
            r.steps,
            r.rejected,
            r.rhs,
            r.jac,
            r.jac_block_evals,
            r.lu,
            r.events,
            r.err_max_disp,
            r.err_max_tilt,
            r.err_final_disp,
            r.err_peak_e_trans,
            r.err_peak_e_rot,
            r.err_t_first,
            r.err_max,
            r.verdict_same,
            r.method
        )
    });
    super::table::write_csv_lines(path, header, lines)
}

/// Plots median CPU time against the largest relative error, one line per method and Jacobian, to
/// the SVG file `path`.
fn plot_rows(rows: &[FreeRow], path: &Path) -> Result<()> {
    let pts: Vec<&FreeRow> = rows.iter().filter(|r| r.err_max.is_finite() && r.err_max > 0.0).collect();
    let series: Vec<(String, Vec<(f64, f64)>)> = [
        ("radau5", "blocks", "Radau IIA, block Jacobian"),
        ("auto", "blocks", "auto (Dormand–Prince / Radau IIA), block Jacobian"),
        ("radau5", "dense", "Radau IIA, dense Jacobian"),
    ]
    .iter()
    .map(|&(method, jacobian, name)| {
        let of = |r: &&&FreeRow| r.method == method && r.jacobian == jacobian;
        (name.to_string(), pts.iter().filter(of).map(|r| (r.err_max, r.cpu_med)).collect())
    })
    .collect();
    super::table::work_precision_chart(
        path,
        "work-precision: the free scene (nominal design, to t_obs)",
        "largest relative error of the §14.4 outputs",
        &series,
        (1e-9, 1e-2),
        (1e-3, 1e-2),
    )
}
