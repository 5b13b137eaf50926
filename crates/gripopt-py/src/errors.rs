//! gripopt's errors as the Python package's exceptions (`gripopt.errors`): the class by the
//! kind of error, gripopt's own message (it names the file and field), the file, the field
//! and the CLI's exit code as attributes.

use gripopt::Error;
use pyo3::prelude::*;

/// The exception class (in `gripopt.errors`) of `e`.
fn class_of(e: &Error) -> &'static str {
    match e {
        Error::ProblemParse { .. } | Error::InvalidField { .. } => "ProblemError",
        Error::Locked { .. } => "RunLockedError",
        Error::RunDir { .. } | Error::Checkpoint { .. } => "RunFolderError",
        Error::Recording { .. } | Error::DamagedRecording { .. } => "RecordingError",
        Error::Stopped { .. } | Error::StoppedBeforeCheckpoint { .. } => "RunStoppedError",
        e if e.is_input() => "InputError",
        _ => "GripoptError",
    }
}

/// The library's command-line flags as the Python arguments that set them: (flag, the
/// argument as a message names it, the argument `e.field` names).
const ARGUMENTS: [(&str, &str, &str); 9] = [
    ("--pop × --generations", "pop × generations", "pop"),
    ("--pop", "pop", "pop"),
    ("--generations", "generations", "generations"),
    ("--threads", "threads", "threads"),
    ("--record-every", "record[\"every\"]", "record"),
    ("--record-full", "record[\"resolution\"]", "record"),
    ("--scene-ms", "record[\"scene_dt\"] (in ms)", "record"),
    ("--zstd-level", "record[\"zstd_level\"]", "record"),
    ("--zstd-threads", "record[\"zstd_threads\"]", "record"),
];

/// Flags named inside the library's messages, as Python spells them.
const PHRASES: [(&str, &str); 5] = [
    ("(--record none or designs)", "(record=False, or record={\"trajectories\": \"none\"})"),
    ("give --record-full too", "give record={…, \"resolution\": \"full\"} too"),
    ("Use --force", "Use force=True"),
    ("use --force", "use force=True"),
    ("with --force", "with force=True"),
];

/// A message of the library in Python's words: Python has no command line, so a flag is
/// named as the argument that sets it.
fn in_python_words(message: &str) -> String {
    let mut m = message.to_string();
    for (flag, python) in PHRASES {
        m = m.replace(flag, python);
    }
    if let Some(rest) = m.strip_prefix("--generations ") {
        m = format!("generations = {rest}");
    }
    m
}

/// `e` as a Python exception of the package's hierarchy.
pub fn to_py(e: Error) -> PyErr {
    if let Error::InvalidField { file, field, value, rule } = &e {
        let flag = ARGUMENTS.iter().find(|a| a.0 == field);
        if let (true, Some((_, shown, name))) = (file.as_os_str() == "command line", flag) {
            let value = if field == "--record-full" { "\"full\"" } else { value };
            let message = format!("argument `{shown}` = {value}: {}", in_python_words(rule));
            return exception("InputError", message, None, Some(name.to_string()), e.exit_code());
        }
    }
    let file = e.file().map(|p| p.display().to_string());
    let field = e.field().map(String::from);
    exception(class_of(&e), in_python_words(&e.to_string()), file, field, e.exit_code())
}

/// An error of reading problem text `text` (None: not at hand) named `file` as a Python
/// exception: a TOML error of that text (unknown, missing or wrongly typed key; not one of
/// another file it reads, a robust object's) names its field, found in the text.
pub fn problem_error(e: Error, text: Option<&str>, file: &std::path::Path) -> PyErr {
    let field = match (&e, text) {
        (Error::ProblemParse { source, file: of, .. }, Some(text)) if of == file => {
            crate::toml_field::field_of(text, source)
        }
        _ => None,
    };
    let Some(field) = field else { return to_py(e) };
    let file = e.file().map(|p| p.display().to_string());
    exception(class_of(&e), in_python_words(&e.to_string()), file, Some(field), e.exit_code())
}

/// An exception of class `class` (in `gripopt.errors`) with gripopt's message and attributes.
fn exception(class: &str, message: String, file: Option<String>, field: Option<String>, code: i32) -> PyErr {
    Python::attach(|py| {
        let made = (|| -> PyResult<PyErr> {
            let cls = py.import("gripopt.errors")?.getattr(class)?;
            let v = cls.call1((message.as_str(), file, field, code))?;
            Ok(PyErr::from_value(v))
        })();
        // the package is installed with its Python side; without it, a plain RuntimeError
        made.unwrap_or_else(|imp| {
            let err = pyo3::exceptions::PyRuntimeError::new_err(message);
            err.set_cause(py, Some(imp));
            err
        })
    })
}

/// An input error (exit code 2) with `message`, e.g. a design array of the wrong shape.
pub fn input(message: impl Into<String>) -> PyErr {
    to_py(Error::Input(message.into()))
}

/// An input error about the function argument `name` (its `field`), with `message`.
pub fn argument(name: &str, message: String) -> PyErr {
    let code = Error::Input(String::new()).exit_code();
    exception("InputError", message, None, Some(name.to_string()), code)
}

/// `Result<T, gripopt::Error>` → `PyResult<T>`.
pub trait IntoPy<T> {
    /// The error as the package's exception.
    fn py(self) -> PyResult<T>;
}

impl<T> IntoPy<T> for gripopt::Result<T> {
    fn py(self) -> PyResult<T> {
        self.map_err(to_py)
    }
}
