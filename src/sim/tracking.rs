//! Criteria tracked during a grasp (MODEL.md §9), shared by the grasp scenes (centred and
//! offset): contact onsets with the first contact's impact and fold verdicts, the
//! filtered-force margin, the time to stability, the first violated criterion, and the
//! stage-3 result built from them. `C` is the number of contacts a scene tracks onsets
//! of: contact `c` is phalanx `c % 2` of finger `c / 2`.

use super::criteria::{impact, Impact};
use super::events::EventKind;
use super::finger::FingerEval;
use super::integrate::Stats;
use super::memory::{Memory, MemoryChange};
use super::result::{DynOutcome, DynamicsResult, FingerSample, FirstContact, Sample};
use super::scene::{End, Response, Run};
use crate::params::SceneParams;
use nalgebra::Matrix2;

/// What a grasp scene knows of its criteria before the run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GraspLimits {
    /// Margin of the static hand force F⁰_hand (N).
    pub static_force_margin: f64,
    /// R_area (N).
    pub r_area: f64,
    /// Compliant equilibrium forces f* (N).
    pub fstar: [f64; 2],
    /// Potential energy V* of the compliant equilibrium (J).
    pub v_star: f64,
    /// η U_min (J).
    pub threshold: f64,
}

impl GraspLimits {
    /// Nothing known but R_area (a scene that could not be set up).
    pub fn unknown(r_area: f64) -> Self {
        let nan = f64::NAN;
        GraspLimits { static_force_margin: nan, r_area, fstar: [nan; 2], v_star: nan, threshold: nan }
    }
}

/// A grasp scene's sample at `t`: finger 1's angles and rates `q` (q11, q21, q̇11, q̇21)
/// and evaluation `f`, the hand force F_hand,y, its filtered value and the scene's total
/// energy (its excess over the compliant equilibrium's `v_star`).
pub fn grasp_sample(t: f64, q: [f64; 4], f: &FingerEval, hand: [f64; 2], energy: f64, v_star: f64) -> Sample {
    let FingerSample { q, qd, theta2, delta, normal, friction } = finger_sample(q, f);
    Sample {
        t,
        q,
        qd,
        theta2,
        delta,
        normal,
        friction,
        hand_fy: hand[0],
        filtered_fy: hand[1],
        energy,
        energy_excess: energy - v_star,
        finger2: None,
    }
}

/// One finger's part of a sample: its angles and rates `q` (q11, q21, q̇11, q̇21) and its
/// evaluation `f` (θ2, the contacts), in its local frame.
pub fn finger_sample(q: [f64; 4], f: &FingerEval) -> FingerSample {
    let c = &f.contacts;
    FingerSample {
        q: [q[0], q[1]],
        qd: [q[2], q[3]],
        theta2: f.theta2,
        delta: [c[0].geom.delta, c[1].geom.delta],
        normal: [c[0].normal_force, c[1].normal_force],
        friction: [c[0].friction_force, c[1].friction_force],
    }
}

/// What a run's last state says, for the result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EndValues {
    /// Normal forces of finger 1 (proximal, distal) at the end (N).
    pub f_end: [f64; 2],
    /// Total energy at the end (J).
    pub energy: f64,
    /// max_k |q̈_k| at the end.
    pub max_qdd: f64,
}

/// The criteria state of one grasp simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tracker<const C: usize> {
    /// Stop at the first violated criterion (pipeline mode).
    pub pipeline: bool,
    /// The first violated criterion, or how the run ended; `Stable` if none.
    pub outcome: DynOutcome,
    /// First contact.
    pub first: Option<FirstContact>,
    /// Impact criterion holds (None: no contact yet).
    pub impact_ok: Option<bool>,
    /// Fold criterion holds.
    pub fold_ok: Option<bool>,
    /// Min of the filtered-force margin so far (N).
    pub min_force_margin: f64,
    /// The force margin is still watched (until its first violation).
    pub force_armed: bool,
    /// Time of the first force-criterion violation.
    pub t_force_violation: Option<f64>,
    /// Time to stability.
    pub t_stab: Option<f64>,
    /// Time of the first onset of each contact.
    pub onsets: [Option<f64>; C],
    /// A knuckle contact was seen at an accepted step.
    pub knuckle: bool,
}

impl<const C: usize> Tracker<C> {
    /// Nothing seen yet.
    pub fn new(pipeline: bool) -> Self {
        Tracker {
            pipeline,
            outcome: DynOutcome::Stable,
            first: None,
            impact_ok: None,
            fold_ok: None,
            min_force_margin: f64::INFINITY,
            force_armed: true,
            t_force_violation: None,
            t_stab: None,
            onsets: [None; C],
            knuckle: false,
        }
    }

    /// Record a violated criterion unless an earlier one is already recorded.
    pub fn fail(&mut self, o: DynOutcome) {
        if self.outcome == DynOutcome::Stable {
            self.outcome = o;
        }
    }

    /// Contact `i` started at `t`.
    pub fn onset(&mut self, i: usize, t: f64) {
        self.onsets[i].get_or_insert(t);
    }

    /// The first contact: among the contacts starting at `t` (`impacts[i]`: contact i's
    /// impact energies, `None` if it did not start), the one of the largest E_cyl (ties to
    /// the lower index), with the fold θ2. Returns true when the simulation must stop.
    pub fn first_contact(&mut self, s: &SceneParams, t: f64, impacts: &[Option<Impact>; C], theta2: f64) -> bool {
        let mut pick: Option<(usize, Impact)> = None;
        for (i, imp) in impacts.iter().enumerate() {
            if let Some(b) = *imp {
                if pick.is_none_or(|(_, a)| b.e_cyl > a.e_cyl) {
                    pick = Some((i, b));
                }
            }
        }
        let Some((i, imp)) = pick else { return false };
        self.first = Some(FirstContact { t, phalanx: i as u8 + 1, impact: imp, theta2 });
        let iok = imp.e_cyl <= imp.e_lim;
        let fok = theta2 <= s.criteria.fold_max;
        self.impact_ok = Some(iok);
        self.fold_ok = Some(fok);
        if !iok {
            self.fail(DynOutcome::ImpactEnergy);
        }
        if !fok {
            self.fail(DynOutcome::Fold);
        }
        self.pipeline && !(iok && fok)
    }

    /// The filtered-force margin at a state (ignored once violated).
    #[inline]
    pub fn force_margin(&mut self, m: f64) {
        if self.force_armed {
            self.min_force_margin = self.min_force_margin.min(m);
        }
    }

    /// The force margin became negative at `t` (`end`: the margin at the end of the step).
    /// Returns true when the simulation must stop.
    pub fn force_violated(&mut self, t: f64, end: f64) -> bool {
        self.t_force_violation = Some(t);
        self.min_force_margin = self.min_force_margin.min(end.min(0.0));
        self.force_armed = false;
        self.fail(DynOutcome::ForceCriterion);
        self.pipeline
    }

    /// The response to the events every grasp scene handles alike, at time `t`
    /// (`force_end`: the force margin at the end of the step): stability reached (stop), the
    /// force criterion violated (stop in pipeline mode), a singular configuration (stop), a
    /// distal stop engaging or releasing (restart: a kink of the right-hand side). Contact
    /// events are the scene's own and get no response here.
    pub fn on_event(&mut self, kind: EventKind, t: f64, force_end: f64) -> Response {
        match kind {
            EventKind::Stability => {
                self.t_stab = Some(t);
                Response { restart: false, stop: true }
            }
            EventKind::Force => Response { restart: false, stop: self.force_violated(t, force_end) },
            EventKind::Singular(_) => {
                self.outcome = DynOutcome::Singular;
                Response { restart: false, stop: true }
            }
            EventKind::Stop(_) => Response { restart: true, stop: false },
            EventKind::Contact(_) => Response { restart: false, stop: false },
        }
    }

    /// A contact event located at `t` on contact `located`: every contact's memory is
    /// updated (`mem[c]`, with finger `finger(c)`'s evaluation), onsets are noted, and the
    /// first onset(s) of the run give the first contact (largest E_cyl; θ2 the largest of
    /// the touching fingers'; phalanx 1 proximal, 2 distal). The memory changed, so the
    /// right-hand side did: restart; stop when the first contact violates a criterion in
    /// pipeline mode.
    pub fn contact_event<'e>(
        &mut self,
        s: &SceneParams,
        t: f64,
        located: usize,
        mem: &mut [Memory; C],
        finger: impl Fn(usize) -> &'e FingerEval,
    ) -> Response {
        let mut impacts: [Option<Impact>; C] = [None; C];
        let mut theta2 = f64::NAN;
        for c in 0..C {
            let fe = finger(c);
            let cs = &fe.contacts[c % 2];
            if mem[c].update(cs.geom.delta, cs.delta_dot, c == located, s.contact.eps_sep, s.contact.v_min)
                == MemoryChange::Onset
            {
                self.onset(c, t);
                if self.first.is_none() {
                    let minv = fe.m.try_inverse().unwrap_or(Matrix2::zeros());
                    let mf = 1.0 / cs.row.dot(&(minv * cs.row));
                    impacts[c] = Some(impact(s, mf, cs.delta_dot));
                    if theta2.is_nan() || fe.theta2 > theta2 {
                        theta2 = fe.theta2;
                    }
                }
            }
        }
        let stop = self.first.is_none() && self.first_contact(s, t, &impacts, theta2);
        if let Some(fc) = self.first.as_mut() {
            // contacts 2, 3 are finger 2's proximal and distal phalanges
            fc.phalanx = (fc.phalanx - 1) % 2 + 1;
        }
        Response { restart: true, stop }
    }

    /// The stage-3 result: the criteria tracked so far with the scene's `limits`, and
    /// what the `run` reached (none: the scene ended before a run). `evals`: the scene's
    /// right-hand-side evaluations (the run's event location adds its own).
    pub fn result<const N: usize, Ev>(
        &self,
        limits: &GraspLimits,
        evals: u64,
        run: Option<(&Run<N, Ev>, Option<EndValues>)>,
    ) -> DynamicsResult {
        // each phalanx's first onset over the fingers
        let mut onsets = [None; 2];
        for (c, t) in self.onsets.iter().enumerate() {
            let o: &mut Option<f64> = &mut onsets[c % 2];
            *o = match (*o, *t) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            };
        }
        let mut r = DynamicsResult {
            outcome: self.outcome,
            first: self.first,
            impact_ok: self.impact_ok,
            fold_ok: self.fold_ok,
            min_force_margin: self.min_force_margin,
            t_force_violation: self.t_force_violation,
            static_force_margin: limits.static_force_margin,
            r_area: limits.r_area,
            t_stab: self.t_stab,
            f_end: [0.0; 2],
            fstar: limits.fstar,
            v_star: limits.v_star,
            threshold: limits.threshold,
            e_ex_end: f64::NAN,
            max_qdd_end: f64::NAN,
            t_end: 0.0,
            events: 0,
            stats: Stats::default(),
            rhs_evals: evals,
            cpu_s: 0.0,
            knuckle_flag: self.knuckle,
            onsets,
        };
        if let Some((run, end)) = run {
            r.t_end = run.t;
            r.events = run.events;
            r.stats = run.stats;
            r.rhs_evals = evals + run.locate_evals;
            if let Some(e) = end {
                r.f_end = e.f_end;
                r.e_ex_end = e.energy - limits.v_star;
                r.max_qdd_end = e.max_qdd;
            }
        }
        r
    }

    /// Record how the driver ended (`Stopped`/`Declined` leave the outcome to the events;
    /// running out of time without stability is the first failure only).
    pub fn on_end(&mut self, end: End) {
        match end {
            End::Stopped | End::Declined => {}
            End::TimeUp => self.fail(DynOutcome::NoStability),
            End::StepBudget => self.outcome = DynOutcome::StepBudget,
            End::StepTooSmall => self.outcome = DynOutcome::StepTooSmall,
            End::Undefined => self.outcome = DynOutcome::DgmFailure,
            End::Aborted => self.outcome = DynOutcome::Aborted,
        }
    }
}
