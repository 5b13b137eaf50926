//! Stage 3 (MODEL.md §10, §14): the design's simulation in a scene, and the one way to
//! simulate a design ([`simulate`]); the whole pipeline ([`evaluate`]).
//!
//! The centred and offset scenes decide by the grasp's criteria. The free kind composes
//! two scenes (an extension of §10 documented in docs/scenes.md): the thesis's impact
//! (§9.1) and force (§9.3) criteria *predict* whether the object moves, the free scene
//! *measures* it. So the centred scene runs in diagnostic mode (t_stab is the objective;
//! E_cyl/E_lim and the force margins stay in the record as the prediction) but its impact
//! and force criteria discard nothing; the free scene at the problem's x_off then discards
//! the design iff the object does not "barely move" (§14.4: moved, toppled or escaped). The
//! finger's own criteria (fold, stability, singular or aborted grasps) discard as in the
//! centred scene.

use super::stages::{evaluate_statics, Discard, EvalOptions, Evaluation, ObjectMotion, Reason, StaticsResult};
use crate::params::{Design, Problem, SceneParams};
use crate::sim::{
    force_margin, r_area, Controls, DynOutcome, DynamicsResult, FreeResult, Integration, Mode, SceneResult, SceneSpec,
    Sink,
};
use std::time::Instant;

/// Evaluate a design through the staged pipeline.
pub fn evaluate(x: &Design, s: &SceneParams, opts: &EvalOptions) -> Evaluation {
    evaluate_into(x, s, opts, &mut ())
}

/// Evaluate, reporting stage 3's samples and events to `sink` (the simulation that
/// decides the verdict; results do not depend on the sink).
pub fn evaluate_into<K: Sink + ?Sized>(x: &Design, s: &SceneParams, opts: &EvalOptions, sink: &mut K) -> Evaluation {
    let ev = evaluate_statics(x, s);
    if !opts.dynamics {
        return ev;
    }
    evaluate_dynamics(ev, s, opts, sink)
}

/// Evaluate the problem's design `x` with all stages.
pub fn evaluate_full(p: &Problem, x: &Design) -> Evaluation {
    evaluate(x, &p.scene, &EvalOptions::full(p))
}

/// Stage 3 of an evaluation from [`evaluate_statics`] in the problem's scene, reporting
/// its samples to `sink`; an evaluation that did not pass stages 0–2 comes back unchanged.
pub fn evaluate_dynamics<K: Sink + ?Sized>(
    ev: Evaluation,
    s: &SceneParams,
    opts: &EvalOptions,
    sink: &mut K,
) -> Evaluation {
    let spec = SceneSpec::of(&s.setup);
    stage3(ev, s, &spec, &opts.integration, &opts.controls, opts.measure_always, sink)
}

/// Simulate design `x` in scene `spec` of the problem's `s`: stages 0–2, then the scene
/// with the numerics `integ` and the controls `ctl` (diagnostic mode runs every criterion
/// to its end), reporting samples and events to `sink`. In the free scene the centred
/// grasp (diagnostic mode) is the prediction and the free scene always runs. The
/// evaluation holds every value and the verdict an evaluation in that scene would give
/// (the free scene's measurement decides); `discard` is stage 0–2's when the scene could
/// not run.
pub fn simulate<K: Sink + ?Sized>(
    x: &Design,
    s: &SceneParams,
    spec: &SceneSpec,
    integ: &Integration,
    ctl: &Controls,
    sink: &mut K,
) -> Evaluation {
    stage3(evaluate_statics(x, s), s, spec, integ, ctl, true, sink)
}

/// Stage 3 in `spec` (`measure_always`: the free scene runs even when the finger's own
/// criteria discard the design).
pub(super) fn stage3<K: Sink + ?Sized>(
    mut ev: Evaluation,
    s: &SceneParams,
    spec: &SceneSpec,
    integ: &Integration,
    ctl: &Controls,
    measure_always: bool,
    sink: &mut K,
) -> Evaluation {
    let (Some(kin), Some(st), None) = (ev.kin, ev.statics, ev.discard) else { return ev };
    let t2 = Instant::now();
    let f = &kin.finger;
    (ev.scene, ev.x_off) = (Some(spec.kind()), spec.x_off());
    if let SceneSpec::Free { .. } = spec {
        let diag = Controls { mode: Mode::Diagnostic, ..*ctl };
        let c = grasp(crate::sim::simulate(f, s, &st, &SceneSpec::Centred, integ, &diag, sink));
        ev.dynamics = Some(c);
        ev.discard = finger_discard(&c);
        if ev.discard.is_none() || measure_always {
            let r = crate::sim::simulate(f, s, &st, spec, integ, &diag, sink);
            let r = *r.free().expect("the free scene gives a free result");
            ev.free = Some(r);
            ev.discard = ev.discard.or(measured_discard(&r, s));
        }
    } else {
        let run = crate::sim::simulate(f, s, &st, spec, integ, ctl, sink);
        if let SceneResult::Offset(o) = run {
            ev.offset = Some(o);
        }
        let d = grasp(run);
        let reason = match ev.offset.and_then(|o| o.grasp_failure.map(|e| (o.x_off, e))) {
            Some((x_off, why)) => Reason::OffsetGrasp(x_off, why),
            None => Reason::Dynamics(d.outcome),
        };
        ev.discard = d.discard_violation().map(|v| Discard { stage: 3, reason, violation: v });
        ev.dynamics = Some(d);
    }
    ev.stage_seconds[3] = t2.elapsed().as_secs_f64();
    ev
}

/// The grasp of a grasp scene's result.
fn grasp(r: SceneResult) -> DynamicsResult {
    *r.grasp().expect("a grasp scene gives a grasp")
}

/// True when stage 3 of a design that passed stages 0–2 is known to end before its
/// simulation starts: the centred scene in pipeline mode with a violated static force
/// criterion (MODEL.md §9.3). Only orders work (a cost hint); the verdict is stage 3's own.
pub fn stage3_ends_at_once(st: &StaticsResult, s: &SceneParams, opts: &EvalOptions) -> bool {
    opts.controls.mode == Mode::Pipeline
        && s.setup.kind.is_centred()
        && force_margin(s, r_area(s), nalgebra::Vector2::new(st.grasp.hand0[0], st.grasp.hand0[1])) < 0.0
}

/// The discard the centred scene gives in a free-kind stage 3: only the finger's own
/// criteria (fold, stability, singular or aborted grasps); the impact and force criteria
/// are the measurement's to decide.
pub(crate) fn finger_discard(c: &DynamicsResult) -> Option<Discard> {
    use DynOutcome as D;
    let fail = match c.outcome {
        D::Stable | D::ImpactEnergy | D::ForceCriterion | D::StaticForceLimit | D::Fold | D::NoStability => {
            if c.fold_ok == Some(false) {
                D::Fold
            } else if c.t_stab.is_none() {
                D::NoStability
            } else {
                return None;
            }
        }
        other => other,
    };
    let v = DynamicsResult { outcome: fail, ..*c }.discard_violation().unwrap_or(1e3);
    Some(Discard { stage: 3, reason: Reason::Dynamics(fail), violation: v })
}

/// The object "barely moves" (§14.4) and the run observed it to the end.
pub fn barely_moves(r: &FreeResult) -> bool {
    r.end.observed() && !(r.moved || r.toppled || r.escaped)
}

/// The discard the free scene's measurement gives, if any (stage 3; violation in stage
/// units: max(displacement/Δx_max, tilt/θ_max) − 1, plus 1 when the object escaped; 1e3
/// when the run ended early, as for an aborted grasp).
fn measured_discard(r: &FreeResult, s: &SceneParams) -> Option<Discard> {
    if !r.end.observed() {
        return Some(Discard { stage: 3, reason: Reason::FreeSceneEnded(r.end), violation: 1e3 });
    }
    if barely_moves(r) {
        return None;
    }
    let c = &s.criteria;
    let m = ObjectMotion {
        displacement: r.object_max_displacement,
        tilt_deg: r.object_max_tilt_deg,
        dx_max: c.dx_max,
        theta_max_deg: c.theta_max.to_degrees(),
        toppled: r.toppled,
        escaped: r.escaped,
        untouched: r.first_contact_t.is_none(),
    };
    let ratio = (m.displacement / m.dx_max).max(m.tilt_deg / m.theta_max_deg) - 1.0;
    let v = ratio.max(0.0) + if m.escaped { 1.0 } else { 0.0 };
    Some(Discard { stage: 3, reason: Reason::ObjectMoved(m), violation: if v.is_finite() { v } else { 1e3 } })
}
