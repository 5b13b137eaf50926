//! The archive of a run: every feasible non-dominated design ever evaluated (not only those
//! that survived into the population), with its hypervolume per generation, which cannot
//! fall (a design leaves the archive only for one that dominates it); the front the run
//! reports (pareto.csv: [`reported_front`], chosen from the archive); and the count of
//! every discard cause over the run ([`Discards`]: what a run without a feasible design
//! says). The population's hypervolume can dip when the survival drops a front member;
//! the archive's is the run's progress.
//!
//! The archive is part of each generation's checkpoint (issue 24: a separate archive.json
//! could be lost, restored from an older backup or damaged on its own, and a resume then
//! started an empty archive), so a resumed run's archive is the uninterrupted run's exactly.

use super::gripper::GripperInfo;
use crate::eval::{Cause, Record};
use crate::optim::{greedy_subset, hypervolume, pareto_ranks, Individual, Nsga2Settings, Nsga2State};
use serde::{de::DeserializeOwned, Deserialize, Serialize};

/// Feasible non-dominated designs of a whole run, the hypervolume per generation, and the
/// discard causes. Its fields are declared in sorted order (it is written streaming into the
/// checkpoint's canonical JSON: checkpoint_json).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(bound = "I: Serialize + DeserializeOwned")]
pub struct Archive<I = GripperInfo> {
    /// Every design evaluated, counted by what discarded it.
    #[serde(default)]
    pub discards: Discards,
    /// The ids of the reported front (pareto.csv; [`Archive::choose_front`]), ascending;
    /// None in a checkpoint of a gripopt before issue 42, whose pareto.csv reported the
    /// population's feasible front (still reported for it: [`reported_front`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub front: Option<Vec<u64>>,
    /// Normalised hypervolume of the reported front after each generation (index 0 =
    /// generation 1; NaN for the generations of a gripopt before issue 42).
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        serialize_with = "crate::optim::serialize",
        deserialize_with = "crate::optim::deserialize"
    )]
    pub front_hv_history: Vec<f64>,
    /// Normalised hypervolume of the archive after each generation (index 0 = generation 1).
    #[serde(serialize_with = "crate::optim::serialize", deserialize_with = "crate::optim::deserialize")]
    pub hv_history: Vec<f64>,
    /// Members, sorted by id.
    pub members: Vec<Individual<I>>,
}

impl<I> Default for Archive<I> {
    fn default() -> Self {
        Archive {
            members: vec![],
            hv_history: vec![],
            discards: Discards::default(),
            front: None,
            front_hv_history: vec![],
        }
    }
}

/// The designs a run evaluated, counted by the stage and cause that discarded them.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Discards {
    /// Designs evaluated.
    pub evaluated: u64,
    /// One entry per (stage, cause), in the order first seen.
    pub causes: Vec<DiscardCause>,
}

/// The designs discarded at one stage for one cause.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DiscardCause {
    /// The stage (0–3).
    pub stage: u8,
    /// What discarded them (the record's `cause`; written as its word, `unknown` for none).
    #[serde(with = "cause_or_unknown")]
    pub cause: Option<Cause>,
    /// How many.
    pub count: u64,
    /// The one closest to passing (smallest violation; ties: smallest id).
    pub closest: u64,
    /// Its violation (MODEL.md §10 units; null when not finite).
    pub violation: Option<f64>,
    /// Its reason.
    pub reason: String,
    /// Its numbers for the criterion (e.g. the impact energy against its limit), when the
    /// reason does not give them.
    pub detail: Option<String>,
}

/// A discard's cause as its word ([`Cause::as_str`]), `unknown` where the record has none.
mod cause_or_unknown {
    use crate::eval::Cause;
    use serde::de::IntoDeserializer;
    use serde::{Deserialize, Deserializer, Serializer};

    const UNKNOWN: &str = "unknown";

    pub fn serialize<S: Serializer>(c: &Option<Cause>, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(c.map_or(UNKNOWN, Cause::as_str))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Cause>, D::Error> {
        let word = String::deserialize(d)?;
        if word == UNKNOWN {
            return Ok(None);
        }
        Cause::deserialize(IntoDeserializer::<D::Error>::into_deserializer(word.as_str())).map(Some)
    }
}

impl Discards {
    /// Count one evaluated design.
    pub fn add(&mut self, id: u64, r: &Record) {
        self.evaluated += 1;
        let Some(stage) = r.verdict.failed_stage else { return };
        let cause = r.verdict.cause;
        let violation = r.verdict.violation.filter(|v| v.is_finite());
        let at = match self.causes.iter().position(|c| c.stage == stage && c.cause == cause) {
            Some(k) => k,
            None => {
                self.causes.push(DiscardCause {
                    stage,
                    cause,
                    count: 0,
                    closest: id,
                    violation,
                    reason: r.verdict.reason.clone().unwrap_or_default(),
                    detail: detail(r),
                });
                self.causes.len() - 1
            }
        };
        let c = &mut self.causes[at];
        c.count += 1;
        let closer = match (violation, c.violation) {
            (Some(v), Some(w)) => v < w || (v == w && id < c.closest),
            (Some(_), None) => true,
            (None, _) => false,
        };
        if closer {
            c.closest = id;
            c.violation = violation;
            c.reason = r.verdict.reason.clone().unwrap_or_default();
            c.detail = detail(r);
        }
    }

    /// Designs no stage discarded.
    pub fn feasible(&self) -> u64 {
        self.evaluated - self.causes.iter().map(|c| c.count).sum::<u64>()
    }

    /// Why no design is feasible: one line for the run, one per cause (most frequent first,
    /// with the design closest to passing); None when a design was feasible or none was
    /// evaluated.
    pub fn explain(&self) -> Option<Vec<String>> {
        if self.evaluated == 0 || self.feasible() > 0 {
            return None;
        }
        let mut causes: Vec<&DiscardCause> = self.causes.iter().collect();
        causes.sort_by(|a, b| b.count.cmp(&a.count).then(a.stage.cmp(&b.stage)));
        let mut out = vec![format!(
            "no feasible design: {} evaluated {} discarded:",
            if self.evaluated == 1 { "the one design".to_string() } else { format!("all {} designs", self.evaluated) },
            if self.evaluated == 1 { "was" } else { "were" }
        )];
        for c in causes {
            let share = 100.0 * c.count as f64 / self.evaluated as f64;
            let share = if share < 1.0 { "<1".to_string() } else { format!("{share:.0}") };
            let v = c.violation.map_or(String::new(), |v| format!(", violation {}", crate::error::short_num(v, 4)));
            let d = c.detail.as_ref().map_or(String::new(), |d| format!(", {d}"));
            out.push(format!(
                "  {share} % at stage {} by {} ({}): {}; closest to passing: design {}{v}{d}",
                c.stage,
                c.cause.map_or("unknown", Cause::as_str).replace('_', " "),
                crate::error::counted(c.count, "design", "designs"),
                c.reason,
                c.closest
            ));
        }
        Some(out)
    }
}

/// The numbers of the criterion that discarded a design, where its reason has none.
fn detail(r: &Record) -> Option<String> {
    let g = &r.grasp;
    match r.verdict.cause? {
        Cause::Impact => {
            let (e, l) = (g.impact.e_cyl?, g.impact.e_lim?);
            Some(format!("E_cyl {:.3} mJ > E_lim {:.3} mJ", e * 1e3, l * 1e3))
        }
        Cause::StaticForce => Some(format!("static hand-force margin {:.3} N", g.static_force_margin?)),
        Cause::Force => Some(format!("filtered hand-force margin {:.3} N", g.min_force_margin?)),
        _ => None,
    }
}

impl Archive<GripperInfo> {
    /// Add the designs evaluated in `st`'s last generation: count their discard causes,
    /// keep the feasible non-dominated ones, and set the hypervolume of generation
    /// `st.generation`.
    pub fn update(&mut self, st: &Nsga2State<GripperInfo>, settings: &Nsga2Settings) {
        for ind in &st.last_evaluated {
            self.discards.add(ind.id, &ind.eval.info.record);
        }
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
        let hv = normalised_hv::<GripperInfo, _>(&self.members, settings);
        push_at(&mut self.hv_history, g, hv);
        let front = self.choose_front(settings);
        let front_hv = if front.len() == self.members.len() {
            hv
        } else {
            let chosen: Vec<&Individual<GripperInfo>> = self.of_ids(&front);
            normalised_hv::<GripperInfo, _>(&chosen, settings)
        };
        self.front = Some(front);
        push_at(&mut self.front_hv_history, g, front_hv);
    }
}

/// Set `history`'s value of generation `g` (1-based) to `v`: later values dropped (a forced
/// resume from an older checkpoint), missing earlier ones NaN.
fn push_at(history: &mut Vec<f64>, g: usize, v: f64) {
    history.truncate(g - 1);
    while history.len() < g - 1 {
        history.push(f64::NAN);
    }
    history.push(v);
}

/// The most designs the reported front holds: the population size (pareto.csv reports as
/// many designs as the population has members, at most).
pub fn front_cap(s: &Nsga2Settings) -> usize {
    s.pop_size
}

impl<I> Archive<I> {
    /// The reported front: the archive's members when there are at most [`front_cap`] of
    /// them, otherwise the `front_cap` chosen greedily, one at a time, each the member
    /// adding the most normalised hypervolume to those chosen (the hypervolume the run
    /// reports; ties: the lower id); a member outside the reference box adds nothing and is
    /// chosen last. Ids ascending.
    pub fn choose_front(&self, s: &Nsga2Settings) -> Vec<u64> {
        let cap = front_cap(s);
        if self.members.len() <= cap || s.hv_ref.is_empty() {
            return self.members.iter().take(cap).map(|m| m.id).collect();
        }
        let pts: Vec<Vec<f64>> = self.members.iter().map(|m| normalised(&m.eval.f, s)).collect();
        greedy_subset(&pts, &vec![1.0; s.hv_ref.len()], cap).into_iter().map(|k| self.members[k].id).collect()
    }

    /// The members with ids `ids` (ascending), in id order; ids not among them are skipped.
    fn of_ids(&self, ids: &[u64]) -> Vec<&Individual<I>> {
        self.members.iter().filter(|m| ids.binary_search(&m.id).is_ok()).collect()
    }
}

/// The front a run reports (pareto.csv, `gripopt show`, Python's `Run.front`,
/// recording/front.mcap, `gripopt verify`): of a run whose archive chose a front (since
/// issue 42), the archive's designs it chose ([`Archive::choose_front`]: the best
/// non-dominated designs the run found, at most the population size); of an older
/// checkpoint, or one without an archive, the population's feasible non-dominated
/// designs, as its pareto.csv reported them. Sorted by id.
pub fn reported_front<'a, I>(st: &'a Nsga2State<I>, archive: Option<&'a Archive<I>>) -> Vec<&'a Individual<I>> {
    match archive.and_then(|a| a.front.as_ref().map(|f| a.of_ids(f))) {
        Some(front) => front,
        None => {
            let mut f = st.feasible_front();
            f.sort_by_key(|p| p.id);
            f
        }
    }
}

/// Minimisation objectives normalised as the optimiser's progress hypervolume (ideal → 0,
/// reference → 1).
fn normalised(f: &[f64], s: &Nsga2Settings) -> Vec<f64> {
    f.iter().enumerate().map(|(k, v)| (v - s.hv_ideal[k]) / (s.hv_ref[k] - s.hv_ideal[k])).collect()
}

/// Hypervolume of designs' minimisation objectives, normalised as the optimiser's progress
/// hypervolume (ideal → 0, reference → 1).
pub fn normalised_hv<I, M: std::borrow::Borrow<Individual<I>>>(members: &[M], s: &Nsga2Settings) -> f64 {
    if s.hv_ref.is_empty() {
        return f64::NAN;
    }
    let pts: Vec<Vec<f64>> = members.iter().map(|p| normalised(&p.borrow().eval.f, s)).collect();
    hypervolume(&pts, &vec![1.0; s.hv_ref.len()])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::{Evaluated, Infeasibility, Operators};

    /// The reported front of an archive larger than the population: the greedy choice
    /// (checked step by step against hypervolume differences), within 1 − 1/e of the best
    /// subset of that size (every subset measured), sorted by id; a smaller archive is
    /// reported whole.
    #[test]
    fn the_front_is_the_greedy_hypervolume_choice() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let settings = |pop: usize| Nsga2Settings {
            pop_size: pop,
            seed: 1,
            operators: Operators::default(),
            eliminate_duplicates: true,
            hv_ideal: vec![0.0, 0.0, 0.0],
            hv_ref: vec![2.0, 2.0, 2.0],
        };
        let members: Vec<Individual<()>> = (0..12)
            .map(|k| {
                let p: Vec<f64> = (0..3).map(|_| rng.random_range(0.05..1.0)).collect();
                let s = p.iter().map(|v| v * v).sum::<f64>().sqrt();
                // raw objectives twice the unit sphere's: normalised, on the sphere
                let f = p.iter().map(|v| 2.0 * v / s).collect();
                Individual {
                    id: 10 + 3 * k,
                    generation: 1,
                    x: vec![],
                    eval: Evaluated { f, cv: Infeasibility::FEASIBLE, info: () },
                }
            })
            .collect();
        let archive = Archive { members: members.clone(), ..Archive::default() };
        let pts: Vec<Vec<f64>> = members.iter().map(|m| m.eval.f.iter().map(|v| v / 2.0).collect()).collect();
        let hv_of = |idx: &[usize]| hypervolume(&idx.iter().map(|&i| pts[i].clone()).collect::<Vec<_>>(), &[1.0; 3]);
        let front = archive.choose_front(&settings(4));
        let chosen: Vec<usize> = front.iter().map(|id| members.iter().position(|m| m.id == *id).unwrap()).collect();
        // the plain greedy, by hypervolume differences
        let mut greedy: Vec<usize> = vec![];
        for _ in 0..4 {
            let gain = |i: usize| hv_of(&[greedy.clone(), vec![i]].concat()) - hv_of(&greedy);
            let best = (0..12).filter(|i| !greedy.contains(i)).max_by(|&a, &b| gain(a).total_cmp(&gain(b))).unwrap();
            greedy.push(best);
        }
        greedy.sort_unstable();
        assert_eq!(chosen, greedy);
        let mut best = 0.0f64;
        for mask in 0u32..(1 << 12) {
            if mask.count_ones() == 4 {
                best = best.max(hv_of(&(0..12).filter(|k| mask & (1 << k) != 0).collect::<Vec<_>>()));
            }
        }
        let ours = hv_of(&chosen);
        assert!(ours >= (1.0 - (-1.0f64).exp()) * best && ours <= best + 1e-15, "{ours} of the best {best}");
        assert!(front.windows(2).all(|w| w[0] < w[1]), "ids ascending: {front:?}");
        assert_eq!(archive.choose_front(&settings(12)), members.iter().map(|m| m.id).collect::<Vec<_>>());
    }
}
