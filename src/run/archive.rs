//! The archive of a run: every feasible non-dominated design ever evaluated (not only those
//! that survived into the population), with its hypervolume per generation, which cannot
//! fall (a design leaves the archive only for one that dominates it); and the count of
//! every discard cause over the run ([`Discards`]: what a run without a feasible design
//! says). The population's hypervolume can dip when crowding selection drops a front
//! member; the archive's is the run's progress.
//!
//! The archive is part of each generation's checkpoint (issue 24: a separate archive.json
//! could be lost, restored from an older backup or damaged on its own, and a resume then
//! started an empty archive), so a resumed run's archive is the uninterrupted run's exactly.

use super::gripper::GripperInfo;
use crate::eval::{Cause, Record};
use crate::optim::{hypervolume, pareto_ranks, Individual, Nsga2Settings, Nsga2State};
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
    /// Normalised hypervolume of the archive after each generation (index 0 = generation 1).
    #[serde(serialize_with = "crate::optim::serialize", deserialize_with = "crate::optim::deserialize")]
    pub hv_history: Vec<f64>,
    /// Members, sorted by id.
    pub members: Vec<Individual<I>>,
}

impl<I> Default for Archive<I> {
    fn default() -> Self {
        Archive { members: vec![], hv_history: vec![], discards: Discards::default() }
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
        self.hv_history.truncate(g - 1);
        while self.hv_history.len() < g - 1 {
            self.hv_history.push(f64::NAN);
        }
        self.hv_history.push(normalised_hv(&self.members, settings));
    }
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
