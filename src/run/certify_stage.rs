//! The certification stage at the end of a robust run (issue 41, docs/robust.md
//! "Certification"): once the search's generations are done, its front is certified on fresh
//! scenarios ([`certify_front`]) and what the run reports becomes the certified front:
//! pareto.csv holds the certified designs (their objectives estimated on the fresh
//! scenarios, the certification's columns after the search's), search_pareto.csv the
//! search's front as it was, certification.json every design tested and the plan, and
//! recording/front.mcap marks the certified designs. The stage is a pure function of the
//! final state, so a run killed during it and resumed writes the same bits.

use super::archive::Archive;
use super::certify::{certified_row, certify_front, write_certification, CertificationFile, CertifiedFront};
use super::gripper::{GripperInfo, GripperProblem};
use super::outputs::{header_with, DesignRow, DESIGN_COLUMNS};
use crate::error::Result;
use crate::fsutil::write_atomic;
use crate::optim::{Individual, Nsga2State};
use std::collections::BTreeMap;
use std::path::Path;

/// The search's front, written beside the certified pareto.csv of a robust run that certifies.
pub const SEARCH_FRONT_FILE: &str = "search_pareto.csv";

/// What the certification stage gives the run's summary.
#[derive(Debug, Clone, PartialEq)]
pub struct CertificationSummary {
    /// Designs tested on fresh scenarios.
    pub tested: usize,
    /// Of them, certified.
    pub certified: usize,
    /// The reported front (certified, non-dominated among the certified), by id.
    pub front: Vec<u64>,
    /// Why nothing was certified (None when some design is).
    pub why_none: Option<String>,
}

/// The designs of the run's state `st` (its archive `archive`), each once, by id: the
/// population's and the archive's.
fn by_id<'a>(st: &'a Nsga2State<GripperInfo>, archive: &'a Archive) -> BTreeMap<u64, &'a Individual<GripperInfo>> {
    let mut by_id: BTreeMap<u64, &Individual<GripperInfo>> = BTreeMap::new();
    for i in archive.members.iter().chain(&st.population) {
        by_id.entry(i.id).or_insert(i);
    }
    by_id
}

/// Run the certification stage of the final state `st` of the run in `out` (its archive
/// `archive`; `search_front` the front the search reports, the designs certified) in the
/// current rayon pool, and write its files. None: the problem does not certify (not robust, or `[robust.certify]`
/// off), nothing is written.
pub fn certify_run(
    out: &Path,
    gp: &GripperProblem,
    st: &Nsga2State<GripperInfo>,
    archive: &Archive,
    search_front: &[&Individual<GripperInfo>],
) -> Result<Option<CertificationSummary>> {
    if super::certify::certification_study(&gp.problem).is_none() {
        return Ok(None);
    }
    // the candidates: the search's front (the prototype's choice, measured in docs/robust.md:
    // certifying every feasible design of the archive tests 5x the designs for a front of
    // near-duplicates and makes verify's audit cost more than the search)
    let by_id = by_id(st, archive);
    let cert = certify_front(gp, search_front);
    let Some(mut file) = cert.file() else { return Ok(None) };
    file.generation = st.generation;
    write_atomic(&out.join(SEARCH_FRONT_FILE), search_table(search_front).as_bytes())?;
    write_atomic(&out.join("pareto.csv"), certified_table(&cert, &file, &by_id).as_bytes())?;
    write_certification(out, &file)?;
    let (tested, certified) = cert.counts();
    Ok(Some(CertificationSummary { tested, certified, front: cert.front, why_none: file.why_none }))
}

/// search_pareto.csv: the search's front, as pareto.csv holds it before certification.
fn search_table(front: &[&Individual<GripperInfo>]) -> String {
    let robust = front.first().map(|p| super::RobustColumns::of(&p.eval.info.record)).unwrap_or_default();
    let title = "search_pareto.csv: the search's front (objectives on its common scenarios; not certified: pareto.csv holds the certified front), by id";
    let mut csv = header_with(title, &DESIGN_COLUMNS, &robust);
    for ind in front {
        csv.push_str(&DesignRow::of(ind, Some(0)).csv_line());
    }
    csv
}

/// The certified front's rows (ids of `file.front`, found among `by_id`), by id.
fn certified_rows(file: &CertificationFile, by_id: &BTreeMap<u64, &Individual<GripperInfo>>) -> Option<Vec<DesignRow>> {
    let rows = file.front.iter().map(|id| Some(certified_row(by_id.get(id)?, file.designs.get(id)?)));
    rows.collect()
}

/// pareto.csv of a certified run: its title says what the rows are, a `#` line why none is
/// certified where none is.
fn certified_table(
    cert: &CertifiedFront,
    file: &CertificationFile,
    by_id: &BTreeMap<u64, &Individual<GripperInfo>>,
) -> String {
    let rows = certified_rows(file, by_id).unwrap_or_default();
    // the columns of a certified row: the first row's, else a tested design's
    let columns = rows.first().map(|r| r.robust.clone()).or_else(|| {
        let (id, rec) = cert.records.iter().next()?;
        Some(certified_row(by_id.get(id)?, rec).robust)
    });
    let title = format!(
        "pareto.csv: the certified front: designs with P(stay) >= {} on every object at confidence {} on fresh scenarios (certification.json), non-dominated by their objectives estimated there, by id",
        file.p_min, file.confidence
    );
    let mut csv = header_with(&title, &DESIGN_COLUMNS, &columns.unwrap_or_default());
    if let Some(why) = &file.why_none {
        // before the column names, as every `#` line
        let at = csv.rfind("\nid,").map_or(0, |k| k + 1);
        csv.insert_str(at, &format!("# {why}\n"));
    }
    for r in &rows {
        csv.push_str(&r.csv_line());
    }
    csv
}

/// The certified front's rows of a checkpoint's state, when `file` (the run's
/// certification.json) certified that very state: its generation; None otherwise (no
/// certification, or one of an earlier end of the run).
pub fn checkpoint_front(
    file: Option<&CertificationFile>,
    st: &Nsga2State<GripperInfo>,
    archive: Option<&Archive>,
) -> Option<Vec<DesignRow>> {
    let file = file.filter(|f| f.generation == st.generation)?;
    let empty = Archive::default();
    certified_rows(file, &by_id(st, archive.unwrap_or(&empty)))
}
