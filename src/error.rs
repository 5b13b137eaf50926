//! The library's one error type. Every variant names the file (or flag) it is about and
//! keeps its source error; the CLI adds context with anyhow and maps errors to exit codes.

use std::path::{Path, PathBuf};

/// Every error the library returns.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file or folder could not be read, written, renamed or created.
    #[error("{}: {action}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What was attempted ("cannot read problem file", "cannot write", …).
        action: &'static str,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A problem file is not valid TOML of the expected shape (syntax, unknown or missing
    /// key, wrong type); the message holds toml's line, column and key.
    #[error("{}: {message}", file.display())]
    ProblemParse {
        /// The file.
        file: PathBuf,
        /// toml's message.
        message: String,
        /// toml's error (boxed: it is large, and every `Result` carries the enum's size).
        #[source]
        source: Box<toml::de::Error>,
    },
    /// A field (of a problem file, or a command-line flag) has a value outside its range.
    #[error("{}: field `{field}` = {value}: {rule}", file.display())]
    InvalidField {
        /// The file (or `command line`).
        file: PathBuf,
        /// Dotted field name, e.g. `object.radius`.
        field: String,
        /// The offending value.
        value: String,
        /// What the value must satisfy.
        rule: String,
    },
    /// A JSON file (checkpoint, run.json, index) could not be parsed or written.
    #[error("{}: {what}: {source}", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// What the file was expected to be.
        what: &'static str,
        /// serde_json's error.
        #[source]
        source: serde_json::Error,
    },
    /// An MCAP file could not be written.
    #[error("{}: {what}: {source}", path.display())]
    Mcap {
        /// The file.
        path: PathBuf,
        /// What failed (e.g. "cannot write").
        what: String,
        /// The mcap crate's error.
        #[source]
        source: McapFault,
    },
    /// A recording file (an MCAP shard) cannot be parsed: it is truncated or damaged (bad
    /// input: exit code 2).
    #[error("{}: {what}: {source}", path.display())]
    DamagedRecording {
        /// The file.
        path: PathBuf,
        /// What could not be read (e.g. "cannot read the MCAP summary").
        what: String,
        /// The mcap crate's error.
        #[source]
        source: McapFault,
    },
    /// A checkpoint is not valid, or does not match the run's inputs.
    #[error("{}: not a valid gripopt checkpoint: {message}", file.display())]
    Checkpoint {
        /// The file.
        file: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A run folder cannot be used as asked (already holds a run, holds no run, inputs changed…).
    #[error("{}: {message}", path.display())]
    RunDir {
        /// The run folder, or the file in it (or the problem file) at fault.
        path: PathBuf,
        /// What is wrong and what to do.
        message: String,
    },
    /// Another process holds the run folder's lock (its pid, when it could be read), or
    /// another call in this one (a run in another thread of a Python session, say).
    #[error("{}: {}", path.display(), holder_text(*pid))]
    Locked {
        /// The run folder.
        path: PathBuf,
        /// The holder's process id.
        pid: Option<u32>,
    },
    /// A recording is missing, incomplete or does not hold what was asked for.
    #[error("{}: {message}", path.display())]
    Recording {
        /// The recording file or folder.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A command-line value that is not a file field (e.g. `--design`), with the flag named.
    #[error("{0}")]
    Input(String),
    /// The optimiser's executor (argmin) failed.
    #[error("optimiser: {0}")]
    Optimiser(String),
    /// A plot could not be drawn or written.
    #[error("{}: plot: {source}", path.display())]
    Plot {
        /// The SVG file.
        path: PathBuf,
        /// The plotting library's error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// The worker thread pool could not be started.
    #[error("cannot start the worker threads: {0}")]
    ThreadPool(#[from] rayon::ThreadPoolBuildError),
    /// The run folder was moved away, removed or replaced while a process wrote into it: the
    /// process stopped without writing into what is now at the folder's path (a failed run,
    /// exit 1; the run resumes where its folder went).
    #[error("{}: the run folder was moved away, removed or replaced while this process was writing into it: stopped, nothing more is written there; resume the run where its folder now is (`gripopt resume NEW_PATH`)", path.display())]
    FolderMoved {
        /// The run folder's path.
        path: PathBuf,
    },
    /// An optimisation run stopped before its last generation (crash hook, failed observer);
    /// its checkpoint allows a resume.
    #[error("run in {} stopped: {source}; resume with `gripopt resume {}`", path.display(), shell_quote(&path.to_string_lossy()))]
    Stopped {
        /// The run folder.
        path: PathBuf,
        /// Why it stopped.
        #[source]
        source: Box<Error>,
    },
    /// An optimisation run stopped before its first checkpoint: there is nothing to resume,
    /// and the folder can be given to `optimise` again.
    #[error("run in {} stopped before its first checkpoint: {source}; nothing to resume: run `gripopt optimise` with `--out {}` again", path.display(), shell_quote(&path.to_string_lossy()))]
    StoppedBeforeCheckpoint {
        /// The run folder.
        path: PathBuf,
        /// Why it stopped.
        #[source]
        source: Box<Error>,
    },
    /// A benchmark could not run as set up (a design discarded, a reference run that does
    /// not reach stability, a failed plot or step of the benchmark).
    #[error("{message}")]
    Bench {
        /// What failed.
        message: String,
        /// The error behind it, if any.
        #[source]
        source: Option<Box<dyn std::error::Error + Send + Sync>>,
    },
}

/// Who holds a folder's lock, in words: another process (its pid), or this very process (a
/// run or run-folder object of the same program still open holds it).
fn holder_text(pid: Option<u32>) -> String {
    match pid {
        Some(p) if p == std::process::id() => format!("the folder is in use by this same process (pid {p}): another call in this process holds its lock (an earlier run, resume, verify or open run folder, or one still going in another thread); finish or close that one first"),
        _ => format!("the run folder is in use by another gripopt process{}; wait for it to end or stop it (the lock is released when it exits, also when killed)", pid.map(|p| format!(" (pid {p})")).unwrap_or_default()),
    }
}

/// `k` and the noun for it: "1 design", "3 designs".
pub fn counted(k: u64, one: &str, many: &str) -> String {
    format!("{k} {}", if k == 1 { one } else { many })
}

/// `s`, a path, as one word of a POSIX shell command line, to be copied from a message: as
/// it is when it holds only characters no shell treats specially, in single quotes
/// otherwise (`'` written `'\''`), and as `$'…'` with escapes when it holds control or
/// invisible format characters (so that none reaches a terminal raw). A path that starts
/// with `-` is written `./-…`, so that the command does not take it for an option.
pub fn shell_quote(s: &str) -> String {
    let dashed;
    let s = if s.starts_with('-') {
        dashed = format!("./{s}");
        dashed.as_str()
    } else {
        s
    };
    let plain = |c: char| c.is_ascii_alphanumeric() || "@%+=:,./_-".contains(c);
    if !s.is_empty() && s.chars().all(plain) {
        return s.to_string();
    }
    if !s.chars().any(hidden) {
        return format!("'{}'", s.replace('\'', r"'\''"));
    }
    let mut out = String::from("$'");
    for c in s.chars() {
        match c {
            '\'' => out.push_str("\\'"),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if hidden(c) && (c as u32) > 0xFFFF => out.push_str(&format!("\\U{:08x}", c as u32)),
            c if hidden(c) => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('\'');
    out
}

/// `s` with its control characters and invisible format characters (bidirectional
/// overrides such as U+202E, zero-width characters, …) written as `\u{…}` escapes (a line
/// break kept), so that none reaches a terminal raw or reorders what it shows.
pub fn printable(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        if hidden(c) && c != '\n' {
            out.push_str(&format!("\\u{{{:x}}}", c as u32));
        } else {
            out.push(c);
        }
    }
    out
}

/// A control character, or a character a terminal does not show as itself: Unicode's format
/// characters (category Cf: bidirectional controls, zero-width characters, the byte-order
/// mark, tags, …) and the line and paragraph separators.
pub fn hidden(c: char) -> bool {
    c.is_control()
        || matches!(c as u32,
            0xAD | 0x600..=0x605 | 0x61C | 0x6DD | 0x70F | 0x890..=0x891 | 0x8E2 | 0x180E
            | 0x200B..=0x200F | 0x2028..=0x202E | 0x2060..=0x2064 | 0x2066..=0x206F | 0xFEFF
            | 0xFFF9..=0xFFFB | 0x110BD | 0x110CD | 0x13430..=0x1343F | 0x1BCA0..=0x1BCA3
            | 0x1D173..=0x1D17A | 0xE0001 | 0xE0020..=0xE007F)
}

/// A number for a message: `{:.decimals}` where that reads well (0, or a magnitude from
/// 1e-3 to below 1e6), otherwise four significant digits in exponent form (`1.478e298`),
/// never hundreds of digits.
pub fn short_num(v: f64, decimals: usize) -> String {
    if !v.is_finite() || v == 0.0 || (1e-3..1e6).contains(&v.abs()) {
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

/// A number for a message, exactly (its shortest round-trip form): as written from 1e-3 to
/// below 1e6 (and 0), otherwise in exponent form (`1.4777425401370882e298`, `1e-300`),
/// never hundreds of digits.
pub fn exact_num(v: f64) -> String {
    if !v.is_finite() || v == 0.0 || (1e-3..1e6).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// `text` cut to at most `max` characters per line (a cut line ends in `… (N more
/// characters)`): what a message echoes from a file (a line of 800 kB) stays readable.
pub fn cap_lines(text: &str, max: usize) -> String {
    let mut out = String::with_capacity(text.len().min(64 << 10));
    for (k, line) in text.split('\n').enumerate() {
        if k > 0 {
            out.push('\n');
        }
        let n = line.chars().count();
        if n > max {
            out.extend(line.chars().take(max));
            out.push_str(&format!("… ({} more characters)", n - max));
        } else {
            out.push_str(line);
        }
    }
    out
}

/// The actions of an [`Error::Io`] on a file the command itself created: a `NotFound` there
/// is a race (something removed the file or its folder meanwhile), exit 1, never bad input.
const RACE_ACTIONS: [&str; 4] = ["cannot write", "cannot sync", "cannot rename", "cannot set aside"];

/// Result with the library's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An I/O error on `path` while doing `action`.
    pub fn io(path: impl Into<PathBuf>, action: &'static str, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), action, source }
    }

    /// True when the error is the user's input (a file, field, flag or folder given that
    /// cannot be used as asked): exit code 2. Other errors are failures of a run: exit 1,
    /// an I/O race included (a file the command made that went missing before its rename).
    pub fn is_input(&self) -> bool {
        use std::io::ErrorKind as K;
        match self {
            Error::ProblemParse { .. }
            | Error::InvalidField { .. }
            | Error::Input(_)
            | Error::RunDir { .. }
            | Error::Checkpoint { .. }
            | Error::Locked { .. }
            | Error::Recording { .. }
            | Error::DamagedRecording { .. } => true,
            Error::Json { .. } => true,
            // a file gripopt made that went missing before it was synced or renamed into
            // place: the file system changed under the command (a race), not its input
            Error::Io { action, source, .. }
                if source.kind() == K::NotFound && RACE_ACTIONS.iter().any(|a| action.starts_with(a)) =>
            {
                false
            }
            Error::Io { source, .. } => matches!(
                source.kind(),
                K::NotFound
                    | K::PermissionDenied
                    | K::InvalidInput
                    | K::InvalidData
                    | K::IsADirectory
                    | K::NotADirectory
                    | K::AlreadyExists
            ),
            _ => false,
        }
    }

    /// The file or folder the error is about, where it names one (the problem file of an
    /// invalid field, `command line` for a flag). A moved run folder
    /// ([`Error::FolderMoved`]) names none: its path is where the folder was.
    pub fn file(&self) -> Option<&Path> {
        match self {
            Error::Io { path, .. }
            | Error::Json { path, .. }
            | Error::Mcap { path, .. }
            | Error::DamagedRecording { path, .. }
            | Error::RunDir { path, .. }
            | Error::Locked { path, .. }
            | Error::Recording { path, .. }
            | Error::Plot { path, .. }
            | Error::Stopped { path, .. }
            | Error::StoppedBeforeCheckpoint { path, .. } => Some(path),
            Error::ProblemParse { file, .. } | Error::Checkpoint { file, .. } | Error::InvalidField { file, .. } => {
                Some(file)
            }
            _ => None,
        }
    }

    /// The field (dotted problem-file name, or the flag) the error is about, where it names one.
    pub fn field(&self) -> Option<&str> {
        match self {
            Error::InvalidField { field, .. } => Some(field),
            _ => None,
        }
    }

    /// The process exit code this error ends the CLI with (README.md, "Exit codes and limits"):
    /// 2 for bad input, 1 for a failed run.
    pub fn exit_code(&self) -> i32 {
        if self.is_input() {
            2
        } else {
            1
        }
    }

    /// A benchmark error with `message` and no source.
    pub fn bench(message: impl Into<String>) -> Self {
        Error::Bench { message: message.into(), source: None }
    }

    /// A benchmark error with `message`, caused by `source`.
    pub fn bench_from(message: impl Into<String>, source: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Self {
        Error::Bench { message: message.into(), source: Some(source.into()) }
    }
}

/// The mcap crate's error, shown on one clean line: its parse errors carry a multi-line
/// backtrace with ANSI colours and the crate's source paths, which a message must not
/// carry. `Display` shows the error and its causes, keeping the error texts of that block (control characters, frame numbers,
/// source locations and the banner removed); `Debug` and [`McapFault::inner`] keep all.
#[derive(Debug)]
pub struct McapFault(pub mcap::McapError);

impl McapFault {
    /// The mcap crate's error.
    pub fn inner(&self) -> &mcap::McapError {
        &self.0
    }
}

impl From<mcap::McapError> for McapFault {
    fn from(e: mcap::McapError) -> Self {
        McapFault(e)
    }
}

impl std::fmt::Display for McapFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // the error and its causes (binrw's backtrace block is the cause of a parse error)
        let mut text = one_line(&self.0.to_string());
        let mut cause = std::error::Error::source(&self.0);
        while let Some(c) = cause {
            let t = one_line(&c.to_string());
            if !text.contains(&t) {
                text = format!("{text}: {t}");
            }
            cause = c.source();
        }
        f.write_str(&text)
    }
}

impl std::error::Error for McapFault {}

/// `text` without ANSI escape sequences and control characters, its lines' banners
/// (box-drawing characters, "Backtrace"), frame numbers and source locations (`at PATH:LINE`)
/// removed, the remaining texts joined with "; ", at most 300 characters.
pub(crate) fn one_line(text: &str) -> String {
    let mut plain = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            // CSI: ESC [ parameters final byte (0x40..=0x7e); other escapes: one character
            if chars.next_if_eq(&'[').is_some() {
                for d in chars.by_ref() {
                    if ('\u{40}'..='\u{7e}').contains(&d) {
                        break;
                    }
                }
            } else {
                chars.next();
            }
        } else if c == '\n' || !c.is_control() {
            plain.push(c);
        } else if c == '\t' {
            plain.push(' ');
        }
    }
    let mut parts: Vec<String> = vec![];
    for line in plain.lines() {
        let line: String = line.chars().filter(|c| !('\u{2500}'..='\u{257f}').contains(c)).collect();
        let line = line.replace("Backtrace", "");
        let mut l = line.trim();
        if l.starts_with("at ") {
            continue; // a source location of the crate
        }
        if let Some((n, rest)) = l.split_once(": ") {
            if !n.is_empty() && n.chars().all(|c| c.is_ascii_digit()) {
                l = rest.trim(); // a frame number
            }
        }
        let l = l.strip_prefix("Error: ").unwrap_or(l).trim().trim_end_matches(':').trim();
        if !l.is_empty() {
            parts.push(l.to_string());
        }
    }
    let mut s = parts.join("; ");
    if s.is_empty() {
        s = "unknown MCAP error".into();
    }
    if s.chars().count() > 300 {
        s = s.chars().take(299).collect::<String>() + "…";
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_and_field_are_those_the_error_names() {
        let invalid = Error::InvalidField {
            file: "p.toml".into(),
            field: "hand.tau".into(),
            value: "-1".into(),
            rule: "must be > 0".into(),
        };
        assert_eq!((invalid.file(), invalid.field()), (Some(Path::new("p.toml")), Some("hand.tau")));
        let io = Error::io("run/a.csv", "cannot write", std::io::Error::other("full"));
        assert_eq!((io.file(), io.field()), (Some(Path::new("run/a.csv")), None));
        let checkpoint = Error::Checkpoint { file: "c.json".into(), message: "bad".into() };
        assert_eq!(checkpoint.file(), Some(Path::new("c.json")));
        assert_eq!((Error::Input("--design".into()).file(), Error::Input(String::new()).field()), (None, None));
        assert_eq!(Error::FolderMoved { path: "run".into() }.file(), None);
    }
}
