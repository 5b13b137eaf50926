//! Where a simulation's samples and events go: the caller's [`Sink`], passed to the
//! driver (ripgrep's `Sink`, rapier's `EventHandler`). Every scene reports through it; a
//! sink that takes no samples (`()`) costs nothing, and sampling never changes a result.

use super::events::EventKind;
use super::memory::Memory;
use super::result::{PoseSample, Sample, Trajectory};

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

/// A located event, as the driver reports it before the scene handles it.
#[derive(Debug, Clone, Copy)]
pub struct EventNote<'a> {
    /// What crossed.
    pub kind: EventKind,
    /// When (s).
    pub t: f64,
    /// The step it was found in (s).
    pub step: [f64; 2],
    /// The scene's contact memories before handling it.
    pub memories: &'a [Memory],
}

/// What a simulation reports as it runs. Every method does nothing by default.
pub trait Sink {
    /// Whether samples are wanted (false: the driver builds none).
    fn wants_samples(&self) -> bool {
        false
    }
    /// A sample of a grasp scene: finger 1 (in the centred scene finger 2 is its mirror
    /// image; in the offset scene finger 2 is not and comes with it, and the hand force is
    /// both fingers').
    fn finger(&mut self, _at: Point, _s: &Sample) {}
    /// A sample of the free scene: the object's pose and both fingers' angles.
    fn pose(&mut self, _at: Point, _s: &PoseSample) {}
    /// A located event (e.g. for a trace).
    fn event(&mut self, _e: &EventNote<'_>) {}
}

/// No samples, no events.
impl Sink for () {}

/// Keeps the grasp samples: steps and events in `samples`, the grid in `grid`.
impl Sink for Trajectory {
    fn wants_samples(&self) -> bool {
        true
    }
    fn finger(&mut self, at: Point, s: &Sample) {
        if at == Point::Grid {
            self.grid.push(*s);
        } else {
            self.samples.push(*s);
        }
    }
}

/// Keeps the free scene's poses at steps and events (the grid is not kept).
impl Sink for Vec<PoseSample> {
    fn wants_samples(&self) -> bool {
        true
    }
    fn pose(&mut self, at: Point, s: &PoseSample) {
        if at != Point::Grid {
            self.push(*s);
        }
    }
}

/// Forwards to both sinks (e.g. a trajectory and a trace).
impl<A: Sink, B: Sink> Sink for (A, B) {
    fn wants_samples(&self) -> bool {
        self.0.wants_samples() || self.1.wants_samples()
    }
    fn finger(&mut self, at: Point, s: &Sample) {
        self.0.finger(at, s);
        self.1.finger(at, s);
    }
    fn pose(&mut self, at: Point, s: &PoseSample) {
        self.0.pose(at, s);
        self.1.pose(at, s);
    }
    fn event(&mut self, e: &EventNote<'_>) {
        self.0.event(e);
        self.1.event(e);
    }
}

impl<K: Sink + ?Sized> Sink for &mut K {
    fn wants_samples(&self) -> bool {
        (**self).wants_samples()
    }
    fn finger(&mut self, at: Point, s: &Sample) {
        (**self).finger(at, s)
    }
    fn pose(&mut self, at: Point, s: &PoseSample) {
        (**self).pose(at, s)
    }
    fn event(&mut self, e: &EventNote<'_>) {
        (**self).event(e)
    }
}
