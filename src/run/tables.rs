//! The run's designs as its state holds them: the front, archive and population of
//! checkpoint.json, as the rows of the CSV views written from them ([`CheckpointTables`]),
//! with run.json checked against the checkpoint. The views are rewritten every generation
//! and a user may copy an older one in, or edit one; `gripopt show` takes the designs from
//! here and says when a view differs ([`RunFolder::view_differs`]).

use super::archive::reported_front;
use super::attribution::run_json_mismatch;
use super::checkpoint::Checkpoint;
use super::folder::{read_table, RunFolder};
use super::gripper::GripperInfo;
use super::lock::{LockHolder, RunLock};
use super::outputs::DesignRow;
use crate::error::Result;

/// The designs of a run's checkpoint, as pareto.csv, archive.csv and population.csv write
/// them (the same rows, in the same order).
#[derive(Debug, Clone)]
pub struct CheckpointTables {
    /// The checkpoint's generation.
    pub generation: u64,
    /// pareto.csv's rows: the reported front ([`super::reported_front`]), by id (a robust
    /// run certified at this generation: the certified front's rows).
    pub front: Vec<DesignRow>,
    /// archive.csv's rows: every feasible non-dominated design of the run, by id.
    pub archive: Vec<DesignRow>,
    /// population.csv's rows: the whole population, by rank then id.
    pub population: Vec<DesignRow>,
    /// Why run.json does not match the checkpoint (None: it does, or a process runs the run
    /// and run.json follows its checkpoints).
    pub run_json_mismatch: Option<String>,
}

impl RunFolder {
    /// The designs of the run's checkpoint (None: no checkpoint.json yet), checked against
    /// run.json. A damaged or edited checkpoint, or one that is not a regular file, is an
    /// error naming it.
    pub fn checkpoint_tables(&self) -> Result<Option<CheckpointTables>> {
        let path = self.dir().join("checkpoint.json");
        // absent: None; anything else there (a folder, a pipe, a device) is read, and refused
        // naming what it is, never taken for a missing checkpoint
        if std::fs::symlink_metadata(&path).is_err() {
            return Ok(None);
        }
        let info = self.info()?;
        let (cp, sha256) = Checkpoint::<GripperInfo>::load_with_sha256(&path)?;
        super::invariants::check_design_length(
            &cp.state,
            cp.archive.as_ref(),
            &path,
            crate::params::DESIGN_NAMES.len(),
        )?;
        let st = &cp.state;
        let running = matches!(RunLock::holder(self.dir())?, LockHolder::Held(_));
        // a robust run certified at this state reports its certified front (certification.json)
        let certification = super::certify::read_certification(self.dir())?;
        let certified = super::certify_stage::checkpoint_front(certification.as_ref(), st, cp.archive.as_ref());
        let front = certified.unwrap_or_else(|| {
            reported_front(st, cp.archive.as_ref()).into_iter().map(|i| DesignRow::of(i, Some(0))).collect()
        });
        let archive =
            cp.archive.as_ref().map_or(vec![], |a| a.members.iter().map(|i| DesignRow::of(i, None)).collect());
        let mut order: Vec<usize> = (0..st.population.len()).collect();
        order.sort_by_key(|&k| (st.rank[k], st.population[k].id));
        let population = order.into_iter().map(|k| DesignRow::of(&st.population[k], Some(st.rank[k]))).collect();
        Ok(Some(CheckpointTables {
            generation: st.generation,
            front,
            archive,
            population,
            run_json_mismatch: run_json_mismatch(&info, st.generation, &sha256, running),
        }))
    }

    /// Why the view `file` (pareto.csv, archive.csv or population.csv) does not hold `rows`
    /// (the checkpoint's, [`RunFolder::checkpoint_tables`]) byte for byte (None: it does). A
    /// missing or damaged view is an error naming it.
    pub fn view_differs(&self, file: &str, rows: &[DesignRow], generation: u64) -> Result<Option<String>> {
        let path = self.dir().join(file);
        // the damaged or truncated file's error, naming the line
        read_table::<DesignRow>(&path)?;
        let text = crate::fsutil::read_regular_string(&path, crate::fsutil::caps::TABLE)
            .map_err(|e| crate::error::Error::io(&path, "cannot read", e))?;
        let data: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).skip(1).collect();
        let expected: Vec<String> = rows.iter().map(DesignRow::csv_line).collect();
        let same =
            data.len() == expected.len() && data.iter().zip(&expected).all(|(a, b)| *a == b.trim_end_matches('\n'));
        Ok((!same).then(|| {
            format!(
                "{file} does not hold the designs of checkpoint.json (generation {generation}): an older, newer or edited copy; shown: the checkpoint's designs (each design's values as the run evaluated them)"
            )
        }))
    }
}
