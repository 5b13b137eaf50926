//! `gripopt export`: the design to export and its scene — a problem file's design, or a run
//! folder's design by id with the problem its generation was evaluated with (from its
//! recording, or from its checkpoint where the run recorded nothing) — on the reference
//! object or one of a robust problem's objects, placed as the problem's `[scene]` says
//! (docs/export.md). The export layer writes the model and the build sheet.

use crate::error::{Error, Result};
use crate::eval::{EvalOptions, Study};
use crate::export::{ExportScene, ExportedDesign};
use crate::params::{Design, Problem};
use crate::record::{problem_of_generation, read_design};
use crate::run::RunFolder;
use std::path::Path;

/// Design `id` (as given: a whole number, the id of pareto.csv and `gripopt show`) of the run
/// folder `dir`, with the problem its generation was evaluated with (problem-G.toml after a
/// forced resume with a changed problem), and where it came from, in words. Refused when
/// that problem file was edited since (the hand would be another), or the run holds no such
/// design.
pub fn run_design(dir: &Path, id: Option<&str>) -> Result<(Problem, Design, String)> {
    let Some(id) = id else {
        return Err(Error::Input(format!(
            "{}: a run folder needs --design ID (a design id of the run: pareto.csv, `gripopt show`)",
            dir.display()
        )));
    };
    let id: u64 = id.trim().parse().map_err(|_| {
        Error::Input(format!(
            "--design `{id}`: with a run folder ({}) the design is its id, a whole number (pareto.csv, `gripopt show`)",
            dir.display()
        ))
    })?;
    // absent; anything else there (a pipe, a folder) is refused by its read, naming it
    if std::fs::symlink_metadata(dir.join("problem.toml")).is_err() {
        if std::fs::symlink_metadata(dir.join("run.json")).is_ok() {
            return Err(missing_problem(dir));
        }
        return Err(Error::Input(format!(
            "{}: not a run folder (no problem.toml); give a folder written by `gripopt optimise`",
            dir.display()
        )));
    }
    // a recorded run: the design's record (any generation's); a run not recorded (`--record
    // none`, run.json's `recording`): the design as its checkpoint holds it
    let (generation, x, from) = match unrecorded_design(dir, id)? {
        Some(found) => found,
        None => {
            let rec = read_design(dir, id)?;
            (rec.record.generation, rec.design(), format!("recorded in {}", rec.file.display()))
        }
    };
    let run = problem_of_generation(dir, generation)?;
    if let Some(why) = run.edited() {
        return Err(Error::Input(format!(
            "{}: {why}; design {id} was evaluated with the file the run recorded: restore it to export the design",
            run.file.display()
        )));
    }
    Ok((run.problem, x, format!("run folder {}, design {id} ({from})", dir.display())))
}

/// A run folder (run.json there) whose problem.toml was deleted: an input error saying so,
/// with the file the run started from and the checksum that tells whether it is still the
/// same (run.json's `problem_path`, `problem_sha256`), when run.json can be read.
fn missing_problem(dir: &Path) -> Error {
    let started = RunFolder::open(dir).and_then(|f| f.info()).ok().map_or(String::new(), |i| {
        format!(
            " (the run started from {}; it is the same file if its SHA-256 is run.json's problem_sha256 {})",
            i.problem_path.display(),
            i.problem_sha256
        )
    });
    Error::Input(format!(
        "{}: problem.toml is missing from the run folder (run.json is there): restore it{started}; a run's designs are exported with the problem they were evaluated with",
        dir.display()
    ))
}

/// Design `id` of a run that recorded nothing (None: the run was recorded), from its
/// checkpoint (population, archive), with its generation; an error when the checkpoint no
/// longer holds it.
fn unrecorded_design(dir: &Path, id: u64) -> Result<Option<(u64, Design, String)>> {
    let folder = RunFolder::open(dir)?;
    if folder.info()?.recording.enabled {
        return Ok(None);
    }
    let Some(t) = folder.checkpoint_tables()? else {
        return Err(Error::Input(format!(
            "{}: design {id}: the run was not recorded (run.json: started with `--record none`) and has no checkpoint yet; nothing holds the design",
            dir.display()
        )));
    };
    let Some(row) = t.population.iter().chain(&t.archive).find(|r| r.id == id) else {
        return Err(Error::Input(format!(
            "{}: design {id} is not in the run's checkpoint (its population and archive of generation {}), and the run was not recorded (run.json: started with `--record none`), so its other designs are not kept",
            dir.display(),
            t.generation
        )));
    };
    let from = format!("from its checkpoint, generation {}; the run was not recorded", t.generation);
    Ok(Some((row.generation, Design::from_array(&row.parameters()), from)))
}

/// Design `x` of problem `p` to export, placed as `p`'s `[scene]` says: on the reference
/// object, or (`object`: its index) on one of a robust problem's objects — the robust
/// evaluation's own per-object scene (its cylinder and grip torque; the spring sized at
/// `[hand] tau`, as there). `source` says where the design came from.
pub fn exported_design(p: &Problem, x: &Design, object: Option<usize>, source: &str) -> Result<ExportedDesign> {
    let placement = ExportScene::of(&p.scene.setup);
    // (the free scene's g_eq = 0 is the library's rule: Problem::load and in_scene name the file and field)
    match object.filter(|_| p.robust.is_some()) {
        Some(o) => {
            let study = Study::of(p, &EvalOptions::full(p));
            let source = format!("{source}, robust object {}", study.object_name(o).unwrap_or_default());
            ExportedDesign::on_object(x, &study, o, placement, &source)
        }
        None => ExportedDesign::new(x, &p.scene, placement, source),
    }
}

/// `x` to 4 significant digits, compactly (`0.001823`, `2.5e-7`).
fn short(x: f64) -> String {
    crate::params::fmt_num(format!("{x:.3e}").parse().unwrap_or(x))
}

/// An exported scene whose open hand already penetrates the object at t = 0 (an offset or
/// free object placed into a finger): refused, as every simulated scene refuses to start
/// there ("open finger penetrates the object at t = 0"), naming `--scene` (`scene`: as
/// given; None: the problem's `[scene]`), the offset, the finger and the depth, and the
/// offset up to which the open hand clears the object (docs/export.md).
pub fn check_open_hand(e: &ExportedDesign, scene: Option<&str>) -> Result<()> {
    let Some(pen) = e.open_penetration() else { return Ok(()) };
    let x_off = e.placement.x_off;
    let asked = match scene {
        Some(arg) => format!("--scene {arg}"),
        None => format!("the problem's [scene] ({}, x_off = {} m)", e.placement.name(), short(x_off)),
    };
    let fix = match e.clear_offset() {
        None => "the open hand touches the object even centred (x_off = 0)".to_string(),
        Some(clear) => format!(
            "the open hand clears the object up to |x_off| = {} mm on this side: give a smaller offset",
            short(clear.abs() * 1e3)
        ),
    };
    Err(Error::Input(format!(
        "{asked}: with the object at x_off = {} m the open finger {}'s {} phalanx penetrates it by {} mm at t = 0; the model would start with the object inside the finger, where a simulation refuses to start (\"open finger penetrates the object at t = 0\"); {fix} (docs/export.md)",
        short(x_off),
        pen.finger,
        pen.phalanx,
        short(pen.depth * 1e3),
    )))
}
