//! What the CLI prints on standard output goes through [`write`] (the `outln!` and `out!`
//! macros): a write that fails (a full disk: `gripopt evaluate --json > /dev/full`, a
//! closed pipe) ends the program at once with one clean line, never a panic: exit 1 and
//! `error: cannot write to standard output: …`, or for a pipe closed by its reader exit 141
//! without a message. And the text of the terminal: paths as shell words ([`path`]), names
//! with their control characters escaped ([`shown`]).

use std::io::Write;
use std::path::{Path, PathBuf};

/// Exit code of a closed output pipe (128 + SIGPIPE), without a message.
pub const EXIT_BROKEN_PIPE: i32 = 141;

/// End the program after a failed write to standard output.
pub fn failed(e: &std::io::Error) -> ! {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(EXIT_BROKEN_PIPE);
    }
    eprintln!("error: cannot write to standard output: {e}");
    std::process::exit(1);
}

/// Write `args` to standard output and flush (see the module doc for a failed write).
pub fn write(args: std::fmt::Arguments<'_>) {
    let mut o = std::io::stdout().lock();
    if let Err(e) = o.write_fmt(args).and_then(|_| o.flush()) {
        failed(&e);
    }
}

/// `println!` that never panics: a failed write ends the program cleanly.
macro_rules! outln {
    () => {
        $crate::cli::out::write(format_args!("\n"))
    };
    ($($t:tt)*) => {
        $crate::cli::out::write(format_args!("{}\n", format_args!($($t)*)))
    };
}

/// `print!` that never panics: a failed write ends the program cleanly.
#[allow(unused_macros)]
macro_rules! out {
    ($($t:tt)*) => {
        $crate::cli::out::write(format_args!($($t)*))
    };
}

/// A path as one shell word, to copy into a command (quoted where needed; control
/// characters escaped).
pub fn path(p: &Path) -> String {
    gripopt::run::shell_quote(&p.to_string_lossy())
}

/// A text from a file (a problem's name) with its control characters escaped.
pub fn shown(s: &str) -> String {
    gripopt::run::printable(s)
}

/// The file `path` with its causes' I/O error, or `e` with `path` named: what a failed
/// write of an output file reports (the file asked for, not the temporary file beside it).
fn naming(path: &Path, e: anyhow::Error) -> anyhow::Error {
    match e.chain().find_map(|c| c.downcast_ref::<std::io::Error>()) {
        Some(io) => gripopt::Error::io(path, "cannot write", std::io::Error::new(io.kind(), io.to_string())).into(),
        None => e.context(format!("cannot write {}", path.display())),
    }
}

/// Write the output file `path` atomically ([`gripopt::write_atomic`]: a temporary file
/// beside it, renamed into place): a failed write (a full disk) leaves no partial file that
/// would block the retry, and its error names `path`.
pub fn write_file(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    gripopt::write_atomic(path, bytes).map_err(|e| naming(path, e.into()))
}

/// Write the output file `path` through `write`, which writes the file it is given (a
/// temporary file beside `path`, renamed into place once written and synced): as
/// [`write_file`] for writers that take a path (the SVG plots).
pub fn write_file_with(path: &Path, write: impl FnOnce(&Path) -> anyhow::Result<()>) -> anyhow::Result<()> {
    let name = path.file_name().map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let tmp: PathBuf = path.with_file_name(format!(".{name}.tmp"));
    let written = write(&tmp).and_then(|_| {
        std::fs::File::open(&tmp)?.sync_all()?;
        std::fs::rename(&tmp, path)?;
        Ok(())
    });
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(naming(path, e));
    }
    Ok(())
}
