//! Criteria tracked during a grasp (MODEL.md §9): the first contact with its impact and
//! fold verdicts, the filtered-force margin, the time to stability, and the first violated
//! criterion. `C` is the number of contacts a scene tracks onsets of.

use super::criteria::Impact;
use super::driver::End;
use super::events::EventKind;
use super::result::{DynOutcome, FirstContact};
use super::scene::Response;
use crate::params::SceneParams;

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
