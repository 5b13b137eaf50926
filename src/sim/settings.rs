//! What a simulation is run with: the numerics ([`Integration`]: method, tolerances, step
//! budget, first step) and the run controls ([`Controls`]: pipeline or diagnostic mode,
//! contacts, the uniform sampling grid). Plain structs passed explicitly (rapier's
//! `IntegrationParameters`); recording and tracing are the caller's [`Sink`](super::Sink).

pub use crate::params::Method;
use crate::params::SolverSettings;
use serde::{Deserialize, Serialize};

/// Revision of the simulator's arithmetic, stamped into every recording. It is raised by a
/// change that moves simulated results within the integration tolerance, so that a grasp
/// recorded before it is no longer reproduced bit for bit (replay then compares verdicts and
/// objectives instead, [`ACROSS_REVISIONS_RTOL`]). 1: up to issue 21 (recordings without the
/// stamp); 2: issue 23's Radau IIA block elimination and cheaper right-hand side; 3: the
/// driver starts from the scene's state after `begin` (the free scene's pre-sunk ground
/// contacts in its first derivative and event values: the free scene's results move by
/// ≤ 3e-5 relative, the grasp scenes' not at all); 4: a contact left past δ = 0 without
/// memory by an event gets its onset there (session 36: some free-scene runs move, the
/// grasp scenes' and the nominal's not at all); 5: a problem without `solver.method` runs
/// the default solver, the switching method with the default's tolerance scaling
/// ([`DEFAULT_AUTO_REVISION`], session 38; RADAU5 and every named method bit for bit as
/// before, so a run that keeps the old default states revision 4, [`revision_of`]).
pub const SIMULATOR_REVISION: u32 = 5;

/// Relative agreement expected of a design's objectives and violation between simulator
/// revisions: the accuracy rule's largest relative error of an objective against the tight
/// reference (docs/benchmarks.md, "The accuracy rule"; 1e-3 before session 38, when issue 23
/// had moved t_stab by at most 1.85e-4 over the work-precision ensemble).
pub const ACROSS_REVISIONS_RTOL: f64 = 2e-3;

/// How the scenes read a problem's tolerances: factors on the `[solver]` rtol and atol per
/// scene and state. [`Scaling::AS_GIVEN`] (every factor 1) for a method a problem names;
/// [`Scaling::DEFAULT`] for the default method (a problem without `solver.method`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Scaling {
    /// Factor on rtol and atol in the grasp scenes (centred and offset), whose t_stab is an
    /// objective.
    pub grasp: f64,
    /// Factor on the absolute tolerance of the fingers' angles and rates in the free scene.
    pub free_fingers_atol: f64,
    /// Factor on the absolute tolerance of the object's velocity and angular velocity in the
    /// free scene.
    pub free_object_rates_atol: f64,
}

impl Scaling {
    /// The tolerances as the problem gives them.
    pub const AS_GIVEN: Scaling = Scaling { grasp: 1.0, free_fingers_atol: 1.0, free_object_rates_atol: 1.0 };
    /// The default method's (docs/benchmarks.md, "The default solver"), chosen on the
    /// accuracy rule's ensembles: the switching method's explicit transient has a phase
    /// error that RADAU5 at the same rtol has not, so the grasp scenes run at a tenth of the
    /// tolerances (then at least as accurate as RADAU5 at the problem's); the free scene,
    /// whose outputs are a verdict and diagnostics, at the problem's rtol, with the fingers'
    /// absolute tolerance 1000 times and the object's rates' 10 times the problem's (the
    /// object's position, which the verdict measures, keeps its own).
    pub const DEFAULT: Scaling = Scaling { grasp: 0.1, free_fingers_atol: 1e3, free_object_rates_atol: 10.0 };

    fn as_given() -> Self {
        Scaling::AS_GIVEN
    }
}

/// The numerics of a simulation (built from the problem's `[solver]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Integration {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance on angles (rad) and rates (rad/s); each scene scales it for its
    /// other states.
    pub atol: f64,
    /// Budget of accepted + rejected steps.
    pub max_steps: u64,
    /// Method.
    pub method: Method,
    /// First step size (s).
    pub h0: f64,
    /// How each scene scales the tolerances.
    #[serde(default = "Scaling::as_given")]
    pub scaling: Scaling,
}

impl Integration {
    /// Radau IIA with these tolerances (as given) and budget, from its own first step.
    pub fn new(rtol: f64, atol: f64, max_steps: u64) -> Self {
        Integration {
            rtol,
            atol,
            max_steps,
            method: Method::Radau5,
            h0: Method::Radau5.first_step(),
            scaling: Scaling::AS_GIVEN,
        }
    }
    /// The problem's `[solver]` settings: its tolerances, budget and method, from the
    /// method's first step; the default method (no `solver.method`, [`Method::PROBLEM_DEFAULT`])
    /// with [`Scaling::DEFAULT`], a named method with the tolerances as given.
    pub fn from_solver(s: &SolverSettings) -> Self {
        Self::overridden(s, None, None)
    }
    /// The problem's settings with a method and an rtol given instead of its own (`simulate
    /// --method --rtol`): a given method is a named one (tolerances as given); an rtol alone
    /// keeps the problem's method and its scaling.
    pub fn overridden(s: &SolverSettings, method: Option<Method>, rtol: Option<f64>) -> Self {
        let m = method.unwrap_or(s.method);
        let i = Self::new(rtol.unwrap_or(s.rtol), s.atol, s.max_steps).with_method(m);
        let default = method.is_none() && !s.method_named && m == Method::PROBLEM_DEFAULT;
        if default {
            i.with_scaling(Scaling::DEFAULT)
        } else {
            i
        }
    }
    /// The settings a design recorded by simulator revision `revision` was evaluated with,
    /// for a problem with solver settings `s`: before revision 5 a problem without
    /// `solver.method` ran RADAU5 with its tolerances as given (the default of then).
    pub fn of_revision(s: &SolverSettings, revision: u32) -> Self {
        if revision < DEFAULT_AUTO_REVISION && !s.method_named {
            Self::new(s.rtol, s.atol, s.max_steps)
        } else {
            Self::from_solver(s)
        }
    }
    /// The same settings with method `m` and its first step.
    pub fn with_method(self, m: Method) -> Self {
        Integration { method: m, h0: m.first_step(), ..self }
    }
    /// The same settings with the scenes' tolerance scaling `scaling`.
    pub fn with_scaling(self, scaling: Scaling) -> Self {
        Integration { scaling, ..self }
    }
}

/// The simulator revision from which a problem without `solver.method` runs the default
/// method, auto with [`Scaling::DEFAULT`] (before it: RADAU5, its tolerances as given).
pub const DEFAULT_AUTO_REVISION: u32 = 5;

/// The revision a recording of a run with solver settings `s` states: the one before
/// [`DEFAULT_AUTO_REVISION`] for a run that keeps the default of then (a problem without
/// `solver.method` resumed from a checkpoint of before session 38 runs RADAU5 as given,
/// [`crate::params::Problem::with_run_method`], and revision 5 differs from 4 only by the default), this
/// build's [`SIMULATOR_REVISION`] otherwise: so that a replay re-evaluates each recording
/// with the settings it ran with ([`Integration::of_revision`]).
pub fn revision_of(s: &SolverSettings) -> u32 {
    if !s.method_named && s.method != Method::PROBLEM_DEFAULT {
        DEFAULT_AUTO_REVISION - 1
    } else {
        SIMULATOR_REVISION
    }
}

/// Pipeline mode stops at the first violated criterion; diagnostic mode runs to t_stab or t_max.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Stop at the first violated criterion.
    Pipeline,
    /// Always run to t_stab (or t_max), reporting every criterion.
    Diagnostic,
}

/// How a run is controlled (not numerics).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Controls {
    /// Pipeline or diagnostic.
    pub mode: Mode,
    /// Contacts with the object (false: the fingers close on nothing — a diagnostic scene
    /// for the linkage alone; no compliant equilibrium, no stability; centred scene only).
    pub contacts: bool,
    /// Also sample a uniform grid with this step (s), when the sink takes samples.
    pub grid_dt: Option<f64>,
}

impl Controls {
    /// Pipeline mode: stop at the first violated criterion.
    pub const PIPELINE: Controls = Controls { mode: Mode::Pipeline, contacts: true, grid_dt: None };
    /// Diagnostic mode: run to t_stab (or t_max), reporting every criterion.
    pub const DIAGNOSTIC: Controls = Controls { mode: Mode::Diagnostic, contacts: true, grid_dt: None };
}
