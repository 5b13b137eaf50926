//! The library's face (what `gripopt::` offers users and the Python package): load a
//! problem, evaluate designs (one, or a batch in parallel), simulate a design in a scene
//! with its trajectory, optimise or resume through a builder ([`Optimiser`]), and read a
//! run folder back ([`RunFolder`]). Everything here is built from the layers below; their
//! own modules are internals (see the crate documentation).
//!
//! For callers that tabulate (the Python package's DataFrames): [`evaluate_rows`] gives a
//! batch as the run's own rows ([`DesignRow`], population.csv's columns) with how the
//! optimiser ranks each design, [`parse_scene`] reads a scene as `--scene` spells it, and
//! [`SAMPLE_COLUMNS`] (with [`FINGER2_COLUMNS`] in the offset scene) / [`POSE_COLUMNS`] name
//! a trajectory's values with their units.

use crate::eval::{EvalOptions, Record, SimulationRecord};
use crate::optim::{Evaluator, Individual, Infeasibility, MooProblem};
use crate::params::{Design, DesignParameters, Problem, SceneKind};
use crate::record::RecordOptions;
use crate::run::{Column, DesignRow, GripperProblem, Progress, RunHooks, RunSpec, RunSummary};
use crate::sim::{Controls, Integration, PoseSample, Sample, SceneSpec, Trajectory};
use crate::{Error, Result};
use rand::SeedableRng;
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
/// over its objects and scenarios until each object's chance constraint is decided —
/// early stop — docs/robust.md).
pub fn evaluate(problem: &Problem, design: &Design, stages: Stages) -> Record {
    crate::eval::evaluate_record(problem, design, &stages.options(problem))
}

/// Evaluate a batch of designs in parallel on `threads` threads (None: all cores): their
/// records, in the order given, the same whatever the thread count.
pub fn evaluate_batch(
    problem: &Problem,
    designs: &[Design],
    stages: Stages,
    threads: Option<usize>,
) -> Result<Vec<Record>> {
    let opts = stages.options(problem);
    let study = crate::eval::Study::of(problem, &opts);
    in_pool(threads, || designs.par_iter().with_max_len(1).map(|x| study.evaluate(x, &opts).record).collect())
}

/// `run` on `threads` threads (None: the current pool, all cores by default).
fn in_pool<T: Send>(threads: Option<usize>, run: impl FnOnce() -> T + Send) -> Result<T> {
    crate::run::check_threads(threads)?;
    Ok(match threads {
        Some(n) => rayon::ThreadPoolBuilder::new().num_threads(n).build()?.install(run),
        None => run(),
    })
}

/// One design of a batch evaluated as a run evaluates it: its row of population.csv, and
/// what the optimiser ranks it by.
#[derive(Debug, Clone, PartialEq)]
pub struct EvaluatedRow {
    /// The row (population.csv's columns; `id` its place in the batch plus the first id,
    /// `generation` 0: not created by a run, `rank` None: not ranked).
    pub row: DesignRow,
    /// The objectives in minimisation form (−max_offset, α, −F̃, t_stab); where one was not
    /// computed, the finite placeholder of MODEL.md §10 (never compared: only feasible
    /// designs are ranked by objectives).
    pub minimised: [f64; 4],
    /// Constrained domination's key (MODEL.md §10): stages not reached (0 = feasible) and
    /// the violation at the failing stage; smaller is better, lexicographically.
    pub infeasibility: Infeasibility,
}

/// Evaluate a batch of designs (ψ in degrees, as written in files) through `stages`, in
/// parallel on `threads` threads (None: all cores), exactly as a run evaluates a
/// generation: each design's row and ranking key, in the order given, the same whatever
/// the thread count. Ids are `first_id`, `first_id + 1`, …
pub fn evaluate_rows(
    problem: &Problem,
    designs: &[DesignParameters],
    first_id: u64,
    stages: Stages,
    threads: Option<usize>,
) -> Result<Vec<EvaluatedRow>> {
    let gp = GripperProblem::with_options(problem.clone(), stages.options(problem));
    // a simulation (ms) is a task of its own, for balance; static evaluations (tens of µs)
    // are split adaptively, in chunks, by rayon
    let max_len = if stages == Stages::All { 1 } else { usize::MAX };
    in_pool(threads, || {
        designs
            .par_iter()
            .enumerate()
            .with_max_len(max_len)
            .map(|(k, d)| {
                let x = d.to_array().to_vec();
                let eval = gp.evaluate(&x);
                let minimised = eval.f.as_slice().try_into().expect("four objectives");
                let infeasibility = eval.cv;
                let ind = Individual { id: first_id + k as u64, generation: 0, x, eval };
                EvaluatedRow { row: DesignRow::of(&ind, None), minimised, infeasibility }
            })
            .collect()
    })
}

/// `n` designs drawn uniformly in `problem`'s bounds from the stream of `seed` (the
/// designs of `gripopt bench static --seed`), ψ in degrees, drawn as they are taken (the
/// caller decides where they go, and so how much memory they take).
pub fn random_designs(problem: &Problem, n: usize, seed: u64) -> impl Iterator<Item = DesignParameters> + '_ {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(move |_| DesignParameters::from_array(&problem.bounds.sample(&mut rng).to_array()))
}

/// A scene as `--scene` spells it: `centred`, `offset:X` or `free[:X]` (the object's
/// offset X in metres; None keeps the problem's), for [`simulate`].
pub fn parse_scene(text: &str) -> Result<(SceneKind, Option<f64>)> {
    let bad = |why: &str| Error::Input(format!("scene `{text}`: {why}"));
    // the offset after `kind:` exactly as written: missing and blank-padded values are
    // refused by name, not read as a number or an empty pair of backticks
    let num = |kind: &str, x: &str| {
        if x.trim().is_empty() {
            return Err(bad(&format!(
                "a number is missing after `{kind}:` (the object offset in metres, e.g. `{kind}:0.002`)"
            )));
        }
        if x.trim() != x {
            return Err(bad(&format!(
                "no blank may surround the number after `{kind}:` (write `{kind}:{}`)",
                x.trim()
            )));
        }
        x.parse::<f64>().map_err(|_| bad(&format!("`{x}` after `{kind}:` is not a number (metres)")))
    };
    match text.trim().split_once(':') {
        None if text.trim() == "centred" => Ok((SceneKind::Centred, None)),
        None if text.trim() == "free" => Ok((SceneKind::Free, None)),
        Some(("offset", x)) => Ok((SceneKind::Offset, Some(num("offset", x)?))),
        Some(("free", x)) => Ok((SceneKind::Free, Some(num("free", x)?))),
        _ => Err(bad("must be centred, offset:X or free[:X] (X in metres)")),
    }
}

/// The values of a grasp [`Sample`] (finger 1, its local frame; finger 2 is its mirror in
/// the centred scene, while the offset scene's finger 2 has its own, [`FINGER2_COLUMNS`]),
/// named as `gripopt simulate --csv` and `replay --csv` name them, with units.
pub const SAMPLE_COLUMNS: [Column; 16] = [
    ("t", "s", "time"),
    ("q11", "rad", "active joint angle q11"),
    ("q21", "rad", "active joint angle q21"),
    ("q11_dot", "rad/s", "its rate"),
    ("q21_dot", "rad/s", "its rate"),
    ("theta2", "rad", "distal phalanx angle θ2"),
    ("delta_1", "m", "penetration of the proximal contact"),
    ("delta_2", "m", "penetration of the distal contact"),
    ("fn_1", "N", "normal force of the proximal contact"),
    ("fn_2", "N", "normal force of the distal contact"),
    ("ft_1", "N", "friction force of the proximal contact (on the finger along t_c)"),
    ("ft_2", "N", "friction force of the distal contact"),
    ("hand_fy", "N", "hand force F_hand,y (raw)"),
    ("filtered_fy", "N", "hand force, filtered"),
    ("energy", "J", "total energy E"),
    ("energy_excess", "J", "E − V*"),
];

/// A [`Sample`]'s values in the order of [`SAMPLE_COLUMNS`].
pub fn sample_values(s: &Sample) -> [f64; 16] {
    [
        s.t,
        s.q[0],
        s.q[1],
        s.qd[0],
        s.qd[1],
        s.theta2,
        s.delta[0],
        s.delta[1],
        s.normal[0],
        s.normal[1],
        s.friction[0],
        s.friction[1],
        s.hand_fy,
        s.filtered_fy,
        s.energy,
        s.energy_excess,
    ]
}

/// Finger 2's own values in an offset-scene trajectory (its mirrored local frame), named
/// as [`SAMPLE_COLUMNS`] names finger 1's with `finger2_` before: after them in
/// `gripopt simulate --scene offset:X --csv`, `replay --csv` of an offset run and the
/// Python trajectories. The centred scene has none (finger 2 is finger 1's mirror).
pub const FINGER2_COLUMNS: [Column; 11] = [
    ("finger2_q11", "rad", "finger 2's q11 (its mirrored frame)"),
    ("finger2_q21", "rad", "finger 2's q21"),
    ("finger2_q11_dot", "rad/s", "its rate"),
    ("finger2_q21_dot", "rad/s", "its rate"),
    ("finger2_theta2", "rad", "finger 2's θ2"),
    ("finger2_delta_1", "m", "penetration of finger 2's proximal contact"),
    ("finger2_delta_2", "m", "penetration of finger 2's distal contact"),
    ("finger2_fn_1", "N", "normal force of finger 2's proximal contact"),
    ("finger2_fn_2", "N", "normal force of finger 2's distal contact"),
    ("finger2_ft_1", "N", "friction force of finger 2's proximal contact (on the finger along its t_c)"),
    ("finger2_ft_2", "N", "friction force of finger 2's distal contact"),
];

/// A grasp trajectory's columns: [`SAMPLE_COLUMNS`], then with `finger2` (the offset
/// scene, where finger 2 moves on its own) [`FINGER2_COLUMNS`].
pub fn trajectory_columns(finger2: bool) -> Vec<Column> {
    let extra = if finger2 { &FINGER2_COLUMNS[..] } else { &[] };
    SAMPLE_COLUMNS.iter().chain(extra).copied().collect()
}

/// A [`Sample`]'s values in the order of [`trajectory_columns`]`(finger2)`: finger 2's NaN
/// where the sample lacks them (a recording of an older gripopt).
pub fn trajectory_row(s: &Sample, finger2: bool) -> Vec<f64> {
    let mut v = sample_values(s).to_vec();
    if finger2 {
        v.extend(s.finger2.map_or([f64::NAN; 11], |f| f.values()));
    }
    v
}

/// The values of a free-scene [`PoseSample`], named as `gripopt simulate
/// --scene free --csv` names them, with units.
pub const POSE_COLUMNS: [Column; 14] = [
    ("t", "s", "time"),
    ("gx", "m", "object centre of mass, x"),
    ("gy", "m", "object centre of mass, y"),
    ("gz", "m", "object centre of mass, z"),
    ("qw", "-", "object orientation quaternion, w"),
    ("qx", "-", "object orientation quaternion, x"),
    ("qy", "-", "object orientation quaternion, y"),
    ("qz", "-", "object orientation quaternion, z"),
    ("tilt_deg", "deg", "object tilt"),
    ("q11_1", "rad", "finger 1: q11"),
    ("q21_1", "rad", "finger 1: q21"),
    ("q11_2", "rad", "finger 2: q11"),
    ("q21_2", "rad", "finger 2: q21"),
    ("energy", "J", "total energy"),
];

/// A [`PoseSample`]'s values in the order of [`POSE_COLUMNS`].
pub fn pose_values(p: &PoseSample) -> [f64; 14] {
    let [a, b, c, d] = p.fingers;
    [p.t, p.g[0], p.g[1], p.g[2], p.q[0], p.q[1], p.q[2], p.q[3], p.tilt.to_degrees(), a, b, c, d, p.energy]
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

#[cfg(test)]
mod tests {
    use super::*;

    fn bottle() -> Problem {
        Problem::load(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).unwrap()
    }

    #[test]
    fn scenes_parse_as_the_cli_spells_them() {
        assert_eq!(parse_scene("centred").unwrap(), (SceneKind::Centred, None));
        assert_eq!(parse_scene("offset:0.002").unwrap(), (SceneKind::Offset, Some(0.002)));
        assert_eq!(parse_scene("free").unwrap(), (SceneKind::Free, None));
        assert_eq!(parse_scene("free:-0.001").unwrap(), (SceneKind::Free, Some(-0.001)));
        for bad in ["offset", "centred:1", "offset:x", "sideways", ""] {
            let e = parse_scene(bad).unwrap_err().to_string();
            assert!(e.contains(&format!("scene `{bad}`")), "{e}");
        }
    }

    /// A batch's rows are each design's own evaluation (its record, one at a time), in
    /// order, numbered from the first id, whatever the thread count; the ranking key is
    /// the verdict's (MODEL.md §10).
    #[test]
    fn batch_rows_are_each_designs_record() {
        let p = bottle();
        let mut xs: Vec<_> = random_designs(&p, 60, 3).collect();
        xs.push(DesignParameters::from_array(&p.nominal.to_array()));
        for stages in [Stages::Static, Stages::All] {
            let one = evaluate_rows(&p, &xs, 7, stages, Some(1)).unwrap();
            assert_eq!(one, evaluate_rows(&p, &xs, 7, stages, Some(2)).unwrap());
            for (k, (x, r)) in xs.iter().zip(&one).enumerate() {
                let rec = evaluate(&p, &x.design(), stages);
                let row = &r.row;
                assert_eq!((row.id, row.generation, row.rank), (7 + k as u64, 0, None));
                assert_eq!(row.design, *x);
                assert_eq!((row.feasible, row.failed_stage), (rec.verdict.feasible, rec.verdict.failed_stage));
                assert_eq!((&row.reason, row.violation), (&rec.verdict.reason, rec.verdict.violation));
                let o = rec.objectives();
                assert_eq!([row.alpha, row.mean_force, row.t_stab], [o[1], o[2], o[3]]);
                assert_eq!(row.max_offset, o[0].filter(|m| *m >= 0.0));
                let short = rec.verdict.failed_stage.map_or(0, |s| 4 - s);
                assert_eq!(r.infeasibility.stages_short, short);
                assert_eq!(r.infeasibility.violation, rec.verdict.violation.unwrap_or(0.0));
                if rec.verdict.feasible {
                    // in minimisation form; t_stab after stage 3 only
                    let sign = [-1.0, 1.0, -1.0, 1.0];
                    for k in 0..4 {
                        if let Some(v) = o[k] {
                            assert_eq!(r.minimised[k], sign[k] * v);
                        }
                    }
                }
                assert!(r.minimised.iter().all(|f| f.is_finite()));
            }
        }
        let all = evaluate_rows(&p, &xs, 0, Stages::All, None).unwrap();
        assert!(all.iter().any(|r| r.row.feasible) && all.iter().any(|r| r.row.failed_stage == Some(1)));
    }

    #[test]
    fn trajectory_values_follow_their_columns() {
        let p = bottle();
        let s = simulate(&p, &p.nominal, None, &Integration::from_solver(&p.solver), &Controls::DIAGNOSTIC).unwrap();
        let x = s.trajectory.samples[s.trajectory.samples.len() / 2];
        let v = sample_values(&x);
        assert_eq!(SAMPLE_COLUMNS.len(), v.len());
        let at = |name: &str| v[SAMPLE_COLUMNS.iter().position(|c| c.0 == name).unwrap()];
        assert_eq!([at("t"), at("q21"), at("fn_2"), at("energy_excess")], [x.t, x.q[1], x.normal[1], x.energy_excess]);
        let f = simulate(
            &p,
            &p.nominal,
            Some((SceneKind::Free, None)),
            &Integration::from_solver(&p.solver),
            &Controls::DIAGNOSTIC,
        )
        .unwrap();
        let q = f.poses[f.poses.len() / 2];
        let v = pose_values(&q);
        let at = |name: &str| v[POSE_COLUMNS.iter().position(|c| c.0 == name).unwrap()];
        assert_eq!(
            [at("gz"), at("qw"), at("tilt_deg"), at("q21_2")],
            [q.g[2], q.q[0], q.tilt.to_degrees(), q.fingers[3]]
        );
    }
}
