//! The one way a file gripopt writes reaches its name ([`AtomicFile`], [`write_atomic`],
//! [`write_rendered`]): a new temporary file beside it (`.NAME.tmp`, created new under a
//! name of the process's own, never opened through whatever stands at that name, and locked
//! while it is written), synced, then renamed into place and the folder synced. A kill mid-write leaves the earlier file
//! whole; the file at the name is replaced, never written into.
//!
//! Nothing is written through, or replaces, a link: a symbolic link at the name (it would
//! send the write outside the folder, or replace what the user linked) and a file with
//! several names (a hard link: `cp -al` backups share every file with the folder they
//! copy) are refused, before the temporary file is made and again just before the rename
//! ([`check_replaceable`]).

use crate::{Error, Result};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The temporary file beside `path` that [`AtomicFile`] writes and renames into place.
pub fn temporary(path: &Path) -> PathBuf {
    let name = path.file_name().map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.tmp"))
}

/// Why the name `path` may not be replaced by a new file, if it may not: a symbolic link
/// (whatever it names, or nothing), or a regular file with more than one name (hard
/// links). Nothing there, a regular file with one name, or what cannot be examined (the
/// write names what is wrong) pass.
pub fn link_at(path: &Path) -> Option<String> {
    let m = std::fs::symlink_metadata(path).ok()?;
    if m.file_type().is_symlink() {
        let to = std::fs::read_link(path).map(|t| format!(" to {}", t.display())).unwrap_or_default();
        return Some(format!(
            "is a symbolic link{to}: gripopt never writes through a link nor replaces one; remove the link (`rm` removes the link, not what it names) or give another name"
        ));
    }
    let names = links(&m);
    (m.is_file() && names > 1).then(|| {
        format!(
            "is a file with {names} names (hard links, as `cp -al` or `ln` make): gripopt never replaces a file another name shares; give the file a name of its own (`cp FILE TMP && mv TMP FILE`), or copy folders with `cp -a`"
        )
    })
}

/// The number of names (hard links) of the file `m` describes (1 where unknown).
fn links(m: &std::fs::Metadata) -> u64 {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        m.nlink()
    }
    #[cfg(not(unix))]
    {
        let _ = m;
        1
    }
}

/// Refuse (naming `path`) to replace the name `path` when [`link_at`] says why not.
pub fn check_replaceable(path: &Path) -> Result<()> {
    match link_at(path) {
        Some(message) => Err(Error::RunDir { path: path.to_path_buf(), message }),
        None => Ok(()),
    }
}

/// Writes made by this process (what makes their first temporary names unique).
static WRITES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// A file being written to a temporary name beside its own, renamed into place by
/// [`AtomicFile::commit`]; dropped uncommitted, the temporary file is removed.
pub struct AtomicFile {
    path: PathBuf,
    tmp: PathBuf,
    out: Option<BufWriter<File>>,
}

impl AtomicFile {
    /// Start writing `path`: refused when a link stands at it ([`check_replaceable`]). The
    /// temporary file is made under a name of this write's own (`.NAME.PID-N.tmp`: created
    /// new, never through a link), locked, and only then given the name `.NAME.tmp` (a hard
    /// link, which never replaces anything): another writer of the same file at the same
    /// moment finds it locked (an error naming `path`, exit 1), never half-made. A stale
    /// `.NAME.tmp` (its writer gone: not locked) is replaced, a link there removed (never
    /// followed), a folder there makes the create fail, naming it. Where the file system has
    /// no hard links, the process's own name is the temporary file.
    pub fn create(path: &Path) -> Result<Self> {
        check_replaceable(path)?;
        let tmp = temporary(path);
        let name = path.file_name().map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
        let mut open = std::fs::OpenOptions::new();
        open.write(true).create_new(true);
        #[cfg(unix)]
        {
            use std::os::unix::fs::OpenOptionsExt;
            open.custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC);
        }
        // a name no other write uses: this process's id and a counter of its writes (a name
        // taken, by a killed process that had this id, is skipped, never removed)
        let (own, file) = loop {
            let n = WRITES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            let own = path.with_file_name(format!(".{name}.{}-{n}.tmp", std::process::id()));
            match open.open(&own) {
                Ok(f) => break (own, f),
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && n % 64 != 63 => continue,
                Err(e) => return Err(Error::io(&tmp, "cannot create", e)),
            }
        };
        // held until the rename: another writer of the same file finds it busy, not stale
        let _ = file.try_lock();
        let claimed = claim(path, &own, &tmp);
        let tmp = match claimed {
            Ok(true) => {
                let _ = std::fs::remove_file(&own);
                tmp
            }
            Ok(false) => own, // no hard links here
            Err(e) => {
                let _ = std::fs::remove_file(&own);
                return Err(e);
            }
        };
        Ok(AtomicFile { path: path.to_path_buf(), tmp, out: Some(BufWriter::with_capacity(1 << 16, file)) })
    }

    /// The temporary file being written.
    pub fn temporary_path(&self) -> &Path {
        &self.tmp
    }

    /// Flush and sync the temporary file, check the name again ([`check_replaceable`]: a
    /// link put there meanwhile is refused, the temporary file removed), rename it into
    /// place and sync the folder. Errors name the file (or the temporary file).
    pub fn commit(mut self) -> Result<()> {
        let out = self.out.take().expect("committed once");
        let done = (|| {
            let f = out.into_inner().map_err(|e| Error::io(&self.tmp, "cannot write", e.into_error()))?;
            f.sync_all().map_err(|e| Error::io(&self.tmp, "cannot sync", e))?;
            check_replaceable(&self.path)?;
            std::fs::rename(&self.tmp, &self.path)
                .map_err(|e| Error::io(&self.path, "cannot rename the temporary file into place", e))
        })();
        if done.is_err() {
            // nothing half-written left behind (the file at the name is untouched)
            let _ = std::fs::remove_file(&self.tmp);
            return done;
        }
        let dir = self.path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        if let Ok(d) = File::open(dir) {
            let _ = d.sync_all();
        }
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.out.as_mut().expect("not committed").write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.out.as_mut().expect("not committed").flush()
    }
}

impl Drop for AtomicFile {
    /// Uncommitted (a failed write): the temporary file goes.
    fn drop(&mut self) {
        if self.out.take().is_some() {
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Give the locked file `own` the temporary name `tmp` of `path` (a hard link: it never
/// replaces what is there): true once it has it; false where the file system has no hard
/// links. A stale file at `tmp` (not locked: its writer is gone) is removed first, a link
/// there removed (never followed); one another process holds is an error naming `path`
/// (exit 1: two commands write the same file at once); a folder there is an error naming
/// it.
fn claim(path: &Path, own: &Path, tmp: &Path) -> Result<bool> {
    for _ in 0..8 {
        match std::fs::hard_link(own, tmp) {
            Ok(()) => return Ok(true),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                if !clear_stale(path, tmp)? {
                    return Err(Error::io(tmp, "cannot create", e));
                }
            }
            Err(_) => return Ok(false),
        }
    }
    Err(busy(path, tmp))
}

/// The error of a file another process is writing right now.
fn busy(path: &Path, tmp: &Path) -> Error {
    Error::io(
        path,
        "cannot write",
        std::io::Error::new(
            std::io::ErrorKind::ResourceBusy,
            format!("another process is writing this file right now (its temporary file {} is in use); wait for it to finish", tmp.display()),
        ),
    )
}

/// Make way at `tmp`, the temporary name of `path`: a link there is removed (the link, not
/// what it names); a regular file whose writer is gone (it is not locked) is removed; one
/// that another process holds is an error naming `path` ([`busy`]). False: a folder (or
/// another kind of file) stands there and stays.
fn clear_stale(path: &Path, tmp: &Path) -> Result<bool> {
    let Ok(m) = std::fs::symlink_metadata(tmp) else { return Ok(true) };
    if m.file_type().is_symlink() {
        let _ = std::fs::remove_file(tmp);
        return Ok(true);
    }
    if !m.is_file() {
        return Ok(false);
    }
    let mut open = std::fs::OpenOptions::new();
    open.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        open.custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK | libc::O_CLOEXEC);
    }
    let Ok(f) = open.open(tmp) else { return Ok(true) };
    match f.try_lock() {
        Err(std::fs::TryLockError::WouldBlock) => Err(busy(path, tmp)),
        _ => {
            // still the file locked here at that name (not one another writer put there since)
            if same_inode(&f, tmp) {
                let _ = std::fs::remove_file(tmp);
            }
            Ok(true)
        }
    }
}

/// The open file `f` is the one at `path` now (device and inode; links not followed).
fn same_inode(f: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        matches!((f.metadata(), std::fs::symlink_metadata(path)), (Ok(a), Ok(b)) if (a.dev(), a.ino()) == (b.dev(), b.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = (f, path);
        true
    }
}

/// Write `bytes` to `path` atomically ([`AtomicFile`]). Errors name the file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut f = AtomicFile::create(path)?;
    f.write_all(bytes).map_err(|e| Error::io(f.temporary_path(), "cannot write", e))?;
    f.commit()
}

/// Write to `path` atomically what `render` puts into a text (an SVG drawn into a string):
/// nothing is written when it fails.
pub fn write_rendered(path: &Path, render: impl FnOnce(&mut String) -> Result<()>) -> Result<()> {
    let mut text = String::new();
    render(&mut text)?;
    write_atomic(path, text.as_bytes())
}
