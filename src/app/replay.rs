//! `gripopt replay`: a recorded design re-run through its study — the study of the problem
//! its generation was evaluated with (`problem.toml`, or after a forced resume with another
//! problem the earlier `problem-G.toml`, as run.json's `problems` say) — and compared with
//! its recording (the record layer reads it and compares, typed: `record::compare_grasp`,
//! `record::compare_robust`). The design's every scenario here; one scenario of a robust
//! design in `scenario`; the design in another scene ([`design_in_scene`]: nothing to
//! compare); a free-kind design's free scene recorded in `free_scene`.

use crate::error::{Error, Result};
use crate::eval::{EvalOptions, Evaluation, Record, Study};
use crate::params::{Design, Problem, SceneChoice};
use crate::record::{
    compare_grasp, compare_robust, problem_of_generation, read_design, run_recording, AcrossRevisions, Recorded,
};
use crate::run::RunFolder;
use crate::sim::{PoseSample, Trajectory};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// What a single-object free-kind design's replay keeps for recording its free scene: the
/// problem, the re-evaluation and its free scene's poses.
#[derive(Debug, Clone)]
pub struct FreeScene {
    pub(crate) problem: Problem,
    pub(crate) evaluation: Option<Evaluation>,
    pub(crate) poses: Vec<PoseSample>,
}

/// A recorded design re-run and compared with its recording.
#[derive(Debug, Clone)]
pub struct Replay {
    /// What was recorded.
    pub recorded: Recorded,
    /// The re-evaluation equals the recording: its trajectory, selected and rounded as
    /// recorded (bitwise for the same build; else within 1e-12 relative for a
    /// full-resolution recording, within one f32 unit, 1.2e-7 relative, for a compact one),
    /// and its record's values (a robust design: every scenario, bit for bit).
    pub verified: bool,
    /// Largest relative difference found.
    pub max_difference: f64,
    /// Trajectory samples compared.
    pub compared: usize,
    /// Values of the `/designs` record compared with the re-evaluation (failing stage,
    /// reason, violation, objectives, simulation steps and RHS evaluations): what verifies a
    /// design recorded without a trajectory (discarded before stage 3, or a scene whose
    /// trajectory is not recorded).
    pub values_compared: usize,
    /// Verdict recomputed.
    pub recomputed_feasible: bool,
    /// The re-evaluation's record.
    pub fresh: Record,
    /// The run's problem file the design was re-evaluated with (the one its generation was
    /// evaluated with, run.json's `problems`).
    pub problem_file: PathBuf,
    /// Why the re-evaluation cannot verify the recording whatever it gives: the problem
    /// file (the one run.json records) is not the one the design's shard names. A problem
    /// file edited since the run is refused instead ([`replay`]).
    pub problem_note: Option<String>,
    /// For a recording made by another simulator revision that this one does not reproduce
    /// bit for bit: whether the re-evaluation agrees with it within the integration tolerance.
    pub across_revisions: Option<AcrossRevisions>,
    /// The free scene's poses of the re-evaluation (a free-kind design's; empty otherwise).
    pub poses: Vec<PoseSample>,
    /// A single-object free-kind design's free scene, to record (`free_scene`).
    pub(crate) free_scene: Option<FreeScene>,
}

/// Replay design `id` of the run in `dir`: read it, re-run it through the study of its
/// generation's problem with the run's recording options, and compare. A problem file
/// edited since the run used it (its hash is not the one run.json recorded) is refused,
/// naming it, before anything is evaluated (as `resume` refuses it); one that the run
/// recorded but the design's shard does not name is used, and the replay is then not
/// verified ([`Replay::problem_note`]).
pub fn replay(dir: &Path, id: u64) -> Result<Replay> {
    let recorded = read_design(dir, id)?;
    let run = problem_of_generation(dir, recorded.record.generation)?;
    if let Some(why) = run.edited() {
        return Err(Error::RunDir {
            path: run.file,
            message: format!(
                "{why}: restore it to replay design {id} (a replay re-evaluates with the problem the run used)"
            ),
        });
    }
    let run_opts = run_recording(dir)?;
    let problem_note = recorded.problem_sha256.as_deref().filter(|s| *s != run.sha256).map(|shard| {
        format!(
            "{} (sha256 {}) is not the problem design {id} was recorded with (sha256 {}, its shard says)",
            run.file.display(),
            &run.sha256[..12],
            &shard[..shard.len().min(12)]
        )
    });
    let comparable = problem_note.is_none();
    let problem = run.problem;
    let design = recorded.design();
    // the settings the design was evaluated with: a problem without `solver.method` ran
    // RADAU5 before simulator revision 5
    let integration = crate::sim::Integration::of_revision(&problem.solver, recorded.simulator_revision);
    let opts = EvalOptions { integration, ..EvalOptions::full(&problem) };
    let study = Study::of(&problem, &opts);
    let (mut traj, mut poses) = (Trajectory::default(), Vec::new());
    let (fresh, evaluation) = rerun(&study, &design, &opts, &mut (&mut traj, &mut poses));
    let c = if study.is_single() {
        compare_grasp(&recorded, &fresh, &traj.samples, &run_opts, comparable)
    } else {
        // a robust design (docs/robust.md): no trajectory; its scenarios compared instead
        compare_robust(&recorded, &fresh, comparable)
    };
    let free = study.is_single() && problem.scene.setup.kind.is_free() && comparable;
    let free_scene = free.then(|| FreeScene { problem: problem.clone(), evaluation, poses: poses.clone() });
    Ok(Replay {
        verified: c.verified,
        max_difference: c.max_difference,
        compared: c.compared,
        values_compared: c.values_compared,
        recomputed_feasible: fresh.verdict.feasible,
        across_revisions: c.across_revisions,
        recorded,
        fresh,
        problem_file: run.file,
        problem_note,
        poses,
        free_scene,
    })
}

/// Design `x` re-run on `study` (every sample to `sink`): its record, and for the 1 × 1
/// study the evaluation of its one scenario (None where stages 0–2 discarded it).
fn rerun<K: crate::sim::Sink + ?Sized>(
    study: &Study,
    x: &Design,
    opts: &EvalOptions,
    sink: &mut K,
) -> (Record, Option<Evaluation>) {
    if !study.is_single() {
        return (study.evaluate_into(x, opts, sink).record, None);
    }
    let start = study.start(x);
    let ran = start.passed().then(|| study.run_scenario(&start, 0, 0, opts, sink));
    let ev = ran.as_ref().map(|r| r.1);
    let record = study.fold(&start, ran.into_iter().map(|(r, e)| (r, Some(e))).collect()).record;
    (record, ev)
}

impl RunFolder {
    /// Re-run design `id` through its study and compare it with its recording ([`replay`]).
    pub fn replay(&self, id: u64) -> Result<Replay> {
        self.check_run()?;
        let r = replay(self.dir(), id);
        self.check_run()?;
        r
    }
}

/// A recorded design to simulate in another scene than its run's (`replay --scene`): the
/// run's problem in that scene, the design and where it came from.
#[derive(Debug, Clone)]
pub struct DesignInScene {
    /// The run's problem in the scene asked for.
    pub problem: Problem,
    /// The design.
    pub design: Design,
    /// What `replay --scene --json` adds to the simulation's record.
    pub replay: ReplayInScene,
}

/// What `replay --scene` adds to `simulate --json`: where the design came from, and that a
/// different scene cannot be verified.
#[derive(Debug, Clone, Serialize)]
pub struct ReplayInScene {
    /// The run, design and shard.
    pub replay: ReplaySource,
    /// Always null: nothing was compared.
    pub verified: Option<bool>,
    /// Why.
    pub note: String,
}

/// Where a replayed design came from.
#[derive(Debug, Clone, Serialize)]
pub struct ReplaySource {
    /// The run folder.
    pub run_dir: String,
    /// The design id.
    pub design: u64,
    /// The shard it was read from.
    pub file: String,
    /// The run's scene.
    pub recorded_scene: String,
    /// The scene simulated.
    pub scene: String,
}

/// Design `id` of the run in `dir` in `scene` (`label`: where the scene was asked for, as an
/// error names it): None when `scene` is the run's own (its `problem.toml`: kind, and x_off
/// for offset and free, compared as numbers) — a replay then verifies the recording as usual;
/// otherwise the run's problem in that scene and the recorded design, to simulate like
/// `simulate --scene` (a different scene cannot be verified against the recording).
pub fn design_in_scene(dir: &Path, id: u64, scene: SceneChoice, label: &Path) -> Result<Option<DesignInScene>> {
    let folder = RunFolder::open(dir)?;
    let run_problem = folder.problem()?;
    let p = run_problem.in_scene(scene, label)?;
    let (a, b) = (&p.scene.setup, &run_problem.scene.setup);
    if a.same_scene(b) {
        return Ok(None);
    }
    let (ran, recorded) = (a.spelled(), b.spelled());
    let rec = folder.design(id)?;
    let note = format!(
        "design {id} of {} re-simulated in the {ran} scene; the run recorded the {recorded} scene, so a different scene cannot be verified against the recording (nothing compared)",
        crate::error::shell_quote(&dir.to_string_lossy())
    );
    let source = ReplaySource {
        run_dir: dir.display().to_string(),
        design: id,
        file: rec.file.display().to_string(),
        recorded_scene: recorded,
        scene: ran,
    };
    Ok(Some(DesignInScene {
        problem: p,
        design: rec.design(),
        replay: ReplayInScene { replay: source, verified: None, note },
    }))
}
