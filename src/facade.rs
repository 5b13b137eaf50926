//! The library's face (what `gripopt::` offers users and the Python package): load a
//! problem, evaluate designs (one, or a batch in parallel), simulate a design in a scene
//! with its trajectory, optimise or resume through a builder ([`Optimiser`]), and read a
//! run folder back ([`RunFolder`]). Everything here is built from the layers below; their
//! own modules are internals (see the crate documentation).

use crate::eval::{EvalOptions, Record, SimulationRecord};
use crate::optim::Evaluator;
use crate::params::{Design, Problem, SceneKind};
use crate::record::RecordOptions;
use crate::run::{GripperProblem, Progress, RunHooks, RunSpec, RunSummary};
use crate::sim::{Controls, Integration, PoseSample, SceneSpec, Trajectory};
use crate::Result;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// Which stages an evaluation runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stages {
    /// Stages 0–2: kinematics, singularities, statics, form closure (tens of µs).
    Static,
    /// Stages 0–3: and the grasp simulation in the problem's scene (ms).
    All,
}

impl Stages {
    fn options(self, p: &Problem) -> EvalOptions {
        match self {
            Stages::Static => EvalOptions::statics_only(),
            Stages::All => EvalOptions::full(p),
        }
    }
}

/// Evaluate `design` through `stages` of `problem`'s pipeline: its record (the JSON of
/// `gripopt evaluate --json`; for a robust problem with all stages, the robust evaluation
/// over every object and scenario, docs/robust.md).
pub fn evaluate(problem: &Problem, design: &Design, stages: Stages) -> Record {
    crate::eval::evaluate_record(problem, design, &stages.options(problem), None)
}

/// Evaluate a batch of designs in parallel on `threads` threads (None: all cores): their
/// records, in the order given, the same whatever the thread count.
pub fn evaluate_batch(
    problem: &Problem,
    designs: &[Design],
    stages: Stages,
    threads: Option<usize>,
) -> Result<Vec<Record>> {
    crate::run::check_threads(threads)?;
    let opts = stages.options(problem);
    let robust = crate::eval::RobustSetup::of(problem);
    let run = || {
        designs
            .par_iter()
            .with_max_len(1)
            .map(|x| crate::eval::evaluate_record(problem, x, &opts, robust.as_ref()))
            .collect()
    };
    Ok(match threads {
        Some(n) => rayon::ThreadPoolBuilder::new().num_threads(n).build()?.install(run),
        None => run(),
    })
}

/// A design simulated in a scene: its record, and the samples of the simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulation {
    /// The record (the JSON of `gripopt simulate --json`).
    pub record: SimulationRecord,
    /// The grasp's samples (the centred or offset scene; in the free scene, the centred
    /// scene's prediction).
    pub trajectory: Trajectory,
    /// The free scene's object poses (empty in the other scenes).
    pub poses: Vec<PoseSample>,
}

/// Simulate `design` in `problem`'s scene, or in `scene` (kind and object offset; None
/// keeps the problem's offset), with the numerics `integration` (e.g.
/// `Integration::from_solver(&problem.solver)`) and the run controls `controls` (e.g.
/// [`Controls::DIAGNOSTIC`]). The scene is checked as a problem file's `[scene]` is (the
/// free scene needs g_eq = 0); stages 0–2 must pass.
pub fn simulate(
    problem: &Problem,
    design: &Design,
    scene: Option<(SceneKind, Option<f64>)>,
    integration: &Integration,
    controls: &Controls,
) -> Result<Simulation> {
    let p = match scene {
        Some((kind, x_off)) => problem.in_scene(kind, x_off, Path::new("the simulation's scene"))?,
        None => problem.clone(),
    };
    let (mut trajectory, mut poses) = (Trajectory::default(), Vec::new());
    let spec = SceneSpec::of(&p.scene.setup);
    let ev = crate::eval::simulate(design, &p.scene, &spec, integration, controls, &mut (&mut trajectory, &mut poses));
    if ev.scene.is_none() {
        let d = ev.discard.expect("a design that did not reach its scene was discarded");
        return Err(crate::Error::Input(format!(
            "the design is discarded at stage {} ({}); a simulation needs stages 0–2",
            d.stage, d.reason
        )));
    }
    let record = SimulationRecord { record: Record::from_eval(&ev), method: integration.method };
    Ok(Simulation { record, trajectory, poses })
}

/// An optimisation run, set up step by step: a new run ([`Optimiser::new`]) or the resume
/// of one ([`Optimiser::resume`]), then [`Optimiser::run`].
pub struct Optimiser {
    spec: RunSpec,
    resume: Option<Resume>,
    hooks: RunHooks,
}

/// What a resume changes.
struct Resume {
    generations: Option<u64>,
    force: bool,
}

impl Optimiser {
    /// A new run of the problem file `problem` in the run folder `out` (new or empty): by
    /// default a population of 100 for 50 generations, seed 1, all cores, every design and
    /// grasp recorded.
    pub fn new(problem: impl Into<PathBuf>, out: impl Into<PathBuf>) -> Self {
        let spec = RunSpec {
            problem_path: problem.into(),
            out: out.into(),
            pop: 100,
            generations: 50,
            seed: 1,
            threads: None,
            record: RecordOptions::default(),
        };
        Optimiser { spec, resume: None, hooks: RunHooks::default() }
    }
    /// The resume of the run in `dir` (stopped, killed or finished).
    pub fn resume(dir: impl Into<PathBuf>) -> Self {
        let mut o = Self::new(PathBuf::new(), dir);
        o.resume = Some(Resume { generations: None, force: false });
        o
    }
    /// Population size (a new run).
    pub fn pop(mut self, n: usize) -> Self {
        self.spec.pop = n;
        self
    }
    /// Total generations (1 = the initial population; for a resume, the new total).
    pub fn generations(mut self, g: u64) -> Self {
        self.spec.generations = g;
        if let Some(r) = &mut self.resume {
            r.generations = Some(g);
        }
        self
    }
    /// Seed (a new run): it fixes the run.
    pub fn seed(mut self, s: u64) -> Self {
        self.spec.seed = s;
        self
    }
    /// Worker threads (results do not depend on them).
    pub fn threads(mut self, n: usize) -> Self {
        self.spec.threads = Some(n);
        self
    }
    /// What to record to MCAP (a new run).
    pub fn record(mut self, r: RecordOptions) -> Self {
        self.spec.record = r;
        self
    }
    /// Resume even if the problem file or the checkpoint's checksum changed.
    pub fn force(mut self, yes: bool) -> Self {
        if let Some(r) = &mut self.resume {
            r.force = yes;
        }
        self
    }
    /// Report every generation (and notes) to `p`.
    pub fn progress(mut self, p: impl Progress + 'static) -> Self {
        self.hooks.progress = Some(Box::new(p));
        self
    }
    /// Stop after the current generation's checkpoint once `flag` is set.
    pub fn stop_flag(mut self, flag: Arc<AtomicBool>) -> Self {
        self.hooks.stop = Some(flag);
        self
    }
    /// Evaluate each generation with `e` instead of the default scheduler.
    pub fn evaluator(mut self, e: impl Evaluator<GripperProblem> + 'static) -> Self {
        self.hooks.evaluator = Some(Box::new(e));
        self
    }
    /// Run it.
    pub fn run(self) -> Result<RunSummary> {
        match self.resume {
            None => crate::run::optimise_with(&self.spec, self.hooks),
            Some(r) => crate::run::resume_with(&self.spec.out, r.generations, r.force, self.spec.threads, self.hooks),
        }
    }
}
