//! An exclusive lock per folder gripopt writes into (a run folder, a sweep's or a
//! benchmark's output folder), held for the life of the [`RunLock`] and released by
//! the OS when the process ends in any way (kill -9 included).
//!
//! On Unix the lock is an OS file lock (`flock`) on the run folder itself, not on a file in
//! it: removing or replacing a file cannot defeat it, and `flock DIR …` (util-linux) takes
//! the same lock from a shell (the Makefile's `run` does, before it moves an earlier run
//! aside). Elsewhere it is the lock of the file `RUN_DIR/.lock`. `RUN_DIR/.lock` holds the
//! holder's pid, so that a second process is told who holds the folder; a clean exit
//! removes it, so nothing that looks like a stale lock is left behind.
//!
//! The lock is bound to the folder, not to its path: a holder checks with
//! [`RunLock::check`] that its path still leads to the folder it locked before it writes (a
//! folder moved away and replaced by another is never written into).

use crate::{Error, Result};
use std::fs::{File, TryLockError};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Name of the pid file inside a run folder.
pub const LOCK_FILE: &str = ".lock";

/// How often a lock held by a passing probe (`gripopt show`) is tried again.
const TRIES: u32 = 5;
const RETRY: Duration = Duration::from_millis(20);

/// A held run-folder lock (released on drop or when the process dies).
#[derive(Debug)]
pub struct RunLock {
    file: File,
    dir: PathBuf,
    path: PathBuf,
}

/// Who holds a run folder's lock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LockHolder {
    /// Nobody: no process runs, resumes or verifies the run.
    Free,
    /// A process (its pid, when `RUN_DIR/.lock` could be read).
    Held(Option<u32>),
}

/// What is locked: the folder itself on Unix, the pid file elsewhere.
fn lock_target(dir: &Path) -> Result<File> {
    #[cfg(unix)]
    let f = File::open(dir);
    #[cfg(not(unix))]
    let f = std::fs::OpenOptions::new().read(true).write(true).create(true).truncate(false).open(dir.join(LOCK_FILE));
    f.map_err(|e| Error::io(dir, "cannot open the run folder to lock it", e))
}

/// The pid written in `dir/.lock` (None when it is not a plain file: a link is not ours).
fn pid_in(dir: &Path) -> Option<u32> {
    let p = dir.join(LOCK_FILE);
    if !std::fs::symlink_metadata(&p).ok()?.is_file() {
        return None;
    }
    std::fs::read_to_string(p).ok()?.trim().parse().ok()
}

/// `dir/.lock` is a symbolic link: refused, never written through (a write would land in
/// the file it points to).
fn refuse_link(dir: &Path) -> Result<()> {
    let p = dir.join(LOCK_FILE);
    match std::fs::symlink_metadata(&p) {
        Ok(m) if m.file_type().is_symlink() => {
            let to = std::fs::read_link(&p).map(|t| format!(" (to {})", t.display())).unwrap_or_default();
            Err(Error::RunDir {
                path: p,
                message: format!("a symbolic link{to}: the run folder's lock file is gripopt's own plain file and gripopt never writes through a link; remove the link (`rm` removes the link, not its target) and run the command again"),
            })
        }
        _ => Ok(()),
    }
}

/// The same file system object (device and inode on Unix).
fn same_object(a: &File, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (a.metadata(), std::fs::metadata(b)) {
            (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (a, b);
        true
    }
}

impl RunLock {
    /// Take the exclusive lock of run folder `dir` (which must exist) without waiting (a
    /// momentary probe is waited out); [`Error::Locked`] names the pid of the process
    /// holding it.
    pub fn acquire(dir: &Path) -> Result<Self> {
        refuse_link(dir)?;
        let target = if cfg!(unix) { dir.to_path_buf() } else { dir.join(LOCK_FILE) };
        for attempt in 1..=TRIES {
            let file = lock_target(dir)?;
            match file.try_lock() {
                Ok(()) => {}
                Err(TryLockError::WouldBlock) if attempt < TRIES => {
                    std::thread::sleep(RETRY);
                    continue;
                }
                Err(TryLockError::WouldBlock) => {
                    return Err(Error::Locked { path: dir.to_path_buf(), pid: pid_in(dir) })
                }
                Err(TryLockError::Error(e)) => return Err(Error::io(dir, "cannot lock the run folder", e)),
            }
            // the folder locked is still the one at `dir` (not moved away meanwhile)
            if !same_object(&file, &target) {
                if attempt < TRIES {
                    continue;
                }
                return Err(Error::FolderMoved { path: dir.to_path_buf() });
            }
            let lock = RunLock { file, dir: dir.to_path_buf(), path: dir.join(LOCK_FILE) };
            // again under the lock; then the pid file replaced by rename, never opened
            // through whatever is at its path
            refuse_link(dir)?;
            // the pid is for messages only: the lock holds without it
            let _ = crate::fsutil::write_atomic(&lock.path, format!("{}\n", std::process::id()).as_bytes());
            return Ok(lock);
        }
        Err(Error::Locked { path: dir.to_path_buf(), pid: pid_in(dir) })
    }

    /// Who holds the lock of `dir`, without taking it (a shared lock tried and released at
    /// once).
    pub fn holder(dir: &Path) -> Result<LockHolder> {
        #[cfg(unix)]
        let f = File::open(dir);
        #[cfg(not(unix))]
        let f = match File::open(dir.join(LOCK_FILE)) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(LockHolder::Free),
            f => f,
        };
        let f = f.map_err(|e| Error::io(dir, "cannot open the run folder", e))?;
        match f.try_lock_shared() {
            Ok(()) => Ok(LockHolder::Free),
            Err(TryLockError::WouldBlock) => Ok(LockHolder::Held(pid_in(dir))),
            Err(TryLockError::Error(e)) => Err(Error::io(dir, "cannot test the run folder's lock", e)),
        }
    }

    /// The pid file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The folder at this lock's path is still the folder it locked: an error
    /// ([`Error::FolderMoved`]) when it was moved away, removed or replaced.
    pub fn check(&self) -> Result<()> {
        let target = if cfg!(unix) { self.dir.clone() } else { self.path.clone() };
        if same_object(&self.file, &target) {
            Ok(())
        } else {
            Err(Error::FolderMoved { path: self.dir.clone() })
        }
    }
}

impl Drop for RunLock {
    fn drop(&mut self) {
        // the pid file, if it is still ours in our folder: a clean exit leaves no stale lock
        if self.check().is_ok() && pid_in(&self.dir) == Some(std::process::id()) {
            let _ = std::fs::remove_file(&self.path);
        }
        let _ = self.file.unlock();
    }
}
