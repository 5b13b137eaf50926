//! The fixed-object grasp scene (MODEL.md §8–9): both fingers close under a constant
//! torque on a fixed, centred cylinder. Integrates one finger (mirror symmetry, D18) with
//! event location for contact onset/separation, the force criterion, time to stability
//! and singularity; evaluates the criteria of §9.

use super::criteria::{force_margin, impact, r_area, u_min, Impact};
use super::finger::{FingerEval, FingerOde, Memory, State, NS};
use super::integrator::{hermite, Dopri5, Radau5, Stats, Stepper, Tol, TrBdf2};
use crate::math::V2;
use crate::model::geometry::Finger;
use crate::model::statics::closed_pose;
use crate::pipeline::StaticsResult;
use crate::params::SceneParams;
use nalgebra::{Matrix2, Vector2};
use serde::Serialize;
use std::fmt;
use std::time::Instant;

/// Integration method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Method {
    /// Radau IIA order 5 (default; stiff, L-stable, stiffly accurate).
    Radau5,
    /// TR-BDF2 (stiff, L-stable, order 2; the thesis' method).
    TrBdf2,
    /// Dormand–Prince 5(4) (explicit; for comparison only).
    Dopri5,
}

/// Pipeline mode stops at the first violated criterion; diagnostic mode runs to t_stab or t_max.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Mode {
    /// Stop at the first violated criterion.
    Pipeline,
    /// Always run to t_stab (or t_max), reporting every criterion.
    Diagnostic,
}

/// Simulation options.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SimOptions {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance on angles (rad) and rates (rad/s).
    pub atol: f64,
    /// Budget of accepted + rejected steps.
    pub max_steps: u64,
    /// Pipeline or diagnostic.
    pub mode: Mode,
    /// Method.
    pub method: Method,
    /// Record a trajectory at accepted steps.
    pub record: bool,
    /// Also sample a uniform grid with this step (s) when recording.
    pub grid_dt: Option<f64>,
    /// Contacts with the object (false: the fingers close on nothing — a diagnostic scene
    /// for the linkage alone; no compliant equilibrium, no stability).
    pub contacts: bool,
}

impl SimOptions {
    /// Pipeline-mode options with Radau IIA.
    pub fn pipeline(rtol: f64, atol: f64, max_steps: u64) -> Self {
        SimOptions { rtol, atol, max_steps, mode: Mode::Pipeline, method: Method::Radau5, record: false, grid_dt: None, contacts: true }
    }
    /// Diagnostic-mode options with Radau IIA.
    pub fn diagnostic(rtol: f64, atol: f64, max_steps: u64) -> Self {
        SimOptions { mode: Mode::Diagnostic, ..Self::pipeline(rtol, atol, max_steps) }
    }
}

/// Maximum number of events before the simulation is aborted (§8.7).
pub const MAX_EVENTS: u32 = 20_000;

/// How a grasp simulation ended, or the first criterion it violated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DynOutcome {
    /// All criteria hold and stability was reached.
    Stable,
    /// Impact energy above the limit at the first contact.
    ImpactEnergy,
    /// Distal fold above fold_max at the first contact.
    Fold,
    /// Filtered hand force left the stability region.
    ForceCriterion,
    /// The static hand force F⁰_hand violates the force criterion.
    StaticForceLimit,
    /// E_ex did not fall below η U_min by t_max.
    NoStability,
    /// |sin q13| fell to 1e-3.
    Singular,
    /// The linkage could not be assembled along the trajectory.
    DgmFailure,
    /// More than 20 000 events.
    Aborted,
    /// More than max_steps steps.
    StepBudget,
    /// The step size underflowed.
    StepTooSmall,
    /// The open finger penetrates the object at t = 0.
    InitialPenetration,
    /// The compliant equilibrium of §8.9 was not found.
    NoEquilibrium,
}

impl fmt::Display for DynOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = match self {
            DynOutcome::Stable => "stable",
            DynOutcome::ImpactEnergy => "impact criterion: first impact energy above the limit",
            DynOutcome::Fold => "spring validity: distal fold at first contact above the limit",
            DynOutcome::ForceCriterion => "force criterion: filtered hand force outside the stability region",
            DynOutcome::StaticForceLimit => "force criterion: static hand force outside the stability region",
            DynOutcome::NoStability => "no stability by t_max",
            DynOutcome::Singular => "singular configuration during the grasp (|sin q13| <= 1e-3)",
            DynOutcome::DgmFailure => "linkage not mountable during the grasp",
            DynOutcome::Aborted => "aborted: more than 20000 events",
            DynOutcome::StepBudget => "aborted: step budget exhausted",
            DynOutcome::StepTooSmall => "aborted: step size underflow",
            DynOutcome::InitialPenetration => "open finger penetrates the object at t = 0",
            DynOutcome::NoEquilibrium => "compliant static equilibrium not found",
        };
        f.write_str(s)
    }
}

/// The first contact onset and its impact criterion (§9.1–9.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FirstContact {
    /// Time of onset (s).
    pub t: f64,
    /// 1 = proximal, 2 = distal.
    pub phalanx: u8,
    /// Impact energies.
    pub impact: Impact,
    /// θ2 at onset (rad).
    pub theta2: f64,
}

/// Stage-3 results.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicsResult {
    /// First violated criterion (pipeline) or, in diagnostic mode, the first in time; `Stable` if none.
    pub outcome: DynOutcome,
    /// First contact.
    pub first: Option<FirstContact>,
    /// Impact criterion holds (None: no contact).
    pub impact_ok: Option<bool>,
    /// Fold criterion holds.
    pub fold_ok: Option<bool>,
    /// Min of the filtered-force margin over [0, end] (N).
    pub min_force_margin: f64,
    /// Time of the first force-criterion violation.
    pub t_force_violation: Option<f64>,
    /// Margin of the static hand force F⁰_hand (N).
    pub static_force_margin: f64,
    /// R_area (N).
    pub r_area: f64,
    /// Time to stability (s).
    pub t_stab: Option<f64>,
    /// Normal forces at t_stab (or at the end).
    pub f_end: [f64; 2],
    /// Compliant equilibrium forces f*.
    pub fstar: [f64; 2],
    /// V*.
    pub v_star: f64,
    /// η U_min.
    pub threshold: f64,
    /// E_ex at the end.
    pub e_ex_end: f64,
    /// max_k |q̈_k| at the end (diagnostic of §9.4).
    pub max_qdd_end: f64,
    /// Time at which the simulation ended.
    pub t_end: f64,
    /// Number of events processed.
    pub events: u32,
    /// Integrator counters.
    pub stats: Stats,
    /// RHS evaluations including event location.
    pub rhs_evals: u64,
    /// CPU (wall) seconds of the simulation.
    pub cpu_s: f64,
    /// A knuckle (O22 cap) contact was seen (double-counted force, §8.5).
    pub knuckle_flag: bool,
    /// Time of the first onset of each phalanx (proximal, distal), if it touched.
    pub onsets: [Option<f64>; 2],
}

impl DynamicsResult {
    /// Violation (§10) when the outcome discards the design; `None` when stable.
    pub fn discard_violation(&self) -> Option<f64> {
        let v = match self.outcome {
            DynOutcome::Stable => return None,
            DynOutcome::ImpactEnergy => self.first.map(|f| f.impact.e_cyl / f.impact.e_lim - 1.0).unwrap_or(1.0),
            DynOutcome::Fold => self.first.map(|f| f.theta2.to_degrees() - 5.0).unwrap_or(1.0),
            DynOutcome::ForceCriterion | DynOutcome::StaticForceLimit => {
                -self.min_force_margin.min(self.static_force_margin) / self.r_area
            }
            DynOutcome::NoStability => self.e_ex_end / self.threshold,
            _ => 1e3,
        };
        Some(if v.is_finite() { v.max(0.0) } else { 1e3 })
    }
}

/// One trajectory sample (finger 1, local frame; finger 2 is its mirror image).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sample {
    /// Time (s).
    pub t: f64,
    /// q11, q21 (rad).
    pub q: [f64; 2],
    /// q̇11, q̇21 (rad/s).
    pub qd: [f64; 2],
    /// θ2 (rad).
    pub theta2: f64,
    /// Penetrations δ (m), proximal and distal.
    pub delta: [f64; 2],
    /// Normal forces (N).
    pub normal: [f64; 2],
    /// Friction forces (N, on the finger along t_c).
    pub friction: [f64; 2],
    /// Raw hand force F_hand,y (N).
    pub hand_fy: f64,
    /// Filtered hand force F̄_y (N).
    pub filtered_fy: f64,
    /// Total energy E (J).
    pub energy: f64,
    /// E_ex = E − V* (J).
    pub energy_excess: f64,
}

/// A recorded trajectory.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Trajectory {
    /// Samples at accepted steps and events, in time order.
    pub samples: Vec<Sample>,
    /// Samples on the uniform grid, if requested.
    pub grid: Vec<Sample>,
}

/// Compliant static equilibrium (§8.9).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Equilibrium {
    /// q* = (q11, q21).
    pub q: Vector2<f64>,
    /// V(q*).
    pub v_star: f64,
    /// f*.
    pub fstar: [f64; 2],
}

/// Damped Newton iteration of §8.9 from the pre-penetrated rigid closed pose.
pub fn compliant_equilibrium(ode: &FingerOde, s: &SceneParams, f0: [f64; 2]) -> Option<Equilibrium> {
    let mut o = *ode;
    o.mem = [Memory { active: true, vminus: 1.0 }; 2];
    let f = o.finger;
    let cp = closed_pose(f, s.object.radius, o.centre.x).ok()?;
    let at = |q: Vector2<f64>| -> Option<FingerEval> { o.evaluate(&State::from([q[0], q[1], 0.0, 0.0, 0.0])) };
    let q_rigid = Vector2::new(cp.pose.q11, cp.pose.q21);
    let e0 = at(q_rigid)?;
    let a = Matrix2::from_rows(&[e0.contacts[0].row.transpose(), e0.contacts[1].row.transpose()]);
    let dl = Vector2::new((f0[0].max(0.0) / s.contact.k_contact).powf(2.0 / 3.0), (f0[1].max(0.0) / s.contact.k_contact).powf(2.0 / 3.0));
    let mut q = q_rigid + a.try_inverse()? * dl;
    let tol = 1e-9 * s.hand.tau;
    for _ in 0..2000 {
        let r = at(q)?.q_total;
        if r.amax() < tol {
            let ev = at(q)?;
            return Some(Equilibrium {
                q,
                v_star: ev.energy,
                fstar: [ev.contacts[0].normal_force, ev.contacts[1].normal_force],
            });
        }
        let h = 1e-9;
        let mut jac = Matrix2::zeros();
        for j in 0..2 {
            let mut qp = q;
            let mut qm = q;
            qp[j] += h;
            qm[j] -= h;
            jac.set_column(j, &((at(qp)?.q_total - at(qm)?.q_total) / (2.0 * h)));
        }
        let mut dq = -(jac.try_inverse()? * r);
        let m = dq.amax();
        if m > 2e-5 {
            dq *= 2e-5 / m;
        }
        q += dq;
    }
    None
}

/// Values of the event functions at a state.
#[derive(Debug, Clone, Copy)]
struct Gs {
    contact: [f64; 2],
    stab: f64,
    force: f64,
    sing: f64,
    stop: f64,
    /// Time derivatives of the contact and stop functions (δ̇ and θ̇2).
    rate: [f64; 3],
}

/// Can the cubic Hermite through (0, a, da) and (h, b, db) take a value `> 0` (`up`) or
/// `≤ 0` (`!up`) strictly inside the step while both ends are on the other side? Used to
/// decide whether an event function must be sampled inside a step.
fn hermite_may_cross(a: f64, da: f64, b: f64, db: f64, h: f64) -> bool {
    // p(s) = h00 a + h10 h da + h01 b + h11 h db on s ∈ [0, 1]; find the extrema of the cubic.
    let (m0, m1) = (h * da, h * db);
    // p'(s) = 6(a − b)(s² − s) + m0(3s² − 4s + 1) + m1(3s² − 2s) = A s² + B s + C
    let qa = 6.0 * (a - b) + 3.0 * m0 + 3.0 * m1;
    let qb = -6.0 * (a - b) - 4.0 * m0 - 2.0 * m1;
    let qc = m0;
    let p = |s: f64| {
        let (s2, s3) = (s * s, s * s * s);
        (2.0 * s3 - 3.0 * s2 + 1.0) * a + (s3 - 2.0 * s2 + s) * m0 + (-2.0 * s3 + 3.0 * s2) * b + (s3 - s2) * m1
    };
    let side = a > 0.0;
    let check = |s: f64| s > 0.0 && s < 1.0 && (p(s) > 0.0) != side;
    if qa.abs() < 1e-300 {
        return qb != 0.0 && check(-qc / qb);
    }
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 {
        return false;
    }
    let r = disc.sqrt();
    check((-qb + r) / (2.0 * qa)) || check((-qb - r) / (2.0 * qa))
}

struct Ctx<'a> {
    s: &'a SceneParams,
    v_star: f64,
    threshold: f64,
    r_area: f64,
}

fn gvals(ode: &FingerOde, ctx: &Ctx, y: &State, ev: &FingerEval, after_first: bool) -> Gs {
    let mut contact = [0.0; 2];
    for i in 0..2 {
        let d = ev.contacts[i].geom.delta;
        // without contacts (a diagnostic scene) the phalanges pass through the object
        contact[i] = if !ode.contacts_enabled { -1.0 } else if ode.mem[i].active { d + ctx.s.contact.eps_sep } else { d };
    }
    Gs {
        contact,
        stab: if after_first { ev.energy - ctx.v_star - ctx.threshold } else { f64::INFINITY },
        force: force_margin(ctx.s, ctx.r_area, V2::new(0.0, y[4])),
        sing: ev.sin_q13.abs() - 1e-3,
        stop: ev.theta2,
        rate: [ev.contacts[0].delta_dot, ev.contacts[1].delta_dot, ev.theta2_dot],
    }
}

/// Number of event kinds.
const N_EVENTS: usize = 6;

/// Did event `k` cross between g values a → b (k: 0,1 contacts; 2 stab; 3 force; 4 sing;
/// 5 distal stop engaging or releasing at θ2 = 0, a kink of the right-hand side)?
fn crossed(k: usize, active: [bool; 2], a: f64, b: f64) -> bool {
    match k {
        0 | 1 => {
            if active[k] {
                a > 0.0 && b <= 0.0
            } else {
                a <= 0.0 && b > 0.0
            }
        }
        3 => a >= 0.0 && b < 0.0,
        5 => (a > 0.0) != (b > 0.0),
        _ => a > 0.0 && b <= 0.0,
    }
}

fn pick(g: &Gs, k: usize) -> f64 {
    match k {
        0 => g.contact[0],
        1 => g.contact[1],
        2 => g.stab,
        3 => g.force,
        4 => g.sing,
        _ => g.stop,
    }
}

fn sample(_ode: &FingerOde, t: f64, y: &State, ev: &FingerEval, v_star: f64) -> Sample {
    let c = &ev.contacts;
    Sample {
        t,
        q: [y[0], y[1]],
        qd: [y[2], y[3]],
        theta2: ev.theta2,
        delta: [c[0].geom.delta, c[1].geom.delta],
        normal: [c[0].normal_force, c[1].normal_force],
        friction: [c[0].friction_force, c[1].friction_force],
        hand_fy: 2.0 * ev.object_force.y,
        filtered_fy: y[4],
        energy: ev.energy,
        energy_excess: ev.energy - v_star,
    }
}

/// Simulate the grasp of the design's finger on the centred object (pipeline entry point).
pub fn simulate_grasp(f: &Finger, s: &SceneParams, st: &StaticsResult, opts: &SimOptions) -> DynamicsResult {
    simulate(f, s, st, opts, None)
}

/// Simulate, recording the trajectory into `traj` when given (the result does not depend
/// on recording).
pub fn simulate_grasp_into(f: &Finger, s: &SceneParams, st: &StaticsResult, opts: &SimOptions, traj: Option<&mut Trajectory>) -> DynamicsResult {
    let o = SimOptions { record: traj.is_some(), ..*opts };
    simulate(f, s, st, &o, traj)
}

/// Simulate and also return the recorded trajectory (forces `record`).
pub fn simulate_grasp_traj(f: &Finger, s: &SceneParams, st: &StaticsResult, opts: &SimOptions) -> (DynamicsResult, Trajectory) {
    let mut tr = Trajectory::default();
    let r = simulate(f, s, st, &SimOptions { record: true, ..*opts }, Some(&mut tr));
    (r, tr)
}

fn tolerances(opts: &SimOptions) -> Tol<NS> {
    // The filter state is in N: an absolute tolerance of 1e4·atol (1e-5 N at atol 1e-9).
    Tol { rtol: opts.rtol, atol: State::from([opts.atol, opts.atol, opts.atol, opts.atol, opts.atol * 1e4]) }
}

fn simulate(f: &Finger, s: &SceneParams, st: &StaticsResult, opts: &SimOptions, traj: Option<&mut Trajectory>) -> DynamicsResult {
    let tol = tolerances(opts);
    match opts.method {
        Method::Radau5 => run(Radau5::<NS>::new(tol, 1e-5), f, s, st, opts, traj),
        Method::TrBdf2 => run(TrBdf2::new(tol, 1e-5), f, s, st, opts, traj),
        Method::Dopri5 => run(Dopri5::new(tol, 1e-6), f, s, st, opts, traj),
    }
}

fn run<St: Stepper<NS>>(
    mut stepper: St,
    f: &Finger,
    s: &SceneParams,
    st: &StaticsResult,
    opts: &SimOptions,
    mut traj: Option<&mut Trajectory>,
) -> DynamicsResult {
    let clock = Instant::now();
    let mut ode = FingerOde::new(f, s, st.tau_s0, 0.0);
    let ra = r_area(s);
    let static_margin = force_margin(s, ra, V2::new(st.hand0[0], st.hand0[1]));
    let threshold = s.criteria.eta_stab * u_min(s, st.f0);
    let mut res = DynamicsResult {
        outcome: DynOutcome::Stable,
        first: None,
        impact_ok: None,
        fold_ok: None,
        min_force_margin: f64::INFINITY,
        t_force_violation: None,
        static_force_margin: static_margin,
        r_area: ra,
        t_stab: None,
        f_end: [0.0; 2],
        fstar: [f64::NAN; 2],
        v_star: f64::NAN,
        threshold,
        e_ex_end: f64::NAN,
        max_qdd_end: f64::NAN,
        t_end: 0.0,
        events: 0,
        stats: Stats::default(),
        rhs_evals: 0,
        cpu_s: 0.0,
        knuckle_flag: false,
        onsets: [None; 2],
    };
    let pipeline = opts.mode == Mode::Pipeline;
    let trace = std::env::var_os("GRIPOPT_TRACE").is_some();
    let finish = |mut r: DynamicsResult, stepper: &St, ode: &FingerOde| {
        r.stats = stepper.stats();
        r.rhs_evals = ode.evals;
        r.cpu_s = clock.elapsed().as_secs_f64();
        r
    };
    let fail_first = |r: &mut DynamicsResult, o: DynOutcome| {
        if r.outcome == DynOutcome::Stable {
            r.outcome = o;
        }
    };
    if static_margin < 0.0 {
        fail_first(&mut res, DynOutcome::StaticForceLimit);
        if pipeline {
            return finish(res, &stepper, &ode);
        }
    }
    let eq = if opts.contacts {
        let Some(eq) = compliant_equilibrium(&ode, s, st.f0) else {
            res.outcome = DynOutcome::NoEquilibrium;
            return finish(res, &stepper, &ode);
        };
        eq
    } else {
        ode.contacts_enabled = false;
        Equilibrium { q: Vector2::repeat(f64::NAN), v_star: f64::NAN, fstar: [f64::NAN; 2] }
    };
    res.v_star = eq.v_star;
    res.fstar = eq.fstar;
    let ctx = Ctx { s, v_star: eq.v_star, threshold, r_area: ra };

    let mut t = 0.0;
    let mut y = State::from([f.open.q11, f.open.q21, 0.0, 0.0, 0.0]);
    let Some(mut ev) = ode.evaluate(&y) else {
        res.outcome = DynOutcome::DgmFailure;
        return finish(res, &stepper, &ode);
    };
    if ev.contacts.iter().any(|c| c.geom.delta > 1e-12) {
        res.outcome = DynOutcome::InitialPenetration;
        return finish(res, &stepper, &ode);
    }
    let mut fy = ode.derivative(&y, &ev);
    let mut g = gvals(&ode, &ctx, &y, &ev, false);
    res.min_force_margin = g.force;
    let mut force_tracking = true;
    let mut grid_next = 0.0;
    let record = opts.record;
    let push = |traj: &mut Option<&mut Trajectory>, smp: Sample| {
        if let Some(tr) = traj.as_deref_mut() {
            tr.samples.push(smp);
        }
    };
    if record {
        push(&mut traj, sample(&ode, t, &y, &ev, eq.v_star));
    }

    loop {
        let stats = stepper.stats();
        if stats.steps + stats.rejected >= opts.max_steps {
            res.outcome = DynOutcome::StepBudget;
            break;
        }
        if t >= s.criteria.t_max * (1.0 - 1e-15) {
            fail_first(&mut res, DynOutcome::NoStability);
            break;
        }
        let acc = match stepper.advance(&mut ode, t, &y, &fy, s.criteria.t_max - t) {
            Ok(a) => a,
            Err(super::integrator::StepError::StepTooSmall) => {
                res.outcome = DynOutcome::StepTooSmall;
                break;
            }
            Err(super::integrator::StepError::RhsFailed) => {
                res.outcome = DynOutcome::DgmFailure;
                break;
            }
        };
        let Some(ev1) = ode.take_accepted(&acc.y).or_else(|| ode.evaluate(&acc.y)) else {
            res.outcome = DynOutcome::DgmFailure;
            break;
        };
        let after_first = res.first.is_some();
        let g1 = gvals(&ode, &ctx, &acc.y, &ev1, after_first);
        let (t0, y0, f0) = (t, y, fy);
        let interp = |tt: f64| hermite(t0, &y0, &f0, acc.t, &acc.y, &acc.f, tt);
        // ---- find the earliest event in (t0, t1] --------------------------------------
        let active = [ode.mem[0].active, ode.mem[1].active];
        let mut best: Option<(f64, usize)> = None;
        let mut sampled = false;
        let bracket = |k: usize, ta: f64, ga: f64, tb: f64, gb: f64, ode: &mut FingerOde| {
            // Illinois on the Hermite interpolant; returns the "after" end of the bracket.
            let (mut a, mut fa, mut b, mut fb) = (ta, ga, tb, gb);
            let mut side = 0i8;
            for _ in 0..80 {
                if (b - a) <= 1e-14 * b.abs().max(1e-3) {
                    break;
                }
                let mut c = (a * fb - b * fa) / (fb - fa);
                if !(c > a && c < b) {
                    c = 0.5 * (a + b);
                }
                let yc = interp(c);
                ode.evals += 1;
                let Some(evc) = ode.evaluate(&yc) else { break };
                let fc = pick(&gvals(ode, &ctx, &yc, &evc, after_first), k);
                if crossed(k, active, fa, fc) {
                    b = c;
                    fb = fc;
                    if side == -1 {
                        fa *= 0.5;
                    }
                    side = -1;
                } else {
                    a = c;
                    fa = fc;
                    if side == 1 {
                        fb *= 0.5;
                    }
                    side = 1;
                }
            }
            b
        };
        for k in 0..N_EVENTS {
            if k == 3 && !force_tracking {
                continue;
            }
            let (ga, gb) = (pick(&g, k), pick(&g1, k));
            if crossed(k, active, ga, gb) {
                let te = bracket(k, t0, ga, acc.t, gb, &mut ode);
                if best.is_none_or(|(tb, _)| te < tb) {
                    best = Some((te, k));
                }
            } else if (k < 2 || k == 5) && !sampled {
                // a contact or the stop may open and close inside one step: sample inside
                // only where the cubic through the end values and rates can change sign
                let ri = if k == 5 { 2 } else { k };
                if hermite_may_cross(ga, g.rate[ri], gb, g1.rate[ri], acc.t - t0) {
                    sampled = true;
                    let mut ta = t0;
                    let mut gprev = g;
                    for j in 1..=4 {
                        let tj = t0 + (acc.t - t0) * j as f64 / 4.0;
                        let gj = if j == 4 {
                            g1
                        } else {
                            let yj = interp(tj);
                            let Some(evj) = ode.evaluate(&yj) else { break };
                            gvals(&ode, &ctx, &yj, &evj, after_first)
                        };
                        for kk in [0usize, 1, 5] {
                            let (a, b) = (pick(&gprev, kk), pick(&gj, kk));
                            if crossed(kk, active, a, b) && j < 4 {
                                let te = bracket(kk, ta, a, tj, b, &mut ode);
                                if best.is_none_or(|(tb, _)| te < tb) {
                                    best = Some((te, kk));
                                }
                            }
                        }
                        if best.is_some_and(|(tb, _)| tb <= tj) {
                            break;
                        }
                        ta = tj;
                        gprev = gj;
                    }
                }
            }
        }
        // uniform grid samples inside the accepted part of the step
        let t_stop = best.map(|b| b.0).unwrap_or(acc.t);
        if record {
            if let Some(dt) = opts.grid_dt {
                while grid_next <= t_stop {
                    let yg = interp(grid_next);
                    if let (Some(evg), Some(tr)) = (ode.evaluate(&yg), traj.as_deref_mut()) {
                        tr.grid.push(sample(&ode, grid_next, &yg, &evg, eq.v_star));
                    }
                    grid_next += dt;
                }
            }
        }
        let Some((te, kind)) = best else {
            t = acc.t;
            y = acc.y;
            fy = acc.f;
            ev = ev1;
            g = g1;
            if force_tracking {
                res.min_force_margin = res.min_force_margin.min(g.force);
            }
            res.knuckle_flag |= FingerOde::knuckle_contact(&ev);
            if record {
                push(&mut traj, sample(&ode, t, &y, &ev, eq.v_star));
            }
            continue;
        };
        // ---- process the event at te ------------------------------------------------
        if trace {
            eprintln!("event kind {kind} at t {te:.9e} (step {t0:.9e}..{:.9e}) mem {:?}", acc.t, ode.mem);
        }
        res.events += 1;
        if res.events > MAX_EVENTS {
            res.outcome = DynOutcome::Aborted;
            break;
        }
        t = te;
        y = interp(te);
        let Some(eve) = ode.evaluate(&y) else {
            res.outcome = DynOutcome::DgmFailure;
            break;
        };
        ev = eve;
        let mut stop = false;
        match kind {
            0 | 1 => {
                let mut first_onsets: [Option<Impact>; 2] = [None, None];
                for i in 0..2 {
                    let c = &ev.contacts[i];
                    let located = i == kind;
                    if !ode.mem[i].active && c.geom.delta > 0.0 && (located || c.delta_dot > 0.0) {
                        ode.mem[i] = Memory { active: true, vminus: c.delta_dot.max(s.contact.v_min) };
                        res.onsets[i].get_or_insert(t);
                        if res.first.is_none() {
                            let minv = ev.m.try_inverse().unwrap_or(Matrix2::zeros());
                            let mf = 1.0 / c.row.dot(&(minv * c.row));
                            first_onsets[i] = Some(impact(s, mf, c.delta_dot));
                        }
                    } else if ode.mem[i].active
                        && c.geom.delta < -s.contact.eps_sep
                        && (located || c.delta_dot < 0.0)
                    {
                        ode.mem[i] = Memory::default();
                    }
                }
                if res.first.is_none() {
                    let pickf = match (first_onsets[0], first_onsets[1]) {
                        (Some(a), Some(b)) => Some(if b.e_cyl > a.e_cyl { (1, b) } else { (0, a) }),
                        (Some(a), None) => Some((0, a)),
                        (None, Some(b)) => Some((1, b)),
                        _ => None,
                    };
                    if let Some((i, imp)) = pickf {
                        res.first = Some(FirstContact { t, phalanx: i as u8 + 1, impact: imp, theta2: ev.theta2 });
                        let iok = imp.e_cyl <= imp.e_lim;
                        let fok = ev.theta2 <= s.criteria.fold_max;
                        res.impact_ok = Some(iok);
                        res.fold_ok = Some(fok);
                        if !iok {
                            fail_first(&mut res, DynOutcome::ImpactEnergy);
                        }
                        if !fok {
                            fail_first(&mut res, DynOutcome::Fold);
                        }
                        stop |= pipeline && !(iok && fok);
                    }
                }
                // memory changed: f is discontinuous
                stepper.restart(stepper.h());
            }
            2 => {
                res.t_stab = Some(t);
                stop = true;
            }
            3 => {
                res.t_force_violation = Some(t);
                res.min_force_margin = res.min_force_margin.min(g1.force.min(0.0));
                force_tracking = false;
                fail_first(&mut res, DynOutcome::ForceCriterion);
                stop |= pipeline;
            }
            4 => {
                res.outcome = DynOutcome::Singular;
                stop = true;
            }
            _ => {
                // the stop engages or releases: the right-hand side has a kink here
                stepper.restart(stepper.h());
            }
        }
        let Some(ev2) = ode.evaluate(&y) else {
            res.outcome = DynOutcome::DgmFailure;
            break;
        };
        ev = ev2;
        fy = ode.derivative(&y, &ev);
        g = gvals(&ode, &ctx, &y, &ev, res.first.is_some());
        if force_tracking {
            res.min_force_margin = res.min_force_margin.min(g.force);
        }
        if record {
            push(&mut traj, sample(&ode, t, &y, &ev, eq.v_star));
        }
        if stop {
            break;
        }
    }
    res.t_end = t;
    res.f_end = [ev.contacts[0].normal_force, ev.contacts[1].normal_force];
    res.e_ex_end = ev.energy - eq.v_star;
    res.max_qdd_end = ev.qdd.amax();
    finish(res, &stepper, &ode)
}

/// Stage-3 keys of the JSON record (MODEL.md §10); all `null` when stage 3 did not run.
#[derive(Debug, Clone, Default, Serialize)]
pub struct DynamicsRecord {
    /// Time of first contact (s).
    pub t_first_contact: Option<f64>,
    /// "proximal" or "distal".
    pub first_contact_phalanx: Option<&'static str>,
    /// Onset velocity (m/s).
    pub v_impact: Option<f64>,
    /// Effective finger mass (kg).
    pub m_finger: Option<f64>,
    /// E_cyl (J).
    pub e_cyl: Option<f64>,
    /// E_trans (J).
    pub e_trans: Option<f64>,
    /// E_rot (J).
    pub e_rot: Option<f64>,
    /// min(E_lim,trans, E_lim,rot) (J).
    pub e_lim: Option<f64>,
    /// θ2 at first contact (rad).
    pub theta2_first_contact: Option<f64>,
    /// Min filtered-force margin (N).
    pub min_force_margin: Option<f64>,
    /// Static hand-force margin (N).
    pub static_force_margin: Option<f64>,
    /// Time to stability (s).
    pub t_stab: Option<f64>,
    /// Proximal normal force at t_stab (N).
    pub f_stab_1: Option<f64>,
    /// Distal normal force at t_stab (N).
    pub f_stab_2: Option<f64>,
    /// f*_1 (N).
    pub fstar_1: Option<f64>,
    /// f*_2 (N).
    pub fstar_2: Option<f64>,
    /// max |q̈| at the end (rad/s²).
    pub max_qdd_end: Option<f64>,
    /// Accepted steps.
    pub steps: Option<u64>,
    /// Rejected steps.
    pub rejected_steps: Option<u64>,
    /// RHS evaluations.
    pub rhs_evals: Option<u64>,
    /// Jacobian evaluations.
    pub jac_evals: Option<u64>,
    /// LU factorisations.
    pub lu_count: Option<u64>,
    /// Newton iterations.
    pub newton_iters: Option<u64>,
    /// Step attempts rejected for Newton failure (part of `rejected_steps`).
    pub newton_failures: Option<u64>,
    /// Events.
    pub events: Option<u32>,
    /// CPU seconds of stage 3.
    pub cpu_s: Option<f64>,
    /// A knuckle contact was seen.
    pub knuckle_contact: Option<bool>,
}

impl DynamicsRecord {
    /// Flatten a result (None → all null).
    pub fn from_result(d: Option<&DynamicsResult>) -> Self {
        let Some(d) = d else { return Self::default() };
        let fin = |v: f64| v.is_finite().then_some(v);
        let fc = d.first;
        DynamicsRecord {
            t_first_contact: fc.map(|f| f.t),
            first_contact_phalanx: fc.map(|f| if f.phalanx == 1 { "proximal" } else { "distal" }),
            v_impact: fc.map(|f| f.impact.v_impact),
            m_finger: fc.map(|f| f.impact.m_finger),
            e_cyl: fc.map(|f| f.impact.e_cyl),
            e_trans: fc.map(|f| f.impact.e_trans),
            e_rot: fc.map(|f| f.impact.e_rot),
            e_lim: fc.map(|f| f.impact.e_lim),
            theta2_first_contact: fc.map(|f| f.theta2),
            min_force_margin: fin(d.min_force_margin),
            static_force_margin: fin(d.static_force_margin),
            t_stab: d.t_stab,
            f_stab_1: d.t_stab.map(|_| d.f_end[0]),
            f_stab_2: d.t_stab.map(|_| d.f_end[1]),
            fstar_1: fin(d.fstar[0]),
            fstar_2: fin(d.fstar[1]),
            max_qdd_end: fin(d.max_qdd_end),
            steps: Some(d.stats.steps),
            rejected_steps: Some(d.stats.rejected),
            rhs_evals: Some(d.rhs_evals),
            jac_evals: Some(d.stats.jac),
            lu_count: Some(d.stats.lu),
            newton_iters: Some(d.stats.newton),
            newton_failures: Some(d.stats.newton_fail),
            events: Some(d.events),
            cpu_s: Some(d.cpu_s),
            knuckle_contact: Some(d.knuckle_flag),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::hermite_may_cross;
    use rand::{Rng, SeedableRng};

    /// §13 item 3 (a contact that opens and closes inside one step): the test that decides
    /// whether to sample inside a step agrees with brute-force sampling of the same cubic
    /// wherever the excursion is not within rounding of zero.
    #[test]
    fn inner_crossing_test_matches_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let (mut crossing, mut checked) = (0, 0);
        for _ in 0..20_000 {
            let h = 10f64.powf(rng.random_range(-8.0..-3.0));
            let a: f64 = rng.random_range(-1e-5..1e-5);
            let b = a.signum() * rng.random_range(1e-9..1e-5);
            let (da, db) = (rng.random_range(-1.0..1.0) * 1e-5 / h, rng.random_range(-1.0..1.0) * 1e-5 / h);
            let p = |s: f64| {
                let (s2, s3) = (s * s, s * s * s);
                (2.0 * s3 - 3.0 * s2 + 1.0) * a + (s3 - 2.0 * s2 + s) * h * da + (-2.0 * s3 + 3.0 * s2) * b + (s3 - s2) * h * db
            };
            // the extreme excursion to the other side, by dense sampling
            let n = 4000;
            let worst = (1..n).map(|i| p(i as f64 / n as f64)).map(|v| if a > 0.0 { -v } else { v }).fold(f64::NEG_INFINITY, f64::max);
            let scale = a.abs().max(b.abs()) + h * (da.abs() + db.abs());
            if worst.abs() < 1e-6 * scale {
                continue; // tangency: either answer is right
            }
            checked += 1;
            let expect = if a > 0.0 { worst >= 0.0 } else { worst > 0.0 };
            crossing += usize::from(expect);
            assert_eq!(hermite_may_cross(a, da, b, db, h), expect, "a {a:e} da {da:e} b {b:e} db {db:e} h {h:e}");
        }
        assert!(checked > 15_000 && crossing > 300, "{checked} checked, {crossing} crossing");
    }
}
