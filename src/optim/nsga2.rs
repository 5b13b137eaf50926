//! The generational optimiser, as an argmin `Solver` whose `State` holds everything a run
//! needs to continue: population, ranks, measures, counters and history. Each generation
//! makes as many offspring as the population has members (binary tournaments, then the
//! [`Variation`]) and keeps the best of parents and offspring (the [`Survival`]); with
//! [`Nsga2::nsga2`] (crowding survival, SBX) it is NSGA-II (Deb et al. 2002), with the
//! defaults (hypervolume survival, differential evolution) a generational SMS-EMOA with DE
//! variation (docs/benchmarks.md "Optimiser: selection and variation"). Constraint
//! domination throughout. Variation draws from per-mating ChaCha streams derived from the
//! seed, the generation and the mating index, so a run is fixed by its seed, independent of
//! the thread count, and resumes exactly from a saved state without any RNG state.

use super::evaluator::{Batch, Evaluator, GenTiming};
use super::operators::Operators;
use super::schedule::Scheduled;
use super::survival::{attributes, survive, Normalisation, Survival};
use super::variation::Variation;
use super::{hv::hypervolume, Evaluated, Individual, MooProblem};
use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{Error, Executor, Problem, Solver, State, TerminationReason, TerminationStatus, KV};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// Algorithm settings (everything that changes the result, except the generation count).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Nsga2Settings {
    /// Population size.
    pub pop_size: usize,
    /// Seed of all random streams.
    pub seed: u64,
    /// Variation operators.
    pub operators: Operators,
    /// Eliminate duplicate offspring (re-mutate up to 20 times).
    pub eliminate_duplicates: bool,
    /// Hypervolume normalisation for progress: ideal point (raw objectives).
    #[serde(with = "super::serde_f64")]
    pub hv_ideal: Vec<f64>,
    /// Hypervolume normalisation: reference point (raw objectives); HV is reported for the
    /// normalised objectives (f − ideal)/(ref − ideal) with reference (1, …, 1).
    #[serde(with = "super::serde_f64")]
    pub hv_ref: Vec<f64>,
}

/// The optimiser state: what a checkpoint stores. The serialised fields are declared in
/// sorted order (the checkpoint is canonical JSON, written streaming: run::checkpoint_json).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(bound = "I: Serialize + DeserializeOwned")]
pub struct Nsga2State<I> {
    /// Each member's measure within its front, which the tournaments prefer larger: its
    /// crowding distance ([`Survival::Crowding`]) or its exclusive hypervolume contribution
    /// ([`Survival::Hypervolume`]); ∞ for infeasible members.
    #[serde(with = "super::serde_f64")]
    pub crowding: Vec<f64>,
    /// Evaluations so far.
    pub evaluations: u64,
    /// Number of feasible members, per generation.
    pub feasible_history: Vec<usize>,
    /// Completed generations (1 after the initial population).
    pub generation: u64,
    /// Normalised hypervolume of the feasible non-dominated set, per generation.
    #[serde(with = "super::serde_f64")]
    pub hv_history: Vec<f64>,
    /// Total generations to run.
    pub max_generations: u64,
    /// Next design id.
    pub next_id: u64,
    /// Current population (survivors of the last generation).
    pub population: Vec<Individual<I>>,
    /// Front index of each member.
    pub rank: Vec<usize>,
    /// Individuals evaluated in the last generation (for recorders; not checkpointed).
    #[serde(skip)]
    pub last_evaluated: Vec<Individual<I>>,
    /// Where the last generation's time went (for benchmarks; not checkpointed).
    #[serde(skip)]
    pub timing: GenTiming,
    #[serde(skip)]
    status: TerminationStatus,
    #[serde(skip)]
    counts: HashMap<String, u64>,
    #[serde(skip)]
    time: Option<Duration>,
}

impl<I> Nsga2State<I> {
    /// Members of the first front that are feasible.
    pub fn feasible_front(&self) -> Vec<&Individual<I>> {
        self.population
            .iter()
            .zip(&self.rank)
            .filter(|(p, r)| **r == 0 && p.eval.cv.is_feasible())
            .map(|(p, _)| p)
            .collect()
    }
    /// Set the total number of generations (resume with a new total).
    pub fn with_max_generations(mut self, g: u64) -> Self {
        self.max_generations = g;
        self
    }
}

impl<I> State for Nsga2State<I> {
    type Param = Vec<f64>;
    type Float = f64;

    fn new() -> Self {
        Nsga2State {
            population: vec![],
            rank: vec![],
            crowding: vec![],
            generation: 0,
            max_generations: 1,
            next_id: 0,
            evaluations: 0,
            hv_history: vec![],
            feasible_history: vec![],
            last_evaluated: vec![],
            timing: GenTiming::default(),
            status: TerminationStatus::NotTerminated,
            counts: HashMap::new(),
            time: None,
        }
    }
    fn update(&mut self) {}
    fn get_param(&self) -> Option<&Vec<f64>> {
        self.population.first().map(|p| &p.x)
    }
    fn get_best_param(&self) -> Option<&Vec<f64>> {
        self.feasible_front().first().map(|p| &p.x)
    }
    /// Generations are counted from 1 (the initial population); argmin's iteration count
    /// is the number of generations after the first.
    fn get_max_iters(&self) -> u64 {
        self.max_generations.saturating_sub(1)
    }
    fn increment_iter(&mut self) {}
    fn get_iter(&self) -> u64 {
        self.generation.saturating_sub(1)
    }
    fn get_cost(&self) -> f64 {
        -self.hv_history.last().copied().unwrap_or(0.0)
    }
    fn get_best_cost(&self) -> f64 {
        self.get_cost()
    }
    fn get_target_cost(&self) -> f64 {
        f64::NEG_INFINITY
    }
    fn func_counts<O>(&mut self, problem: &Problem<O>) {
        for (k, v) in problem.counts.iter() {
            self.counts.insert(k.to_string(), *v);
        }
    }
    fn get_func_counts(&self) -> &HashMap<String, u64> {
        &self.counts
    }
    fn time(&mut self, time: Option<Duration>) -> &mut Self {
        self.time = time;
        self
    }
    fn get_time(&self) -> Option<Duration> {
        self.time
    }
    fn get_last_best_iter(&self) -> u64 {
        self.get_iter()
    }
    fn is_best(&self) -> bool {
        true
    }
    fn terminate_with(mut self, reason: TerminationReason) -> Self {
        self.status = TerminationStatus::Terminated(reason);
        self
    }
    fn get_termination_status(&self) -> &TerminationStatus {
        &self.status
    }
    fn get_termination_reason(&self) -> Option<&TerminationReason> {
        match &self.status {
            TerminationStatus::Terminated(r) => Some(r),
            TerminationStatus::NotTerminated => None,
        }
    }
}

/// The optimiser, evaluating each generation's designs with `E` (by default
/// [`Scheduled`]); its survival and variation are the defaults unless set
/// ([`Nsga2::nsga2`]: NSGA-II's).
#[derive(Debug, Clone)]
pub struct Nsga2<E = Scheduled> {
    /// Settings.
    pub settings: Nsga2Settings,
    /// The batch evaluator (what it learns of the designs' costs orders the work only; it
    /// is not part of the state: a resumed run learns again).
    pub evaluator: E,
    /// When set, the run stops after the current generation (its checkpoint is written)
    /// with argmin's `TerminationReason::Interrupt` (ctrl-c, a caller's stop button).
    pub stop: Option<Arc<AtomicBool>>,
    /// How each generation's survivors are chosen (a run keeps the one it started with: a
    /// checkpoint's run options state it).
    pub survival: Survival,
    /// How offspring are made (a run keeps the one it started with, as the survival).
    pub variation: Variation,
}

fn stream(seed: u64, generation: u64, k: u64) -> ChaCha8Rng {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    r.set_stream((generation << 32) ^ k);
    r
}

fn bits(x: &[f64]) -> Vec<u64> {
    x.iter().map(|v| v.to_bits()).collect()
}

/// A small multiply–rotate hasher (FxHash) for the duplicate set: the keys are not
/// adversarial, and SipHash cost more than the rest of a generation's bookkeeping.
#[derive(Default, Clone, Copy)]
struct Fx(u64);
impl std::hash::Hasher for Fx {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for c in bytes.chunks(8) {
            let mut b = [0u8; 8];
            b[..c.len()].copy_from_slice(c);
            self.write_u64(u64::from_le_bytes(b));
        }
    }
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }
}
type FxSet<T> = HashSet<T, std::hash::BuildHasherDefault<Fx>>;

impl Nsga2 {
    /// New solver with the default evaluator.
    pub fn new(settings: Nsga2Settings) -> Self {
        Self::with_evaluator(settings, Scheduled::default())
    }
}

impl<E> Nsga2<E> {
    /// New solver evaluating with `evaluator`.
    pub fn with_evaluator(settings: Nsga2Settings, evaluator: E) -> Self {
        Nsga2 { settings, evaluator, stop: None, survival: Survival::default(), variation: Variation::default() }
    }
    /// Make offspring with `variation`.
    pub fn with_variation(mut self, variation: Variation) -> Self {
        self.variation = variation;
        self
    }
    /// The NSGA-II of the reference implementation (pymoo's): crowding survival, SBX
    /// (`moo-test` validates it against the reference's hypervolume bands).
    pub fn nsga2(self) -> Self {
        self.with_survival(Survival::Crowding).with_variation(Variation::Sbx)
    }
    /// Choose the survivors with `survival`.
    pub fn with_survival(mut self, survival: Survival) -> Self {
        self.survival = survival;
        self
    }
    /// The hypervolume normalisation of the settings, for the survival.
    fn normalisation(&self) -> Normalisation<'_> {
        Normalisation { ideal: &self.settings.hv_ideal, reference: &self.settings.hv_ref }
    }
    /// Stop after the current generation once `flag` is set.
    pub fn stop_on(mut self, flag: Arc<AtomicBool>) -> Self {
        self.stop = Some(flag);
        self
    }

    /// Evaluate a generation's designs with the evaluator and make them individuals
    /// (ids from `first_id`).
    fn evaluate_all<P: MooProblem>(
        &mut self,
        p: &P,
        xs: Vec<Vec<f64>>,
        first_id: u64,
        generation: u64,
    ) -> (Vec<Individual<P::Info>>, GenTiming)
    where
        E: Evaluator<P>,
    {
        let out = self.evaluator.evaluate(p, &Batch { xs: &xs, first_id, generation });
        assert_eq!(out.evaluated.len(), xs.len(), "an evaluator gives one evaluation per design");
        let pop = xs
            .into_iter()
            .zip(out.evaluated)
            .enumerate()
            .map(|(k, (x, eval))| Individual { id: first_id + k as u64, generation, x, eval })
            .collect();
        (pop, out.timing)
    }

    fn normalised_hv<I>(&self, pop: &[Individual<I>], rank: &[usize]) -> f64 {
        let s = &self.settings;
        if s.hv_ref.is_empty() {
            return f64::NAN;
        }
        let pts: Vec<Vec<f64>> = pop
            .iter()
            .zip(rank)
            .filter(|(p, r)| **r == 0 && p.eval.cv.is_feasible())
            .map(|(p, _)| {
                p.eval.f.iter().enumerate().map(|(k, v)| (v - s.hv_ideal[k]) / (s.hv_ref[k] - s.hv_ideal[k])).collect()
            })
            .collect();
        hypervolume(&pts, &vec![1.0; s.hv_ref.len()])
    }

    fn finish_generation<I: Clone>(
        &self,
        mut state: Nsga2State<I>,
        pop: Vec<Individual<I>>,
        rank: Vec<usize>,
        crowd: Vec<f64>,
        evaluated: Vec<Individual<I>>,
    ) -> Nsga2State<I> {
        let t = std::time::Instant::now();
        state.hv_history.push(self.normalised_hv(&pop, &rank));
        state.timing.hv_s = t.elapsed().as_secs_f64();
        state.feasible_history.push(pop.iter().filter(|p| p.eval.cv.is_feasible()).count());
        state.population = pop;
        state.rank = rank;
        state.crowding = crowd;
        state.last_evaluated = evaluated;
        state
    }

    /// Binary tournament between members `a` and `b`: smaller infeasibility key if either is
    /// infeasible; for two feasible members domination, then the larger measure (crowding
    /// distance or hypervolume contribution), then a coin.
    fn tournament<I>(state: &Nsga2State<I>, a: usize, b: usize, rng: &mut ChaCha8Rng) -> usize {
        let (pa, pb) = (&state.population[a].eval, &state.population[b].eval);
        if !(pa.cv.is_feasible() && pb.cv.is_feasible()) {
            return match pa.cv.cmp_key(&pb.cv) {
                std::cmp::Ordering::Less => a,
                std::cmp::Ordering::Greater => b,
                _ => {
                    if rng.random::<bool>() {
                        a
                    } else {
                        b
                    }
                }
            };
        }
        if super::dominates(&pa.f, &pb.f) {
            return a;
        }
        if super::dominates(&pb.f, &pa.f) {
            return b;
        }
        if state.crowding[a] != state.crowding[b] {
            return if state.crowding[a] > state.crowding[b] { a } else { b };
        }
        if rng.random::<bool>() {
            a
        } else {
            b
        }
    }
}

/// A population member from an individual just evaluated ([`MooProblem::member_info`]).
fn member<P: MooProblem>(p: &P, i: &Individual<P::Info>) -> Individual<P::Info> {
    Individual {
        id: i.id,
        generation: i.generation,
        x: i.x.clone(),
        eval: Evaluated { f: i.eval.f.clone(), cv: i.eval.cv, info: p.member_info(&i.eval.info) },
    }
}

/// Tournament candidates: concatenated random permutations of 0..n (each member takes part
/// in about the same number of tournaments), `count` entries.
fn permutation_candidates(rng: &mut ChaCha8Rng, n: usize, count: usize) -> Vec<usize> {
    let mut out = Vec::with_capacity(count + n);
    while out.len() < count {
        let mut p: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            let j = rng.random_range(0..=i);
            p.swap(i, j);
        }
        out.extend(p);
    }
    out.truncate(count);
    out
}

impl<P: MooProblem, E: Evaluator<P>> Solver<P, Nsga2State<P::Info>> for Nsga2<E> {
    fn name(&self) -> &str {
        match (self.survival, self.variation) {
            (Survival::Crowding, Variation::Sbx) => "NSGA-II",
            (Survival::Hypervolume, _) => "hypervolume survival",
            _ => "crowding survival",
        }
    }

    /// Generation 1: a random population (idempotent: a state that already has a
    /// population, e.g. from a checkpoint, is returned unchanged).
    fn init(
        &mut self,
        problem: &mut Problem<P>,
        state: Nsga2State<P::Info>,
    ) -> Result<(Nsga2State<P::Info>, Option<KV>), Error> {
        if !state.population.is_empty() {
            return Ok((state, None));
        }
        let t_start = std::time::Instant::now();
        let p = problem.problem.as_ref().ok_or_else(|| Error::msg("no problem"))?;
        let (lo, hi) = (p.lower().to_vec(), p.upper().to_vec());
        let n = self.settings.pop_size;
        let xs: Vec<Vec<f64>> = (0..n)
            .map(|k| {
                let mut rng = stream(self.settings.seed, 1, k as u64);
                (0..lo.len()).map(|i| lo[i] + rng.random::<f64>() * (hi[i] - lo[i])).collect()
            })
            .collect();
        let (pop, timing) = self.evaluate_all(p, xs, 0, 1);
        *problem.counts.entry("evaluations").or_insert(0) += n as u64;
        let mut state = state;
        state.next_id = n as u64;
        state.evaluations = n as u64;
        state.generation = 1;
        let evaluated = pop;
        let pop: Vec<_> = evaluated.iter().map(|i| member(p, i)).collect();
        let (rank, crowd) = {
            let f: Vec<&[f64]> = pop.iter().map(|p| p.eval.f.as_slice()).collect();
            let cv: Vec<_> = pop.iter().map(|p| p.eval.cv).collect();
            attributes(self.survival, &f, &cv, self.normalisation())
        };
        let mut state = self.finish_generation(state, pop, rank, crowd, evaluated);
        state.timing =
            GenTiming { serial_s: t_start.elapsed().as_secs_f64() - timing.eval_s, hv_s: state.timing.hv_s, ..timing };
        Ok((state, None))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<P>,
        mut state: Nsga2State<P::Info>,
    ) -> Result<(Nsga2State<P::Info>, Option<KV>), Error> {
        let t_start = std::time::Instant::now();
        // the observers have had the last generation's designs: they are not kept while the
        // next one evaluates (with a recording's trajectories they are most of the memory)
        state.last_evaluated = Vec::new();
        let p = problem.problem.as_ref().ok_or_else(|| Error::msg("no problem"))?;
        let (lo, hi) = (p.lower(), p.upper());
        let s = &self.settings;
        let n = s.pop_size;
        let g = state.generation + 1;
        let mut seen: FxSet<Vec<u64>> = if s.eliminate_duplicates {
            state.population.iter().map(|p| bits(&p.x)).collect()
        } else {
            FxSet::default()
        };
        let mut xs: Vec<Vec<f64>> = Vec::with_capacity(n + 1);
        let matings = n.div_ceil(2);
        // candidates for 2 tournaments (of 2) per mating; extra rounds if duplicates force more
        let mut cand_rng = stream(s.seed, g, u32::MAX as u64);
        let mut cand = permutation_candidates(&mut cand_rng, n, 4 * matings);
        let parents: Vec<&[f64]> = state.population.iter().map(|p| p.x.as_slice()).collect();
        let mut k = 0u64;
        while xs.len() < n {
            let mut rng = stream(s.seed, g, k);
            let base = 4 * k as usize;
            if base + 4 > cand.len() {
                cand.extend(permutation_candidates(&mut cand_rng, n, 4 * matings));
            }
            k += 1;
            let a = Self::tournament(&state, cand[base], cand[base + 1], &mut rng);
            let b = Self::tournament(&state, cand[base + 2], cand[base + 3], &mut rng);
            let children = self.variation.offspring(&mut rng, &parents, (a, b), (lo, hi), &s.operators);
            for c in children {
                // duplicates of a member or of an earlier child are dropped and replaced by
                // further matings (after 100 rounds of matings they are accepted)
                if s.eliminate_duplicates && (k as usize) < 100 * matings && !seen.insert(bits(&c)) {
                    continue;
                }
                if xs.len() < n {
                    xs.push(c);
                }
            }
        }
        let (offspring, timing) = self.evaluate_all(p, xs, state.next_id, g);
        *problem.counts.entry("evaluations").or_insert(0) += n as u64;
        state.next_id += n as u64;
        state.evaluations += n as u64;
        state.generation = g;
        let mut merged = std::mem::take(&mut state.population);
        merged.extend(offspring.iter().map(|i| member(p, i)));
        let (keep, rank, crowd) = {
            let f: Vec<&[f64]> = merged.iter().map(|p| p.eval.f.as_slice()).collect();
            let cv: Vec<_> = merged.iter().map(|p| p.eval.cv).collect();
            survive(self.survival, &f, &cv, n, self.normalisation())
        };
        let mut slots: Vec<Option<Individual<P::Info>>> = merged.into_iter().map(Some).collect();
        let pop: Vec<_> = keep.iter().map(|&i| slots[i].take().expect("each survivor once")).collect();
        let mut state = self.finish_generation(state, pop, rank, crowd, offspring);
        state.timing =
            GenTiming { serial_s: t_start.elapsed().as_secs_f64() - timing.eval_s, hv_s: state.timing.hv_s, ..timing };
        Ok((state, None))
    }

    fn terminate(&mut self, state: &Nsga2State<P::Info>) -> TerminationStatus {
        if self.stop.as_ref().is_some_and(|s| s.load(Ordering::SeqCst)) {
            TerminationStatus::Terminated(TerminationReason::Interrupt)
        } else if state.generation >= state.max_generations {
            TerminationStatus::Terminated(TerminationReason::MaxItersReached)
        } else {
            TerminationStatus::NotTerminated
        }
    }
}

/// Run NSGA-II (`solver`, with its evaluator and stop flag) from `state` (a fresh
/// `Nsga2State::new()` or a restored state) until `state.max_generations` in argmin's
/// `Executor`, after `observers` added its observers. Returns the problem and the final
/// state. An observer's [`crate::Error`] comes back as it was; any other executor error
/// becomes [`crate::Error::Optimiser`].
pub fn execute<P, E, O>(
    problem: P,
    solver: Nsga2<E>,
    state: Nsga2State<P::Info>,
    observers: O,
) -> crate::Result<(P, Nsga2State<P::Info>)>
where
    P: MooProblem + 'static,
    P::Info: 'static,
    E: Evaluator<P>,
    O: FnOnce(Executor<P, Nsga2<E>, Nsga2State<P::Info>>) -> Executor<P, Nsga2<E>, Nsga2State<P::Info>>,
{
    use crate::Error as LibError;
    let exec = Executor::new(problem, solver).configure(|_| state).timer(false);
    let exec = observers(exec);
    let mut res =
        exec.run().map_err(|e| e.downcast::<LibError>().unwrap_or_else(|e| LibError::Optimiser(e.to_string())))?;
    let p = res.problem.take_problem().ok_or_else(|| LibError::Optimiser("problem lost".into()))?;
    Ok((p, res.state))
}

/// Add an observer to an executor, called after the initial population and every generation.
pub fn observe<P, E, OBS>(
    exec: Executor<P, Nsga2<E>, Nsga2State<P::Info>>,
    obs: OBS,
) -> Executor<P, Nsga2<E>, Nsga2State<P::Info>>
where
    P: MooProblem,
    E: Evaluator<P>,
    OBS: Observe<Nsga2State<P::Info>> + 'static,
{
    exec.add_observer(obs, ObserverMode::Always)
}
