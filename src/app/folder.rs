//! A run folder read back for a front end (the Python package's `gripopt.Run`): opened only
//! where it holds a run, pinned to that run; its design tables as the run's checkpoint holds
//! them (as `show` reads them).

use crate::error::{Error, Result};
use crate::run::{DesignRow, RunFolder, RunState, RUN_FILE};
use std::path::Path;

/// The run folder `dir`, pinned to the run it holds ([`RunFolder::open_pinned`]). A folder
/// that holds no run (no run.json: not a folder `optimise` wrote, or not yet) is refused
/// here, naming it, rather than at its first read with another error.
pub fn open_run(dir: &Path) -> Result<RunFolder> {
    if std::fs::symlink_metadata(dir.join(RUN_FILE)).is_err() && dir.is_dir() {
        return Err(Error::RunDir {
            path: dir.to_path_buf(),
            message: format!("not a run folder (no {RUN_FILE}); give a folder written by `gripopt optimise`"),
        });
    }
    RunFolder::open_pinned(dir)
}

/// The design table `name` (`front`, `population` or `archive`) of the run in `folder`: the
/// view's rows (pareto.csv, population.csv, archive.csv), or where the view does not hold
/// the designs of the run's checkpoint (an older copy, or edited by hand) the checkpoint's,
/// with why (as `gripopt show` does; not while a process runs the run: its views follow its
/// checkpoints).
pub fn design_table(folder: &RunFolder, name: &str) -> Result<(Vec<DesignRow>, Option<String>)> {
    let (rows, file) = match name {
        "front" => (folder.front()?, "pareto.csv"),
        "population" => (folder.population()?, "population.csv"),
        "archive" => (folder.archive()?, "archive.csv"),
        _ => {
            return Err(Error::Input(format!("table `{name}`: must be front, population, archive or history")));
        }
    };
    if matches!(folder.state()?, RunState::Running(_)) {
        return Ok((rows, None));
    }
    let Some(t) = folder.checkpoint_tables()? else { return Ok((rows, None)) };
    let checkpoint = match name {
        "front" => t.front,
        "archive" => t.archive,
        _ => t.population,
    };
    Ok(match folder.view_differs(file, &checkpoint, t.generation)? {
        Some(why) => (checkpoint, Some(format!("{}: {why}", folder.dir().display()))),
        None => (rows, None),
    })
}
