//! The result files of a run folder, rewritten atomically as generations finish (at most every
//! 250 ms, see `persist::VIEWS_MIN_INTERVAL`, and after the last one) so that a
//! running run can be watched: `pareto.csv` (the population's feasible non-dominated
//! designs, deterministic), `archive.csv` (every feasible non-dominated design ever
//! evaluated), `population.csv` (the whole population with discard stages and reasons; the
//! same design columns as pareto.csv), `pareto_timings.csv` (wall-clock stage timings, not
//! deterministic), `history.csv`; at the end the plots `pareto_matrix.svg` and
//! `hypervolume.svg`.
//!
//! Every CSV starts with `#` comment lines giving the unit and, for objectives, the
//! direction of each column (`pandas.read_csv(path, comment='#')` skips them); the table
//! [`DESIGN_COLUMNS`] is the one source of both, also listed in docs/outputs.md.

use super::archive::Archive;
use super::gripper::{GripperInfo, GripperProblem};
use crate::fsutil::write_atomic;
use crate::optim::Individual;
use crate::optim::Nsga2State;
use crate::Result;
use std::fmt::Write as _;
use std::path::Path;

/// A CSV column: name, unit ("-" = dimensionless), meaning (with the direction of objectives).
pub type Column = (&'static str, &'static str, &'static str);

/// Columns of pareto.csv, archive.csv and population.csv, in order.
pub const DESIGN_COLUMNS: [Column; 25] = [
    ("id", "-", "design id (replay with `gripopt replay RUN --design ID`)"),
    ("generation", "-", "generation that created the design (1 = initial population)"),
    ("rank", "-", "non-domination rank in the population (0 = front; empty in archive.csv)"),
    ("feasible", "bool", "no stage discarded the design"),
    ("failed_stage", "-", "stage that discarded it (0-3; empty when feasible)"),
    ("violation", "stage units", "how far the failing criterion was missed (MODEL.md §10)"),
    ("reason", "text", "why it was discarded"),
    ("l21", "m", "design: proximal phalanx length"),
    ("b", "m", "design: palm length"),
    ("t22", "m", "design: distal phalanx length"),
    ("r", "-", "design: transmission ratio l22/l11"),
    ("p", "-", "design: ratio l11/l21"),
    ("psi_deg", "deg", "design: distal angle"),
    ("l11", "m", "derived length"),
    ("l12", "m", "derived length"),
    ("l22", "m", "derived length"),
    ("l_hand", "m", "hand length b + 2 t22 + 2 l21"),
    ("form_closed", "bool", "form closed at the centred object (false: max_offset is empty)"),
    ("max_offset", "m", "objective, MAXIMISE: largest object offset still form closed"),
    ("alpha", "-", "objective, MINIMISE: force isotropy (force model in force_model)"),
    ("mean_force", "N", "objective, MAXIMISE: mean contact force"),
    ("t_stab", "s", "objective, MINIMISE: time to stability"),
    ("sim_steps", "-", "accepted steps of the grasp simulation"),
    ("sim_rhs_evals", "-", "right-hand-side evaluations of the grasp simulation"),
    ("force_model", "text", "forces defining alpha and mean_force (mobilised or frictionless)"),
];

/// Columns of history.csv.
pub const HISTORY_COLUMNS: [Column; 5] = [
    ("generation", "-", "generation"),
    ("evaluations", "-", "designs evaluated up to this generation"),
    ("feasible", "-", "feasible designs in the population"),
    ("hypervolume", "-", "normalised hypervolume of the population's feasible front (can dip)"),
    ("archive_hypervolume", "-", "normalised hypervolume of archive.csv (never falls)"),
];

/// The `#` header lines of a CSV with `columns`.
pub fn header(title: &str, columns: &[Column]) -> String {
    let mut s = format!("# gripopt {title}\n# units:");
    for (n, u, _) in columns {
        let _ = write!(s, " {n} [{u}]");
    }
    s.push_str("\n# objectives: max_offset maximise, alpha minimise, mean_force maximise, t_stab minimise\n");
    s.push_str(&columns.iter().map(|c| c.0).collect::<Vec<_>>().join(","));
    s.push('\n');
    s
}

fn opt(v: Option<f64>) -> String {
    v.map(|x| format!("{x}")).unwrap_or_default()
}

/// One row of [`DESIGN_COLUMNS`].
fn design_row(s: &mut String, ind: &Individual<GripperInfo>, rank: Option<usize>, force_model: &str) {
    let i = &ind.eval.info;
    let x = &ind.x;
    let l = i.lengths.map(|l| l.map(Some)).unwrap_or([None; 3]);
    let w = i.sim_work.map(|w| (w[0].to_string(), w[1].to_string())).unwrap_or_default();
    // MODEL.md §6.7: a design not form closed at 0 has max_offset = −Δ_off internally (the
    // optimiser's finite placeholder); the file says form_closed = false and leaves it empty
    let form_closed = i.objectives[0].map(|m| m >= 0.0);
    let max_offset = i.objectives[0].filter(|m| *m >= 0.0);
    let _ = writeln!(
        s,
        "{},{},{},{},{},{},\"{}\",{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
        ind.id,
        ind.generation,
        rank.map(|r| r.to_string()).unwrap_or_default(),
        ind.eval.cv.is_feasible(),
        i.failed_stage.map(|s| s.to_string()).unwrap_or_default(),
        opt(i.violation),
        i.reason.clone().unwrap_or_default().replace('"', "'"),
        x[0],
        x[1],
        x[2],
        x[3],
        x[4],
        x[5],
        opt(l[0]),
        opt(l[1]),
        opt(l[2]),
        i.l_hand,
        form_closed.map(|b| b.to_string()).unwrap_or_default(),
        opt(max_offset),
        opt(i.objectives[1]),
        opt(i.objectives[2]),
        opt(i.objectives[3]),
        w.0,
        w.1,
        if i.objectives[0].is_some() { force_model } else { "" },
    );
}

/// The population's feasible non-dominated designs, sorted by id.
pub fn final_front(st: &Nsga2State<GripperInfo>) -> Vec<&Individual<GripperInfo>> {
    let mut f = st.feasible_front();
    f.sort_by_key(|p| p.id);
    f
}

/// Rewrite the CSV files of state `st` (and the archive) in `out`, each atomically.
pub fn write_tables(out: &Path, force_model: &str, st: &Nsga2State<GripperInfo>, archive: &Archive) -> Result<()> {
    write_tables_timed(out, force_model, st, archive).map(|_| ())
}

/// [`write_tables`], the five files built and written in parallel (in the current rayon
/// pool): the seconds each took (built and written), in the order pareto, pareto_timings,
/// archive, population, history.
pub fn write_tables_timed(
    out: &Path,
    force_model: &str,
    st: &Nsga2State<GripperInfo>,
    archive: &Archive,
) -> Result<[f64; 5]> {
    use rayon::prelude::*;
    const FILES: [&str; 5] = ["pareto.csv", "pareto_timings.csv", "archive.csv", "population.csv", "history.csv"];
    let front = final_front(st);
    let build = |k: usize| -> String {
        match k {
            0 => {
                let mut csv =
                    header("pareto.csv: the population's feasible non-dominated designs, by id", &DESIGN_COLUMNS);
                for ind in &front {
                    design_row(&mut csv, ind, Some(0), force_model);
                }
                csv
            }
            1 => {
                let mut tim = String::from("# gripopt pareto_timings.csv: wall-clock seconds per stage (not deterministic)\nid,stage01_s,stage2_s,stage3_s\n");
                for ind in &front {
                    let i = &ind.eval.info;
                    let _ = writeln!(
                        tim,
                        "{},{},{},{}",
                        ind.id, i.stage_seconds[1], i.stage_seconds[2], i.stage_seconds[3]
                    );
                }
                tim
            }
            2 => {
                let mut arc = header(
                    "archive.csv: every feasible non-dominated design evaluated in the run, by id",
                    &DESIGN_COLUMNS,
                );
                for ind in &archive.members {
                    design_row(&mut arc, ind, None, force_model);
                }
                arc
            }
            3 => {
                let mut pop = header("population.csv: the whole population, by rank then id", &DESIGN_COLUMNS);
                let mut order: Vec<usize> = (0..st.population.len()).collect();
                order.sort_by_key(|&k| (st.rank[k], st.population[k].id));
                for k in order {
                    design_row(&mut pop, &st.population[k], Some(st.rank[k]), force_model);
                }
                pop
            }
            _ => {
                let mut hist = header("history.csv: per generation", &HISTORY_COLUMNS);
                for (g, (hv, fe)) in st.hv_history.iter().zip(&st.feasible_history).enumerate() {
                    let ahv = archive.hv_history.get(g).copied().filter(|v| v.is_finite());
                    let _ = writeln!(
                        hist,
                        "{},{},{},{},{}",
                        g + 1,
                        (g as u64 + 1) * st.population.len() as u64,
                        fe,
                        hv,
                        opt(ahv)
                    );
                }
                hist
            }
        }
    };
    let secs: Vec<Result<f64>> = (0..FILES.len())
        .into_par_iter()
        .with_max_len(1)
        .map(|k| {
            let t = std::time::Instant::now();
            write_atomic(&out.join(FILES[k]), build(k).as_bytes())?;
            Ok(t.elapsed().as_secs_f64())
        })
        .collect();
    let mut times = [0.0; 5];
    for (k, r) in secs.into_iter().enumerate() {
        times[k] = r?;
    }
    Ok(times)
}

/// Write every result file of the final state `st` into the run folder `out`: the tables
/// and the plots.
pub fn write_outputs(out: &Path, gp: &GripperProblem, st: &Nsga2State<GripperInfo>, archive: &Archive) -> Result<()> {
    write_tables(out, gp.problem.scene.criteria.force_model.as_str(), st, archive)?;
    super::plots::pareto_matrix(&out.join("pareto_matrix.svg"), gp, st)?;
    super::plots::hypervolume(&out.join("hypervolume.svg"), &st.hv_history, &archive.hv_history)?;
    Ok(())
}
