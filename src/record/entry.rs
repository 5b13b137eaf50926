//! The recorder's input: one evaluated design ([`DesignEntry`]: its identity, its
//! evaluation record and kept trajectory), and the [`Recordable`] trait through which higher
//! layers hand their own types to the recorder (the run layer implements it for its
//! individuals), so this layer never names them.

use super::kept::KeptTrajectory;
use super::scenario_kept::ScenarioScene;
use crate::eval::Record;

/// One design as the recorder writes it.
#[derive(Debug, Clone, Copy)]
pub struct DesignEntry<'a> {
    /// Unique id within a run (its time window in a shard is [id s, id s + 1 s)).
    pub id: u64,
    /// Generation in which it was created (1 = initial population).
    pub generation: u64,
    /// Parameters in optimiser units (l21, b, t22, r, p, ψ in degrees), as evaluated.
    pub parameters: [f64; 6],
    /// The evaluation's record.
    pub record: &'a Record,
    /// Wall time per stage (s): [unused, stages 0–1, stage 2, stage 3].
    pub stage_seconds: [f64; 4],
    /// The stage-3 trajectory, if kept (the samples its recording uses).
    pub trajectory: Option<&'a KeptTrajectory>,
    /// A robust design's deciding scenario, if kept: what its window draws instead of the
    /// reference object's pictures.
    pub scenario: Option<&'a ScenarioScene>,
}

/// Something the recorder can write as one design.
pub trait Recordable: Sync {
    /// The design as a [`DesignEntry`] borrowing from `self`.
    fn entry(&self) -> DesignEntry<'_>;
}

impl Recordable for DesignEntry<'_> {
    fn entry(&self) -> DesignEntry<'_> {
        *self
    }
}
