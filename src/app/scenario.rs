//! `gripopt replay RUN_DIR --design ID --scenario OBJECT:K` (issue 22): one scenario of a
//! robust design re-simulated — its inputs re-drawn from the problem its generation was
//! evaluated with (the same common-random-number stream; after a forced resume that changed
//! the problem, the earlier file run.json names), stage 3 exactly as the optimisation ran it
//! — and compared with what the recording's `/designs` message says of that scenario; the
//! free scene's poses are recorded to `RUN_DIR/scenario-ID-OBJECT-K.mcap` (band 3 of the
//! run's time axis) so the scenario can be watched in Foxglove with the verify layout.

use crate::error::{Error, Result};
use crate::eval::{EvalOptions, Record, ScenarioRecord, Study};
use crate::run::{row_of, RunFolder, RunLock, VerifyRecording};
use crate::sim::PoseSample;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// A replayed scenario.
#[derive(Debug, Clone, Serialize)]
pub struct ScenarioReplay {
    /// Design id.
    pub id: u64,
    /// Object name.
    pub object: String,
    /// Scenario index within the object.
    pub k: usize,
    /// What the re-simulation gives (inputs and outcome).
    pub scenario: ScenarioRecord,
    /// What the recording says of this scenario (None: the design's scenarios stopped
    /// early before it, or the run recorded no robust record).
    pub recorded: Option<ScenarioRecord>,
    /// The re-simulation equals the recording (None: nothing recorded to compare).
    pub verified: Option<bool>,
    /// The scenario's evaluation record (the free kind: the centred grasp and the free scene).
    pub record: Record,
    /// The recording written (None: not asked, or nothing to record).
    pub recording: Option<PathBuf>,
    /// Why nothing was recorded although asked (the scenario never reached the free
    /// scene: there is no motion of the free object to record).
    pub not_recorded: Option<String>,
    /// The free object's poses (not serialised).
    #[serde(skip)]
    pub poses: Vec<PoseSample>,
}

/// Which scenario of which design of which run.
struct ScenarioAt<'a> {
    dir: &'a Path,
    id: u64,
    object: &'a str,
    o: usize,
    k: usize,
}

/// Record the scenario `at` (its verify row and free-scene poses, in the scenario's own
/// problem `ps`) to `RUN_DIR/scenario-ID-OBJECT-K.mcap`, in its window of band 3; an existing
/// file is replaced only when this run's replay of this scenario wrote it.
fn record_scenario(
    at: &ScenarioAt<'_>,
    study: &Study,
    ps: &crate::params::Problem,
    row: crate::run::VerifyRow,
    poses: &[PoseSample],
) -> Result<PathBuf> {
    let ScenarioAt { dir, id, object, o, k } = *at;
    let name = format!("scenario-{id}-{object}-{k}.mcap");
    let what = format!("design {id} scenario {object}:{k}");
    let window = crate::record::scenario_window(id, o, k, study.objects(), study.k);
    // the scenario's hand height is the object's grasp height + its drawn height offset
    let sc = study.scenario(o, k);
    let tag = crate::record::ScenarioTag {
        object: object.to_string(),
        index: k as u64,
        grasp_height: study.objects[o].scene.object.grasp_height,
        height_offset: sc.scenario.value("height_offset").unwrap_or(0.0),
    };
    let r = VerifyRecording::for_scenario(dir, &name, what.clone(), window, tag)?;
    // replaced only when this run's replay of this scenario wrote it: same epoch (the run's
    // start, in every file of its time axis) and the same source
    let epoch = r.opts.epoch_s;
    let desc = format!("the recording `replay --scenario {object}:{k}` wrote for this run (epoch {epoch})");
    super::free_scene::check_ours(&dir.join(&name), &desc, |m| {
        let (e, src) = (m.epoch_s, m.source.as_deref());
        if e == Some(epoch) && src == Some(what.as_str()) {
            Ok(())
        } else {
            Err(format!(
                "written by another run or command (epoch {}, source {:?})",
                e.map_or("none".to_string(), |e| e.to_string()),
                src.unwrap_or("none")
            ))
        }
    })?;
    let kept = crate::record::keep_poses(poses, r.opts.scene_dt);
    r.write(ps, vec![(row, kept)])
}

/// Parse `OBJECT:K`.
pub fn parse_scenario(arg: &str) -> Result<(String, usize)> {
    let bad = || {
        Error::Input(format!(
            "--scenario {arg}: expected OBJECT:K, e.g. can:3 (an object of the run's [robust] and a scenario index)"
        ))
    };
    let (o, k) = arg.rsplit_once(':').ok_or_else(bad)?;
    Ok((o.to_string(), k.parse().map_err(|_| bad())?))
}

/// Replay scenario `k` of object `object` of design `id` of the robust run in `dir`;
/// `record`: write its MCAP.
///
/// With `record`, the run folder's lock is held throughout (a run resumed, or verified, in
/// it meanwhile is refused, and a replay while one runs is refused: [`Error::Locked`]).
pub fn replay_scenario(dir: &Path, id: u64, object: &str, k: usize, record: bool) -> Result<ScenarioReplay> {
    let folder = RunFolder::open(dir)?;
    // it writes into the run folder: under its lock, as verify does
    let _lock = if record { Some(RunLock::acquire(dir)?) } else { None };
    let not_robust = |file: PathBuf| Error::RunDir {
        path: file,
        message: "not a robust problem (no [robust]): --scenario needs one".into(),
    };
    let (p, file) = folder.problem_in_force()?;
    if p.robust.is_none() {
        return Err(not_robust(file));
    }
    let rec = folder.design(id)?;
    // the problem the design's generation was evaluated with (issue 44 class 5)
    let (p, file) = folder.problem_file_of_generation(rec.record.generation)?;
    if p.robust.is_none() {
        return Err(not_robust(file));
    }
    // the settings the design was evaluated with (before simulator revision 5 a problem
    // without `solver.method` ran RADAU5)
    let integration = crate::sim::Integration::of_revision(&p.solver, rec.simulator_revision);
    let opts = EvalOptions { integration, ..EvalOptions::full(&p) };
    let study = Study::of(&p, &opts);
    let names: Vec<&str> = (0..study.objects()).filter_map(|o| study.object_name(o)).collect();
    let o = names.iter().position(|n| *n == object).ok_or_else(|| {
        Error::Input(format!("--scenario {object}:{k}: no object {object:?} (the run's objects: {})", names.join(", ")))
    })?;
    if k >= study.k {
        return Err(Error::Input(format!(
            "--scenario {object}:{k}: the run has scenarios 0 to {} per object",
            study.k - 1
        )));
    }
    let design = rec.design();
    let start = study.start(&design);
    if let Some(d) = &start.discard {
        let (stage, why) = (d.stage(), d.reason(&study));
        return Err(Error::Input(format!("design {id} is discarded at stage {stage} ({why}): it has no scenarios")));
    }
    let mut poses: Vec<PoseSample> = vec![];
    let (scenario, ev) = study.run_scenario(&start, o, k, &opts, &mut poses);
    let recorded = rec.scenario(o, k).cloned();
    // compared as written: the solver's account (`abort`) is not in the recording
    let verified = recorded.as_ref().map(|r| *r == scenario.as_written());
    let row = row_of(id, &design, &ev);
    let not_recorded = (record && row.is_none()).then(|| {
        format!(
            "nothing recorded: the scenario never reached the free scene (it ended with cause `{}`), so there is no motion of the object to record",
            scenario.cause.map_or("?", |c| c.as_str())
        )
    });
    let recording = match (record, row) {
        (true, Some(row)) => {
            let at = ScenarioAt { dir, id, object, o, k };
            let mut ps = p.clone();
            ps.scene = study.scenario(o, k).scene.clone();
            Some(record_scenario(&at, &study, &ps, row, &poses)?)
        }
        _ => None,
    };
    Ok(ScenarioReplay {
        id,
        object: object.to_string(),
        k,
        scenario,
        recorded,
        verified,
        record: Record::from_eval(&ev),
        recording,
        not_recorded,
        poses,
    })
}
