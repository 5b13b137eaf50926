//! The result files of a run folder, rewritten atomically as generations finish (at most every
//! 250 ms, see `persist::VIEWS_MIN_INTERVAL`, and after the last one) so that a
//! running run can be watched: `pareto.csv` (the reported front: the best non-dominated
//! designs the run found, at most the population size, chosen from the archive:
//! [`super::archive::reported_front`]; deterministic), `archive.csv` (every feasible
//! non-dominated design ever evaluated), `population.csv` (the whole population with discard stages and reasons; the
//! same design columns as pareto.csv), `pareto_timings.csv` (wall-clock stage timings, not
//! deterministic), `history.csv`; at the end the plots `pareto_matrix.svg` and
//! `hypervolume.svg`.
//!
//! Every CSV starts with `#` comment lines giving the unit and, for objectives, the
//! direction of each column (`pandas.read_csv(path, comment='#')` skips them); the table
//! [`DESIGN_COLUMNS`] is the one source of both, also listed in docs/outputs.md.

use super::archive::{reported_front, Archive};
use super::gripper::{GripperInfo, GripperProblem};
use super::robust_columns::{float_cell, line_with_floats, RobustColumns};
use crate::cells::{line, Floats, RawCell};
use crate::eval::OBJECTIVES;
use crate::fsutil::write_atomic;
use crate::optim::Individual;
use crate::optim::Nsga2State;
use crate::params::{DesignParameters, ForceModel};
use crate::Result;
use serde::{Deserialize, Serialize, Serializer};
use std::fmt::Write as _;
use std::path::Path;

/// A CSV column: name, unit ("-" = dimensionless), meaning (with the direction of objectives).
pub type Column = (&'static str, &'static str, &'static str);

/// Columns of pareto.csv, archive.csv and population.csv, in order (the fields of
/// [`DesignRow`], with units and meanings; a test checks they agree).
pub const DESIGN_COLUMNS: [Column; 25] = [
    ("id", "-", "design id (replay with `gripopt replay RUN --design ID`)"),
    ("generation", "-", "generation that created the design (1 = initial population)"),
    ("rank", "-", "non-domination rank (pareto.csv: 0; population.csv: in the population; empty in archive.csv)"),
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
    OBJECTIVES[0].column(),
    OBJECTIVES[1].column(),
    OBJECTIVES[2].column(),
    OBJECTIVES[3].column(),
    ("sim_steps", "-", "accepted steps of the grasp simulation"),
    ("sim_rhs_evals", "-", "right-hand-side evaluations of the grasp simulation"),
    ("force_model", "text", "forces defining alpha and mean_force (mobilised or frictionless)"),
];

/// One row of pareto.csv, archive.csv and population.csv: a design's identity and the
/// values of its evaluation record (read back with the csv crate: `#` lines are comments).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DesignRow {
    /// Design id.
    pub id: u64,
    /// Generation that created it.
    pub generation: u64,
    /// Non-domination rank: 0 in pareto.csv, the population's in population.csv (None in
    /// archive.csv).
    pub rank: Option<usize>,
    /// No stage discarded it.
    pub feasible: bool,
    /// The stage that discarded it.
    pub failed_stage: Option<u8>,
    /// By how much (§10 units).
    pub violation: Option<f64>,
    /// Why (written quoted, double quotes as single ones).
    #[serde(serialize_with = "quoted_text")]
    pub reason: Option<String>,
    /// The design as evaluated.
    #[serde(flatten)]
    pub design: DesignParameters,
    /// l11 (m), when stages 0–1 built the finger.
    pub l11: Option<f64>,
    /// l12 (m).
    pub l12: Option<f64>,
    /// l22 (m).
    pub l22: Option<f64>,
    /// l_hand (m).
    pub l_hand: f64,
    /// Form closed at the centred object.
    pub form_closed: Option<bool>,
    /// Objective (m), when form closed.
    pub max_offset: Option<f64>,
    /// Objective α.
    pub alpha: Option<f64>,
    /// Objective F̃ (N).
    pub mean_force: Option<f64>,
    /// Objective t_stab (s).
    pub t_stab: Option<f64>,
    /// Accepted steps of the grasp simulation.
    pub sim_steps: Option<u64>,
    /// Its right-hand-side evaluations.
    pub sim_rhs_evals: Option<u64>,
    /// The force model of α and F̃ (when stage 2 ran).
    pub force_model: Option<ForceModel>,
    /// A robust problem's columns (docs/robust.md); none for a single-object problem.
    #[serde(flatten, default)]
    pub robust: RobustColumns,
}

/// A text cell always in double quotes (its own double quotes as single ones), as the
/// run's tables have always written `reason`.
fn quoted_text<S: Serializer>(v: &Option<String>, s: S) -> std::result::Result<S::Ok, S::Error> {
    RawCell(format!("\"{}\"", v.as_deref().unwrap_or_default().replace('"', "'"))).serialize(s)
}

impl DesignRow {
    /// Each column with its value as text (as in the file, `reason` unquoted; empty: not
    /// computed).
    pub fn text_cells(&self) -> Vec<(String, String)> {
        let mut c = self.csv_cells();
        if let Some(r) = c.iter_mut().find(|(k, _)| k == "reason") {
            r.1 = self.reason.clone().unwrap_or_default();
        }
        c
    }

    /// Each column with its cell as written (`reason` quoted): a robust problem's measured
    /// values always with a decimal point (`0.0`, not `0`: pandas reads the column as
    /// floats even where every value is whole); the other columns as [`line`] writes them.
    fn csv_cells(&self) -> Vec<(String, String)> {
        let mut c = crate::cells::cells(self, Floats::Display);
        if !self.robust.0.is_empty() {
            for (k, v) in &mut c {
                if self.robust.is_float(k) {
                    float_cell(v);
                }
            }
        }
        c
    }

    /// The row's line of pareto.csv, archive.csv or population.csv, with its line break.
    pub fn csv_line(&self) -> String {
        if self.robust.0.is_empty() {
            return line(self, Floats::Display);
        }
        line_with_floats(self, |k| self.robust.is_float(k))
    }

    /// The design as evaluated (l21, b, t22, r, p, ψ°).
    pub fn parameters(&self) -> [f64; 6] {
        self.design.to_array()
    }

    /// The row of an individual (`rank`: None in archive.csv).
    pub fn of(ind: &Individual<GripperInfo>, rank: Option<usize>) -> Self {
        let r = &ind.eval.info.record;
        let v = &r.verdict;
        let d = r.derived();
        // a design not form closed: form_closed = false, max_offset empty (MODEL.md §6.7)
        let o = r.reported_objectives();
        let w = r.sim_work();
        DesignRow {
            id: ind.id,
            generation: ind.generation,
            rank,
            feasible: ind.eval.cv.is_feasible(),
            failed_stage: v.failed_stage,
            violation: v.violation,
            reason: v.reason.clone(),
            design: DesignParameters::from_array(ind.x.as_slice().try_into().expect("six design variables")),
            l11: d.l11,
            l12: d.l12,
            l22: d.l22,
            l_hand: d.l_hand,
            form_closed: r.form_closed(),
            max_offset: o.max_offset,
            alpha: o.alpha,
            mean_force: o.mean_force,
            t_stab: o.t_stab,
            sim_steps: w.map(|w| w[0]),
            sim_rhs_evals: w.map(|w| w[1]),
            force_model: r.statics.force_model,
            robust: RobustColumns::of(r),
        }
    }
}

/// One row of history.csv.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HistoryRow {
    /// Generation.
    pub generation: u64,
    /// Designs evaluated up to it.
    pub evaluations: u64,
    /// Feasible designs in the population.
    pub feasible: usize,
    /// Normalised hypervolume of the population's feasible front.
    pub hypervolume: f64,
    /// Normalised hypervolume of the archive.
    pub archive_hypervolume: Option<f64>,
    /// Normalised hypervolume of the reported front (pareto.csv; empty for the generations
    /// of a gripopt before issue 42, and in a history.csv it wrote).
    #[serde(default)]
    pub pareto_hypervolume: Option<f64>,
}

/// One row of pareto_timings.csv (wall seconds, not deterministic).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TimingRow {
    /// Design id.
    pub id: u64,
    /// Stages 0–1 (s).
    pub stage01_s: f64,
    /// Stage 2 (s).
    pub stage2_s: f64,
    /// Stage 3 (s).
    pub stage3_s: f64,
}

/// Columns of history.csv.
pub const HISTORY_COLUMNS: [Column; 6] = [
    ("generation", "-", "generation"),
    ("evaluations", "-", "designs evaluated up to this generation"),
    ("feasible", "-", "feasible designs in the population"),
    ("hypervolume", "-", "normalised hypervolume of the population's feasible front (can dip)"),
    ("archive_hypervolume", "-", "normalised hypervolume of archive.csv (never falls)"),
    ("pareto_hypervolume", "-", "normalised hypervolume of pareto.csv, the reported front (the archive's best designs, at most the population size)"),
];

/// The `#` header lines of a CSV with `columns`.
pub fn header(title: &str, columns: &[Column]) -> String {
    header_with(title, columns, &RobustColumns::default())
}

/// The `#` header lines of a design table, with a robust problem's columns after `columns`
/// (those of `robust`, a row of the table).
pub(super) fn header_with(title: &str, columns: &[Column], robust: &RobustColumns) -> String {
    let extra = robust.columns();
    let mut s = format!("# gripopt {title}\n# units:");
    for (n, u, _) in columns {
        let _ = write!(s, " {n} [{u}]");
    }
    for (n, u) in &extra {
        let _ = write!(s, " {n} [{u}]");
    }
    let senses: Vec<String> = OBJECTIVES.iter().map(|o| format!("{} {}", o.name, o.sense.word())).collect();
    let _ = writeln!(s, "\n# objectives: {}", senses.join(", "));
    if !extra.is_empty() {
        s.push_str("# robust problem: the objectives are aggregated over the objects and scenarios (docs/robust.md); NAME.* are per object\n");
    }
    let names = columns.iter().map(|c| c.0.to_string()).chain(extra.into_iter().map(|c| c.0));
    s.push_str(&names.collect::<Vec<_>>().join(","));
    s.push('\n');
    s
}

/// One row of [`DESIGN_COLUMNS`].
fn design_row(s: &mut String, ind: &Individual<GripperInfo>, rank: Option<usize>) {
    s.push_str(&DesignRow::of(ind, rank).csv_line());
}

/// Rewrite the CSV files of state `st` (and the archive) in `out`, each atomically.
pub fn write_tables(out: &Path, st: &Nsga2State<GripperInfo>, archive: &Archive) -> Result<()> {
    write_tables_timed(out, st, archive).map(|_| ())
}

/// [`write_tables`], the five files built and written in parallel (in the current rayon
/// pool): the seconds each took (built and written), in the order pareto, pareto_timings,
/// archive, population, history.
pub fn write_tables_timed(out: &Path, st: &Nsga2State<GripperInfo>, archive: &Archive) -> Result<[f64; 5]> {
    use rayon::prelude::*;
    const FILES: [&str; 5] = VIEW_FILES;
    let front = reported_front(st, Some(archive));
    // a robust problem's columns, named by its objects (every row of a run has the same)
    let robust = st.population.first().map(|p| RobustColumns::of(&p.eval.info.record)).unwrap_or_default();
    let dheader = |title: &str, columns: &[Column]| header_with(title, columns, &robust);
    let build = |k: usize| -> String {
        match k {
            0 => {
                let mut csv = dheader(
                    "pareto.csv: the run's front (the best non-dominated designs it found), by id",
                    &DESIGN_COLUMNS,
                );
                for ind in &front {
                    design_row(&mut csv, ind, Some(0));
                }
                csv
            }
            1 => {
                let mut tim = String::from("# gripopt pareto_timings.csv: wall-clock seconds per stage (not deterministic)\n# units: id [-] stage01_s [s] stage2_s [s] stage3_s [s]\nid,stage01_s,stage2_s,stage3_s\n");
                for ind in &front {
                    let t = ind.eval.info.stage_seconds;
                    let row = TimingRow { id: ind.id, stage01_s: t[1], stage2_s: t[2], stage3_s: t[3] };
                    tim.push_str(&line(&row, Floats::Display));
                }
                tim
            }
            2 => {
                let mut arc = dheader(
                    "archive.csv: every feasible non-dominated design evaluated in the run, by id",
                    &DESIGN_COLUMNS,
                );
                for ind in &archive.members {
                    design_row(&mut arc, ind, None);
                }
                arc
            }
            3 => {
                let mut pop = dheader("population.csv: the whole population, by rank then id", &DESIGN_COLUMNS);
                let mut order: Vec<usize> = (0..st.population.len()).collect();
                order.sort_by_key(|&k| (st.rank[k], st.population[k].id));
                for k in order {
                    design_row(&mut pop, &st.population[k], Some(st.rank[k]));
                }
                pop
            }
            _ => {
                let mut hist = header("history.csv: per generation", &HISTORY_COLUMNS);
                for (g, (hv, fe)) in st.hv_history.iter().zip(&st.feasible_history).enumerate() {
                    let row = HistoryRow {
                        generation: g as u64 + 1,
                        evaluations: (g as u64 + 1) * st.population.len() as u64,
                        feasible: *fe,
                        hypervolume: *hv,
                        archive_hypervolume: archive.hv_history.get(g).copied().filter(|v| v.is_finite()),
                        pareto_hypervolume: archive.front_hv_history.get(g).copied().filter(|v| v.is_finite()),
                    };
                    hist.push_str(&line(&row, Floats::Display));
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

/// The tables a run rewrites at every generation, in the order they are written.
pub const VIEW_FILES: [&str; 5] = ["pareto.csv", "pareto_timings.csv", "archive.csv", "population.csv", "history.csv"];

/// Every file a run rewrites at every generation: the tables and the two plots
/// ([`crate::fsutil::check_rewritable`] checks them before a run or resume does any work).
pub const REWRITTEN_FILES: [&str; 7] =
    [VIEW_FILES[0], VIEW_FILES[1], VIEW_FILES[2], VIEW_FILES[3], VIEW_FILES[4], "pareto_matrix.svg", "hypervolume.svg"];

/// Write every result file of the final state `st` into the run folder `out`: the tables
/// and the plots.
pub fn write_outputs(out: &Path, gp: &GripperProblem, st: &Nsga2State<GripperInfo>, archive: &Archive) -> Result<()> {
    write_tables(out, st, archive)?;
    super::plots::pareto_matrix(&out.join("pareto_matrix.svg"), gp, st)?;
    super::plots::hypervolume(
        &out.join("hypervolume.svg"),
        &st.hv_history,
        &archive.hv_history,
        &archive.front_hv_history,
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A feasible single-object row with nothing computed past stage 1.
    fn plain_row() -> DesignRow {
        DesignRow {
            id: 1,
            generation: 1,
            rank: Some(0),
            feasible: true,
            failed_stage: None,
            violation: None,
            reason: None,
            design: DesignParameters::from_array(&[0.05, 0.06, 0.035, 0.5, 0.4, 130.0]),
            l11: None,
            l12: None,
            l22: None,
            l_hand: 0.23,
            form_closed: None,
            max_offset: None,
            alpha: None,
            mean_force: None,
            t_stab: None,
            sim_steps: None,
            sim_rhs_evals: None,
            force_model: None,
            robust: RobustColumns::default(),
        }
    }

    /// The documented columns (names, units, meanings) are the row types' fields, in order.
    #[test]
    fn the_column_tables_are_the_rows_fields() {
        let row = plain_row();
        let names: Vec<&str> = DESIGN_COLUMNS.iter().map(|c| c.0).collect();
        assert_eq!(crate::cells::header(&row), names);
        let h = HistoryRow {
            generation: 1,
            evaluations: 4,
            feasible: 0,
            hypervolume: 0.0,
            archive_hypervolume: None,
            pareto_hypervolume: None,
        };
        let names: Vec<&str> = HISTORY_COLUMNS.iter().map(|c| c.0).collect();
        assert_eq!(crate::cells::header(&h), names);
        // a row read back from its own line is the row
        let text = format!("{}{}", header("test", &DESIGN_COLUMNS), line(&row, Floats::Display));
        let back: Vec<DesignRow> = csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .from_reader(text.as_bytes())
            .deserialize()
            .collect::<std::result::Result<_, _>>()
            .unwrap();
        assert_eq!(back, vec![row.clone()]);
        assert_eq!(row.csv_line(), line(&row, Floats::Display), "a single-object problem's row as before");
    }

    /// A robust row's measured values are written with a decimal point (pandas reads a column
    /// of `0` as int64), its counts as whole numbers; the line reads back as the row.
    #[test]
    fn robust_measured_values_are_float_literals() {
        let cells = [
            ("scenarios_run", Some(8.0)),
            ("scenarios_saved", Some(0.0)),
            ("bottle.p_stay", Some(0.0)),
            ("bottle.p_stay_lo", Some(0.0)),
            ("bottle.p_stay_hi", Some(0.25)),
            ("bottle.stays", Some(0.0)),
            ("bottle.scenarios", Some(8.0)),
            ("bottle.max_displacement", Some(1.0)),
            ("bottle.max_offset", None),
        ];
        let robust = RobustColumns(cells.iter().map(|(k, v)| (k.to_string(), *v)).collect());
        let row = DesignRow {
            id: 3,
            generation: 0,
            rank: None,
            feasible: false,
            failed_stage: Some(4),
            violation: Some(1.0),
            reason: Some("p".into()),
            l11: Some(0.0),
            robust,
            ..plain_row()
        };
        let line = row.csv_line();
        assert!(line.ends_with(",8,0,0.0,0.0,0.25,0,8,1.0,\n"), "{line}");
        assert!(line.contains(",1,\"p\",") && line.contains(",0,,,0.23,"), "other columns as before: {line}");
        let header: Vec<String> = crate::cells::header(&row);
        let text = format!("{}\n{line}", header.join(","));
        let back: Vec<DesignRow> =
            csv::Reader::from_reader(text.as_bytes()).deserialize().collect::<std::result::Result<_, _>>().unwrap();
        assert_eq!(back, vec![row]);
    }
}
