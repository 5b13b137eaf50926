//! `[scene]`: which bodies stage 3 integrates (MODEL.md §14) and the free scene's ground.

use serde::{Deserialize, Serialize};
use std::fmt;

/// The scene of stage 3, `simulate` and `replay` (MODEL.md §14).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum SceneKind {
    /// One finger and its mirror on the fixed object centred at (0, R) (§8; the default).
    #[default]
    Centred,
    /// Both fingers on the fixed object at (x_off, R).
    Offset,
    /// Both fingers and the object as a free rigid body on the ground, against the palm.
    Free,
}

impl SceneKind {
    /// The problem-file spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            SceneKind::Centred => "centred",
            SceneKind::Offset => "offset",
            SceneKind::Free => "free",
        }
    }
    /// Parse the problem-file spelling.
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "centred" => Some(SceneKind::Centred),
            "offset" => Some(SceneKind::Offset),
            "free" => Some(SceneKind::Free),
            _ => None,
        }
    }
}

impl fmt::Display for SceneKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// `[scene]`: the scene kind, the object's offset and the free scene's ground (§14).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SceneSetup {
    /// Which scene.
    pub kind: SceneKind,
    /// Object offset x_off along the palm (m; the offset and free scenes).
    pub x_off: f64,
    /// Observation time t_obs of the free scene (s): it ends at min(t_max, t_obs).
    pub t_obs: f64,
    /// Number n_g of ground points on the base rim.
    pub ground_points: usize,
    /// Ground Hertz stiffness K_g (N/m^1.5).
    pub ground_k: f64,
    /// Ground friction static transition velocity v_sg (m/s).
    pub ground_v_s: f64,
    /// Ground friction dynamic transition velocity v_dg (m/s).
    pub ground_v_d: f64,
}

impl SceneSetup {
    /// MODEL.md §14's defaults with the centred scene (for code that builds scenes by hand).
    pub fn centred(k_contact: f64) -> Self {
        SceneSetup {
            kind: SceneKind::Centred,
            x_off: 0.0,
            t_obs: 0.1,
            ground_points: 16,
            ground_k: k_contact,
            ground_v_s: 1e-4,
            ground_v_d: 2e-4,
        }
    }
}
