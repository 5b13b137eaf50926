//! Scenes: what stage 3 integrates (MODEL.md §14). A scene owns its state layout (`N`
//! states), its event functions (`E` of them) and what they do, its criteria and its
//! outputs; the generic [`driver`](crate::sim::driver) steps it, locates its events and
//! samples it. Today's scene is [`centred`] (one finger, its mirror, the fixed centred
//! object); the offset scene (two fingers, fixed object at x_off: N = 10) and the free scene
//! (two fingers and the object as a rigid body: N = 21) are further implementations.

pub mod centred;
pub mod free;
pub mod offset;

use super::driver::Run;
use super::events::{Crossing, EventKind, EventValues};
use super::integrate::Rhs;
use nalgebra::SVector;

/// Where in a run a state was reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Point {
    /// The initial state.
    Start,
    /// The end of an accepted step without an event.
    Step,
    /// A located event, after the scene handled it.
    Event,
    /// A point of the uniform sampling grid (dense output inside a step).
    Grid,
}

/// What handling an event asks of the driver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Response {
    /// The right-hand side changed (a memory or a kink): restart the stepper.
    pub restart: bool,
    /// End the run here.
    pub stop: bool,
}

/// A simulated scene with `N` states and `E` event functions. The scene is the system the
/// stepper integrates ([`Rhs`]) and keeps whatever changes at events (contact memories),
/// its criteria and its outputs.
pub trait Scene<const N: usize, const E: usize>: Rhs<N> {
    /// The full model at one state (forces, contacts, energy).
    type Eval: Copy;
    /// What the run produces.
    type Output;

    /// The event functions, in the order of [`EventValues`] (events located at the same
    /// time go to the first).
    fn events(&self) -> [EventKind; E];
    /// The initial state.
    fn initial_state(&self) -> SVector<f64, N>;
    /// The model at `y` (not counted as a right-hand-side evaluation); `None` where it is
    /// undefined.
    fn evaluate(&self, y: &SVector<f64, N>) -> Option<Self::Eval>;
    /// The full evaluation kept by the last [`Rhs::eval_accepted`], if it was at `y`.
    fn take_accepted(&mut self, y: &SVector<f64, N>) -> Option<Self::Eval>;
    /// y' from a full evaluation.
    fn derivative(&self, y: &SVector<f64, N>, ev: &Self::Eval) -> SVector<f64, N>;
    /// The event functions' values at a state.
    fn event_values(&self, y: &SVector<f64, N>, ev: &Self::Eval) -> EventValues<E>;
    /// How event `i` triggers now; `None`: not watched.
    fn crossing(&self, i: usize) -> Option<Crossing>;
    /// Check the initial state; false ends the run before the first step (the scene
    /// keeps why).
    fn begin(&mut self, y: &SVector<f64, N>, ev: &Self::Eval, g: &EventValues<E>) -> bool;
    /// Handle event `i` located at `t` (memories, criteria); `end`: the event values at
    /// the end of the step it was found in.
    fn handle(&mut self, i: usize, t: f64, ev: &Self::Eval, end: &EventValues<E>) -> Response;
    /// Track the criteria at a state reached at `at` ([`Point::Step`] or [`Point::Event`]).
    fn track(&mut self, at: Point, ev: &Self::Eval, g: &EventValues<E>);
    /// Record a trajectory sample (called only when recording).
    fn sample(&mut self, at: Point, t: f64, y: &SVector<f64, N>, ev: &Self::Eval);
    /// The scene's state for a trace line (memories, …).
    fn trace_state(&self) -> String {
        String::new()
    }
    /// The output of a finished run.
    fn finish(self, run: &Run<Self::Eval>) -> Self::Output;
}
