//! `gripopt verify RUN_DIR` on a robust run (issue 22): the out-of-sample check. Every design
//! of the run's front (from its checkpoint; the certified front where the run certified it)
//! is evaluated on another study — the problem's
//! `verify_scenarios` per object from another ChaCha stream (`STREAM_VERIFY`) than the
//! optimisation's, every scenario run (no early stop); the problem its generation was
//! evaluated with, so that both figures concern the same objects — and each object's
//! P(stay) is compared with `p_min`: how many front designs keep it, i.e. whether the
//! optimiser overfitted its K scenarios. Writes `RUN_DIR/verify_robust.csv` (one row per design and object) atomically,
//! under the run folder's lock; the rows do not depend on the thread count.

use super::folder::RunFolder;
use super::lock::RunLock;
use super::robust_columns::line_with_floats;
use super::verify::{run_line, CheckedState, CHECKPOINT_FILE};
use crate::error::{Error, Result};
use crate::eval::{DesignStart, EvalOptions, ScenarioRecord, Study};
use crate::fsutil::write_atomic;
use crate::params::{Design, Problem, STREAM_VERIFY};
use crate::record::ProblemUse;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The file `verify` writes for a robust run.
pub const VERIFY_ROBUST_FILE: &str = "verify_robust.csv";

/// One front design on one object, in sample (the run's K scenarios) and out of sample.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobustVerifyRow {
    /// Design id.
    pub id: u64,
    /// Object name.
    pub object: String,
    /// P(stay) over the optimisation's scenarios (the run's record of the design).
    pub p_stay_in: Option<f64>,
    /// Scenarios of it.
    pub scenarios_in: Option<f64>,
    /// P(stay) over the fresh draw.
    pub p_stay_out: Option<f64>,
    /// Its Clopper–Pearson interval, lower end.
    pub p_stay_out_lo: Option<f64>,
    /// Upper end.
    pub p_stay_out_hi: Option<f64>,
    /// Scenarios of the fresh draw in which the object stayed.
    pub stays_out: usize,
    /// Scenarios of the fresh draw.
    pub scenarios_out: usize,
    /// Worst displacement of the free object over the fresh draw (m).
    pub max_displacement_out: Option<f64>,
    /// The fresh draw's P(stay) ≥ p_min, and the solver aborted none of its scenarios (an
    /// aborted scenario measured nothing: see [`RobustVerifySummary::aborted`]).
    pub keeps: bool,
}

/// A front design on one object whose fresh draw had scenarios the solver aborted (step
/// budget, step-size underflow, a free scene that ended before t_obs): whether the object
/// stays in them is unknown, so the design does not keep P(stay) ≥ p_min on the object, as
/// the optimisation's verdict makes such a design a solver-failure discard (docs/robust.md).
#[derive(Debug, Clone, PartialEq)]
pub struct AbortedOutOfSample {
    /// Design id.
    pub id: u64,
    /// Object name.
    pub object: String,
    /// Scenarios of the fresh draw the solver aborted.
    pub aborted: usize,
    /// Scenarios of the fresh draw.
    pub scenarios: usize,
    /// The first of them (index within the object).
    pub first_k: usize,
    /// The solver's message for it.
    pub message: String,
}

impl AbortedOutOfSample {
    /// Says what was aborted and why the design does not keep (one line, no newline).
    pub fn line(&self) -> String {
        format!(
            "design {} on {}: {} of {} fresh scenarios aborted by the solver (first: scenario {}: {}): whether the object stays is unknown, so it does not keep",
            self.id, self.object, self.aborted, self.scenarios, self.first_k, self.message
        )
    }
}

/// What `verify` found on a robust run.
#[derive(Debug, Clone)]
pub struct RobustVerifySummary {
    /// The file written.
    pub file: PathBuf,
    /// Rows, by design id then object.
    pub rows: Vec<RobustVerifyRow>,
    /// Front designs verified.
    pub designs: usize,
    /// Of them, those that keep P(stay) ≥ p_min on every object out of sample.
    pub keep_all: usize,
    /// p_min, and scenarios per object of the fresh draw.
    pub p_min: f64,
    /// Scenarios per object out of sample.
    pub scenarios: usize,
    /// The rows whose fresh draw had scenarios the solver aborted (they do not keep).
    pub aborted: Vec<AbortedOutOfSample>,
}

impl RobustVerifySummary {
    /// Designs whose every object's interval lies at or above p_min (demonstrably keep), and
    /// those with some object's interval wholly below it (demonstrably below), at the
    /// problem's confidence; the rest the fresh draw cannot tell apart.
    pub fn demonstrably(&self) -> (usize, usize) {
        let mut ids: Vec<u64> = self.rows.iter().map(|r| r.id).collect();
        ids.dedup();
        let rows = |id: u64| self.rows.iter().filter(move |r| r.id == id);
        let keep = ids.iter().filter(|&&id| rows(id).all(|r| r.p_stay_out_lo.is_some_and(|l| l >= self.p_min)));
        let below = ids.iter().filter(|&&id| rows(id).any(|r| r.p_stay_out_hi.is_some_and(|h| h < self.p_min)));
        (keep.count(), below.count())
    }
}

impl RobustVerifySummary {
    /// The report `gripopt verify` prints.
    pub fn report(&self) -> String {
        let mut s = format!(
            "verified {} out of sample ({} fresh scenarios per object, a stream the optimiser never saw) → {}\n",
            crate::error::counted(self.designs as u64, "front design", "front designs"),
            self.scenarios,
            self.file.display()
        );
        s.push_str(&format!(
            "  {} of {} keep P(stay) >= p_min {} on every object\n",
            self.keep_all, self.designs, self.p_min
        ));
        let (keep, below) = self.demonstrably();
        s.push_str(&format!(
            "  {keep} demonstrably keep (every object's Clopper-Pearson interval at or above p_min), {below} demonstrably below (some object's interval wholly below it)\n"
        ));
        for a in &self.aborted {
            s.push_str(&format!("  {}\n", a.line()));
        }
        let mut objects: Vec<&str> = vec![];
        for r in &self.rows {
            if !objects.contains(&r.object.as_str()) {
                objects.push(&r.object);
            }
        }
        for o in objects {
            let mine: Vec<&RobustVerifyRow> = self.rows.iter().filter(|r| r.object == o).collect();
            let keep = mine.iter().filter(|r| r.keeps).count();
            let mean = |f: &dyn Fn(&RobustVerifyRow) -> Option<f64>| {
                let v: Vec<f64> = mine.iter().filter_map(|r| f(r)).collect();
                if v.is_empty() {
                    f64::NAN
                } else {
                    v.iter().sum::<f64>() / v.len() as f64
                }
            };
            s.push_str(&format!(
                "  {o:<14} keeps {keep}/{}  mean P(stay) in sample {:.3}, out of sample {:.3}\n",
                mine.len(),
                mean(&|r| r.p_stay_in),
                mean(&|r| r.p_stay_out)
            ));
        }
        s
    }
}

/// True when `dir` holds a run of a robust problem.
pub fn is_robust_run(dir: &Path) -> bool {
    Problem::load(dir.join("problem.toml")).is_ok_and(|p| p.robust.is_some())
}

/// Verify the front of the robust run in `dir` out of sample (in the current rayon pool).
pub fn verify_robust(dir: &Path) -> Result<RobustVerifySummary> {
    let folder = RunFolder::open(dir)?;
    let _lock = RunLock::acquire(dir)?;
    // a folder or pipe where the table goes would fail its write only after the work
    crate::fsutil::check_rewritable(dir, &[VERIFY_ROBUST_FILE])?;
    let file = dir.join("problem.toml");
    // the problem in force, checked against the hash run.json recorded (a missing run.json or
    // an edited problem.toml is an error naming the file): the figures are the run's
    let p = folder.problem()?;
    let r = p
        .robust
        .clone()
        .ok_or_else(|| Error::RunDir { path: file.clone(), message: "not a robust problem (no [robust])".into() })?;
    // the front of the run's state (its checkpoint), not pareto.csv, a view a user may edit
    let info = folder.info()?;
    let checked = CheckedState::load(dir, &info)?;
    // a run certified at this state: its certified front (certification.json)
    let certification = super::certify::read_certification(dir)?;
    let (st, archive) = (&checked.checkpoint.state, checked.checkpoint.archive.as_ref());
    let certified = super::certify_stage::checkpoint_front(certification.as_ref(), st, archive);
    let front = certified.unwrap_or_else(|| checked.front_rows());
    if front.is_empty() {
        // why, as verify says it for a single-object run (the run's discard counts)
        let message = match info.discards.explain() {
            Some(why) => format!("nothing to verify, nothing written; {}", why.join("\n")),
            None => "no feasible design on the run's front; nothing to verify, nothing written".into(),
        };
        return Err(Error::RunDir { path: dir.join(CHECKPOINT_FILE), message });
    }
    // each design on the verify study of the problem its generation was evaluated with
    let files = info.problem_files();
    let problem_of = |g: u64| ProblemUse::of_generation(&files, g).map_or(1, |f| f.first_generation);
    let mut studies: Vec<(u64, Study)> = vec![];
    for row in &front {
        let g = problem_of(row.generation);
        if !studies.iter().any(|(h, _)| *h == g) {
            let pg = folder.problem_of_generation(row.generation)?;
            let rg = pg.robust.clone().ok_or_else(|| Error::RunDir {
                path: file.clone(),
                message: format!("generation {}'s problem is not a robust problem (no [robust])", row.generation),
            })?;
            studies.push((g, Study::drawn(&pg, &rg, STREAM_VERIFY, rg.verify_scenarios, false)));
        }
    }
    let study_of = |row: &super::outputs::DesignRow| {
        let g = problem_of(row.generation);
        &studies.iter().find(|(h, _)| *h == g).expect("a study per generation's problem").1
    };
    let opts = EvalOptions::full(&p);
    let starts: Vec<DesignStart> =
        front.par_iter().map(|row| study_of(row).start(&Design::from_array(&row.parameters()))).collect();
    let tasks: Vec<(usize, usize, usize)> = (0..starts.len())
        .filter(|&d| starts[d].passed())
        .flat_map(|d| study_of(&front[d]).sequence().map(move |(o, k)| (d, o, k)).collect::<Vec<_>>())
        .collect();
    let done: Vec<ScenarioRecord> = tasks
        .par_iter()
        .with_max_len(1)
        .map(|&(d, o, k)| study_of(&front[d]).run_scenario(&starts[d], o, k, &opts, &mut ()).0)
        .collect();
    let mut rows = vec![];
    let mut keep_all = 0;
    let mut aborted = vec![];
    for (d, row) in front.iter().enumerate() {
        let scen: Vec<(ScenarioRecord, _)> =
            tasks.iter().zip(&done).filter(|((td, ..), _)| *td == d).map(|(_, s)| (s.clone(), None)).collect();
        let rec = study_of(row).fold(&starts[d], scen).record;
        let rb = rec.robust.as_ref().expect("a robust record");
        let mut all = starts[d].passed();
        for (oi, o) in rb.objects.iter().enumerate() {
            let gone: Vec<&ScenarioRecord> = rb.scenarios.iter().filter(|s| s.object == oi && s.aborted()).collect();
            if let Some(first) = gone.first() {
                aborted.push(AbortedOutOfSample {
                    id: row.id,
                    object: o.name.clone(),
                    aborted: gone.len(),
                    scenarios: o.scenarios,
                    first_k: first.k,
                    message: first.abort.as_ref().map_or_else(
                        || first.cause.map_or("aborted", |c| c.as_str()).to_string(),
                        |a| a.message.clone(),
                    ),
                });
            }
            let keeps = gone.is_empty() && o.p_stay.is_some_and(|p| p >= r.p_min);
            all &= keeps;
            rows.push(RobustVerifyRow {
                id: row.id,
                object: o.name.clone(),
                p_stay_in: row.robust.get(&o.name, "p_stay"),
                scenarios_in: row.robust.get(&o.name, "scenarios"),
                p_stay_out: o.p_stay,
                p_stay_out_lo: o.p_stay_lo,
                p_stay_out_hi: o.p_stay_hi,
                stays_out: o.stays,
                scenarios_out: o.scenarios,
                max_displacement_out: o.max_displacement,
                keeps,
            });
        }
        keep_all += usize::from(all);
    }
    let in_force: Vec<&ProblemUse> = files.iter().filter(|f| f.file == "problem.toml").collect();
    let mut csv = format!(
        "# gripopt verify_robust.csv: the front re-evaluated out of sample ({} fresh scenarios per object, stream {STREAM_VERIFY}; p_min {}, Clopper-Pearson {} %)\n{}# units: p_stay_* [-] scenarios_* [-] stays_out [-] max_displacement_out [m] keeps [bool]\n",
        r.verify_scenarios,
        r.p_min,
        r.confidence * 100.0,
        // which run state it checked, as verify.csv says it (show tells when it is stale)
        run_line(&info.run_id, &checked.attribution(), &in_force),
    );
    // a trace of the aborted scenarios (only where there are: other files are unchanged)
    for a in &aborted {
        csv.push_str(&format!("# aborted: {}\n", a.line()));
    }
    csv.push_str("id,object,p_stay_in,scenarios_in,p_stay_out,p_stay_out_lo,p_stay_out_hi,stays_out,scenarios_out,max_displacement_out,keeps\n");
    for row in &rows {
        // P(stay) and the displacement as floats even where every value is whole
        csv.push_str(&line_with_floats(row, |k| k.starts_with("p_stay") || k == "max_displacement_out"));
    }
    let out = dir.join(VERIFY_ROBUST_FILE);
    write_atomic(&out, csv.as_bytes())?;
    Ok(RobustVerifySummary {
        file: out,
        designs: front.len(),
        keep_all,
        p_min: r.p_min,
        scenarios: r.verify_scenarios,
        rows,
        aborted,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(id: u64, object: &str, lo: f64, hi: f64) -> RobustVerifyRow {
        RobustVerifyRow {
            id,
            object: object.into(),
            p_stay_in: None,
            scenarios_in: None,
            p_stay_out: Some((lo + hi) / 2.0),
            p_stay_out_lo: Some(lo),
            p_stay_out_hi: Some(hi),
            stays_out: 0,
            scenarios_out: 128,
            max_displacement_out: None,
            keeps: false,
        }
    }

    /// A design keeps demonstrably when every object's interval is at or above p_min, is
    /// demonstrably below when one object's interval is wholly below it; the rest neither.
    #[test]
    fn demonstrably_keep_and_below_are_read_from_the_intervals() {
        let rows = vec![
            row(1, "a", 0.86, 0.99),
            row(1, "b", 0.90, 1.0),
            row(2, "a", 0.86, 0.99),
            row(2, "b", 0.70, 0.84),
            row(3, "a", 0.80, 0.95),
            row(3, "b", 0.90, 1.0),
        ];
        let s = RobustVerifySummary {
            file: PathBuf::new(),
            rows,
            designs: 3,
            keep_all: 0,
            p_min: 0.85,
            scenarios: 128,
            aborted: vec![],
        };
        assert_eq!(s.demonstrably(), (1, 1));
        assert!(s.report().contains("1 demonstrably keep") && s.report().contains("1 demonstrably below"));
    }
}
