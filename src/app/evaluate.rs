//! Evaluating designs on their problem's study ([`crate::eval::Study::of`]: a robust
//! problem's objects and scenarios, or its one object in its scene): one design's record
//! (`gripopt evaluate`, Python's `Problem.record`), a batch of records in parallel, or a batch
//! as a run evaluates a generation — its rows and the optimiser's ranking key (Python's
//! `Problem.evaluate`, the pymoo problem, the Dask chunks).

use crate::error::{Error, Result};
use crate::eval::{EvalOptions, EvaluationRecord, Record, Study};
use crate::optim::{Individual, Infeasibility, MooProblem};
use crate::params::{Design, DesignParameters, Problem};
use crate::run::{DesignRow, GripperProblem, RobustColumns, OBJECT_COLUMNS, ROBUST_COLUMNS};
use crate::sim::Sink;
use rand::SeedableRng;
use rayon::prelude::*;

/// Which stages an evaluation runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stages {
    /// Stages 0–2: kinematics, singularities, statics, form closure (tens of µs).
    Static,
    /// Stages 0–3: and the grasp simulation in the problem's scene (ms).
    All,
}

impl Stages {
    /// `Static` when `static_only` (`--static-only`, `static_only=True`), else `All`.
    pub fn of(static_only: bool) -> Self {
        if static_only {
            Stages::Static
        } else {
            Stages::All
        }
    }
    /// The evaluation options of these stages for problem `p`.
    pub(crate) fn options(self, p: &Problem) -> EvalOptions {
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
    evaluate_into(problem, design, stages, &mut ())
}

/// [`evaluate`], every simulation's samples and events given to `sink` (the CLI's progress
/// of a long simulation).
pub fn evaluate_into<K: Sink + ?Sized>(problem: &Problem, design: &Design, stages: Stages, sink: &mut K) -> Record {
    let opts = stages.options(problem);
    Study::of(problem, &opts).evaluate_into(design, &opts, sink).record
}

/// `record` of `problem` through `stages` as `gripopt evaluate --json` prints it (with the
/// integration method where stage 3 ran with another than the default).
pub fn evaluation_record<'a>(problem: &Problem, record: &'a Record, stages: Stages) -> EvaluationRecord<'a> {
    EvaluationRecord::new(record, problem.solver.method, stages == Stages::All)
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
    let study = Study::of(problem, &opts);
    in_pool(threads, || designs.par_iter().with_max_len(1).map(|x| study.evaluate(x, &opts).record).collect())
}

/// `run` on `threads` threads (None: the current pool, all cores by default).
pub(crate) fn in_pool<T: Send>(threads: Option<usize>, run: impl FnOnce() -> T + Send) -> Result<T> {
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

/// A row with the columns every row of a batch of `problem` through `stages` has (the
/// nominal design's stages 0–2, and a robust problem's columns where `stages` runs its
/// scenarios, every value of those missing): the columns of an empty batch, which are those
/// of any other.
pub fn row_template(problem: &Problem, stages: Stages) -> Result<DesignRow> {
    let nominal = [DesignParameters::from_array(&problem.nominal.to_array())];
    let template = evaluate_rows(problem, &nominal, 0, Stages::Static, Some(1))?;
    let mut row = template.into_iter().next().ok_or_else(|| Error::Input("no template row".into()))?.row;
    if let (Some(robust), Stages::All) = (&problem.robust, stages) {
        let design = ROBUST_COLUMNS.iter().map(|c| (c.0.to_string(), None));
        let objects = robust
            .objects
            .iter()
            .flat_map(|o| OBJECT_COLUMNS.iter().map(move |c| (format!("{}.{}", o.name, c.0), None)));
        row.robust = RobustColumns(design.chain(objects).collect());
    }
    Ok(row)
}

/// `n` designs drawn uniformly in `problem`'s bounds from the stream of `seed` (the
/// designs of `gripopt bench static --seed`), ψ in degrees, drawn as they are taken (the
/// caller decides where they go, and so how much memory they take).
pub fn random_designs(problem: &Problem, n: usize, seed: u64) -> impl Iterator<Item = DesignParameters> + '_ {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(move |_| DesignParameters::from_array(&problem.bounds.sample(&mut rng).to_array()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bottle() -> Problem {
        Problem::load(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).unwrap()
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
}
