//! The centred scene (MODEL.md §8–9, the thesis's stage 3): both fingers close under a
//! constant torque on a fixed cylinder centred between them. Finger 2 is the mirror image
//! of finger 1 (D18), so one finger is integrated — state y = (q11, q21, q̇11, q̇21, F̄_y),
//! its four mechanical states plus the low-pass filtered hand force of the force criterion
//! (§9.3) — and the hand force is twice finger 1's.

use super::{KeptEval, Response, Run, Scene};
use crate::math::V2;
use crate::model::Finger;
use crate::model::StaticsResult;
use crate::params::SceneParams;
use crate::sim::criteria::{force_margin, r_area, u_min};
use crate::sim::driver;
use crate::sim::equilibrium::{finger_equilibrium, Equilibrium};
use crate::sim::events::{Crossing, EventKind, EventValues};
use crate::sim::finger::{FingerEval, FingerModel};
use crate::sim::integrate::{Partition, Piece, Rhs, Tol};
use crate::sim::memory::Memory;
use crate::sim::result::{DynOutcome, DynamicsResult};
use crate::sim::settings::{Controls, Integration, Mode};
use crate::sim::sink::{Point, Sink};
use crate::sim::tracking::{grasp_sample, EndValues, GraspLimits, Tracker};
use nalgebra::{SVector, Vector2};

/// State dimension of the centred scene.
pub const NS: usize = 5;
/// State vector of the centred scene.
pub type State = SVector<f64, NS>;

/// The ODE of the centred scene: finger 1 against the object centred at `centre` (local
/// frame) plus the filtered hand force, finger 2 being its mirror image.
#[derive(Debug, Clone, Copy)]
pub struct FingerOde<'a> {
    /// The finger model.
    pub model: FingerModel<'a>,
    /// Object centre in the finger's local frame ((0, R) in the centred scene).
    pub centre: V2,
    /// Filter time constant T_f.
    pub t_filter: f64,
    /// Contact memories (proximal, distal).
    pub mem: [Memory; 2],
    /// Contacts enabled (false: free finger, for energy tests).
    pub contacts_enabled: bool,
    /// Right-hand-side evaluations.
    pub evals: u64,
    /// The full evaluation at the end of the last accepted step (see [`FingerOde::take_accepted`]).
    accepted: KeptEval<NS, FingerEval>,
}

impl<'a> FingerOde<'a> {
    /// The finger of the grasp scene closing on the object centred at local (x_c, R).
    pub fn new(finger: &'a Finger, scene: &'a SceneParams, tau_s0: f64, x_c: f64) -> Self {
        FingerOde {
            model: FingerModel::new(finger, scene, tau_s0),
            centre: V2::new(x_c, scene.object.radius),
            t_filter: scene.criteria.t_filter,
            mem: [Memory::default(); 2],
            contacts_enabled: true,
            evals: 0,
            accepted: KeptEval::default(),
        }
    }

    /// Evaluate the full model at state `y`; `None` where the DGM or kinematics fail.
    #[inline]
    pub fn evaluate(&self, y: &State) -> Option<FingerEval> {
        self.evaluate_with(y, true)
    }

    /// The model at `y` (`full = false`: the lean path of [`FingerModel::evaluate`]).
    #[inline(always)]
    fn evaluate_with(&self, y: &State, full: bool) -> Option<FingerEval> {
        self.model.evaluate(
            Vector2::new(y[0], y[1]),
            Vector2::new(y[2], y[3]),
            self.centre,
            &self.mem,
            self.contacts_enabled,
            full,
        )
    }

    /// The full evaluation the integrator made at the end of its last accepted step, if
    /// that step ended at `y` (saves the driver a second evaluation per step).
    #[inline]
    pub fn take_accepted(&mut self, y: &State) -> Option<FingerEval> {
        self.accepted.take(y)
    }

    /// The hand force F_hand,y: twice finger 1's force on the object (the mirror image).
    #[inline(always)]
    pub fn hand_fy(ev: &FingerEval) -> f64 {
        2.0 * ev.object_force.y
    }

    /// Time derivative from a full evaluation.
    #[inline]
    pub fn derivative(&self, y: &State, ev: &FingerEval) -> State {
        let hand_y = Self::hand_fy(ev);
        State::from([y[2], y[3], ev.qdd[0], ev.qdd[1], (hand_y - y[4]) / self.t_filter])
    }

    /// True when a knuckle cap (O22, shared by both capsules) carries a contact.
    pub fn knuckle_contact(ev: &FingerEval) -> bool {
        ev.knuckle_contact()
    }
}

impl Rhs<NS> for FingerOde<'_> {
    #[inline]
    fn eval(&mut self, _t: f64, y: &State) -> Option<State> {
        self.evals += 1;
        let ev = self.evaluate_with(y, false)?;
        Some(self.derivative(y, &ev))
    }

    /// Smooth piece: the finger's [`Kink`](crate::sim::finger::Kink)s.
    fn piece(&self, y: &State) -> Piece {
        self.evaluate_with(y, false).map_or(Piece::UNDEFINED, |ev| ev.piece)
    }

    #[inline]
    fn eval_piece(&mut self, _t: f64, y: &State) -> Option<(State, Piece)> {
        self.evals += 1;
        let ev = self.evaluate_with(y, false)?;
        Some((self.derivative(y, &ev), ev.piece))
    }

    /// The full evaluation (its forces equal the lean one's), kept for the driver.
    fn eval_accepted(&mut self, _t: f64, y: &State) -> Option<(State, Piece)> {
        self.evals += 1;
        let ev = self.evaluate_with(y, true)?;
        let out = (self.derivative(y, &ev), ev.piece);
        self.accepted.keep(y, ev);
        Some(out)
    }

    /// The angles (rates: the velocities) eliminated, the filter state solved last (its
    /// rate is linear in itself: −1/T_f).
    fn newton_partition(&self) -> Option<Partition<NS>> {
        Partition::new(&[&[0], &[1]])?.with_trailing_linear(&[(4, -1.0 / self.t_filter)])
    }
}

/// Compliant static equilibrium (§8.9) of the scene's finger on its object.
pub fn compliant_equilibrium(ode: &FingerOde, s: &SceneParams, f0: [f64; 2]) -> Option<Equilibrium> {
    finger_equilibrium(&ode.model, ode.centre, s, f0)
}

/// The event functions of the centred scene, in the order of their values.
pub const EVENTS: [EventKind; 6] = [
    EventKind::Contact(0),
    EventKind::Contact(1),
    EventKind::Stability,
    EventKind::Force,
    EventKind::Singular(0),
    EventKind::Stop(0),
];
/// Index of the force event in [`EVENTS`].
const FORCE: usize = 3;

/// The centred scene during a run: the ODE and the criteria.
pub struct CentredScene<'a> {
    ode: FingerOde<'a>,
    s: &'a SceneParams,
    limits: GraspLimits,
    tracker: Tracker<2>,
}

impl<'a> CentredScene<'a> {
    /// The scene of finger `f` with its statics `st` (before [`CentredScene::prepare`]).
    pub fn new(f: &'a Finger, s: &'a SceneParams, st: &StaticsResult, ctl: &Controls) -> Self {
        let ode = FingerOde::new(f, s, st.tau_s0, 0.0);
        let r_area = r_area(s);
        let limits = GraspLimits {
            static_force_margin: force_margin(s, r_area, V2::new(st.grasp.hand0[0], st.grasp.hand0[1])),
            threshold: s.criteria.eta_stab * u_min(s, st.grasp.f0),
            ..GraspLimits::unknown(r_area)
        };
        CentredScene { ode, s, limits, tracker: Tracker::new(ctl.mode == Mode::Pipeline) }
    }

    /// The static force criterion and the compliant equilibrium (from the static forces
    /// `f0`) before the run. False: the simulation ends here (pipeline mode and a violated
    /// static force criterion, or no equilibrium); [`CentredScene::result`] says why.
    pub fn prepare(&mut self, f0: [f64; 2], ctl: &Controls) -> bool {
        if self.limits.static_force_margin < 0.0 {
            self.tracker.fail(DynOutcome::StaticForceLimit);
            if self.tracker.pipeline {
                return false;
            }
        }
        if ctl.contacts {
            let Some(eq) = compliant_equilibrium(&self.ode, self.s, f0) else {
                self.tracker.outcome = DynOutcome::NoEquilibrium;
                return false;
            };
            (self.limits.fstar, self.limits.v_star) = (eq.fstar, eq.v_star);
        } else {
            self.ode.contacts_enabled = false;
        }
        true
    }

    /// The result as far as known, without a run.
    pub fn result(&self) -> DynamicsResult {
        self.tracker.result::<NS, FingerEval>(&self.limits, self.ode.evals, None)
    }
}

impl Rhs<NS> for CentredScene<'_> {
    #[inline]
    fn eval(&mut self, t: f64, y: &State) -> Option<State> {
        self.ode.eval(t, y)
    }
    #[inline]
    fn piece(&self, y: &State) -> Piece {
        self.ode.piece(y)
    }
    #[inline]
    fn eval_piece(&mut self, t: f64, y: &State) -> Option<(State, Piece)> {
        self.ode.eval_piece(t, y)
    }
    #[inline]
    fn eval_accepted(&mut self, t: f64, y: &State) -> Option<(State, Piece)> {
        self.ode.eval_accepted(t, y)
    }
    fn newton_partition(&self) -> Option<Partition<NS>> {
        self.ode.newton_partition()
    }
}

impl Scene<NS, 6> for CentredScene<'_> {
    type Eval = FingerEval;

    fn initial_state(&self) -> State {
        let f = self.ode.model.finger;
        State::from([f.open.q11, f.open.q21, 0.0, 0.0, 0.0])
    }

    #[inline]
    fn evaluate(&self, y: &State) -> Option<FingerEval> {
        self.ode.evaluate(y)
    }

    #[inline]
    fn take_accepted(&mut self, y: &State) -> Option<FingerEval> {
        self.ode.take_accepted(y)
    }

    #[inline]
    fn derivative(&self, y: &State, ev: &FingerEval) -> State {
        self.ode.derivative(y, ev)
    }

    fn events(&self) -> [EventKind; 6] {
        EVENTS
    }

    fn event_values(&self, y: &State, ev: &FingerEval) -> EventValues<6> {
        let s = self.s;
        let mut contact = [0.0; 2];
        for i in 0..2 {
            // without contacts (a diagnostic scene) the phalanges pass through the object
            contact[i] = if !self.ode.contacts_enabled {
                -1.0
            } else {
                self.ode.mem[i].event_value(ev.contacts[i].geom.delta, s.contact.eps_sep)
            };
        }
        let stab = if self.tracker.first.is_some() {
            ev.energy - self.limits.v_star - self.limits.threshold
        } else {
            f64::INFINITY
        };
        let force = force_margin(s, self.limits.r_area, V2::new(0.0, y[4]));
        let sing = ev.sin_q13.abs() - 1e-3;
        EventValues {
            g: [contact[0], contact[1], stab, force, sing, ev.theta2],
            rate: [ev.contacts[0].delta_dot, ev.contacts[1].delta_dot, 0.0, 0.0, 0.0, ev.theta2_dot],
        }
    }

    /// The force margin from the filter state alone; the contacts, the singularity and the
    /// stop from the pose (the DGM, no kinematics or forces); stability from the full model.
    fn event_value(&self, i: usize, y: &State) -> Option<f64> {
        let f = self.ode.model.finger;
        let pose = || f.dgm_fast(y[0], y[1]).ok();
        match EVENTS[i] {
            EventKind::Force => Some(force_margin(self.s, self.limits.r_area, V2::new(0.0, y[4]))),
            EventKind::Contact(_) if !self.ode.contacts_enabled => Some(-1.0),
            EventKind::Contact(c) => {
                let (p, c) = (pose()?, c as usize);
                let g = self.ode.model.phalanx(&p, f.distal_dir(&p), self.ode.centre, c);
                Some(self.ode.mem[c].event_value(g.delta, self.s.contact.eps_sep))
            }
            EventKind::Singular(_) => pose().map(|p| crate::math::cross(p.x12, p.x22).abs() - 1e-3),
            EventKind::Stop(_) => pose().map(|p| p.q22_from_vectors() + f.psi),
            EventKind::Stability => {
                let ev = self.evaluate(y)?;
                Some(self.event_values(y, &ev).g[i])
            }
        }
    }

    fn crossing(&self, i: usize) -> Option<Crossing> {
        match EVENTS[i] {
            EventKind::Force if !self.tracker.force_armed => None,
            EventKind::Contact(c) => Some(EVENTS[i].crossing(self.ode.mem[c as usize].active)),
            kind => Some(kind.crossing(false)),
        }
    }

    fn begin(&mut self, _y: &State, ev: &FingerEval, g: &EventValues<6>) -> bool {
        if ev.contacts.iter().any(|c| c.geom.delta > 1e-12) {
            self.tracker.outcome = DynOutcome::InitialPenetration;
            return false;
        }
        self.tracker.min_force_margin = g.g[FORCE];
        true
    }

    fn handle(&mut self, i: usize, t: f64, ev: &FingerEval, end: &EventValues<6>) -> Response {
        match EVENTS[i] {
            EventKind::Contact(_) => self.tracker.contact_event(self.s, t, i, &mut self.ode.mem, |_| ev),
            other => self.tracker.on_event(other, t, end.g[FORCE]),
        }
    }

    fn track(&mut self, at: Point, ev: &FingerEval, g: &EventValues<6>) {
        self.tracker.force_margin(g.g[FORCE]);
        if at == Point::Step {
            self.tracker.knuckle |= ev.knuckle_contact();
        }
    }

    fn memories(&self) -> &[Memory] {
        &self.ode.mem
    }

    fn sample<K: Sink + ?Sized>(&self, at: Point, t: f64, y: &State, ev: &FingerEval, sink: &mut K) {
        let hand = [FingerOde::hand_fy(ev), y[4]];
        sink.finger(at, &grasp_sample(t, [y[0], y[1], y[2], y[3]], ev, hand, ev.energy, self.limits.v_star));
    }
}

impl CentredScene<'_> {
    /// The output of a finished run: the criteria's verdicts and the measured values.
    pub(crate) fn finish(mut self, run: &Run<NS, FingerEval>) -> DynamicsResult {
        self.tracker.on_end(run.end);
        let end = run.last.map(|ev| EndValues {
            f_end: [ev.contacts[0].normal_force, ev.contacts[1].normal_force],
            energy: ev.energy,
            max_qdd: ev.qdd.amax(),
        });
        self.tracker.result(&self.limits, self.ode.evals, Some((run, end)))
    }
}

/// Tolerances of the centred scene's state: the problem's, times the grasp scenes' factor of
/// `integ.scaling`.
pub fn tolerances(integ: &Integration) -> Tol<NS> {
    // The filter state is in N: an absolute tolerance of 1e4·atol (1e-5 N at atol 1e-9).
    let c = integ.scaling.grasp;
    let (rtol, atol) = (integ.rtol * c, integ.atol * c);
    Tol { rtol, atol: State::from([atol, atol, atol, atol, atol * 1e4]) }
}

/// Simulate the grasp of the design's finger on the centred object, reporting to `sink`
/// (the result does not depend on it).
// not inlined: its own symbol for `make bench-instructions`' inclusive count
#[inline(never)]
pub(crate) fn run<K: Sink + ?Sized>(
    f: &Finger,
    s: &SceneParams,
    st: &StaticsResult,
    integ: &Integration,
    ctl: &Controls,
    sink: &mut K,
) -> DynamicsResult {
    let mut scene = CentredScene::new(f, s, st, ctl);
    if scene.prepare(st.grasp.f0, ctl) {
        let run = driver::simulate(&mut scene, integ, ctl, tolerances(integ), s.criteria.t_max, sink);
        scene.finish(&run)
    } else {
        scene.result()
    }
}
