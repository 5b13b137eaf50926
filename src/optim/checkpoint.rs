//! Checkpoints: the whole optimiser state as JSON, written atomically (temporary file,
//! fsync, rename, fsync of the folder) after every generation, with hashes of the problem
//! file and of the settings so that a resume with changed inputs is refused.

use super::nsga2::{Nsga2Settings, Nsga2State};
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Format tag written into every checkpoint.
pub const FORMAT: &str = "gripopt-checkpoint";
/// Format version.
pub const VERSION: u32 = 1;

/// Checkpoint errors (always naming the file).
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// I/O error.
    #[error("{file}: {err}")]
    Io {
        /// File.
        file: PathBuf,
        /// Error.
        err: std::io::Error,
    },
    /// Not a valid checkpoint.
    #[error("{file}: not a valid gripopt checkpoint: {message}")]
    Invalid {
        /// File.
        file: PathBuf,
        /// What is wrong.
        message: String,
    },
}

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

/// Write `bytes` to `path` atomically: temp file in the same folder, fsync, rename, fsync folder.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), CheckpointError> {
    let io = |err| CheckpointError::Io { file: path.to_path_buf(), err };
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let tmp = dir.join(format!(".{}.tmp", path.file_name().and_then(|s| s.to_str()).unwrap_or("checkpoint")));
    {
        let mut f = std::fs::File::create(&tmp).map_err(io)?;
        f.write_all(bytes).map_err(io)?;
        f.sync_all().map_err(io)?;
    }
    std::fs::rename(&tmp, path).map_err(io)?;
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

impl<I: Serialize + DeserializeOwned> Checkpoint<I> {
    /// Save atomically.
    pub fn save(&self, path: &Path) -> Result<(), CheckpointError> {
        let bytes = serde_json::to_vec(self).map_err(|e| CheckpointError::Invalid { file: path.to_path_buf(), message: e.to_string() })?;
        write_atomic(path, &bytes)
    }

    /// Load and check the format.
    pub fn load(path: &Path) -> Result<Self, CheckpointError> {
        let bytes = std::fs::read(path).map_err(|err| CheckpointError::Io { file: path.to_path_buf(), err })?;
        let head: serde_json::Value = serde_json::from_slice(&bytes)
            .map_err(|e| CheckpointError::Invalid { file: path.to_path_buf(), message: format!("not JSON ({e}); the file may be truncated") })?;
        let fmt = head.get("format").and_then(|v| v.as_str());
        if fmt != Some(FORMAT) {
            return Err(CheckpointError::Invalid { file: path.to_path_buf(), message: format!("field `format` is {fmt:?}, expected \"{FORMAT}\"") });
        }
        let ver = head.get("version").and_then(|v| v.as_u64());
        if ver != Some(VERSION as u64) {
            return Err(CheckpointError::Invalid { file: path.to_path_buf(), message: format!("field `version` is {ver:?}, expected {VERSION}") });
        }
        let cp: Self = serde_json::from_value(head).map_err(|e| CheckpointError::Invalid { file: path.to_path_buf(), message: e.to_string() })?;
        let st = &cp.state;
        let consistent = st.population.len() == cp.settings.pop_size
            && st.rank.len() == st.population.len()
            && st.crowding.len() == st.population.len()
            && st.generation >= 1
            && st.hv_history.len() as u64 == st.generation;
        if !consistent {
            return Err(CheckpointError::Invalid {
                file: path.to_path_buf(),
                message: "field `state` is inconsistent (population, ranks, generation and history disagree)".into(),
            });
        }
        Ok(cp)
    }
}
