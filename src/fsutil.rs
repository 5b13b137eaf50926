//! File-system helpers shared by the layers that write files (record, run). No layer
//! dependencies besides the error type.

use crate::{Error, Result};
use std::io::Write;
use std::path::Path;

/// SHA-256 of `data` as 64 lowercase hex digits (what run folders record of their files).
pub fn sha256_hex(data: &[u8]) -> String {
    use sha2::Digest;
    sha2::Sha256::digest(data).iter().map(|b| format!("{b:02x}")).collect()
}

/// The files that make a folder a gripopt run folder: no command writes an output of its
/// own (a sweep's table, an export) into one.
pub const RUN_FOLDER_FILES: [&str; 4] = ["run.json", "checkpoint.json", ".lock", "recording"];

/// The first of `RUN_FOLDER_FILES` that `dir` holds (None: not a run folder, or not a
/// folder that can be listed).
pub fn run_folder_file(dir: &Path) -> Option<&'static str> {
    RUN_FOLDER_FILES.into_iter().find(|f| std::fs::symlink_metadata(dir.join(f)).is_ok())
}

/// Check a file a command was asked to write (`flag` names the option, e.g. `--out`,
/// `--csv`): a folder is refused, and a file that exists unless `force` — no command writes
/// over a file it was not told it may replace (a run's checkpoint or shard, a user's file).
pub fn check_new_file(flag: &str, path: &Path, force: bool) -> Result<()> {
    let refuse = |why: &str| Err(Error::Input(format!("{flag} {}: {why}", path.display())));
    if path.is_dir() {
        return refuse("is a folder, not a file");
    }
    if path.exists() && !force {
        return refuse("the file exists; add --force to overwrite it");
    }
    Ok(())
}

/// Write `bytes` to `path` atomically: a temporary file in the same folder, fsync, rename,
/// fsync of the folder. Errors name the file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let tmp = dir.join(format!(".{}.tmp", path.file_name().and_then(|s| s.to_str()).unwrap_or("checkpoint")));
    let written = (|| {
        // a new file, never one opened through a link (or a file) left at the temporary
        // name: that name is removed first (a link, not its target), and create-new fails
        // on anything that appears there meanwhile
        if std::fs::symlink_metadata(&tmp).is_ok_and(|m| !m.is_dir()) {
            let _ = std::fs::remove_file(&tmp);
        }
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
            .map_err(|e| Error::io(&tmp, "cannot create", e))?;
        f.write_all(bytes).map_err(|e| Error::io(&tmp, "cannot write", e))?;
        f.sync_all().map_err(|e| Error::io(&tmp, "cannot sync", e))?;
        drop(f);
        std::fs::rename(&tmp, path).map_err(|e| Error::io(path, "cannot rename the temporary file into place", e))
    })();
    if written.is_err() {
        // no temporary file left behind (the file at `path`, if any, is untouched)
        let _ = std::fs::remove_file(&tmp);
    }
    written?;
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_failed_write_leaves_the_target_and_no_temporary_file() {
        let d = std::env::temp_dir().join(format!("gripopt-fsutil-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        // the target is a folder: the rename fails after the temporary file was written
        let target = d.join("out.csv");
        std::fs::create_dir_all(target.join("inside")).unwrap();
        let e = super::write_atomic(&target, b"x").unwrap_err().to_string();
        assert!(e.contains("out.csv"), "{e}");
        assert!(!d.join(".out.csv.tmp").exists(), "temporary file left behind");
        assert!(target.join("inside").is_dir(), "the target was touched");
        std::fs::remove_dir_all(&d).unwrap();
    }
}
