//! The record of a design on a chance-constrained study (a robust problem, docs/robust.md):
//! the flat part, the `robust` sub-record folded from its scenarios (per object P(stay) with
//! its Clopper–Pearson interval, the aggregated objectives) and the verdict over all objects.

use super::binomial::clopper_pearson;
use super::objectives::Objectives;
use super::record::{Record, Verdict};
use super::record_robust::{ObjectRecord, RobustRecord, ScenarioRecord};
use super::scenario::DesignStart;
use super::scene_record::fin;
use super::stages::Cause;
use super::stop::{decided, Decided};
use super::study::Study;

/// The record of a design on a chance-constrained study, and the aggregated max_offset the
/// optimiser ranks (m): an object not form closed at 0 counts as −Δ_off there (MODEL.md §6.7), a placeholder the record never
/// carries (its max_offset, the object's and the aggregate where negative, is None).
pub(super) fn chance_record(study: &Study, start: &DesignStart, scen: Vec<ScenarioRecord>) -> (Record, Option<f64>) {
    let spec = study.chance().expect("a chance-constrained study");
    let mut rec = Record::from_eval(&start.base);
    let n = study.objects();
    let fmax = study.failures_allowed();
    let agg = &spec.aggregate;
    let t_max = study.base.criteria.t_max;
    let mut objects = Vec::with_capacity(n);
    let mut all_t = vec![];
    let mut raw_offsets = Vec::with_capacity(n);
    for o in 0..n {
        let st = match &start.objects[o] {
            Some(Ok(st)) => Some(st),
            _ => None,
        };
        let mine: Vec<&ScenarioRecord> = scen.iter().filter(|r| r.object == o).collect();
        let stays = mine.iter().filter(|r| r.stays).count();
        let runs = mine.len();
        // a scenario that did not stabilise (or had no grasp to simulate) counts at t_max,
        // MODEL.md §10's value of a missing t_stab: never better than one that settled
        let t: Vec<f64> = mine.iter().map(|r| r.t_stab.unwrap_or(t_max)).collect();
        all_t.extend(&t);
        raw_offsets.push(st.map(|s| s.max_offset));
        let (lo, hi) = clopper_pearson(stays as u64, runs as u64, spec.confidence);
        let meets = if runs - stays > fmax {
            Some(false)
        } else if runs == study.k {
            Some(true)
        } else {
            None
        };
        objects.push(ObjectRecord {
            name: spec.objects[o].name.clone(),
            objectives: Objectives {
                max_offset: st.map(|s| s.max_offset).filter(|m| *m >= 0.0),
                alpha: st.and_then(|s| fin(s.alpha)),
                mean_force: st.map(|s| s.mean_force),
                t_stab: fin(agg[3].apply(&t)),
            },
            scenarios: runs,
            stays,
            p_stay: (runs > 0).then(|| stays as f64 / runs as f64),
            p_stay_lo: (runs > 0).then_some(lo),
            p_stay_hi: (runs > 0).then_some(hi),
            meets_p_min: (runs > 0 || start.passed()).then_some(meets).flatten(),
            max_displacement: mine
                .iter()
                .filter_map(|r| r.max_displacement)
                .fold(None, |a, b| Some(a.map_or(b, |a: f64| a.max(b)))),
        });
    }
    let statics_known = objects.iter().all(|o| o.objectives.mean_force.is_some());
    let over_objects = |k: usize, vals: Vec<Option<f64>>, sign: f64| -> Option<f64> {
        if !statics_known {
            return None;
        }
        let vals: Vec<f64> = vals.iter().map(|v| sign * v.unwrap_or(f64::NAN)).collect();
        if vals.iter().any(|x| !x.is_finite()) {
            return None;
        }
        fin(sign * agg[k].apply(&vals))
    };
    let of = |v: fn(&ObjectRecord) -> Option<f64>| objects.iter().map(v).collect::<Vec<_>>();
    let ranked_offset = over_objects(0, raw_offsets, -1.0);
    let objectives = Objectives {
        max_offset: ranked_offset.filter(|m| *m >= 0.0),
        alpha: over_objects(1, of(|o| o.objectives.alpha), 1.0),
        mean_force: over_objects(2, of(|o| o.objectives.mean_force), -1.0),
        t_stab: fin(agg[3].apply(&all_t)),
    };
    let sum = |f: fn(&ScenarioRecord) -> [u64; 2]| {
        scen.iter().fold([0, 0], |a, r| {
            let v = f(r);
            [a[0] + v[0], a[1] + v[1]]
        })
    };
    let planned = if start.passed() { study.planned() } else { 0 };
    let rr = RobustRecord {
        objectives,
        scenarios_planned: planned,
        scenarios_run: scen.len(),
        scenarios_saved: planned - scen.len(),
        rhs_evals: sum(|r| r.rhs_evals),
        steps: sum(|r| r.steps),
        objects,
        scenarios: scen,
    };
    rec.verdict = verdict(study, start, &rr);
    if start.passed() {
        // the scene its scenarios ran in (their offsets are drawn: none is the design's)
        (rec.scene, rec.x_off) = (Some(study.scenario(0, 0).scene.setup.kind), None);
    }
    rec.robust = Some(rr);
    (rec, ranked_offset)
}

/// Feasible iff every object passed stage 2, no scenario's simulation was aborted and every
/// object meets P(stay) ≥ p_min over its scenarios; otherwise stage 2's discard (the first
/// failing object's reason, the violations summed) or stage 3's: the first aborted scenario
/// in the order run, unless a measured failure made an object's constraint impossible before
/// it (the single-object discard's cause and violation, the reason naming the object and the
/// scenario), else the P(stay) failure, violation Σ_o max(0, p_min − P̂_o) over the
/// scenarios run.
fn verdict(study: &Study, start: &DesignStart, rr: &RobustRecord) -> Verdict {
    if let Some(d) = &start.discard {
        return Verdict {
            feasible: false,
            failed_stage: Some(d.stage()),
            reason: Some(d.reason(study)),
            violation: Some(d.violation),
            cause: d.cause(),
        };
    }
    if let Some(Decided::Aborted(j)) = decided(study, &rr.scenarios) {
        return aborted_verdict(study, rr, j);
    }
    let spec = study.chance().expect("a chance-constrained study");
    let failing: Vec<&ObjectRecord> = rr.objects.iter().filter(|o| o.meets_p_min == Some(false)).collect();
    let Some(first) = failing.first() else { return Verdict { feasible: true, ..Verdict::default() } };
    let violation: f64 = rr.objects.iter().filter_map(|o| o.p_stay).map(|p| (spec.p_min - p).max(0.0)).sum();
    let mut reason = format!(
        "object {}: stays (finger criteria met, object barely moves) in {} of {} scenarios (P(stay) {:.3} < p_min {}; Clopper–Pearson {}%: [{:.3}, {:.3}])",
        first.name,
        first.stays,
        first.scenarios,
        first.p_stay.unwrap_or(0.0),
        spec.p_min,
        spec.confidence * 100.0,
        first.p_stay_lo.unwrap_or(0.0),
        first.p_stay_hi.unwrap_or(1.0)
    );
    if rr.scenarios_saved > 0 {
        reason.push_str(&format!("; stopped early after {} of {} scenarios", rr.scenarios_run, rr.scenarios_planned));
    }
    Verdict {
        feasible: false,
        failed_stage: Some(3),
        reason: Some(reason),
        violation: Some(violation),
        cause: Some(Cause::PStay),
    }
}

/// The discard of a design whose scenario at position `j` (in the order run) the solver
/// aborted: as the single-object pipeline's (stage 3, its cause and violation), the reason
/// naming the object, the scenario and the solver's message.
fn aborted_verdict(study: &Study, rr: &RobustRecord, j: usize) -> Verdict {
    let r = &rr.scenarios[j];
    let name = study.object_name(r.object).unwrap_or_default();
    // a record read back has no message: its cause's word, and stage 3's violation of one
    let (message, violation) = match &r.abort {
        Some(a) => (a.message.clone(), a.violation),
        None => (r.cause.map_or("aborted", |c| c.as_str()).to_string(), 1e3),
    };
    let mut reason = format!("object {name}: scenario {}: {message}", r.k);
    if rr.scenarios_saved > 0 {
        reason.push_str(&format!("; stopped early after {} of {} scenarios", rr.scenarios_run, rr.scenarios_planned));
    }
    Verdict { feasible: false, failed_stage: Some(3), reason: Some(reason), violation: Some(violation), cause: r.cause }
}
