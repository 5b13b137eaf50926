//! The offset scene (MODEL.md §14): both fingers close on the fixed object at (x_off, R).
//! Finger 1 sees the centre (x_off, R), finger 2 (−x_off, R) in its local frame; the hand
//! force is the sum of both fingers' forces in the world frame, and F_hand,x ≠ 0 in
//! general. State y = (finger 1: q11, q21, q̇11, q̇21 | finger 2: the same | F̄_x, F̄_y).

use super::{KeptEval, Response, Run, Scene};
use crate::math::V2;
use crate::model::{grasp_at, Finger, OffsetFailure, StaticsResult};
use crate::params::SceneParams;
use crate::sim::criteria::{force_margin, r_area, u_min};
use crate::sim::driver;
use crate::sim::equilibrium::finger_equilibrium;
use crate::sim::events::{Crossing, EventKind, EventValues};
use crate::sim::finger::{FingerEval, FingerModel, Kink};
use crate::sim::integrate::{Piece, Rhs, Tol};
use crate::sim::memory::Memory;
use crate::sim::result::{DynOutcome, DynamicsResult};
use crate::sim::settings::{Controls, Integration, Mode};
use crate::sim::sink::{Point, Sink};
use crate::sim::tracking::{finger_sample, grasp_sample, EndValues, GraspLimits, Tracker};
use nalgebra::{SVector, Vector2};

/// State dimension of the offset scene.
pub const NO: usize = 10;
/// Number of event functions of the offset scene.
pub const EO: usize = 10;
type St = SVector<f64, NO>;

/// The event functions of the offset scene: contacts 0, 1 (finger 1 proximal, distal),
/// 2, 3 (finger 2), then the criteria and each finger's singularity and stop.
pub const OFFSET_EVENTS: [EventKind; EO] = [
    EventKind::Contact(0),
    EventKind::Contact(1),
    EventKind::Contact(2),
    EventKind::Contact(3),
    EventKind::Stability,
    EventKind::Force,
    EventKind::Singular(0),
    EventKind::Singular(1),
    EventKind::Stop(0),
    EventKind::Stop(1),
];
const FORCE: usize = 5;

/// Both fingers' evaluations at one state.
#[derive(Debug, Clone, Copy)]
pub struct PairEval {
    /// Finger 1 and finger 2 (local frames).
    pub f: [FingerEval; 2],
    /// The hand force F_hand on the object (world).
    pub hand: V2,
    /// Total energy (both fingers).
    pub energy: f64,
}

/// What an offset-scene run gives: the stage-3 results and the hand force at the end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OffsetResult {
    /// The stage-3 results (criteria over both fingers; `onsets` per phalanx, the earlier finger).
    pub dynamics: DynamicsResult,
    /// The object offset x_off (m).
    pub x_off: f64,
    /// F_hand at the end of the run (world, N).
    pub hand_end: [f64; 2],
    /// F⁰_hand of the static model at the offset (world, N).
    pub hand0: [f64; 2],
    /// Why the static grasp at the offset does not exist, when it does not (then the
    /// outcome is [`DynOutcome::NoOffsetGrasp`] and nothing was simulated).
    pub grasp_failure: Option<OffsetFailure>,
}

/// Why an offset scene cannot start.
#[derive(Debug, Clone, Copy)]
pub enum StartFailure {
    /// No static grasp of the object at the offset (a finger has no closed pose, or its
    /// static forces are not admissible).
    NoGrasp(OffsetFailure),
    /// A finger's compliant equilibrium (§8.9) was not found.
    NoEquilibrium,
}

/// The offset scene during a run.
pub struct OffsetScene<'a> {
    model: FingerModel<'a>,
    centre: [V2; 2],
    mem: [Memory; 4],
    s: &'a SceneParams,
    limits: GraspLimits,
    hand0: [f64; 2],
    tracker: Tracker<4>,
    evals: u64,
    accepted: KeptEval<NO, PairEval>,
    x_off: f64,
}

impl<'a> OffsetScene<'a> {
    /// The scene of finger `f` (statics `st` of the centred grasp for the spring preload)
    /// on the object at world offset `x_off`; `Err` names why it cannot start.
    pub fn new(
        f: &'a Finger,
        s: &'a SceneParams,
        st: &StaticsResult,
        x_off: f64,
        ctl: &Controls,
    ) -> Result<Self, StartFailure> {
        let model = FingerModel::new(f, s, st.tau_s0);
        let r = s.object.radius;
        let centre = [V2::new(x_off, r), V2::new(-x_off, r)];
        let g = grasp_at(f, s, st.tau_s0, x_off).map_err(StartFailure::NoGrasp)?;
        let f0 = [g.forces[0].f0, g.forces[1].f0];
        let r_area = r_area(s);
        let limits = GraspLimits {
            static_force_margin: force_margin(s, r_area, g.hand0),
            // E_ex sums both fingers: the centred scene's per-finger threshold η U_min, once per finger
            threshold: 2.0 * s.criteria.eta_stab * u_min(s, f0[0]).min(u_min(s, f0[1])),
            ..GraspLimits::unknown(r_area)
        };
        let mut sc = OffsetScene {
            model,
            centre,
            mem: [Memory::default(); 4],
            s,
            limits,
            hand0: [g.hand0.x, g.hand0.y],
            tracker: Tracker::new(ctl.mode == Mode::Pipeline),
            evals: 0,
            accepted: KeptEval::default(),
            x_off,
        };
        if limits.static_force_margin < 0.0 {
            sc.tracker.fail(DynOutcome::StaticForceLimit);
        }
        let e1 = finger_equilibrium(&sc.model, centre[0], s, f0[0]);
        let e2 = finger_equilibrium(&sc.model, centre[1], s, f0[1]);
        if let (Some(a), Some(b)) = (e1, e2) {
            sc.limits.v_star = a.v_star + b.v_star;
            sc.limits.fstar = [a.fstar[0].max(b.fstar[0]), a.fstar[1].max(b.fstar[1])];
        } else {
            return Err(StartFailure::NoEquilibrium);
        }
        Ok(sc)
    }

    fn eval_with(&self, y: &St, full: bool) -> Option<PairEval> {
        let mut f = [None, None];
        for (i, slot) in f.iter_mut().enumerate() {
            let o = 4 * i;
            let mem = [self.mem[2 * i], self.mem[2 * i + 1]];
            *slot = Some(self.model.evaluate(
                Vector2::new(y[o], y[o + 1]),
                Vector2::new(y[o + 2], y[o + 3]),
                self.centre[i],
                &mem,
                true,
                full,
            )?);
        }
        let f = [f[0]?, f[1]?];
        let hand = V2::new(f[0].object_force.x - f[1].object_force.x, f[0].object_force.y + f[1].object_force.y);
        Some(PairEval { f, hand, energy: f[0].energy + f[1].energy })
    }

    fn piece_of(ev: &PairEval) -> Piece {
        let mut p = ev.f[0].piece;
        for b in 0..Kink::BITS {
            if ev.f[1].piece.has(b) {
                p = p.with(b + Kink::BITS);
            }
        }
        p
    }

    fn deriv(&self, y: &St, ev: &PairEval) -> St {
        let tf = self.s.criteria.t_filter;
        let (a, b) = (&ev.f[0], &ev.f[1]);
        St::from([
            y[2],
            y[3],
            a.qdd[0],
            a.qdd[1],
            y[6],
            y[7],
            b.qdd[0],
            b.qdd[1],
            (ev.hand.x - y[8]) / tf,
            (ev.hand.y - y[9]) / tf,
        ])
    }
}

impl Rhs<NO> for OffsetScene<'_> {
    fn eval(&mut self, _t: f64, y: &St) -> Option<St> {
        self.evals += 1;
        let ev = self.eval_with(y, false)?;
        Some(self.deriv(y, &ev))
    }
    fn piece(&self, y: &St) -> Piece {
        self.eval_with(y, false).map_or(Piece::UNDEFINED, |e| Self::piece_of(&e))
    }
    fn eval_piece(&mut self, _t: f64, y: &St) -> Option<(St, Piece)> {
        self.evals += 1;
        let ev = self.eval_with(y, false)?;
        Some((self.deriv(y, &ev), Self::piece_of(&ev)))
    }
    fn eval_accepted(&mut self, _t: f64, y: &St) -> Option<(St, Piece)> {
        self.evals += 1;
        let ev = self.eval_with(y, true)?;
        let out = (self.deriv(y, &ev), Self::piece_of(&ev));
        self.accepted.keep(y, ev);
        Some(out)
    }
}

impl Scene<NO, EO> for OffsetScene<'_> {
    type Eval = PairEval;

    fn events(&self) -> [EventKind; EO] {
        OFFSET_EVENTS
    }
    fn initial_state(&self) -> St {
        let o = &self.model.finger.open;
        St::from([o.q11, o.q21, 0.0, 0.0, o.q11, o.q21, 0.0, 0.0, 0.0, 0.0])
    }
    fn evaluate(&self, y: &St) -> Option<PairEval> {
        self.eval_with(y, true)
    }
    fn take_accepted(&mut self, y: &St) -> Option<PairEval> {
        self.accepted.take(y)
    }
    fn derivative(&self, y: &St, ev: &PairEval) -> St {
        self.deriv(y, ev)
    }
    fn event_values(&self, y: &St, ev: &PairEval) -> EventValues<EO> {
        let eps = self.s.contact.eps_sep;
        let c = |k: usize| &ev.f[k / 2].contacts[k % 2];
        let g_c = |k: usize| self.mem[k].event_value(c(k).geom.delta, eps);
        let stab = if self.tracker.first.is_some() {
            ev.energy - self.limits.v_star - self.limits.threshold
        } else {
            f64::INFINITY
        };
        let force = force_margin(self.s, self.limits.r_area, V2::new(y[8], y[9]));
        EventValues {
            g: [
                g_c(0),
                g_c(1),
                g_c(2),
                g_c(3),
                stab,
                force,
                ev.f[0].sin_q13.abs() - 1e-3,
                ev.f[1].sin_q13.abs() - 1e-3,
                ev.f[0].theta2,
                ev.f[1].theta2,
            ],
            rate: [
                c(0).delta_dot,
                c(1).delta_dot,
                c(2).delta_dot,
                c(3).delta_dot,
                0.0,
                0.0,
                0.0,
                0.0,
                ev.f[0].theta2_dot,
                ev.f[1].theta2_dot,
            ],
        }
    }
    fn crossing(&self, i: usize) -> Option<Crossing> {
        match OFFSET_EVENTS[i] {
            EventKind::Force if !self.tracker.force_armed => None,
            EventKind::Contact(c) => Some(OFFSET_EVENTS[i].crossing(self.mem[c as usize].active)),
            kind => Some(kind.crossing(false)),
        }
    }
    fn begin(&mut self, _y: &St, ev: &PairEval, g: &EventValues<EO>) -> bool {
        if ev.f.iter().any(|f| f.contacts.iter().any(|c| c.geom.delta > 1e-12)) {
            self.tracker.outcome = DynOutcome::InitialPenetration;
            return false;
        }
        if self.tracker.pipeline && self.tracker.outcome != DynOutcome::Stable {
            return false;
        }
        self.tracker.min_force_margin = g.g[FORCE];
        true
    }
    fn handle(&mut self, i: usize, t: f64, ev: &PairEval, end: &EventValues<EO>) -> Response {
        match OFFSET_EVENTS[i] {
            EventKind::Contact(_) => self.tracker.contact_event(self.s, t, i, &mut self.mem, |k| &ev.f[k / 2]),
            other => self.tracker.on_event(other, t, end.g[FORCE]),
        }
    }
    fn track(&mut self, at: Point, ev: &PairEval, g: &EventValues<EO>) {
        self.tracker.force_margin(g.g[FORCE]);
        if at == Point::Step {
            self.tracker.knuckle |= ev.f[0].knuckle_contact() || ev.f[1].knuckle_contact();
        }
    }
    fn memories(&self) -> &[Memory] {
        &self.mem
    }
    /// Finger 1's sample (its angles, rates, contacts and θ2) with finger 2's own
    /// (`finger2`: finger 2 is not finger 1's mirror image here), the hand force (both
    /// fingers, y component), its filtered value and the energy of both fingers.
    fn sample<K: Sink + ?Sized>(&self, at: Point, t: f64, y: &St, ev: &PairEval, sink: &mut K) {
        let q = [y[0], y[1], y[2], y[3]];
        let mut s = grasp_sample(t, q, &ev.f[0], [ev.hand.y, y[9]], ev.energy, self.limits.v_star);
        s.finger2 = Some(finger_sample([y[4], y[5], y[6], y[7]], &ev.f[1]));
        sink.finger(at, &s);
    }
}

impl OffsetScene<'_> {
    /// The output of a finished run: the criteria's verdicts and the measured values.
    fn finish(mut self, run: &Run<NO, PairEval>) -> OffsetResult {
        self.tracker.on_end(run.end);
        let end = run.last.map(|ev| EndValues {
            f_end: [ev.f[0].contacts[0].normal_force, ev.f[0].contacts[1].normal_force],
            energy: ev.energy,
            max_qdd: ev.f[0].qdd.amax().max(ev.f[1].qdd.amax()),
        });
        let dynamics = self.tracker.result(&self.limits, self.evals, Some((run, end)));
        let hand_end = run.last.map_or([f64::NAN; 2], |ev| [ev.hand.x, ev.hand.y]);
        OffsetResult { dynamics, x_off: self.x_off, hand_end, hand0: self.hand0, grasp_failure: None }
    }
}

/// Tolerances of the offset scene (the filter states in N: 1e4·atol).
fn tolerances(integ: &Integration) -> Tol<NO> {
    let c = integ.scaling.grasp;
    let a = integ.atol * c;
    let mut atol = St::repeat(a);
    atol[8] = a * 1e4;
    atol[9] = a * 1e4;
    Tol { rtol: integ.rtol * c, atol }
}

/// Simulate the grasp of the design's fingers on the fixed object at world offset `x_off`,
/// reporting both fingers' samples to `sink`.
pub(crate) fn run<K: Sink + ?Sized>(
    f: &Finger,
    s: &SceneParams,
    st: &StaticsResult,
    x_off: f64,
    integ: &Integration,
    ctl: &Controls,
    sink: &mut K,
) -> OffsetResult {
    match OffsetScene::new(f, s, st, x_off, ctl) {
        Ok(mut sc) => {
            let run = driver::simulate(&mut sc, integ, ctl, tolerances(integ), s.criteria.t_max, sink);
            sc.finish(&run)
        }
        Err(why) => {
            // the scene could not be set up: nothing simulated, nothing known but R_area
            let mut k = Tracker::<4>::new(ctl.mode == Mode::Pipeline);
            let grasp_failure = match why {
                StartFailure::NoGrasp(e) => Some(e),
                StartFailure::NoEquilibrium => None,
            };
            k.outcome = if grasp_failure.is_some() { DynOutcome::NoOffsetGrasp } else { DynOutcome::NoEquilibrium };
            k.min_force_margin = f64::NAN;
            let dynamics = k.result::<NO, PairEval>(&GraspLimits::unknown(r_area(s)), 0, None);
            OffsetResult { dynamics, x_off, hand_end: [f64::NAN; 2], hand0: [f64::NAN; 2], grasp_failure }
        }
    }
}
