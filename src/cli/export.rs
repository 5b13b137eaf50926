//! `gripopt export`: a design (of a problem file, or of a run folder by id) to a MuJoCo
//! model (MJCF) or a build sheet (JSON, CSV). The library's `export` layer writes the
//! files; this resolves the design and the scene (docs/export.md).

use anyhow::{bail, Context, Result};
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

/// `gripopt export SOURCE [--design ...] --format F --out FILE [--scene S] [--object NAME] [--force]`.
pub fn run(a: ExportArgs) -> Result<()> {
    let format = format_of(&a)?;
    let (p, x, source) = if a.source.is_dir() {
        gripopt::app::run_design(&a.source, a.design.as_deref())?
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
    // the robust evaluation's own per-object scene (its cylinder and grip torque) in the
    // scene asked for; the spring sized at [hand] tau, as there
    let e = gripopt::app::exported_design(&p, &x, object, &source)?;
    gripopt::app::check_open_hand(&e, a.scene.as_deref())?;
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
    gripopt::app::write_export(&a.out, &text, a.force).with_context(|| format!("exporting {source}"))?;
    let kind = match format {
        FormatArg::Mjcf => format!("MuJoCo model, scene {}", e.placement.name()),
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
