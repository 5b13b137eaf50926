//! The one way to simulate a finger in a scene: [`simulate`] with a [`SceneSpec`], the
//! numerics ([`Integration`]), the run controls ([`Controls`]) and the caller's [`Sink`].

use super::result::{DynamicsResult, FreeEnd};
use super::scene::free::{FreeResult, FreeSetup};
use super::scene::offset::OffsetResult;
use super::scene::{centred, free, offset};
use super::settings::{Controls, Integration};
use super::sink::Sink;
use crate::model::{Finger, StaticsResult};
use crate::params::{SceneKind, SceneParams, SceneSetup};
use std::time::Instant;

/// Which scene to simulate, with its inputs beyond the problem (MODEL.md §14).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SceneSpec {
    /// One finger and its mirror on the fixed object centred at (0, R).
    Centred,
    /// Both fingers on the fixed object at (x_off, R).
    Offset {
        /// Object offset (m).
        x_off: f64,
    },
    /// Both fingers and the free object on the ground.
    Free {
        /// Object offset (m).
        x_off: f64,
        /// Test and study inputs (the default: the problem's scene as it is).
        setup: FreeSetup,
        /// End time (s); None: min(t_max, t_obs).
        t_end: Option<f64>,
    },
}

impl SceneSpec {
    /// The scene of a problem's `[scene]`.
    pub fn of(setup: &SceneSetup) -> Self {
        match setup.kind {
            SceneKind::Centred => SceneSpec::Centred,
            SceneKind::Offset => SceneSpec::Offset { x_off: setup.x_off },
            SceneKind::Free => SceneSpec::free(setup.x_off),
        }
    }
    /// The free scene at `x_off` as the problem sets it up.
    pub fn free(x_off: f64) -> Self {
        SceneSpec::Free { x_off, setup: FreeSetup::default(), t_end: None }
    }
    /// Its kind.
    pub fn kind(&self) -> SceneKind {
        match self {
            SceneSpec::Centred => SceneKind::Centred,
            SceneSpec::Offset { .. } => SceneKind::Offset,
            SceneSpec::Free { .. } => SceneKind::Free,
        }
    }
    /// The object offset (m; 0 in the centred scene).
    pub fn x_off(&self) -> f64 {
        match *self {
            SceneSpec::Centred => 0.0,
            SceneSpec::Offset { x_off } | SceneSpec::Free { x_off, .. } => x_off,
        }
    }
}

/// What a scene's run gives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SceneResult {
    /// The centred grasp.
    Centred(DynamicsResult),
    /// The offset grasp (with the hand forces).
    Offset(OffsetResult),
    /// The free object's measured motion (MODEL.md §14.4).
    Free(FreeResult),
}

impl SceneResult {
    /// The grasp's stage-3 results (centred or offset scene).
    pub fn grasp(&self) -> Option<&DynamicsResult> {
        match self {
            SceneResult::Centred(d) => Some(d),
            SceneResult::Offset(o) => Some(&o.dynamics),
            SceneResult::Free(_) => None,
        }
    }
    /// The free scene's results.
    pub fn free(&self) -> Option<&FreeResult> {
        match self {
            SceneResult::Free(f) => Some(f),
            _ => None,
        }
    }
    /// Wall seconds of the simulation.
    pub fn cpu_s(&self) -> f64 {
        match self {
            SceneResult::Centred(d) => d.cpu_s,
            SceneResult::Offset(o) => o.dynamics.cpu_s,
            SceneResult::Free(f) => f.cpu_s,
        }
    }
    /// Accepted steps and right-hand-side evaluations (including event location).
    pub fn work(&self) -> [u64; 2] {
        match self {
            SceneResult::Centred(d) => [d.stats.steps, d.rhs_evals],
            SceneResult::Offset(o) => [o.dynamics.stats.steps, o.dynamics.rhs_evals],
            SceneResult::Free(f) => [f.stats.steps, f.rhs_evals],
        }
    }
    /// How the free scene ended (None for a grasp scene).
    pub fn free_end(&self) -> Option<FreeEnd> {
        self.free().map(|f| f.end)
    }
}

/// Simulate finger `f` (its statics `st` from stage 2) in scene `spec` of the problem's
/// `s`, with the numerics `integ` and the controls `ctl` (the free scene always runs to its
/// end, as in diagnostic mode), reporting samples and events to `sink` (the results do not
/// depend on it).
pub fn simulate<K: Sink + ?Sized>(
    f: &Finger,
    s: &SceneParams,
    st: &StaticsResult,
    spec: &SceneSpec,
    integ: &Integration,
    ctl: &Controls,
    sink: &mut K,
) -> SceneResult {
    let clock = Instant::now();
    match *spec {
        SceneSpec::Centred => {
            let mut r = centred::run(f, s, st, integ, ctl, sink);
            r.cpu_s = clock.elapsed().as_secs_f64();
            SceneResult::Centred(r)
        }
        SceneSpec::Offset { x_off } => {
            let mut r = offset::run(f, s, st, x_off, integ, ctl, sink);
            r.dynamics.cpu_s = clock.elapsed().as_secs_f64();
            SceneResult::Offset(r)
        }
        SceneSpec::Free { x_off, setup, t_end } => {
            let mut r = free::run(f, s, st.tau_s0, x_off, setup, t_end, integ, sink);
            r.cpu_s = clock.elapsed().as_secs_f64();
            SceneResult::Free(r)
        }
    }
}

/// The centred grasp in diagnostic mode with nothing sampled: [`simulate`]'s shorthand for
/// the work-precision benchmarks and tests.
pub fn diagnostic_grasp(f: &Finger, s: &SceneParams, st: &StaticsResult, integ: &Integration) -> DynamicsResult {
    match simulate(f, s, st, &SceneSpec::Centred, integ, &Controls::DIAGNOSTIC, &mut ()) {
        SceneResult::Centred(d) => d,
        _ => unreachable!("the centred scene gives a centred result"),
    }
}
