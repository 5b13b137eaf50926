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
/// grasp scenes' and the nominal's not at all).
pub const SIMULATOR_REVISION: u32 = 4;

/// Relative agreement expected of a design's objectives and violation between simulator
/// revisions: issue 23 moved t_stab by at most 1.85e-4 relative over the work-precision
/// ensemble (a threshold crossing moved by one oscillation; docs/benchmarks.md).
pub const ACROSS_REVISIONS_RTOL: f64 = 1e-3;

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
}

impl Integration {
    /// Radau IIA with these tolerances and budget, from its own first step.
    pub fn new(rtol: f64, atol: f64, max_steps: u64) -> Self {
        Integration { rtol, atol, max_steps, method: Method::Radau5, h0: Method::Radau5.first_step() }
    }
    /// The problem's `[solver]` settings: its tolerances, budget and method, from the
    /// method's first step.
    pub fn from_solver(s: &SolverSettings) -> Self {
        Self::new(s.rtol, s.atol, s.max_steps).with_method(s.method)
    }
    /// The same settings with method `m` and its first step.
    pub fn with_method(self, m: Method) -> Self {
        Integration { method: m, h0: m.first_step(), ..self }
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
