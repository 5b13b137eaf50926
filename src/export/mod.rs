//! Hand-over of a chosen design to other tools: a MuJoCo model (MJCF) of the gripper and
//! the object, and a build sheet (JSON or CSV) for CAD and for building the prototype
//! (`gripopt export`, docs/export.md).
//!
//! Beside `sweep` above `eval`: it imports `params`, `model`, `sim` (the open hand's start
//! check) and `eval` only (never the run
//! folder, the recording or the optimiser; the CLI resolves a run's design).

mod clearance;
mod mjcf;
mod sheet;
mod xml;

pub use clearance::{OpenPenetration, START_PENETRATION_TOL};
pub use mjcf::{mjcf, MujocoSettings, MUJOCO};
pub use sheet::{build_sheet, BuildSheet, SheetRow};
pub use xml::XmlWriter;

use crate::error::{Error, Result};
use crate::eval::Study;
use crate::model::{spring_preload, Finger};
use crate::params::{Design, SceneKind, SceneParams, SceneSetup};

/// What the object does in the exported scene (MODEL.md §8, §14).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObjectMode {
    /// Welded to the world at (x_off, R): the centred scene (x_off = 0) or the offset scene.
    Fixed,
    /// A free rigid body standing on the ground z = −h_c against the palm (§14.1).
    Free,
}

/// The exported scene: the object's mode and its offset x_off along the palm (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExportScene {
    /// Fixed or free object.
    pub object: ObjectMode,
    /// Object offset x_off along the palm (m).
    pub x_off: f64,
}

impl ExportScene {
    /// The centred scene: the object fixed at (0, R).
    pub fn centred() -> Self {
        ExportScene { object: ObjectMode::Fixed, x_off: 0.0 }
    }
    /// The free scene with the object at offset `x_off`.
    pub fn free(x_off: f64) -> Self {
        ExportScene { object: ObjectMode::Free, x_off }
    }
    /// Where a problem's `[scene]` puts the object: the centred scene's at x = 0, the offset
    /// scene's fixed at its x_off, the free scene's free on the ground at its x_off.
    pub fn of(setup: &SceneSetup) -> Self {
        match setup.kind {
            SceneKind::Centred => ExportScene::centred(),
            SceneKind::Offset => ExportScene { object: ObjectMode::Fixed, x_off: setup.x_off },
            SceneKind::Free => ExportScene::free(setup.x_off),
        }
    }
    /// `centred`, `offset:X` or `free:X`, as `--scene` spells scenes (X as [`num`] writes it:
    /// `free:1e-320`, not 320 digits).
    pub fn name(&self) -> String {
        match (self.object, self.x_off) {
            (ObjectMode::Fixed, 0.0) => "centred".into(),
            (ObjectMode::Fixed, x) => format!("offset:{}", num(x)),
            (ObjectMode::Free, x) => format!("free:{}", num(x)),
        }
    }
}

/// A design ready to export: the finger (derived lengths, open pose, masses; MODEL.md
/// §3–§4), the spring preload (§6.2) and the scene it is exported in.
#[derive(Debug, Clone)]
pub struct ExportedDesign {
    /// The design vector.
    pub design: Design,
    /// The scene constants (problem file).
    pub scene: SceneParams,
    /// Fixed or free object, and its offset.
    pub placement: ExportScene,
    /// Finger 1 in its local frame (= the world frame; finger 2 is its mirror).
    pub finger: Finger,
    /// τ_s^min (N·m, before clipping).
    pub tau_s_min: f64,
    /// Spring preload τ_s0 = max(0, τ_s^min) (N·m).
    pub tau_s0: f64,
    /// Where the design comes from (problem file or run folder and design id), for the
    /// files' headers.
    pub source: String,
    /// Stages 0–2's verdict: `None` when the design passes them, else the discard's text.
    pub statics_discard: Option<String>,
}

impl ExportedDesign {
    /// Build the finger of `x` in scene `s`; an error (bad input) when the design has no
    /// open pose, cannot be assembled, or its spring preload is undefined, or when the
    /// placement is not finite.
    pub fn new(x: &Design, s: &SceneParams, placement: ExportScene, source: &str) -> Result<Self> {
        let ev = crate::eval::evaluate_statics(x, s);
        let statics_discard = ev.discard.map(|d| format!("discarded at stage {}: {}", d.stage, d.reason));
        Self::build(x, s, s, placement, source, statics_discard)
    }

    /// Design `x` of a robust problem on its object `o` (`--object`, docs/export.md): the
    /// object's nominal scene as its study builds it ([`Study::objects`]: its cylinder and
    /// its grip torque τ), the spring sized once at the problem's `[hand] tau` as there (a
    /// spring is hardware), and the object's own stage 0–2 verdict from [`Study::start`].
    pub fn on_object(x: &Design, study: &Study, o: usize, placement: ExportScene, source: &str) -> Result<Self> {
        let Some(object) = study.objects.get(o) else {
            return Err(Error::Input(format!("{source}: the problem has no robust object {o}")));
        };
        let name = object.name.as_deref().unwrap_or("the problem's [object]");
        let start = study.start(x);
        let statics_discard = match (&start.discard, &start.objects[o]) {
            (Some(d), _) if d.stage() < 2 => Some(format!("discarded at stage {}: {}", d.stage(), d.reason(study))),
            (_, Some(Err(d))) => Some(format!("discarded at stage 2 on object {name}: {}", d.reason)),
            (Some(d), _) => Some(format!(
                "passes stages 0-2 on object {name}; the robust design is discarded at stage {} ({})",
                d.stage(),
                d.reason(study)
            )),
            (None, _) => None,
        };
        Self::build(x, &object.scene, &study.base, placement, source, statics_discard)
    }

    /// The finger of `x` in scene `s`, its spring sized in `spring_scene` (its `[hand] tau`).
    fn build(
        x: &Design,
        s: &SceneParams,
        spring_scene: &SceneParams,
        placement: ExportScene,
        source: &str,
        statics_discard: Option<String>,
    ) -> Result<Self> {
        if !placement.x_off.is_finite() {
            return Err(Error::Input(format!("export: object offset x_off = {} is not finite", placement.x_off)));
        }
        let finger = Finger::new(x, s).map_err(|g| {
            // which length, and its value (a subnormal input underflows to a zero length)
            let why = match (g, x.invalid_length()) {
                (crate::model::GeomError::InvalidLength, Some(why)) => why,
                _ => g.reason().to_string(),
            };
            Error::Input(format!("{source}: the design cannot be exported: {why} (MODEL.md §3)"))
        })?;
        let (tau_s_min, tau_s0) = spring_preload(&finger, spring_scene).ok_or_else(|| {
            Error::Input(format!(
                "{source}: the design cannot be exported: spring preload undefined (singular open pose)"
            ))
        })?;
        Ok(ExportedDesign {
            design: *x,
            scene: s.clone(),
            placement,
            finger,
            tau_s_min,
            tau_s0,
            source: source.to_string(),
            statics_discard,
        })
    }

    /// The MuJoCo model (MJCF text) with [`MUJOCO`]'s settings.
    pub fn mjcf(&self) -> String {
        mjcf(self, &MUJOCO)
    }

    /// The build sheet.
    pub fn build_sheet(&self) -> BuildSheet {
        build_sheet(self)
    }
}

/// A number as MJCF and CSV text: the shortest decimal that reads back to the same f64
/// (exponent notation outside [1e-3, 1e7)).
pub fn num(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if (1e-3..1e7).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Write an export to `path`: refused when the file exists and `force` is false, or when
/// `path` is a folder; written atomically (a temporary file renamed into place). Errors name
/// the file.
pub fn write_file(path: &std::path::Path, text: &str, force: bool) -> Result<()> {
    crate::fsutil::check_new_file("--out", path, force)?;
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty());
    if let Some(d) = dir.filter(|d| !d.is_dir()) {
        return Err(Error::Input(format!("--out {}: the folder {} does not exist", path.display(), d.display())));
    }
    crate::fsutil::write_atomic(path, text.as_bytes()).map_err(|e| match e {
        // name the file asked for, not the temporary file beside it
        Error::Io { source, .. } => Error::io(path, "cannot write the export", source),
        other => other,
    })
}

#[cfg(test)]
mod tests {
    use super::num;

    #[test]
    fn numbers_read_back_exactly() {
        for x in [0.0, 1e-5, 0.0494, -129.76, 5.3e8, 1.0 / 3.0, std::f64::consts::PI, -1e-300, 2.5e-3] {
            let s = num(x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{x} -> {s}");
        }
        assert_eq!(num(-0.0), "0");
        assert_eq!(num(1e-5), "1e-5");
    }
}
