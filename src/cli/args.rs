//! Flags and checks shared by several commands: the recording and method choices, `--rtol`,
//! `--threads`, output files, and the run hooks the CLI gives an optimise or resume run.

use anyhow::Result;

/// Recording choice.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum RecordArg {
    /// Every design and the trajectory of every grasp simulated.
    All,
    /// Every design; trajectories of feasible designs only.
    Feasible,
    /// Design records only.
    Designs,
    /// Nothing.
    None,
}

/// Integration method choice, spelled as in a problem file's `solver.method`.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum MethodArg {
    /// Radau IIA order 5 (stiff).
    Radau5,
    /// TR-BDF2 (stiff, order 2).
    #[value(name = "trbdf2", alias = "tr-bdf2")]
    TrBdf2,
    /// Dormand–Prince 5(4) (explicit; comparison only).
    Dopri5,
    /// Dormand–Prince 5(4), switching to RADAU5 where stiff (automatic; a problem's default).
    Auto,
}

impl MethodArg {
    /// The library's method of this choice.
    pub fn to_method(self) -> gripopt::app::Method {
        match self {
            MethodArg::Radau5 => gripopt::app::Method::Radau5,
            MethodArg::TrBdf2 => gripopt::app::Method::TrBdf2,
            MethodArg::Dopri5 => gripopt::app::Method::Dopri5,
            MethodArg::Auto => gripopt::app::Method::Auto,
        }
    }
}

/// `--rtol`, checked against the range of the problem file's solver.rtol.
pub fn check_rtol(r: Option<f64>) -> Result<Option<f64>> {
    if let Some(v) = r {
        // the same range as the problem file's solver.rtol
        gripopt::app::check_rtol(v).map_err(|rule| anyhow::anyhow!("--rtol {}: {rule}", gripopt::app::fmt_num(v)))?;
    }
    Ok(r)
}

/// `--threads`, checked as a run checks it.
pub fn check_threads(t: Option<usize>) -> Result<()> {
    Ok(gripopt::app::check_threads(t)?)
}

/// An optimise or resume run with what it gets from the CLI: the progress bar and ctrl-c.
pub fn with_hooks(o: gripopt::app::Optimiser) -> gripopt::app::Optimiser {
    o.progress(super::progress::Bar::new()).stop_flag(super::progress::ctrl_c_flag())
}

/// Refuse an output file (`--csv`, `--plot`) that exists unless `force`, or a folder, a
/// pipe or device, one of the command's `inputs` or an existing file inside an input folder
/// even with `force` ([`gripopt::check_output_file`], as `export --out`); `-` (standard output carries the
/// report), a file in a folder that does not exist, and a `--plot` not named `.svg` (the
/// plot is SVG): exit 2 before anything runs.
pub fn check_output(
    flag: &str,
    path: Option<&std::path::Path>,
    force: bool,
    inputs: &[&std::path::Path],
) -> Result<()> {
    let Some(p) = path else { return Ok(()) };
    let refuse =
        |why: String| -> Result<()> { Err(gripopt::Error::Input(format!("{flag} {}: {why}", p.display())).into()) };
    if p.as_os_str() == "-" {
        return refuse("standard output carries the report; give a file name".into());
    }
    if let Some(d) = p.parent().filter(|d| !d.as_os_str().is_empty() && !d.is_dir()) {
        return refuse(format!("the folder {} does not exist", d.display()));
    }
    gripopt::check_output_file(flag, p, force, inputs)?;
    let svg = p.extension().is_some_and(|e| e.eq_ignore_ascii_case("svg"));
    if flag == "--plot" && !svg {
        return refuse("the plot is written as SVG; give a file name ending in .svg".into());
    }
    Ok(())
}
