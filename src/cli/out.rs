//! What the CLI prints on standard output goes through [`write`] (the `outln!` and `out!`
//! macros): a write that fails (a full disk: `gripopt evaluate --json > /dev/full`, a
//! closed pipe) ends the program at once with one clean line, never a panic: exit 1 and
//! `error: cannot write to standard output: …`, or for a pipe closed by its reader exit 141
//! without a message. And the text of the terminal: paths as shell words ([`path`]), names
//! with their control characters escaped ([`shown`]). A command's error ends here too
//! ([`report_error`]): one line `error: …` on stderr, its exit code, and with `--json` one
//! JSON object on stdout.

use std::io::Write;
use std::path::Path;

/// Exit code of a closed output pipe (128 + SIGPIPE), without a message.
pub const EXIT_BROKEN_PIPE: i32 = 141;

/// Exit code of a check that did not pass: `replay` did not verify the recording,
/// `moo-test`'s hypervolume median lies outside the reference band.
pub const EXIT_CHECK_FAILED: i32 = 3;

/// The error and its causes on one line, each cause once: the library's errors name their
/// file and often repeat their source's text, which anyhow's `{:#}` would print twice.
pub fn error_message(e: &anyhow::Error) -> String {
    let mut msg = String::new();
    for cause in e.chain() {
        let s = cause.to_string();
        let s = s.trim();
        if !msg.contains(s) {
            if !msg.is_empty() {
                msg.push_str(": ");
            }
            msg.push_str(s);
        }
    }
    // whatever a message echoes of a file, at most a screenful: long lines and many of them cut
    let msg = gripopt::app::cap_lines(&msg, 2000);
    let msg = match msg.char_indices().nth(8000) {
        Some((at, _)) => format!("{}… (cut: the message is longer)", &msg[..at]),
        None => msg,
    };
    gripopt::app::printable(&msg)
}

/// The message of clap's rendered usage error `text` on one line: its lines before the
/// usage block, without the `error: ` prefix: a list's indented items after its colon,
/// separated by ", ", other lines (clap's tips) after "; " (e.g. "the following required
/// arguments were not provided: --out <OUT>, <PROBLEM>").
pub fn usage_message(text: &str) -> String {
    let lines = text.lines().take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"));
    let mut joined = String::new();
    let mut item = false;
    for raw in lines.filter(|l| !l.trim().is_empty()) {
        // clap indents the items of a list (missing arguments, possible values)
        let indented = raw.starts_with(' ');
        if !joined.is_empty() {
            joined.push_str(match (joined.ends_with(':'), item && indented) {
                (true, _) => " ",
                (false, true) => ", ",
                _ => "; ",
            });
        }
        joined.push_str(raw.trim());
        item = indented;
    }
    joined.strip_prefix("error: ").unwrap_or(&joined).to_string()
}

/// Exit code of an error: the library's classification where it is a library error, a
/// closed pipe quietly, 1 for other I/O failures, 2 for the CLI's own checks of its flags.
pub fn error_exit_code(e: &anyhow::Error) -> i32 {
    let io = e.chain().find_map(|c| c.downcast_ref::<std::io::Error>());
    if io.is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe) {
        return EXIT_BROKEN_PIPE;
    }
    if let Some(g) = e.chain().find_map(|c| c.downcast_ref::<gripopt::Error>()) {
        return g.exit_code();
    }
    if io.is_some() {
        return 1;
    }
    2
}

/// What a failed command prints with `--json`: one object on stdout, the error's stderr
/// line without its `error: ` and the process's exit code.
#[derive(serde::Serialize)]
struct ErrorJson<'a> {
    error: &'a str,
    exit_code: i32,
}

/// Print one JSON object `{"error": message, "exit_code": code}` on stdout (a script that
/// parses stdout reads the failure, not an empty string). A write that fails is left
/// unreported: the error is on stderr already.
pub fn error_json(message: &str, exit_code: i32) {
    let v = ErrorJson { error: message, exit_code };
    if let Ok(text) = serde_json::to_string(&v) {
        let mut o = std::io::stdout().lock();
        let _ = writeln!(o, "{text}").and_then(|_| o.flush());
    }
}

/// Report a command's error and give its exit code: one line `error: …` on stderr and,
/// with `--json`, [`error_json`] on stdout; a closed output pipe quietly (exit 141).
pub fn report_error(e: &anyhow::Error, json: bool) -> i32 {
    let code = error_exit_code(e);
    if code == EXIT_BROKEN_PIPE {
        return code;
    }
    let message = error_message(e);
    // never a panic when stderr is gone (a closed terminal: SIGHUP)
    let _ = writeln!(std::io::stderr(), "error: {message}");
    if json {
        error_json(&message, code);
    }
    code
}

/// End the program after a failed write to standard output.
pub fn failed(e: &std::io::Error) -> ! {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(EXIT_BROKEN_PIPE);
    }
    let _ = writeln!(std::io::stderr(), "error: cannot write to standard output: {e}");
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
    gripopt::app::shell_quote(&p.to_string_lossy())
}

/// A text from a file (a problem's name) with its control characters escaped.
pub fn shown(s: &str) -> String {
    gripopt::app::printable(s)
}

/// The file `path` with its causes' I/O error, or `e` with `path` named: what a failed
/// write of an output file reports (the file asked for, not the temporary file beside it).
fn naming(path: &Path, e: anyhow::Error) -> anyhow::Error {
    // the library's own error keeps what it says (a link refused, its action and kind)
    let action = match e.chain().find_map(|c| c.downcast_ref::<gripopt::Error>()) {
        Some(gripopt::Error::Io { action, .. }) => *action,
        Some(_) => return e,
        None => "cannot write",
    };
    match e.chain().find_map(|c| c.downcast_ref::<std::io::Error>()) {
        Some(io) => gripopt::Error::io(path, action, std::io::Error::new(io.kind(), io.to_string())).into(),
        None => e.context(format!("cannot write {}", path.display())),
    }
}

/// Write the output file `path` atomically ([`gripopt::write_atomic`]: a temporary file
/// beside it, renamed into place): a failed write (a full disk) leaves no partial file that
/// would block the retry, and its error names `path`.
pub fn write_file(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    gripopt::write_atomic(path, bytes).map_err(|e| naming(path, e.into()))
}

/// Write the output file `path` through `write`, a writer that writes it atomically itself
/// (the SVG plots: [`gripopt::app::grasp_plot`]); its error names `path`.
pub fn write_file_with(path: &Path, write: impl FnOnce(&Path) -> anyhow::Result<()>) -> anyhow::Result<()> {
    write(path).map_err(|e| naming(path, e))
}
