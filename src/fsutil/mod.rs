//! File-system helpers shared by the layers that write files (record, run, sweep, bench).
//! No layer dependencies besides the error type: every file written goes through
//! [`atomic`] (one atomic, link-refusing write), every folder written into is held by a
//! [`lock`], and what a cleanup cannot prove is its own is set aside ([`aside`]), never
//! deleted.

pub mod aside;
pub mod atomic;
pub mod lock;

pub use aside::{set_aside, SET_ASIDE_DIR};
pub use atomic::{check_replaceable, link_at, write_atomic, write_rendered, AtomicFile};

use crate::{Error, Result};
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
/// Even with `force`, only a regular file is replaced: a device, pipe or socket (a link is
/// judged by what it points to) is refused. [`check_output_file`] also refuses the
/// command's own input files.
pub fn check_new_file(flag: &str, path: &Path, force: bool) -> Result<()> {
    check_output_file(flag, path, force, &[])
}

/// [`check_new_file`] for a command that reads `inputs` (its problem file, a run folder):
/// an output that is one of them (the same file: the same path, a link to it, or a hard
/// link), or for an input that is a folder an existing file inside it (links resolved: the
/// run's run.json, checkpoint, shards, problem copies, …), is refused even with `force`,
/// which replaces an earlier output and nothing else; a new file may be written inside the
/// folder. A link (symbolic, dangling included, or a file with several names) is refused
/// even with `force`: gripopt never writes through one nor replaces it.
pub fn check_output_file(flag: &str, path: &Path, force: bool, inputs: &[&Path]) -> Result<()> {
    let refuse = |why: String| Err(Error::Input(format!("{flag} {}: {why}", path.display())));
    let exists = std::fs::symlink_metadata(path).is_ok();
    if let Some(folder) = inputs.iter().filter(|i| exists && i.is_dir()).find(|i| inside(path, i)) {
        return refuse(format!(
            "is a file of the folder {} the command reads (its own file, or one the user put there): an output never replaces it, --force included; give a new file name",
            folder.display()
        ));
    }
    if let Some((run, mark)) = exists.then(|| run_folder_around(path)).flatten() {
        return refuse(format!(
            "is a file of the gripopt run folder {} (it holds {mark}): an output never replaces a run's file, --force included; give a new file name",
            run.display()
        ));
    }
    let Ok(link) = std::fs::symlink_metadata(path) else {
        return Ok(()); // nothing there (or a folder that cannot be searched: the write names it)
    };
    // what a link points to; a dangling link names nothing, and is replaced as a file
    if let Ok(kind) = std::fs::metadata(path) {
        if kind.is_dir() {
            return refuse("is a folder, not a file".into());
        }
        if !kind.is_file() {
            return refuse(format!(
                "is not a regular file ({}): gripopt never writes over it, --force included (it replaces an earlier output file and nothing else); give a file name",
                file_kind(&kind)
            ));
        }
    } else if !link.file_type().is_symlink() {
        return Ok(()); // cannot be examined: the write names what is wrong
    }
    if let Some(input) = inputs.iter().find(|i| same_file(path, i)) {
        return refuse(format!(
            "is the command's input {}: an output never replaces an input, --force included (it replaces an earlier output and nothing else); give another file name",
            input.display()
        ));
    }
    // a link is never written through nor replaced, --force included ([`atomic`])
    if let Some(why) = link_at(path) {
        return refuse(why);
    }
    if !force {
        return refuse("the file exists; add --force to overwrite it".into());
    }
    Ok(())
}

/// The run folder the file `path` (existing or not) would lie in, links resolved: its
/// folder when that holds one of `RUN_FOLDER_FILES`, or an ancestor holding run.json or
/// checkpoint.json (a file of its recording/), with the mark found; None outside any.
pub fn run_folder_around(path: &Path) -> Option<(std::path::PathBuf, &'static str)> {
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let folder = parent.canonicalize().ok()?;
    if let Some(mark) = run_folder_file(&folder) {
        return Some((folder, mark));
    }
    folder.ancestors().skip(1).find_map(|run| {
        ["run.json", "checkpoint.json"].into_iter().find(|f| run.join(f).is_file()).map(|f| (run.to_path_buf(), f))
    })
}

/// Refuse, before any work, files a command rewrites in a folder (a run's views at every
/// generation, verify's table) where something other than a regular file of one name
/// stands: a folder, pipe or device there would fail the write's rename only after the
/// work, and again on every retry; a link (symbolic or hard) is never replaced
/// ([`check_replaceable`]). Absent files and regular files pass.
pub fn check_rewritable(dir: &Path, files: &[&str]) -> Result<()> {
    for f in files {
        let path = dir.join(f);
        let Ok(m) = std::fs::metadata(&path) else {
            check_replaceable(&path)?; // a dangling link
            continue;
        };
        if !m.is_file() {
            return Err(Error::RunDir {
                path,
                message: format!(
                    "not a regular file ({}): gripopt rewrites this file as the command runs; move it away (nothing was done)",
                    file_kind(&m)
                ),
            });
        }
        check_replaceable(&path)?;
    }
    Ok(())
}

/// Whether `a` and `b` are the same file (device and inode, links followed); false when
/// either cannot be read.
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        #[cfg(unix)]
        (Ok(x), Ok(y)) => {
            use std::os::unix::fs::MetadataExt;
            (x.dev(), x.ino()) == (y.dev(), y.ino())
        }
        #[cfg(not(unix))]
        (Ok(_), Ok(_)) => matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y),
        _ => false,
    }
}

/// Whether the file `path` (existing or not) lies inside the folder `folder`, links of both
/// resolved (false when either cannot be resolved: the write names what is wrong).
fn inside(path: &Path, folder: &Path) -> bool {
    let parent = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    match (parent.canonicalize(), path.file_name(), folder.canonicalize()) {
        (Ok(parent), Some(name), Ok(folder)) => parent.join(name).starts_with(folder),
        _ => false,
    }
}

/// What a file that is not a regular file is, in words.
fn file_kind(m: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = m.file_type();
        if t.is_fifo() {
            return "a named pipe";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if m.is_dir() {
        "a folder"
    } else {
        "a device, pipe or socket"
    }
}

/// Size caps of the files a run folder reads back ([`read_regular`]): each far above what
/// gripopt writes, so that a run's own file is never refused, and a file put in its place
/// by mistake (a video, a disk image) is refused before it is read into memory.
pub mod caps {
    /// `checkpoint.json`: about 3 kB per design of the population and the archive (pop
    /// 1000: ~3 MB): 4 GiB holds a population of over a million designs, more than any run
    /// evaluates in a night.
    pub const CHECKPOINT: u64 = 4 << 30;
    /// `run.json`: a few kB, ~0.3 kB more per resume.
    pub const RUN_JSON: u64 = 64 << 20;
    /// `recording/index.jsonl`: ~0.3 kB per recorded generation.
    pub const INDEX: u64 = 256 << 20;
    /// The CSV views (`pareto.csv`, `archive.csv`, `population.csv`, `history.csv`): ~0.5 kB
    /// per design, as the checkpoint.
    pub const TABLE: u64 = 4 << 30;
}

/// Open `path` for reading when it is a regular file (a link followed): a folder, pipe,
/// socket or device is refused before it is opened (kind `InvalidInput`: a pipe would wait
/// for a writer forever, `/dev/zero` never ends); a missing file is `NotFound`.
pub fn open_regular(path: &Path) -> std::io::Result<std::fs::File> {
    use std::io::{Error as E, ErrorKind as K};
    let not_regular = |m: &std::fs::Metadata| {
        E::new(K::InvalidInput, format!("not a regular file ({}, where gripopt reads a file)", file_kind(m)))
    };
    let m = std::fs::metadata(path)?;
    if !m.is_file() {
        return Err(not_regular(&m));
    }
    let mut open = std::fs::OpenOptions::new();
    open.read(true);
    #[cfg(unix)]
    {
        // should a pipe replace the file between the check and the open, the open does not
        // wait for a writer (and the check below refuses it)
        use std::os::unix::fs::OpenOptionsExt;
        open.custom_flags(libc::O_NONBLOCK);
    }
    let f = open.open(path)?;
    let m = f.metadata()?;
    if !m.is_file() {
        return Err(not_regular(&m));
    }
    Ok(f)
}

/// Read `path` whole when it is a regular file (a link followed) of at most `cap` bytes.
/// A folder, pipe, socket or device is refused before it is opened (kind `InvalidInput`:
/// a pipe would wait for a writer forever, `/dev/zero` fill the memory), a larger file
/// before it is read (kind `InvalidData`); a missing file is `NotFound`. The caller's
/// [`Error::io`] names the file.
pub fn read_regular(path: &Path, cap: u64) -> std::io::Result<Vec<u8>> {
    use std::io::{Error as E, ErrorKind as K, Read};
    let f = open_regular(path)?;
    let m = f.metadata()?;
    let too_large = || {
        E::new(K::InvalidData, format!("larger than {cap} bytes: far more than gripopt writes there: not its file (restore the file gripopt wrote)"))
    };
    if m.len() > cap {
        return Err(too_large());
    }
    let mut bytes = Vec::with_capacity(m.len() as usize);
    f.take(cap + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > cap {
        return Err(too_large());
    }
    Ok(bytes)
}

/// [`read_regular`] as UTF-8 text (kind `InvalidData` when it is not).
pub fn read_regular_string(path: &Path, cap: u64) -> std::io::Result<String> {
    String::from_utf8(read_regular(path, cap)?)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, format!("not UTF-8 text ({e})")))
}

#[cfg(test)]
mod tests {
    #[test]
    fn an_output_is_never_an_input_nor_inside_an_input_folder() {
        let d = std::env::temp_dir().join(format!("gripopt-fsutil-inputs-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(d.join("run/recording")).unwrap();
        let (input, run) = (d.join("problem.toml"), d.join("run"));
        std::fs::write(&input, "x").unwrap();
        std::fs::hard_link(&input, d.join("hard.toml")).unwrap();
        std::fs::write(run.join("run.json"), "{}").unwrap();
        let check = |out: &std::path::Path| super::check_output_file("--csv", out, true, &[&input, &run]);
        for out in [input.clone(), d.join("hard.toml"), d.join("./problem.toml"), run.join("run.json")] {
            let e = check(&out).unwrap_err().to_string();
            assert!(e.starts_with(&format!("--csv {}: is ", out.display())), "{e}");
        }
        // an existing file inside the run folder (through a `..` too, or in a sub-folder) is
        // refused; a new one may be written there
        std::fs::write(run.join("recording/index.jsonl"), "").unwrap();
        for out in [run.join("recording/../run.json"), run.join("recording/index.jsonl")] {
            assert!(check(&out).unwrap_err().to_string().contains("is a file of the folder"), "{}", out.display());
        }
        assert!(check(&run.join("new.csv")).is_ok());
        // beside the inputs: a new file, and an earlier output replaced with force
        assert!(check(&d.join("out.csv")).is_ok());
        std::fs::write(d.join("out.csv"), "earlier").unwrap();
        assert!(check(&d.join("out.csv")).is_ok());
        assert!(super::check_new_file("--csv", &d.join("out.csv"), false).is_err());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn only_a_regular_file_is_read_and_within_its_cap() {
        let d = std::env::temp_dir().join(format!("gripopt-fsutil-read-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        let f = d.join("a.json");
        std::fs::write(&f, b"12345").unwrap();
        assert_eq!(super::read_regular(&f, 5).unwrap(), b"12345");
        let e = super::read_regular(&f, 4).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidData, "{e}");
        let e = super::read_regular(&d, 1 << 20).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput, "{e}");
        assert!(e.to_string().contains("not a regular file (a folder"), "{e}");
        #[cfg(unix)]
        {
            // a link to /dev/zero: refused before it is opened (never read without end)
            std::os::unix::fs::symlink("/dev/zero", d.join("zero")).unwrap();
            let e = super::read_regular(&d.join("zero"), 1 << 20).unwrap_err();
            assert!(e.to_string().contains("not a regular file (a device"), "{e}");
        }
        let e = super::read_regular(&d.join("missing"), 1).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::NotFound);
        std::fs::remove_dir_all(&d).unwrap();
    }

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
