//! Files set aside, never deleted: what a cleanup cannot prove is the command's own and
//! superseded (a file whose content does not name this run, a temporary file a killed
//! writer left, another program's file at a name gripopt uses) is moved into the folder's
//! `set-aside/` folder under its own name (`NAME.1`, `NAME.2`, … when taken), where the user
//! finds it. Only a file whose content proves it is the command's own and superseded (its
//! metadata names the run; it is byte for byte what gripopt writes there) is removed.

use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// The folder, inside a folder gripopt cleans up (a run folder, its `recording/`, a
/// sweep's folder), that holds what it set aside.
pub const SET_ASIDE_DIR: &str = "set-aside";

/// Move `dir/name` into `dir/set-aside/` (created if need be) under a name not taken there:
/// `name`, else `name.1`, `name.2`, …; the new path. Nothing is overwritten; an error names
/// the file.
pub fn set_aside(dir: &Path, name: &str) -> Result<PathBuf> {
    let from = dir.join(name);
    let aside = dir.join(SET_ASIDE_DIR);
    if std::fs::symlink_metadata(&aside).is_ok_and(|m| !m.is_dir()) {
        return Err(Error::RunDir {
            path: aside,
            message: format!(
                "is not a folder: gripopt sets aside {} there (nothing was moved); move it away",
                from.display()
            ),
        });
    }
    std::fs::create_dir_all(&aside)
        .map_err(|e| Error::io(&aside, "cannot create the folder for files set aside", e))?;
    for k in 0u32.. {
        let to = aside.join(if k == 0 { name.to_string() } else { format!("{name}.{k}") });
        if std::fs::symlink_metadata(&to).is_ok() {
            continue;
        }
        // a hard link then the old name removed: never over a name that appeared meanwhile
        // (`link` fails where rename would replace); folders (and file systems without
        // hard links) are renamed
        #[cfg(unix)]
        if std::fs::symlink_metadata(&from).is_ok_and(|m| !m.is_dir()) {
            match std::fs::hard_link(&from, &to) {
                Ok(()) => {
                    return std::fs::remove_file(&from)
                        .map(|()| to)
                        .map_err(|e| Error::io(&from, "cannot set aside (its old name stays)", e));
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(_) => {}
            }
        }
        return std::fs::rename(&from, &to).map(|()| to).map_err(|e| Error::io(&from, "cannot set aside", e));
    }
    unreachable!("a free name")
}

#[cfg(test)]
mod tests {
    /// Issue 44 class 2: a file set aside keeps its bytes, under a name not taken.
    #[test]
    fn a_file_set_aside_keeps_its_bytes_and_never_replaces_one() {
        let d = std::env::temp_dir().join(format!("gripopt-aside-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        for content in ["first", "second"] {
            std::fs::write(d.join("pareto.csv"), content).unwrap();
            super::set_aside(&d, "pareto.csv").unwrap();
        }
        let aside = d.join(super::SET_ASIDE_DIR);
        assert_eq!(std::fs::read_to_string(aside.join("pareto.csv")).unwrap(), "first");
        assert_eq!(std::fs::read_to_string(aside.join("pareto.csv.1")).unwrap(), "second");
        assert!(!d.join("pareto.csv").exists());
        std::fs::remove_dir_all(&d).unwrap();
    }
}
