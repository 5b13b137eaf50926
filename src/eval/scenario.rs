//! A design on a [`Study`]: stages 0–1 once per design (they concern the hand only), stage 2
//! once per object at its nominal inputs (the spring sized once, at the problem's `[hand]
//! tau`; each object gripped with its own torque): the static objectives per object, and a
//! discard naming the object a design cannot hold statically ([`start`]). Then each scenario's
//! stage 3 in its own scene ([`run_scenario`]): a drawn scenario first recomputes its static
//! grasp at its own torque and friction with the same spring.

use super::record_robust::ScenarioRecord;
use super::stage3::{evaluate_dynamics, stage3};
use super::stages::{
    kinematics_partial, statics_with_spring, Cause, Discard, EvalOptions, Evaluation, Reason, MISSING_POSE_VIOLATION,
};
use super::study::Study;
use crate::model::{spring_preload, CentredGrasp, OffsetFailure, StaticsResult};
use crate::params::Design;
use crate::sim::{Controls, Integration, SceneSpec, Sink};
use std::time::Instant;

/// Why stages 0–2 discarded a design, knowing the object it failed on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartDiscard {
    /// The first failing object's discard (stages 0–1 and the spring: the design's own).
    pub discard: Discard,
    /// The object it failed on first (None: stages 0–1 or the spring, whatever the object).
    pub object: Option<usize>,
    /// The violation, summed over the objects that fail stage 2.
    pub violation: f64,
}

impl StartDiscard {
    /// The reason in words: `object NAME: …` where the study names its objects.
    pub fn reason(&self, study: &Study) -> String {
        match self.object.and_then(|o| study.object_name(o)) {
            Some(name) => format!("object {name}: {}", self.discard.reason),
            None => self.discard.reason.to_string(),
        }
    }
    /// The failing stage.
    pub fn stage(&self) -> u8 {
        self.discard.stage
    }
    /// Its class.
    pub fn cause(&self) -> Option<Cause> {
        self.discard.reason.cause()
    }
}

/// A design after stages 0–2 on every object of its study.
#[derive(Debug, Clone)]
pub struct DesignStart {
    /// Stages 0–1 and the first object's stage 2: the flat part of the design's record (the
    /// whole of it for a design that goes no further in a 1 × 1 study).
    pub base: Evaluation,
    /// Stage 2 per object (None: stages 0–1 or the spring discarded the design first).
    pub objects: Vec<Option<Result<StaticsResult, Discard>>>,
    /// The design's stage 0–2 discard, if any.
    pub discard: Option<StartDiscard>,
}

impl DesignStart {
    /// True when the design goes on to its scenarios.
    pub fn passed(&self) -> bool {
        self.discard.is_none()
    }
}

impl Study {
    /// Stages 0–2 of `x` on every object (for the 1 × 1 study: `evaluate_statics`, bit for
    /// bit).
    // A stage's discard carries its partial values by value: an evaluation allocates nothing.
    #[allow(clippy::result_large_err)]
    pub fn start(&self, x: &Design) -> DesignStart {
        let t0 = Instant::now();
        let mut base = Evaluation::new(*x);
        let n = self.objects();
        let whole = |base: Evaluation, d: Discard| DesignStart {
            base,
            objects: vec![None; n],
            discard: Some(StartDiscard { discard: d, object: None, violation: d.violation }),
        };
        let kin = match kinematics_partial(x, &self.base) {
            Ok(k) => k,
            Err((d, partial)) => {
                (base.discard, base.partial) = (Some(d), partial);
                base.stage_seconds[1] = t0.elapsed().as_secs_f64();
                return whole(base, d);
            }
        };
        base.kin = Some(kin);
        let t1 = Instant::now();
        base.stage_seconds[1] = (t1 - t0).as_secs_f64();
        let Some((tau_s_min, tau_s0)) = spring_preload(&kin.finger, &self.base) else {
            let d = Discard { stage: 2, reason: Reason::SpringUndefined, violation: MISSING_POSE_VIOLATION };
            base.discard = Some(d);
            base.stage_seconds[2] = t1.elapsed().as_secs_f64();
            return whole(base, d);
        };
        let objects: Vec<_> =
            self.objects.iter().map(|o| statics_with_spring(&kin.finger, &o.scene, tau_s_min, tau_s0)).collect();
        match &objects[0] {
            Ok(st) => base.statics = Some(*st),
            Err((d, partial)) => (base.discard, base.partial) = (Some(*d), *partial),
        }
        base.stage_seconds[2] = t1.elapsed().as_secs_f64();
        let failing = || objects.iter().enumerate().filter_map(|(o, r)| r.as_ref().err().map(|(d, _)| (o, *d)));
        let discard = failing().next().map(|(o, d)| StartDiscard {
            discard: d,
            object: Some(o),
            violation: failing().map(|(_, d)| d.violation).sum(),
        });
        let objects = objects.into_iter().map(|r| Some(r.map_err(|(d, _)| d))).collect();
        DesignStart { base, objects, discard }
    }

    /// Scenario k of object o of a design that passed stages 0–2: its stage 3 (samples and
    /// events to `sink`), as a compact record, and the evaluation (for the 1 × 1 study the
    /// design's whole evaluation).
    pub fn run_scenario<K: Sink + ?Sized>(
        &self,
        start: &DesignStart,
        o: usize,
        k: usize,
        opts: &EvalOptions,
        sink: &mut K,
    ) -> (ScenarioRecord, Evaluation) {
        let t = Instant::now();
        let sc = self.scenario(o, k);
        let Some(Some(Ok(st_o))) = start.objects.get(o) else { panic!("scenario of a design that failed stage 2") };
        if !sc.drawn {
            let mut ev = start.base;
            ev.statics = Some(*st_o);
            let ev = evaluate_dynamics(ev, &sc.scene, opts, sink);
            return (ScenarioRecord::of(&sc.scenario, &ev), ev);
        }
        let kin = start.base.kin.expect("a started design has its finger");
        let mut ev = Evaluation::new(start.base.design);
        ev.kin = Some(kin);
        // the scenario's statics: the same spring, the scenario's torque and object
        match crate::model::grasp_at(&kin.finger, &sc.scene, st_o.tau_s0, 0.0) {
            Ok(g) if g.forces[0].f0.iter().all(|f| *f > 0.0) => {
                ev.statics = Some(StaticsResult { grasp: CentredGrasp::of(&g), ..*st_o });
                ev = evaluate_dynamics(ev, &sc.scene, opts, sink);
            }
            _ => {
                let reason = Reason::Grasp(OffsetFailure::ForceNotPositive(0.0));
                ev.discard = Some(Discard { stage: 2, reason, violation: 1.0 });
            }
        }
        ev.stage_seconds[3] = t.elapsed().as_secs_f64();
        (ScenarioRecord::of(&sc.scenario, &ev), ev)
    }

    /// The diagnostic simulation of `x` on object `o` in `spec` (`simulate --object`), as
    /// [`super::simulate`] does on the reference object: stages 0–2 as this study has them on
    /// that object, then stage 3 in the object's nominal scene.
    pub fn simulate_object<K: Sink + ?Sized>(
        &self,
        x: &Design,
        o: usize,
        spec: &SceneSpec,
        integ: &Integration,
        ctl: &Controls,
        sink: &mut K,
    ) -> Evaluation {
        let st = self.start(x);
        let mut ev = Evaluation::new(*x);
        (ev.kin, ev.stage_seconds) = (st.base.kin, st.base.stage_seconds);
        match st.objects.get(o) {
            Some(Some(Ok(statics))) => ev.statics = Some(*statics),
            Some(Some(Err(d))) => ev.discard = Some(*d),
            // stages 0–1 or the spring discarded the design, whatever the object
            _ => return st.base,
        }
        stage3(ev, &self.objects[o].scene, spec, integ, ctl, true, sink)
    }
}
