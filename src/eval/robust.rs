//! Robust evaluation (issue 22): a design against several objects and the uncertainty of
//! the grasp. Stages 0–1 run once per design (they concern the hand only); stage 2 once per
//! object at its nominal inputs (the spring sized once, at `[hand] tau`; each object gripped
//! with its own torque): it gives the static objectives max_offset, α and F̃ per object and
//! discards a design that cannot hold some object statically. Then each scenario (an object
//! and a draw of the uncertain inputs) runs stage 3 of the free kind: the centred grasp (t_stab
//! and the finger's own criteria) and the free scene at the drawn offset (does the object
//! barely move, MODEL.md §14.4). Scenarios run in a fixed order — round k visits every
//! object's scenario k — and stop early once some object's constraint P(stay) ≥ p_min can no
//! longer be met: the result depends on that order only, never on which thread ran what.

use super::record_robust::ScenarioRecord;
use super::stage3::{evaluate_dynamics, stage3};
use super::stages::{kinematics_partial, statics_with_spring, Cause, Discard, EvalOptions, Evaluation};
use crate::model::{spring_preload, CentredGrasp, StaticsResult};
use crate::params::{Design, Problem, Robust, Scenario, SceneParams, STREAM_OPTIMISE};
use crate::sim::{Controls, Integration, SceneSpec, Sink};
use std::time::Instant;

/// What a robust evaluation needs of its problem, computed once: the objects' nominal scenes
/// and every scenario with its scene.
#[derive(Debug, Clone)]
pub struct RobustSetup {
    /// The problem's `[robust]`.
    pub spec: Robust,
    /// The problem's own scene (the hand, the spring's sizing torque, the contact laws).
    pub base: SceneParams,
    /// Per object: its nominal scene (its cylinder and grip torque, the free kind).
    pub object_scenes: Vec<SceneParams>,
    /// K: scenarios per object.
    pub k: usize,
    /// Every scenario, object-major (index o·K + k).
    pub scenarios: Vec<Scenario>,
    /// The scene of each scenario (same index).
    pub scenario_scenes: Vec<SceneParams>,
    /// Stop a design's scenarios once an object's constraint fails.
    pub early_stop: bool,
}

impl RobustSetup {
    /// The optimisation's setup of a robust problem (None: the problem is not robust).
    pub fn of(p: &Problem) -> Option<Self> {
        p.robust.as_ref().map(|r| Self::with_stream(p, r, STREAM_OPTIMISE, r.count(STREAM_OPTIMISE), r.early_stop))
    }

    /// The setup of `n` scenarios per object drawn from `stream` (verify: an out-of-sample
    /// stream, every scenario run).
    pub fn with_stream(p: &Problem, r: &Robust, stream: u64, n: usize, early_stop: bool) -> Self {
        let base = p.scene.clone();
        let object_scenes = r
            .objects
            .iter()
            .map(|o| {
                let mut s = base.clone();
                s.object = o.object;
                s.hand.tau = o.tau;
                s
            })
            .collect();
        let scenarios: Vec<Scenario> = (0..r.objects.len())
            .flat_map(|o| (0..n).map(move |k| (o, k)))
            .map(|(o, k)| r.scenario(&base, o, k, stream))
            .collect();
        let scenario_scenes = scenarios.iter().map(|sc| sc.scene(&base, &r.objects[sc.object])).collect();
        RobustSetup { spec: r.clone(), base, object_scenes, k: n, scenarios, scenario_scenes, early_stop }
    }

    /// Number of objects.
    pub fn objects(&self) -> usize {
        self.object_scenes.len()
    }

    /// The order scenarios are run in: round k visits object 0's, 1's, … scenario k.
    pub fn sequence(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        (0..self.k).flat_map(move |k| (0..self.objects()).map(move |o| (o, k)))
    }

    /// Scenarios in all.
    pub fn planned(&self) -> usize {
        self.k * self.objects()
    }

    /// Failures an object may have while P̂ ≥ p_min holds over K scenarios.
    pub fn failures_allowed(&self) -> usize {
        self.spec.failures_allowed(self.k)
    }
}

/// A design after stages 0–2 on every object.
#[derive(Debug, Clone)]
pub struct RobustStart {
    /// Stages 0–1 and the first object's stage 2: the flat part of the design's record.
    pub base: Evaluation,
    /// Stage 2 per object (None: stages 0–1 or the spring discarded the design first).
    pub objects: Vec<Option<Result<StaticsResult, Discard>>>,
    /// The design's stage 0–2 discard: the stage, the reason (naming the object) and the
    /// violation (summed over the objects that fail).
    pub discard: Option<(u8, String, f64, Option<Cause>)>,
}

impl RobustStart {
    /// True when the design goes on to its scenarios.
    pub fn passed(&self) -> bool {
        self.discard.is_none()
    }
}

/// Stages 0–2 of `x` on every object of `setup`.
pub fn start(x: &Design, setup: &RobustSetup) -> RobustStart {
    let t0 = Instant::now();
    let mut base = Evaluation::new(*x);
    let n = setup.objects();
    let kin = match kinematics_partial(x, &setup.base) {
        Ok(k) => k,
        Err((d, partial)) => {
            base.discard = Some(d);
            base.partial = partial;
            base.stage_seconds[1] = t0.elapsed().as_secs_f64();
            let why = (d.stage, d.reason.to_string(), d.violation, d.reason.cause());
            return RobustStart { base, objects: vec![None; n], discard: Some(why) };
        }
    };
    base.kin = Some(kin);
    let t1 = Instant::now();
    base.stage_seconds[1] = (t1 - t0).as_secs_f64();
    let Some((tau_s_min, tau_s0)) = spring_preload(&kin.finger, &setup.base) else {
        // the same discard as the single-object pipeline's
        let ev = super::stages::evaluate_statics(x, &setup.base);
        let d = ev.discard.expect("no spring preload discards the design");
        base.discard = Some(d);
        base.partial = ev.partial;
        let why = (d.stage, d.reason.to_string(), d.violation, d.reason.cause());
        return RobustStart { base, objects: vec![None; n], discard: Some(why) };
    };
    let objects: Vec<_> =
        setup.object_scenes.iter().map(|s| Some(statics_with_spring(&kin.finger, s, tau_s_min, tau_s0))).collect();
    match &objects[0] {
        Some(Ok(st)) => base.statics = Some(*st),
        Some(Err((d, partial))) => {
            base.discard = Some(*d);
            base.partial = *partial;
        }
        None => {}
    }
    base.stage_seconds[2] = t1.elapsed().as_secs_f64();
    let mut discard = None;
    let mut total = 0.0;
    for (o, r) in objects.iter().enumerate() {
        if let Some(Err((d, _))) = r {
            total += d.violation;
            if discard.is_none() {
                let name = &setup.spec.objects[o].name;
                discard = Some((2, format!("object {name}: {}", d.reason), 0.0, d.reason.cause()));
            }
        }
    }
    if let Some(d) = discard.as_mut() {
        d.2 = total;
    }
    let objects = objects.into_iter().map(|r| r.map(|r| r.map_err(|(d, _)| d))).collect();
    RobustStart { base, objects, discard }
}

/// The diagnostic simulation of `x` on object `o` of `setup` in `spec` (`simulate --object`),
/// as [`super::simulate`] does on the reference object: stages 0–2 as the robust evaluation
/// has them on that object (its cylinder and grip torque, the spring sized at `[hand] tau`),
/// then stage 3 in the object's nominal scene.
pub fn simulate_object<K: Sink + ?Sized>(
    x: &Design,
    setup: &RobustSetup,
    o: usize,
    spec: &SceneSpec,
    integ: &Integration,
    ctl: &Controls,
    sink: &mut K,
) -> Evaluation {
    let st = start(x, setup);
    let mut ev = Evaluation::new(*x);
    (ev.kin, ev.stage_seconds) = (st.base.kin, st.base.stage_seconds);
    match st.objects.get(o) {
        Some(Some(Ok(statics))) => ev.statics = Some(*statics),
        Some(Some(Err(d))) => ev.discard = Some(*d),
        // stages 0–1 or the spring discarded the design, whatever the object
        _ => return st.base,
    }
    stage3(ev, &setup.object_scenes[o], spec, integ, ctl, true, sink)
}

/// Scenario k of object o of a design that passed stages 0–2: stage 3 of the free kind in the
/// scenario's scene (its samples to `sink`), as a compact record, and the evaluation.
pub fn run_scenario<K: Sink + ?Sized>(
    start: &RobustStart,
    setup: &RobustSetup,
    o: usize,
    k: usize,
    opts: &EvalOptions,
    sink: &mut K,
) -> (ScenarioRecord, Evaluation) {
    let t = Instant::now();
    let i = o * setup.k + k;
    let (sc, s) = (&setup.scenarios[i], &setup.scenario_scenes[i]);
    let kin = start.base.kin.expect("a started design has its finger");
    let Some(Some(Ok(st_o))) = start.objects.get(o) else { panic!("scenario of a design that failed stage 2") };
    let mut ev = Evaluation::new(start.base.design);
    ev.kin = Some(kin);
    // the scenario's statics: the same spring, the scenario's torque and object
    match crate::model::grasp_at(&kin.finger, s, st_o.tau_s0, 0.0) {
        Ok(g) if g.forces[0].f0.iter().all(|f| *f > 0.0) => {
            let st = StaticsResult { grasp: CentredGrasp::of(&g), ..*st_o };
            ev.statics = Some(st);
            ev = evaluate_dynamics(ev, s, opts, sink);
        }
        _ => {
            let reason = crate::model::OffsetFailure::ForceNotPositive(0.0);
            ev.discard = Some(Discard { stage: 2, reason: super::stages::Reason::Grasp(reason), violation: 1.0 });
        }
    }
    ev.stage_seconds[3] = t.elapsed().as_secs_f64();
    (ScenarioRecord::of(sc, &ev), ev)
}

/// What decides a robust design's stage 3, scanning its scenarios in their order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decided {
    /// The solver aborted the scenario at this position (in the order run): the design is a
    /// solver-failure discard, as the single-object pipeline's aborted simulation.
    Aborted(usize),
    /// The scenario at this position gave its object more failures than P(stay) ≥ p_min
    /// allows over K.
    PStay(usize),
}

/// The sequential stopping rule: fed a design's scenarios in their order, it says when the
/// verdict is known — at the first aborted scenario (its object's motion was never measured,
/// so it is not counted as a failure) or at the first measured failure that makes some
/// object's constraint impossible.
#[derive(Debug, Clone)]
pub struct StopRule {
    fmax: usize,
    fails: Vec<usize>,
    seen: usize,
}

impl StopRule {
    /// The rule for the designs of `setup`.
    pub fn new(setup: &RobustSetup) -> Self {
        StopRule { fmax: setup.failures_allowed(), fails: vec![0; setup.objects()], seen: 0 }
    }

    /// The next scenario; Some once this one decides the verdict.
    pub fn push(&mut self, r: &ScenarioRecord) -> Option<Decided> {
        let j = self.seen;
        self.seen += 1;
        if r.aborted() {
            return Some(Decided::Aborted(j));
        }
        if !r.stays {
            self.fails[r.object] += 1;
            if self.fails[r.object] > self.fmax {
                return Some(Decided::PStay(j));
            }
        }
        None
    }
}

/// What decides the verdict of a design with scenarios `scen` (in their order), if anything
/// does: the first event of [`StopRule`].
pub fn decided(setup: &RobustSetup, scen: &[ScenarioRecord]) -> Option<Decided> {
    let mut rule = StopRule::new(setup);
    scen.iter().find_map(|r| rule.push(r))
}

/// The scenarios of a design in their order, each from `get(o, k)`, stopping after the one
/// that decides the verdict ([`StopRule`]: an aborted scenario, or one that makes some
/// object's constraint impossible) when `setup.early_stop` is set.
pub fn fold(setup: &RobustSetup, mut get: impl FnMut(usize, usize) -> ScenarioRecord) -> Vec<ScenarioRecord> {
    let mut rule = StopRule::new(setup);
    let mut out = Vec::with_capacity(setup.planned());
    for (o, k) in setup.sequence() {
        let r = get(o, k);
        let decided = rule.push(&r).is_some();
        out.push(r);
        if decided && setup.early_stop {
            break;
        }
    }
    out
}

/// The last position in the sequence a design can still need, knowing only some of its
/// scenarios (`done[j]`: the record of position j once it has run): the first known position
/// that [`StopRule`] stops at whatever the unknown positions before it hold — an aborted
/// scenario, or one whose object already has more measured failures than allowed among the
/// known positions up to it. The true stop can only be earlier (unknown positions before it
/// may stop the rule too), so no position after this bound is needed.
pub fn needed_bound(setup: &RobustSetup, done: &[Option<ScenarioRecord>]) -> usize {
    let last = setup.planned().saturating_sub(1);
    if !setup.early_stop {
        return last;
    }
    let fmax = setup.failures_allowed();
    let mut fails = vec![0usize; setup.objects()];
    for (j, (o, _)) in setup.sequence().enumerate() {
        let Some(r) = done.get(j).and_then(Option::as_ref) else { continue };
        if r.aborted() {
            return j;
        }
        if !r.stays {
            fails[o] += 1;
            if fails[o] > fmax {
                return j;
            }
        }
    }
    last
}

/// A robust design evaluated one scenario after the other (what a worker or the facade
/// does; the batch evaluator gives the same result in parallel).
pub fn evaluate_sequential(x: &Design, setup: &RobustSetup, opts: &EvalOptions) -> (RobustStart, Vec<ScenarioRecord>) {
    let st = start(x, setup);
    let scen = if st.passed() { fold(setup, |o, k| run_scenario(&st, setup, o, k, opts, &mut ()).0) } else { vec![] };
    (st, scen)
}
