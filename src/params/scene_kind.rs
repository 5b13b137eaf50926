//! `[scene]`: which bodies stage 3 integrates (MODEL.md §14) and the free scene's ground.

use crate::error::{Error, Result};
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
    /// The centred scene: finger 1 and its mirror on the fixed object at x = 0.
    pub fn is_centred(self) -> bool {
        self == SceneKind::Centred
    }
    /// The object is a free rigid body on the ground (its stage 3 measures its motion; its
    /// samples are poses, its trajectory's grasp is the centred prediction).
    pub fn is_free(self) -> bool {
        self == SceneKind::Free
    }
    /// Finger 2 moves on its own, not as finger 1's mirror image, and holds the object
    /// fixed at x_off (the offset scene): a grasp trajectory has finger 2's own columns, the
    /// grasp drawn holds the object at x_off, the record has an `offset_scene` part.
    pub fn has_finger2(self) -> bool {
        self == SceneKind::Offset
    }
    /// The object stands at `x_off` along the palm (the offset and free scenes; the centred
    /// scene ignores x_off).
    pub fn uses_offset(self) -> bool {
        self != SceneKind::Centred
    }
    /// The finger may close on nothing (`simulate --no-contact`): the centred scene only (the
    /// others need the object).
    pub fn runs_without_contacts(self) -> bool {
        self == SceneKind::Centred
    }
    /// A passing stage 3 in words: "the object barely moves" (the free scene's measurement)
    /// or "stable" (the grasp scenes).
    pub fn passing_words(self) -> &'static str {
        if self.is_free() {
            "the object barely moves"
        } else {
            "stable"
        }
    }
    /// The scene as `--scene` spells it with the object at `x_off`: `centred`, `offset:X`,
    /// `free:X`.
    pub fn spelled(self, x_off: f64) -> String {
        if self.uses_offset() {
            format!("{self}:{x_off}")
        } else {
            self.as_str().into()
        }
    }
    /// What a recording of this scene draws, said in its metadata (None: the centred grasp,
    /// as every recording before session 36 and so unsaid).
    pub fn drawn_in_recordings(self) -> Option<&'static str> {
        match self {
            SceneKind::Centred => None,
            SceneKind::Offset => Some("the offset scene's grasp (object at x_off)"),
            SceneKind::Free => Some("centred grasp (object at x = 0); the label gives the free scene's verdict"),
        }
    }
}

impl std::str::FromStr for SceneKind {
    type Err = ();
    /// The problem-file spelling: `centred`, `offset` or `free`.
    fn from_str(s: &str) -> std::result::Result<Self, ()> {
        match s {
            "centred" => Ok(SceneKind::Centred),
            "offset" => Ok(SceneKind::Offset),
            "free" => Ok(SceneKind::Free),
            _ => Err(()),
        }
    }
}

/// The scene kinds whose stage 3 uses the `[scene]` field `field` (MODEL.md §14): the
/// object's offset `scene.x_off` the offset and free scenes, the observation time and the
/// ground (`scene.t_obs`, `scene.ground_*`) the free scene only; None for a field outside
/// `[scene]` (used whatever the scene).
pub fn scene_kinds_using(field: &str) -> Option<&'static [SceneKind]> {
    match field {
        "scene.x_off" => Some(&[SceneKind::Offset, SceneKind::Free]),
        "scene.t_obs" | "scene.ground_points" | "scene.ground_k" | "scene.ground_v_s" | "scene.ground_v_d" => {
            Some(&[SceneKind::Free])
        }
        _ => None,
    }
}

/// A scene as `--scene` (and Python's `scene=`) names it: a kind, and the object's offset
/// where given (None keeps the problem's).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneChoice {
    /// The scene kind.
    pub kind: SceneKind,
    /// The object's offset x_off (m); None: the problem's.
    pub x_off: Option<f64>,
}

impl SceneChoice {
    /// The free scene with the object at `x_off` (None: the problem's), where `verify`
    /// measures.
    pub fn free(x_off: Option<f64>) -> Self {
        SceneChoice { kind: SceneKind::Free, x_off }
    }

    /// `centred`, `offset:X` or `free[:X]` (X in metres): an input error naming the text
    /// otherwise (a missing, blank-padded or non-numeric X named as such).
    pub fn parse(text: &str) -> Result<Self> {
        let bad = |why: &str| Error::Input(format!("scene `{text}`: {why}"));
        // the offset after `kind:` exactly as written: missing and blank-padded values are
        // refused by name, not read as a number or an empty pair of backticks
        let num = |kind: &str, x: &str| {
            if x.trim().is_empty() {
                return Err(bad(&format!(
                    "a number is missing after `{kind}:` (the object offset in metres, e.g. `{kind}:0.002`)"
                )));
            }
            if x.trim() != x {
                return Err(bad(&format!(
                    "no blank may surround the number after `{kind}:` (write `{kind}:{}`)",
                    x.trim()
                )));
            }
            x.parse::<f64>().map_err(|_| bad(&format!("`{x}` after `{kind}:` is not a number (metres)")))
        };
        let choice = |kind, x_off| Ok(SceneChoice { kind, x_off });
        match text.trim().split_once(':') {
            None if text.trim() == "centred" => choice(SceneKind::Centred, None),
            None if text.trim() == "free" => choice(SceneKind::Free, None),
            Some(("offset", x)) => choice(SceneKind::Offset, Some(num("offset", x)?)),
            Some(("free", x)) => choice(SceneKind::Free, Some(num("free", x)?)),
            _ => Err(bad("must be centred, offset:X or free[:X] (X in metres)")),
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
    /// This setup in the free scene (the object where it stands).
    pub fn to_free(self) -> Self {
        SceneSetup { kind: SceneKind::Free, ..self }
    }
    /// This setup in the centred scene.
    pub fn to_centred(self) -> Self {
        SceneSetup { kind: SceneKind::Centred, ..self }
    }
    /// The scene as `--scene` spells it: `centred`, `offset:X`, `free:X`.
    pub fn spelled(&self) -> String {
        self.kind.spelled(self.x_off)
    }
    /// The same scene as `other`: the same kind and, where the kind places the object off
    /// centre, the same offset (numerically: `free:-0` is `free:0`).
    pub fn same_scene(&self, other: &SceneSetup) -> bool {
        self.kind == other.kind && (!self.kind.uses_offset() || self.x_off == other.x_off)
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scenes_parse_as_the_cli_spells_them() {
        let c = |kind, x_off| SceneChoice { kind, x_off };
        assert_eq!(SceneChoice::parse("centred").unwrap(), c(SceneKind::Centred, None));
        assert_eq!(SceneChoice::parse("offset:0.002").unwrap(), c(SceneKind::Offset, Some(0.002)));
        assert_eq!(SceneChoice::parse("free").unwrap(), c(SceneKind::Free, None));
        assert_eq!(SceneChoice::parse("free:-0.001").unwrap(), c(SceneKind::Free, Some(-0.001)));
        for bad in ["offset", "centred:1", "offset:x", "sideways", ""] {
            let e = SceneChoice::parse(bad).unwrap_err().to_string();
            assert!(e.contains(&format!("scene `{bad}`")), "{e}");
        }
        for k in [SceneKind::Centred, SceneKind::Offset, SceneKind::Free] {
            assert_eq!(k.as_str().parse::<SceneKind>(), Ok(k));
            // the spelling reads back as the same scene
            let back = SceneChoice::parse(&k.spelled(0.003)).unwrap();
            assert_eq!(back.kind, k);
            assert_eq!(back.x_off, k.uses_offset().then_some(0.003));
        }
    }
}
