//! Checkpoints: the whole optimiser state as JSON, written atomically (temporary file,
//! fsync, rename, fsync of the folder) after every generation, with hashes of the problem
//! file and of the settings so that a resume with changed inputs is refused.

use crate::{Error, Result};
use crate::fsutil::write_atomic;
use crate::optim::{Nsga2Settings, Nsga2State};
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::Path;

/// Format tag written into every checkpoint.
pub const FORMAT: &str = "gripopt-checkpoint";
/// Format version.
pub const VERSION: u32 = 1;

/// A checkpoint file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(bound = "I: Serialize + DeserializeOwned")]
pub struct Checkpoint<I> {
    /// Always [`FORMAT`].
    pub format: String,
    /// Always [`VERSION`].
    pub version: u32,
    /// SHA-256 of the problem file's text.
    pub problem_hash: String,
    /// SHA-256 of the canonical JSON of the settings (and run options).
    pub settings_hash: String,
    /// Algorithm settings.
    pub settings: Nsga2Settings,
    /// Run options that change the outcome besides the algorithm settings.
    pub options: serde_json::Value,
    /// Optimiser state after the last completed generation.
    pub state: Nsga2State<I>,
    /// Wall time spent so far (s).
    pub wall_s: f64,
}

/// SHA-256 hex of bytes.
pub fn sha256_hex(data: &[u8]) -> String {
    let d = Sha256::digest(data);
    d.iter().map(|b| format!("{b:02x}")).collect()
}

/// Hash of settings and options (canonical JSON).
pub fn settings_hash(settings: &Nsga2Settings, options: &serde_json::Value) -> String {
    let v = serde_json::json!({ "settings": settings, "options": options });
    sha256_hex(serde_json::to_string(&v).expect("serialisable").as_bytes())
}

impl<I: Serialize + DeserializeOwned> Checkpoint<I> {
    /// A checkpoint of `state` in the current format, with the hash of `settings` and `options`.
    pub fn new(problem_hash: String, settings: Nsga2Settings, options: serde_json::Value, state: Nsga2State<I>, wall_s: f64) -> Self {
        let settings_hash = settings_hash(&settings, &options);
        Checkpoint { format: FORMAT.into(), version: VERSION, problem_hash, settings_hash, settings, options, state, wall_s }
    }

    /// Save atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        let bytes = serde_json::to_vec(self).map_err(|source| Error::Json { path: path.to_path_buf(), what: "cannot serialise the checkpoint", source })?;
        write_atomic(path, &bytes)
    }

    /// Load and check the format.
    pub fn load(path: &Path) -> Result<Self> {
        let invalid = |message: String| Error::Checkpoint { file: path.to_path_buf(), message };
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, "cannot read the checkpoint", e))?;
        let head: serde_json::Value =
            serde_json::from_slice(&bytes).map_err(|source| Error::Json { path: path.to_path_buf(), what: "not a valid gripopt checkpoint: not JSON; the file may be truncated", source })?;
        let fmt = head.get("format").and_then(|v| v.as_str());
        if fmt != Some(FORMAT) {
            return Err(invalid(format!("field `format` is {fmt:?}, expected \"{FORMAT}\"")));
        }
        let ver = head.get("version").and_then(|v| v.as_u64());
        if ver != Some(VERSION as u64) {
            return Err(invalid(format!("field `version` is {ver:?}, expected {VERSION}")));
        }
        let cp: Self = serde_json::from_value(head).map_err(|source| Error::Json { path: path.to_path_buf(), what: "not a valid gripopt checkpoint", source })?;
        let st = &cp.state;
        let consistent = st.population.len() == cp.settings.pop_size
            && st.rank.len() == st.population.len()
            && st.crowding.len() == st.population.len()
            && st.generation >= 1
            && st.hv_history.len() as u64 == st.generation;
        if !consistent {
            return Err(invalid("field `state` is inconsistent (population, ranks, generation and history disagree)".into()));
        }
        Ok(cp)
    }
}
