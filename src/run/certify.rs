//! The certification stage of a robust run (issue 41, docs/robust.md "Certification"): the
//! search found designs that meet P(stay) ≥ p_min on its K common scenarios, which
//! optimising over one sample biases upwards; the designs it reports are those certified on
//! fresh scenarios (`STREAM_CERTIFY`) by the group-sequential test of
//! [`CertifyPlan`](crate::eval::CertifyPlan), and non-dominated among the certified ones by
//! their objectives estimated on the fresh scenarios.
//!
//! Which designs are tested: the candidates (a run's: the search's front); the
//! non-dominated set of those not rejected (certified ones by their fresh objectives,
//! untested ones by their search objectives) is taken, its untested members
//! certified (in parallel, (design, scenario) tasks), the rejected dropped, and this repeated
//! until every member of the set is certified: the reported front is exactly the
//! non-dominated set of the certified designs, and a design dominated by a certified one is
//! never tested. Each certification is a pure function of the design and the problem, so the
//! stage gives the same bits at any thread count and after a kill and a resume.

use super::gripper::{GripperInfo, GripperProblem};
use super::outputs::DesignRow;
use crate::error::{Error, Result};
use crate::eval::{minimised, CertificationRecord, CertifyPlan, DesignStart, EvalOptions, ScenarioRecord, Study};
use crate::optim::{pareto_ranks, Individual};
use crate::params::{Problem, STREAM_CERTIFY};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// What the certification stage gives.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CertifiedFront {
    /// The plan of the test.
    pub plan: Option<CertifyPlan>,
    /// Every design tested, by id.
    pub records: BTreeMap<u64, CertificationRecord>,
    /// The reported front: certified, non-dominated among the certified, by id.
    pub front: Vec<u64>,
}

impl CertifiedFront {
    /// Designs tested and, of them, certified.
    pub fn counts(&self) -> (usize, usize) {
        (self.records.len(), self.records.values().filter(|r| r.certified).count())
    }

    /// Why nothing was certified, per object: how many tested designs failed on it and how
    /// often (None when some design is certified or none was tested).
    pub fn why_none(&self) -> Option<String> {
        if self.records.is_empty() || self.records.values().any(|r| r.certified) {
            return None;
        }
        let mut by_object: BTreeMap<&str, (usize, usize, usize)> = BTreeMap::new();
        for r in self.records.values() {
            for o in r.objects.iter().filter(|o| o.certified == Some(false)) {
                let e = by_object.entry(&o.name).or_default();
                e.0 += 1;
                e.1 += o.scenarios - o.stays;
                e.2 += o.scenarios;
            }
        }
        let parts: Vec<String> = by_object
            .iter()
            .map(|(name, (designs, fails, runs))| {
                format!("{name}: {designs} designs given up ({fails} failures in {runs} fresh scenarios)")
            })
            .collect();
        Some(format!(
            "no design certified: {} tested, none keeps P(stay) >= p_min on fresh scenarios at the plan's confidence; {}",
            self.records.len(),
            parts.join("; ")
        ))
    }
}

/// The certification study of problem `p`: its objects on `STREAM_CERTIFY`, K = the plan's
/// last look (None: the problem is not robust or does not certify).
pub fn certification_study(p: &Problem) -> Option<(Study, CertifyPlan)> {
    let r = p.robust.as_ref().filter(|r| r.certify.enabled)?;
    let plan = CertifyPlan::new(&r.certify, r.p_min);
    Some((Study::drawn(p, r, STREAM_CERTIFY, plan.last(), true), plan))
}

/// Certify `candidates` (the run's feasible designs, each once) of problem `gp` in the
/// current rayon pool: the reported front and every design tested.
pub fn certify_front(gp: &GripperProblem, candidates: &[&Individual<GripperInfo>]) -> CertifiedFront {
    let Some((study, plan)) = certification_study(&gp.problem) else { return CertifiedFront::default() };
    let opts = gp.options;
    let crit = &gp.problem.scene.criteria;
    let mut records: BTreeMap<u64, CertificationRecord> = BTreeMap::new();
    loop {
        // the pool: every candidate not rejected, by its fresh objectives once certified
        let pool: Vec<(&Individual<GripperInfo>, [f64; 4])> = candidates
            .iter()
            .filter(|c| records.get(&c.id).is_none_or(|r| r.certified))
            .map(|c| {
                let o = match records.get(&c.id) {
                    Some(r) => r.objectives.to_array(),
                    None => c.eval.info.record.objectives(),
                };
                (*c, minimised(o, crit))
            })
            .collect();
        let f: Vec<&[f64]> = pool.iter().map(|p| p.1.as_slice()).collect();
        let ranks = pareto_ranks(&f);
        let untested: Vec<&Individual<GripperInfo>> = pool
            .iter()
            .zip(&ranks)
            .filter(|(p, r)| **r == 0 && !records.contains_key(&p.0.id))
            .map(|(p, _)| p.0)
            .collect();
        if untested.is_empty() {
            let mut front: Vec<u64> = pool.iter().zip(&ranks).filter(|(_, r)| **r == 0).map(|(p, _)| p.0.id).collect();
            front.sort_unstable();
            return CertifiedFront { plan: Some(plan), records, front };
        }
        let done = certify_batch(&study, &plan, &opts, &untested);
        records.extend(untested.iter().map(|c| c.id).zip(done));
    }
}

/// A design of a batch while it is certified: its start, and the records of its positions done.
struct Pending {
    start: DesignStart,
    done: Mutex<Vec<Option<ScenarioRecord>>>,
}

/// Certify `designs` in parallel: their (design, position) tasks round by round (list
/// scheduling from a shared counter), each task skipped once the records known show it is not
/// needed; then each design's certification folded in the study's order (a position the
/// skipping did not foresee is run then, so the result never depends on the schedule).
fn certify_batch(
    study: &Study,
    plan: &CertifyPlan,
    opts: &EvalOptions,
    designs: &[&Individual<GripperInfo>],
) -> Vec<CertificationRecord> {
    let design = |c: &Individual<GripperInfo>| {
        crate::params::Design::from_array(c.x.as_slice().try_into().expect("six design variables"))
    };
    let n = study.planned();
    let pending: Vec<Pending> = designs
        .par_iter()
        .map(|c| Pending { start: study.start(&design(c)), done: Mutex::new(vec![None; n]) })
        .collect();
    let seq: Vec<(usize, usize)> = study.sequence().collect();
    let tasks: Vec<(usize, usize)> =
        (0..n).flat_map(|j| (0..pending.len()).filter(|&d| pending[d].start.passed()).map(move |d| (d, j))).collect();
    let next = AtomicUsize::new(0);
    let workers = rayon::current_num_threads().min(tasks.len()).max(1);
    (0..workers).into_par_iter().with_max_len(1).for_each(|_| loop {
        let t = next.fetch_add(1, Ordering::Relaxed);
        let Some(&(d, j)) = tasks.get(t) else { break };
        let (o, k) = seq[j];
        {
            let done = pending[d].done.lock().expect("certification");
            if j > study.certify_bound(plan, &done) || study.certified_before(plan, &done, o, k) {
                continue;
            }
        }
        let (r, _) = study.run_scenario(&pending[d].start, o, k, opts, &mut ());
        pending[d].done.lock().expect("certification")[j] = Some(r);
    });
    pending
        .into_par_iter()
        .map(|p| {
            let mut done = p.done.into_inner().expect("certification");
            let objects = study.objects();
            study.certify(plan, &p.start, |o, k| match done[k * objects + o].take() {
                Some(r) => r,
                None => study.run_scenario(&p.start, o, k, opts, &mut ()).0,
            })
        })
        .collect()
}

/// The file of a robust run's certification (every design tested, the plan, the front).
pub const CERTIFICATION_FILE: &str = "certification.json";

/// certification.json: what the certification stage found, as written.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CertificationFile {
    /// The generation of the run's state certified (the last of the search).
    #[serde(default)]
    pub generation: u64,
    /// P(stay) ≥ p_min, the constraint certified.
    pub p_min: f64,
    /// 1 − α of the test.
    pub confidence: f64,
    /// Scenarios per object at each look.
    pub looks: Vec<usize>,
    /// Per look the fewest stays that certify an object.
    pub min_stays: Vec<usize>,
    /// The reported front (certified, non-dominated among the certified), by id.
    pub front: Vec<u64>,
    /// Why nothing was certified (None when some design is).
    pub why_none: Option<String>,
    /// Every design tested, by id.
    pub designs: BTreeMap<u64, CertificationRecord>,
}

impl CertifiedFront {
    /// The file of this certification (None: nothing was certified, the problem does not
    /// certify).
    pub fn file(&self) -> Option<CertificationFile> {
        let plan = self.plan.as_ref()?;
        Some(CertificationFile {
            generation: 0,
            p_min: plan.p_min,
            confidence: plan.confidence,
            looks: plan.looks.clone(),
            min_stays: plan.min_stays.clone(),
            front: self.front.clone(),
            why_none: self.why_none(),
            designs: self.records.clone(),
        })
    }
}

/// Write `RUN_DIR/certification.json` (atomically).
pub fn write_certification(dir: &Path, c: &CertificationFile) -> Result<()> {
    let text = serde_json::to_string_pretty(c).map_err(|e| Error::Input(format!("certification: {e}")))?;
    crate::fsutil::write_atomic(&dir.join(CERTIFICATION_FILE), text.as_bytes())
}

/// `RUN_DIR/certification.json`, if the run wrote one.
pub fn read_certification(dir: &Path) -> Result<Option<CertificationFile>> {
    let path = dir.join(CERTIFICATION_FILE);
    if std::fs::symlink_metadata(&path).is_err() {
        return Ok(None);
    }
    let text = crate::fsutil::read_regular_string(&path, crate::fsutil::caps::TABLE)
        .map_err(|e| Error::io(&path, "cannot read", e))?;
    serde_json::from_str(&text).map(Some).map_err(|source| Error::Json {
        path,
        what: "invalid certification.json",
        source,
    })
}

/// pareto.csv's row of design `ind` certified as `c`: its objectives estimated on the fresh
/// scenarios (t_stab aggregated over them; the static ones are stage 2's), the search's
/// robust columns, then the certification's (per object its fresh counts and the one-sided
/// lower bound on P(stay)).
pub fn certified_row(ind: &Individual<GripperInfo>, c: &CertificationRecord) -> DesignRow {
    let mut row = DesignRow::of(ind, Some(0));
    let search_t_stab = row.t_stab;
    let o = c.objectives.reported();
    (row.max_offset, row.alpha, row.mean_force, row.t_stab) = (o.max_offset, o.alpha, o.mean_force, o.t_stab);
    row.robust = std::mem::take(&mut row.robust).with_certification(c, search_t_stab);
    row
}
