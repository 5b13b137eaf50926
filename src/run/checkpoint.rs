//! Checkpoints: the whole optimiser state as JSON, written atomically (temporary file,
//! fsync, rename, fsync of the folder) after every generation, with hashes of the problem
//! file and of the settings so that a resume with changed inputs is refused, and a SHA-256
//! of its own content (`sha256`: the canonical JSON of every other field, keys sorted), so
//! that a hand-edited or damaged checkpoint is refused (unless forced).

use super::archive::Archive;
use super::checkpoint_json::{self, Canonical};
use crate::fsutil::write_atomic;
use crate::optim::{Nsga2Settings, Nsga2State, Survival, Variation};
use crate::params::{Method, SolverSettings};
use crate::record::RecordOptions;
use crate::{Error, Result};
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use std::path::Path;

/// Format tag written into every checkpoint.
pub const FORMAT: &str = "gripopt-checkpoint";
/// Format version (3: each individual's info holds its typed evaluation record; 4: the
/// run's id and archive inside).
pub const VERSION: u32 = 4;

/// The checkpoint's content checksum did not match (or was missing).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ChecksumMismatch {
    /// The checksum in the file (None: missing).
    pub stored: Option<String>,
    /// The checksum of the content as read.
    pub computed: String,
}

/// A checkpoint file. Its fields are declared in sorted order: the file is canonical JSON
/// (every object's keys sorted) written streaming ([`Checkpoint::to_bytes_and_sha256`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(bound = "I: Serialize + DeserializeOwned")]
pub struct Checkpoint<I> {
    /// The run's archive after the same generation (None: written without one, e.g. by a
    /// benchmark).
    #[serde(default)]
    pub archive: Option<Archive<I>>,
    /// Always [`FORMAT`].
    pub format: String,
    /// Run options that change the outcome besides the algorithm settings.
    pub options: RunOptions,
    /// SHA-256 of the problem file's text.
    pub problem_hash: String,
    /// The run that wrote it (run.json's `run_id`).
    #[serde(default)]
    pub run_id: String,
    /// Algorithm settings.
    pub settings: Nsga2Settings,
    /// SHA-256 of the canonical JSON of the settings (and run options).
    pub settings_hash: String,
    /// Optimiser state after the last completed generation.
    pub state: Nsga2State<I>,
    /// Always [`VERSION`].
    pub version: u32,
    /// Wall time spent so far (s).
    pub wall_s: f64,
}

/// What the pipeline of a run's stage 3 is, as its checkpoints state it.
pub const PIPELINE: &str = "stages 0-3, stage 3 in pipeline mode";

/// Run options that change results besides the algorithm settings: a checkpoint's `options`,
/// hashed with the settings into its `settings_hash`. Written as the canonical JSON of every
/// checkpoint (keys sorted), so the declaration order does not matter. Every field is
/// written by [`RunOptions::of`]; read back, one may be absent: the integration method is
/// stated only when it is not RADAU5, the default (a run of a problem without
/// `solver.method` writes the options it wrote before the key existed), and a top-level
/// field removed by hand stays absent (its hash then differs, and the resume names the field
/// as missing beside the run's value); inside `recording` a required field removed by hand
/// fails the checkpoint's load (serde names it), and one with a default reads as that
/// default. A field the type does not know is an error naming it: the checkpoint is then not
/// read at all (resume, `show` and `export` refuse it alike).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunOptions {
    /// The evaluation pipeline ([`PIPELINE`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pipeline: Option<String>,
    /// Relative tolerance of the integration (`[solver] rtol`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rtol: Option<f64>,
    /// Absolute tolerance (`[solver] atol`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub atol: Option<f64>,
    /// Step limit (`[solver] max_steps`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_steps: Option<u64>,
    /// The run's recording options (run.json's `recording`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub recording: Option<RecordOptions>,
    /// The integration method, where not the default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub method: Option<Method>,
    /// How the optimiser chooses each generation's survivors; absent in a checkpoint of a
    /// gripopt before issue 42, whose run resumes with the selection it started with,
    /// [`Survival::Crowding`] (NSGA-II).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub survival: Option<Survival>,
    /// How the optimiser makes offspring; absent as `survival` (then [`Variation::Sbx`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub variation: Option<Variation>,
}

impl RunOptions {
    /// The options of a new run of a problem with solver settings `s`, recording `rec` (the
    /// default survival).
    pub fn of(s: &SolverSettings, rec: &RecordOptions) -> Self {
        RunOptions {
            pipeline: Some(PIPELINE.into()),
            rtol: Some(s.rtol),
            atol: Some(s.atol),
            max_steps: Some(s.max_steps),
            recording: Some(*rec),
            method: (!s.method.is_default()).then_some(s.method),
            survival: Some(Survival::default()),
            variation: Some(Variation::default()),
        }
    }
    /// As a JSON tree (for comparing field by field: [`field_differences`]).
    pub(crate) fn to_value(&self) -> serde_json::Value {
        // numbers, strings and plain structs: serialising cannot fail
        serde_json::to_value(self).expect("run options serialise")
    }
}

impl ChecksumMismatch {
    /// The error refusing the checkpoint at `path`.
    pub fn error(&self, path: &Path) -> Error {
        let message = match &self.stored {
            Some(s) => format!("content checksum mismatch (field `sha256` {} but the content hashes to {}): the file was edited or damaged after it was written; resuming would put parameters next to objectives that were never evaluated for them. Use --force only if you know what was edited (recorded in run.json)", short(s), short(&self.computed)),
            None => "no content checksum; use --force to resume it (recorded in run.json)".into(),
        };
        Error::Checkpoint { file: path.to_path_buf(), message }
    }
}

pub use crate::fsutil::sha256_hex;

/// SHA-256 of the canonical JSON (keys sorted, shortest round-trip numbers) of a checkpoint
/// read as a tree, without its `sha256` field (streamed into the hash).
fn content_sha256(v: &serde_json::Value) -> serde_json::Result<String> {
    Ok(checkpoint_json::sha256_of(v, &[])?.0)
}

/// The structs of a checkpoint whose fields are declared in sorted order: written through,
/// never buffered (the large ones: the state with its population, the archive).
const SORTED_STRUCTS: &[&str] = &["Checkpoint", "Nsga2State", "Archive"];

fn short(s: &str) -> &str {
    &s[..s.len().min(12)]
}

/// Each field of a checkpoint's object `name` (`ours`) whose value differs from the run's
/// (`theirs`), with both values and where the run's value comes from (`source(field)`):
/// nested objects are compared field by field, so that a message names the innermost field.
pub(crate) fn field_differences(
    name: &str,
    ours: &serde_json::Value,
    theirs: &serde_json::Value,
    source: &dyn Fn(&str) -> String,
) -> Vec<String> {
    use serde_json::Value;
    let (Value::Object(a), Value::Object(b)) = (ours, theirs) else {
        return if ours == theirs {
            vec![]
        } else {
            vec![format!("{name} {ours} differs from the run's {theirs} ({})", source(name))]
        };
    };
    let mut out = vec![];
    let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
    for k in keys {
        let field = format!("{name}.{k}");
        match (a.get(k), b.get(k)) {
            (Some(x), Some(y)) => out.extend(field_differences(&field, x, y, source)),
            (None, Some(y)) => out.push(format!("{field} is missing (the run's is {y}, {})", source(&field))),
            (Some(x), None) => out.push(format!("{field} {x} is not among the run's fields ({})", source(&field))),
            (None, None) => {}
        }
    }
    out
}

/// The integration method a run's checkpoint at `path` records (its options' `method`;
/// None inside: RADAU5, a checkpoint that names none), or None where the run has no
/// checkpoint (or one that cannot be read: the caller then goes on with the problem file as
/// it is). Only the options are read.
pub fn recorded_method(path: &Path) -> Option<Option<Method>> {
    #[derive(Deserialize)]
    struct OptionsOnly {
        options: RunOptions,
    }
    let bytes = crate::fsutil::read_regular(path, crate::fsutil::caps::CHECKPOINT).ok()?;
    serde_json::from_slice::<OptionsOnly>(&bytes).ok().map(|c| c.options.method)
}

/// Hash of settings and options (canonical JSON).
pub fn settings_hash(settings: &Nsga2Settings, options: &RunOptions) -> String {
    let v = serde_json::json!({ "settings": settings, "options": options });
    sha256_hex(serde_json::to_string(&v).expect("serialisable").as_bytes())
}

impl<I: Serialize + DeserializeOwned> Checkpoint<I> {
    /// A checkpoint of `state` in the current format, with the hash of `settings` and `options`.
    pub fn new(
        problem_hash: String,
        settings: Nsga2Settings,
        options: RunOptions,
        state: Nsga2State<I>,
        wall_s: f64,
    ) -> Self {
        let settings_hash = settings_hash(&settings, &options);
        Checkpoint {
            format: FORMAT.into(),
            version: VERSION,
            problem_hash,
            settings_hash,
            settings,
            options,
            state,
            wall_s,
            run_id: String::new(),
            archive: None,
        }
    }

    /// This checkpoint with the run's id and archive.
    pub fn of_run(mut self, run_id: String, archive: Option<Archive<I>>) -> Self {
        self.run_id = run_id;
        self.archive = archive;
        self
    }

    /// Save atomically, with the content checksum `sha256`. A checkpoint larger than it is
    /// read back at ([`crate::fsutil::caps::CHECKPOINT`]) is refused (the earlier one stays).
    pub fn save(&self, path: &Path) -> Result<()> {
        write_atomic(path, &self.to_bytes(path)?)
    }

    /// The file's bytes, with the content checksum `sha256` (errors name `path`).
    pub fn to_bytes(&self, path: &Path) -> Result<Vec<u8>> {
        Ok(self.to_bytes_and_sha256(path)?.0)
    }

    /// The file's bytes and its content checksum (its field `sha256`; errors name `path`).
    pub fn to_bytes_and_sha256(&self, path: &Path) -> Result<(Vec<u8>, String)> {
        let ser = |source| Error::Json { path: path.to_path_buf(), what: "cannot serialise the checkpoint", source };
        // streamed twice, never as a tree: the content into its hash, then the file's bytes
        // with the hash at its sorted place (`,"sha256":"…"`)
        let (sum, len) = checkpoint_json::sha256_of(self, SORTED_STRUCTS).map_err(ser)?;
        if len as u64 > crate::fsutil::caps::CHECKPOINT {
            // it could never be read back: the earlier checkpoint stays the run's last
            return Err(Error::Checkpoint {
                file: path.to_path_buf(),
                message: format!(
                    "would be {len} bytes, more than the {} bytes a checkpoint is read back at: not written (the earlier checkpoint resumes the run); the population and archive hold too many robust scenario records (fewer designs, scenarios or objects)",
                    crate::fsutil::caps::CHECKPOINT
                ),
            });
        }
        let mut c = Canonical::new(Vec::with_capacity(len + 12 + sum.len()), SORTED_STRUCTS).with_field("sha256", &sum);
        self.serialize(&mut c).map_err(ser)?;
        Ok((c.into_inner(), sum))
    }

    /// Load, check the format and the content checksum (a mismatch is an error).
    pub fn load(path: &Path) -> Result<Self> {
        Self::load_with_sha256(path).map(|(cp, _)| cp)
    }

    /// [`Checkpoint::load`], with the content checksum it verified (the file's field
    /// `sha256`), from the one read of the file.
    pub fn load_with_sha256(path: &Path) -> Result<(Self, String)> {
        let (cp, computed, mismatch) = Self::read(path)?;
        match mismatch {
            None => Ok((cp, computed)),
            Some(m) => Err(m.error(path)),
        }
    }

    /// Load and check the format; a checksum mismatch is returned beside the checkpoint
    /// instead of refused (for `resume --force`), with the checksum the file states (its
    /// field `sha256`; the content's when it has none): the one run.json records of it.
    pub fn load_unverified(path: &Path) -> Result<(Self, String, Option<ChecksumMismatch>)> {
        Self::read(path).map(|(cp, computed, mismatch)| {
            let stated = mismatch.as_ref().and_then(|m| m.stored.clone()).unwrap_or(computed);
            (cp, stated, mismatch)
        })
    }

    /// Read `path`: the checkpoint, its content's checksum, and the mismatch with the
    /// stored one if any.
    fn read(path: &Path) -> Result<(Self, String, Option<ChecksumMismatch>)> {
        let invalid = |message: String| Error::Checkpoint { file: path.to_path_buf(), message };
        let bytes = crate::fsutil::read_regular(path, crate::fsutil::caps::CHECKPOINT)
            .map_err(|e| Error::io(path, "cannot read the checkpoint", e))?;
        let head: serde_json::Value = serde_json::from_slice(&bytes).map_err(|source| Error::Json {
            path: path.to_path_buf(),
            what: "not a valid gripopt checkpoint: not JSON; the file may be truncated",
            source,
        })?;
        let fmt = head.get("format").and_then(|v| v.as_str());
        if fmt != Some(FORMAT) {
            return Err(invalid(format!("field `format` is {fmt:?}, expected \"{FORMAT}\"")));
        }
        let ver = head.get("version").and_then(|v| v.as_u64());
        if let Some(old @ (1..=3)) = ver {
            let before =
                if old == 3 { "the archive inside the checkpoint (issue 24)" } else { "the typed evaluation record" };
            return Err(invalid(format!(
                "field `version` is {old}: written by a gripopt before {before} (version {VERSION}); resume the run with the gripopt that started it, or start a new one"
            )));
        }
        if ver != Some(VERSION as u64) {
            return Err(invalid(format!("field `version` is {ver:?}, expected {VERSION}")));
        }
        let mut head = head;
        let stored = head.as_object_mut().and_then(|m| m.remove("sha256")).and_then(|v| v.as_str().map(String::from));
        let computed = content_sha256(&head).map_err(|source| Error::Json {
            path: path.to_path_buf(),
            what: "cannot serialise the checkpoint",
            source,
        })?;
        let mismatch = (stored.as_deref() != Some(computed.as_str()))
            .then(|| ChecksumMismatch { stored: stored.clone(), computed: computed.clone() });
        let cp: Self = serde_json::from_value(head).map_err(|source| Error::Json {
            path: path.to_path_buf(),
            what: "not a valid gripopt checkpoint",
            source,
        })?;
        let st = &cp.state;
        let consistent = st.population.len() == cp.settings.pop_size
            && st.rank.len() == st.population.len()
            && st.crowding.len() == st.population.len()
            && st.generation >= 1
            && st.hv_history.len() as u64 == st.generation;
        if !consistent {
            return Err(invalid(
                "field `state` is inconsistent (population, ranks, generation and history disagree)".into(),
            ));
        }
        // what no checksum overrides (`resume --force` included)
        super::invariants::check_invariants(&cp.state, cp.archive.as_ref(), path)?;
        Ok((cp, computed, mismatch))
    }
}
