//! The recorder's input: one evaluated design, flattened ([`DesignEntry`]), and the
//! [`Recordable`] trait through which higher layers hand their own types to the recorder
//! (the run layer implements it for its individuals), so this layer never names them.

use crate::sim::Trajectory;

/// One design as the recorder writes it: identity, parameters, the flattened evaluation
/// and, when kept, its stage-3 trajectory.
#[derive(Debug, Clone, Copy)]
pub struct DesignEntry<'a> {
    /// Unique id within a run (its time window in a shard is [id s, id s + 1 s)).
    pub id: u64,
    /// Generation in which it was created (1 = initial population).
    pub generation: u64,
    /// Parameters in optimiser units (l21, b, t22, r, p, ψ in degrees), as evaluated.
    pub parameters: [f64; 6],
    /// Derived lengths l11, l12, l22 (m), when stage 1 built the finger.
    pub lengths: Option<[f64; 3]>,
    /// l_hand (m).
    pub l_hand: f64,
    /// Objectives in natural sense: max_offset (m), α, F̃ (N), t_stab (s).
    pub objectives: [Option<f64>; 4],
    /// Failing stage, if discarded.
    pub failed_stage: Option<u8>,
    /// Why it was discarded.
    pub reason: Option<&'a str>,
    /// Violation at the failing stage.
    pub violation: Option<f64>,
    /// Stage-3 work: accepted steps and RHS evaluations.
    pub sim_work: Option<[u64; 2]>,
    /// Wall time per stage (s): [unused, stages 0–1, stage 2, stage 3].
    pub stage_seconds: [f64; 4],
    /// The free scene's §14.4 keys (a JSON object), when the run's scene is free.
    pub free: Option<&'a serde_json::Value>,
    /// The stage-3 trajectory, if kept.
    pub trajectory: Option<&'a Trajectory>,
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
