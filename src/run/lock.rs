//! An exclusive lock per run folder: an OS file lock (`flock` on Unix, `LockFileEx` on
//! Windows) on `RUN_DIR/.lock`, held for the life of the [`RunLock`] and released by the OS
//! when the process ends in any way (kill -9 included). The file holds the holder's pid, so
//! a second process is told who holds the folder.

use crate::{Error, Result};
use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Name of the lock file inside a run folder.
pub const LOCK_FILE: &str = ".lock";

/// A held run-folder lock (released on drop or when the process dies).
#[derive(Debug)]
pub struct RunLock {
    file: File,
    path: PathBuf,
}

impl RunLock {
    /// Take the exclusive lock of run folder `dir` (which must exist) without waiting;
    /// [`Error::Locked`] names the pid of the process holding it.
    pub fn acquire(dir: &Path) -> Result<Self> {
        let path = dir.join(LOCK_FILE);
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| Error::io(&path, "cannot open the run-folder lock", e))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(TryLockError::WouldBlock) => {
                let mut s = String::new();
                let _ = file.read_to_string(&mut s);
                let pid = s.trim().parse::<u32>().ok();
                return Err(Error::Locked { path: dir.to_path_buf(), pid });
            }
            Err(TryLockError::Error(e)) => return Err(Error::io(&path, "cannot lock the run folder", e)),
        }
        let pid = std::process::id();
        let w = (|| {
            file.set_len(0)?;
            file.seek(SeekFrom::Start(0))?;
            writeln!(file, "{pid}")?;
            file.sync_all()
        })();
        w.map_err(|e| Error::io(&path, "cannot write the pid into the run-folder lock", e))?;
        Ok(RunLock { file, path })
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for RunLock {
    fn drop(&mut self) {
        let _ = self.file.unlock();
    }
}
