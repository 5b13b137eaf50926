//! The archive of a run: every feasible non-dominated design ever evaluated (not only those
//! that survived into the population), kept in `archive.json` beside the checkpoint, with
//! its hypervolume per generation, which cannot fall (a design leaves the archive only for
//! one that dominates it). The population's hypervolume can dip when crowding selection
//! drops a front member; the archive's is the run's progress.
//!
//! Written before each checkpoint. A run killed after the archive of generation g+1 is
//! written but before its checkpoint re-evaluates generation g+1 identically on resume
//! (same ids, same values), and adding a design twice changes nothing, so the archive of a
//! resumed run equals that of an uninterrupted one.

use super::gripper::GripperInfo;
use crate::fsutil::write_atomic;
use crate::optim::{hypervolume, pareto_ranks, Individual, Nsga2Settings, Nsga2State};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// File name of the archive in a run folder.
pub const ARCHIVE_FILE: &str = "archive.json";

/// Feasible non-dominated designs of a whole run, and the hypervolume per generation.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Archive {
    /// Members, sorted by id.
    pub members: Vec<Individual<GripperInfo>>,
    /// Normalised hypervolume of the archive after each generation (index 0 = generation 1).
    #[serde(serialize_with = "crate::optim::serialize", deserialize_with = "crate::optim::deserialize")]
    pub hv_history: Vec<f64>,
}

impl Archive {
    /// Load `RUN_DIR/archive.json` (empty when absent).
    pub fn load(dir: &Path) -> Result<Self> {
        let p = dir.join(ARCHIVE_FILE);
        match std::fs::read(&p) {
            Ok(b) => serde_json::from_slice(&b).map_err(|source| Error::Json {
                path: p,
                what: "not a valid archive",
                source,
            }),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Archive::default()),
            Err(e) => Err(Error::io(p, "cannot read the archive", e)),
        }
    }

    /// Save atomically.
    pub fn save(&self, dir: &Path) -> Result<()> {
        save_bytes(dir, &self.to_bytes(dir)?)
    }

    /// The bytes [`Archive::save`] writes into `dir` (serialised now, written later by
    /// `save_bytes`).
    pub fn to_bytes(&self, dir: &Path) -> Result<Vec<u8>> {
        serde_json::to_vec(self).map_err(|source| Error::Json {
            path: dir.join(ARCHIVE_FILE),
            what: "cannot serialise the archive",
            source,
        })
    }

    /// Add the feasible designs evaluated in `st`'s last generation, keep the non-dominated
    /// ones, and set the hypervolume of generation `st.generation`.
    pub fn update(&mut self, st: &Nsga2State<GripperInfo>, settings: &Nsga2Settings) {
        for ind in st.last_evaluated.iter().filter(|i| i.eval.cv.is_feasible()) {
            if !self.members.iter().any(|m| m.id == ind.id) {
                let mut c = ind.clone();
                c.eval.info.trajectory = None;
                self.members.push(c);
            }
        }
        let f: Vec<&[f64]> = self.members.iter().map(|m| m.eval.f.as_slice()).collect();
        let rank = pareto_ranks(&f);
        let mut k = 0;
        self.members.retain(|_| {
            k += 1;
            rank[k - 1] == 0
        });
        self.members.sort_by_key(|m| m.id);
        let g = st.generation.max(1) as usize;
        self.hv_history.truncate(g - 1);
        while self.hv_history.len() < g - 1 {
            self.hv_history.push(f64::NAN);
        }
        self.hv_history.push(normalised_hv(&self.members, settings));
    }
}

/// Write archive bytes from [`Archive::to_bytes`] atomically into `dir`.
pub fn save_bytes(dir: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(&dir.join(ARCHIVE_FILE), bytes)
}

/// Hypervolume of designs' minimisation objectives, normalised as the optimiser's progress
/// hypervolume (ideal → 0, reference → 1).
pub fn normalised_hv(members: &[Individual<GripperInfo>], s: &Nsga2Settings) -> f64 {
    if s.hv_ref.is_empty() {
        return f64::NAN;
    }
    let pts: Vec<Vec<f64>> = members
        .iter()
        .map(|p| {
            p.eval.f.iter().enumerate().map(|(k, v)| (v - s.hv_ideal[k]) / (s.hv_ref[k] - s.hv_ideal[k])).collect()
        })
        .collect();
    hypervolume(&pts, &vec![1.0; s.hv_ref.len()])
}
