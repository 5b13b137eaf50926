//! `gripopt export`: a design (of a problem file, or of a run folder by id) to a MuJoCo
//! model (MJCF) or a build sheet (JSON, CSV). The library's `export` layer writes the
//! files; this resolves the design and the scene (docs/export.md).

use anyhow::{bail, Context, Result};
use gripopt::eval::{EvalOptions, Study};
use gripopt::export::{write_file, ExportScene, ExportedDesign, ObjectMode};
use gripopt::params::{Design, Problem, SceneKind};
use std::path::{Path, PathBuf};

/// Arguments of `gripopt export`.
#[derive(clap::Args)]
pub struct ExportArgs {
    /// Problem file (TOML), or a run folder (then --design is a design id of the run).
    source: PathBuf,
    /// With a problem file: l21=..,b=..,t22=..,r=..,p=..,psi_deg=.. (default: the nominal);
    /// with a run folder: the design id (pareto.csv, `gripopt show`).
    #[arg(long)]
    design: Option<String>,
    /// mjcf (MuJoCo model), json or csv (build sheet); default: from the --out extension
    /// (.xml or .mjcf, .json, .csv).
    #[arg(long, value_enum)]
    format: Option<FormatArg>,
    /// The file to write (`-` for standard output).
    #[arg(long)]
    out: PathBuf,
    /// centred (the object fixed at (0, R)), offset:X (fixed at x = X metres) or free[:X]
    /// (a free body on the ground at x = X; `free` alone: the problem's or run's x_off, as
    /// replay); default: the problem's [scene] (an offset scene's object fixed at its x_off,
    /// a free one at its x_off).
    #[arg(long)]
    scene: Option<String>,
    /// Robust problem or run only: export the design on this object of [[robust.objects]]
    /// (its cylinder, mass and grip torque) instead of the reference [object].
    #[arg(long, value_name = "NAME")]
    object: Option<String>,
    /// Overwrite --out if it exists.
    #[arg(long)]
    force: bool,
}

/// Output format.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FormatArg {
    /// MuJoCo MJCF model.
    Mjcf,
    /// Build sheet as JSON.
    Json,
    /// Build sheet as CSV.
    Csv,
}

fn format_of(a: &ExportArgs) -> Result<FormatArg> {
    match (a.format, format_named_by(&a.out)) {
        (Some(f), _) | (None, Some(f)) => Ok(f),
        (None, None) => {
            bail!("--out {}: give --format mjcf|json|csv (the extension does not say which)", a.out.display())
        }
    }
}

/// Refuse an `--out` whose extension names another format than `format` (`hand.json` with
/// `--format mjcf`): a file a tool would open as the wrong kind. Checked after the refusals
/// that protect a run folder and the inputs, which say more.
fn check_extension(a: &ExportArgs, format: FormatArg) -> Result<()> {
    let Some(named) = format_named_by(&a.out) else { return Ok(()) };
    if named != format {
        bail!(
            "--out {}: the extension says {} but --format is {}; name the file after its format",
            a.out.display(),
            format_name(named),
            format_name(format)
        );
    }
    Ok(())
}

/// The format a file name's extension names (`.xml`/`.mjcf`, `.json`, `.csv`), if any.
fn format_named_by(out: &Path) -> Option<FormatArg> {
    let ext = out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("xml") | Some("mjcf") => Some(FormatArg::Mjcf),
        Some("json") => Some(FormatArg::Json),
        Some("csv") => Some(FormatArg::Csv),
        _ => None,
    }
}

/// The format's name as `--format` spells it.
fn format_name(f: FormatArg) -> &'static str {
    match f {
        FormatArg::Mjcf => "mjcf",
        FormatArg::Json => "json",
        FormatArg::Csv => "csv",
    }
}

/// The design and problem of a run folder's design `id`, with a source text.
fn run_design(dir: &Path, id: &Option<String>) -> Result<(Problem, Design, String)> {
    let Some(id) = id else {
        bail!("{}: a run folder needs --design ID (a design id of the run: pareto.csv, `gripopt show`)", dir.display());
    };
    let id: u64 = id.trim().parse().map_err(|_| {
        gripopt::Error::Input(format!(
            "--design `{id}`: with a run folder ({}) the design is its id, a whole number (pareto.csv, `gripopt show`)",
            dir.display()
        ))
    })?;
    // absent; anything else there (a pipe, a folder) is refused by its read, naming it
    if std::fs::symlink_metadata(dir.join("problem.toml")).is_err() {
        if std::fs::symlink_metadata(dir.join("run.json")).is_ok() {
            return Err(missing_problem(dir).into());
        }
        return Err(gripopt::Error::Input(format!(
            "{}: not a run folder (no problem.toml); give a folder written by `gripopt optimise`",
            dir.display()
        ))
        .into());
    }
    // a recorded run: the design's record (any generation's); a run not recorded (`--record
    // none`, run.json's `recording`): the design as its checkpoint holds it
    let (generation, x, from) = match unrecorded_design(dir, id)? {
        Some(found) => found,
        None => {
            let rec = gripopt::record::read_design(dir, id)?;
            (rec.record.generation, rec.design(), format!("recorded in {}", rec.file.display()))
        }
    };
    // the problem the design's generation was evaluated with (problem-G.toml after a forced
    // resume with a changed problem), refused when edited since: the hand would be another
    let run = gripopt::record::problem_of_generation(dir, generation)?;
    if let Some(why) = run.edited() {
        return Err(gripopt::Error::Input(format!(
            "{}: {why}; design {id} was evaluated with the file the run recorded: restore it to export the design",
            run.file.display()
        ))
        .into());
    }
    Ok((run.problem, x, format!("run folder {}, design {id} ({from})", dir.display())))
}

/// A run folder (run.json there) whose problem.toml was deleted: an input error saying so,
/// with the file the run started from and the checksum that tells whether it is still the
/// same (run.json's `problem_path`, `problem_sha256`), when run.json can be read.
fn missing_problem(dir: &Path) -> gripopt::Error {
    let started = gripopt::RunFolder::open(dir).and_then(|f| f.info()).ok().map_or(String::new(), |i| {
        format!(
            " (the run started from {}; it is the same file if its SHA-256 is run.json's problem_sha256 {})",
            i.problem_path.display(),
            i.problem_sha256
        )
    });
    gripopt::Error::Input(format!(
        "{}: problem.toml is missing from the run folder (run.json is there): restore it{started}; a run's designs are exported with the problem they were evaluated with",
        dir.display()
    ))
}

/// Design `id` of a run that recorded nothing (None: the run was recorded), from its
/// checkpoint (population, archive), with its generation; an error when the checkpoint no
/// longer holds it.
fn unrecorded_design(dir: &Path, id: u64) -> Result<Option<(u64, Design, String)>> {
    let folder = gripopt::RunFolder::open(dir)?;
    if folder.info()?.recording.enabled {
        return Ok(None);
    }
    let Some(t) = folder.checkpoint_tables()? else {
        return Err(gripopt::Error::Input(format!(
            "{}: design {id}: the run was not recorded (run.json: started with `--record none`) and has no checkpoint yet; nothing holds the design",
            dir.display()
        ))
        .into());
    };
    let Some(row) = t.population.iter().chain(&t.archive).find(|r| r.id == id) else {
        return Err(gripopt::Error::Input(format!(
            "{}: design {id} is not in the run's checkpoint (its population and archive of generation {}), and the run was not recorded (run.json: started with `--record none`), so its other designs are not kept",
            dir.display(),
            t.generation
        ))
        .into());
    };
    let from = format!("from its checkpoint, generation {}; the run was not recorded", t.generation);
    Ok(Some((row.generation, Design::from_array(&row.parameters()), from)))
}

/// `--out` inside the source run folder `run` (its run.json, checkpoint, problem files, a
/// shard of recording/: even with --force, which replaces an earlier export, never a run's
/// file), or in a folder that is a run folder (sweep's rule, [`gripopt::run_folder_file`])
/// or inside one: an input error naming the path and the folder.
fn refuse_out_in_run_folder(out: &Path, run: Option<&Path>) -> Result<()> {
    let parent = out.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    // the folder the file would be written in, links resolved (a missing folder is refused
    // later, naming it)
    let (Ok(folder), Some(name)) = (parent.canonicalize(), out.file_name()) else {
        return Ok(());
    };
    let target = folder.join(name);
    let refuse = |why: String| -> Result<()> {
        Err(gripopt::Error::Input(format!(
            "--out {}: {why}; an export never writes into a run folder (--force replaces an earlier export, never a run's file): give a path outside it",
            out.display()
        ))
        .into())
    };
    if let Some(run) = run.and_then(|r| r.canonicalize().ok()) {
        if target.starts_with(&run) {
            return refuse(format!("inside the run folder {} the design is exported from", run.display()));
        }
    }
    // the folder itself a run folder (sweep's rule), or inside one (its recording/)
    if let Some((run, f)) = gripopt::run_folder_around(out) {
        return refuse(format!("in a gripopt run folder ({} holds {f})", run.display()));
    }
    Ok(())
}

/// `x` to 4 significant digits, compactly (`0.001823`, `2.5e-7`).
fn short(x: f64) -> String {
    gripopt::params::fmt_num(format!("{x:.3e}").parse().unwrap_or(x))
}

/// An exported scene whose open hand already penetrates the object at t = 0 (an offset or
/// free object placed into a finger): refused, as every simulated scene refuses to start
/// there ("open finger penetrates the object at t = 0"), naming `--scene` (or the problem's
/// `[scene]`), the offset, the finger and the depth, and the offset up to which the open hand
/// clears the object (docs/export.md).
fn refuse_open_penetration(e: &ExportedDesign, scene: Option<&str>) -> Result<()> {
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
    bail!(
        "{asked}: with the object at x_off = {} m the open finger {}'s {} phalanx penetrates it by {} mm at t = 0; the model would start with the object inside the finger, where a simulation refuses to start (\"open finger penetrates the object at t = 0\"); {fix} (docs/export.md)",
        short(x_off),
        pen.finger,
        pen.phalanx,
        short(pen.depth * 1e3),
    )
}

/// `gripopt export SOURCE [--design ...] --format F --out FILE [--scene S] [--object NAME] [--force]`.
pub fn run(a: ExportArgs) -> Result<()> {
    let format = format_of(&a)?;
    let (p, x, source) = if a.source.is_dir() {
        run_design(&a.source, &a.design)?
    } else {
        let p = super::load_problem(&a.source)?;
        let x = super::design_of(&p, &a.design)?;
        let what = match &a.design {
            None => "the nominal design".to_string(),
            Some(d) => format!("design {d}"),
        };
        let src = format!("problem file {}, {what}", a.source.display());
        (p, x, src)
    };
    let without = "the export holds without --object";
    let object = a.object.as_deref().map(|name| super::robust::object_index(&p, name, &source, without)).transpose()?;
    if p.robust.is_some() && object.is_none() {
        // as sweep says it: the exported hand grips the reference object only
        eprintln!(
            "note: {source}: the problem has [robust]: the export holds the reference [object] and [scene] only, not the robust objects or scenarios; --object NAME exports the design on one of its objects ({}) (docs/robust.md, docs/export.md)",
            super::robust::object_names(&p)
        );
    }
    // `--scene` as simulate and replay read it (`free` alone keeps the problem's x_off)
    let p = match &a.scene {
        Some(arg) => super::scenes::apply_scene(&p, &a.source, arg)?,
        None => p,
    };
    let setup = p.scene.setup;
    let placement = match setup.kind {
        SceneKind::Centred => ExportScene::centred(),
        SceneKind::Offset => ExportScene { object: ObjectMode::Fixed, x_off: setup.x_off },
        SceneKind::Free => ExportScene::free(setup.x_off),
    };
    // (the free scene's g_eq = 0 is the library's rule: Problem::load and in_scene name the file and field)
    let study = p.robust.is_some().then(|| Study::of(&p, &EvalOptions::full(&p)));
    let e = match (object, study) {
        // the robust evaluation's own per-object scene (its cylinder and grip torque) in the
        // scene asked for; the spring sized at [hand] tau, as there
        (Some(o), Some(study)) => {
            let source = format!("{source}, robust object {}", study.object_name(o).unwrap_or_default());
            ExportedDesign::on_object(&x, &study, o, placement, &source)?
        }
        _ => ExportedDesign::new(&x, &p.scene, placement, &source)?,
    };
    refuse_open_penetration(&e, a.scene.as_deref())?;
    let source = &e.source;
    let text = match format {
        FormatArg::Mjcf => e.mjcf(),
        FormatArg::Json => e.build_sheet().to_json(),
        FormatArg::Csv => e.build_sheet().to_csv(),
    };
    if a.out.as_os_str() == "-" {
        out!("{text}");
        return Ok(());
    }
    refuse_out_in_run_folder(&a.out, a.source.is_dir().then_some(a.source.as_path()))?;
    // never over (or into) the problem file or run folder exported from, nor over a
    // device, pipe or socket, --force included
    let objects = if a.source.is_dir() { vec![] } else { p.object_files(&a.source) };
    let inputs: Vec<&Path> = std::iter::once(a.source.as_path()).chain(objects.iter().map(|f| f.as_path())).collect();
    gripopt::check_output_file("--out", &a.out, a.force, &inputs)?;
    check_extension(&a, format)?;
    write_file(&a.out, &text, a.force).with_context(|| format!("exporting {source}"))?;
    let kind = match format {
        FormatArg::Mjcf => format!("MuJoCo model, scene {}", placement.name()),
        FormatArg::Json => "build sheet (JSON)".into(),
        FormatArg::Csv => "build sheet (CSV)".into(),
    };
    eprintln!("wrote {} ({kind}) from {source}", a.out.display());
    if let Some(d) = &e.statics_discard {
        eprintln!("note: gripopt {d}");
    }
    if format == FormatArg::Mjcf {
        eprintln!(
            "view it: python -m mujoco.viewer --mjcf={}  (load the keyframe `grasp` to close the hand; docs/export.md)",
            a.out.display()
        );
    }
    Ok(())
}
