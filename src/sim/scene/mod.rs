//! Scenes: what stage 3 integrates (MODEL.md §14). A scene is three things to the generic
//! [`driver`](crate::sim::driver): a system (its state of `N` values, the right-hand side
//! [`Rhs`], the full model at a state), its roots (`E` event functions and how each
//! crosses) and its response to them (contact memories, criteria; restart or stop). It
//! reports samples to the caller's [`Sink`] and gives its own output at the end. The
//! criteria the grasp scenes share are the [`Tracker`](super::tracking::Tracker)'s.
//! Implementations: [`centred`] (one finger, its mirror, the fixed centred object),
//! [`offset`] (both fingers, the fixed object at x_off: N = 10) and [`free`] (both fingers
//! and the object as a rigid body: N = 21).

pub mod centred;
pub mod free;
pub mod offset;

use super::events::{Crossing, EventKind, EventValues};
use super::integrate::{Rhs, Stats};
use super::memory::Memory;
use super::sink::{Point, Sink};
use nalgebra::SVector;

/// The full evaluation the integrator made at the end of its last accepted step
/// ([`Rhs::eval_accepted`]), kept for the driver: the scene hands it back when the driver
/// asks for the model at that state (one evaluation per step saved).
#[derive(Debug, Clone, Copy)]
pub struct KeptEval<const N: usize, Ev>(Option<(SVector<f64, N>, Ev)>);

impl<const N: usize, Ev> Default for KeptEval<N, Ev> {
    fn default() -> Self {
        KeptEval(None)
    }
}

impl<const N: usize, Ev> KeptEval<N, Ev> {
    /// Keep `ev`, the evaluation at `y`.
    pub fn keep(&mut self, y: &SVector<f64, N>, ev: Ev) {
        self.0 = Some((*y, ev));
    }
    /// The kept evaluation if it was at `y` (it is handed out once).
    pub fn take(&mut self, y: &SVector<f64, N>) -> Option<Ev> {
        match self.0.take() {
            Some((ya, ev)) if ya == *y => Some(ev),
            _ => None,
        }
    }
}

/// What handling an event asks of the driver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Response {
    /// The right-hand side changed (a memory or a kink): restart the stepper.
    pub restart: bool,
    /// End the run here.
    pub stop: bool,
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum End {
    /// The scene asked to stop at an event.
    Stopped,
    /// The end time was reached.
    TimeUp,
    /// The budget of accepted + rejected steps was spent.
    StepBudget,
    /// The step size underflowed.
    StepTooSmall,
    /// The model was undefined at a state the run reached.
    Undefined,
    /// More than [`MAX_EVENTS`](super::MAX_EVENTS) events.
    Aborted,
    /// The scene refused the initial state ([`Scene::begin`]).
    Declined,
}

/// The driver's account of a run.
#[derive(Debug, Clone, Copy)]
pub struct Run<const N: usize, Ev> {
    /// How it ended.
    pub end: End,
    /// The time reached.
    pub t: f64,
    /// The state reached (with the scene's memories of that moment).
    pub y: SVector<f64, N>,
    /// The evaluation at the last state reached (None: ended before the first step).
    pub last: Option<Ev>,
    /// Events located (including one that aborted the run).
    pub events: u32,
    /// The stepper's counters.
    pub stats: Stats,
    /// Model evaluations made to locate events (count as right-hand-side evaluations).
    pub locate_evals: u64,
}

/// A simulated scene with `N` states and `E` event functions.
pub trait Scene<const N: usize, const E: usize>: Rhs<N> {
    /// The full model at one state (forces, contacts, energy).
    type Eval: Copy;

    // ---- the system (with `Rhs`)
    /// The initial state.
    fn initial_state(&self) -> SVector<f64, N>;
    /// The model at `y` (not counted as a right-hand-side evaluation); `None` where it is
    /// undefined.
    fn evaluate(&self, y: &SVector<f64, N>) -> Option<Self::Eval>;
    /// The full evaluation kept by the last [`Rhs::eval_accepted`], if it was at `y`.
    fn take_accepted(&mut self, y: &SVector<f64, N>) -> Option<Self::Eval>;
    /// y' from a full evaluation.
    fn derivative(&self, y: &SVector<f64, N>, ev: &Self::Eval) -> SVector<f64, N>;

    // ---- the roots
    /// The event functions, in the order of [`EventValues`] (events located at the same
    /// time go to the first).
    fn events(&self) -> [EventKind; E];
    /// The event functions' values at a state.
    fn event_values(&self, y: &SVector<f64, N>, ev: &Self::Eval) -> EventValues<E>;
    /// How event `i` triggers now; `None`: not watched.
    fn crossing(&self, i: usize) -> Option<Crossing>;
    /// Event function `i` alone at `y`, as [`Scene::event_values`] gives it: what event
    /// location evaluates, many times per event. The default evaluates the full model; a
    /// scene overrides it with the part event `i` needs, in the same arithmetic (`None`
    /// where that part is undefined).
    fn event_value(&self, i: usize, y: &SVector<f64, N>) -> Option<f64> {
        let ev = self.evaluate(y)?;
        Some(self.event_values(y, &ev).g[i])
    }

    // ---- the response
    /// Check the initial state; false ends the run before the first step (the scene
    /// keeps why).
    fn begin(&mut self, y: &SVector<f64, N>, ev: &Self::Eval, g: &EventValues<E>) -> bool;
    /// Handle event `i` located at `t` (memories, criteria); `end`: the event values at
    /// the end of the step it was found in.
    fn handle(&mut self, i: usize, t: f64, ev: &Self::Eval, end: &EventValues<E>) -> Response;
    /// Track the criteria at a state reached at `at` ([`Point::Step`] or [`Point::Event`]).
    fn track(&mut self, at: Point, ev: &Self::Eval, g: &EventValues<E>);
    /// The contact memories (for the sink's event notes).
    fn memories(&self) -> &[Memory];

    // ---- output
    /// Report a sample to `sink` (called only when it takes samples).
    fn sample<K: Sink + ?Sized>(&self, at: Point, t: f64, y: &SVector<f64, N>, ev: &Self::Eval, sink: &mut K);
}
