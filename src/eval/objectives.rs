//! The four objectives as every output reports them: the run's CSV rows, `/designs`, a
//! design's [`Record`](super::Record) and the robust record's aggregated and per-object
//! objectives.

use serde::{Deserialize, Serialize};

/// The four objectives in their natural sense (MODEL.md §10): a design's, or a robust
/// design's aggregated or per object; `None` where not computed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Objectives {
    /// Objective 1: the largest object offset still form closed (m, maximise).
    pub max_offset: Option<f64>,
    /// Objective 2: force isotropy α (minimise).
    pub alpha: Option<f64>,
    /// Objective 3: mean contact force F̃ (N, maximise).
    pub mean_force: Option<f64>,
    /// Objective 4: time to stability (s, minimise).
    pub t_stab: Option<f64>,
}

impl Objectives {
    /// The objectives in the order max_offset, α, F̃, t_stab.
    pub fn from_array([max_offset, alpha, mean_force, t_stab]: [Option<f64>; 4]) -> Self {
        Objectives { max_offset, alpha, mean_force, t_stab }
    }
    /// In the order max_offset, α, F̃, t_stab.
    pub fn to_array(&self) -> [Option<f64>; 4] {
        [self.max_offset, self.alpha, self.mean_force, self.t_stab]
    }
    /// As the outputs report them: max_offset only when form closed (MODEL.md §6.7: a
    /// design not form closed at 0 carries max_offset = −Δ_off inside the optimiser, a
    /// placeholder never reported).
    pub fn reported(self) -> Self {
        Objectives { max_offset: self.max_offset.filter(|m| *m >= 0.0), ..self }
    }
}
