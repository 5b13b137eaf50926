//! `[robust]`: robust multi-object design (issue 22) — the objects a gripper must hold, the
//! uncertain inputs of a grasp, how many scenarios per object and how they are drawn (common
//! random numbers: ChaCha8 streams keyed by (seed, object, scenario), the same scenarios for
//! every design; or a deterministic centre-plus-corners design), how each objective is
//! aggregated over them and the constraint P(object barely moves) ≥ p_min per object.

use super::scene::{ObjectCase, SceneParams};
use super::uncertainty::{Dist, Uncertainty, INPUTS, N_INPUTS};
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

/// Scenario draws of an optimisation (stream 0) and of `verify`'s out-of-sample check (1).
pub const STREAM_OPTIMISE: u64 = 0;
/// The out-of-sample stream of `gripopt verify` on a robust run.
pub const STREAM_VERIFY: u64 = 1;
/// The stream of the certification of a robust run's front (issue 41): scenarios neither
/// the search nor `verify` uses.
pub const STREAM_CERTIFY: u64 = 2;

/// `[robust.certify]`: how a robust run certifies its front on fresh scenarios — a
/// group-sequential one-sided exact binomial test per object of H₀: P(stay) < p_min, at
/// level 1 − `confidence` split evenly over the looks (docs/robust.md, "Certification").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Certify {
    /// Certify the front (false: pareto.csv is the search front, uncertified).
    pub enabled: bool,
    /// 1 − α of the test (e.g. 0.95).
    pub confidence: f64,
    /// Scenarios per object at each look, increasing (e.g. [24, 48]).
    pub looks: Vec<usize>,
}

impl Certify {
    /// The default plan for `p_min` at `confidence`: two looks, the first the fewest
    /// scenarios that can certify an object that stayed in all of them at level α/2
    /// (n₁ = ⌈ln(α/2) / ln p_min⌉), the second twice as many. None when p_min is 0 (nothing
    /// to certify) or 1 (no finite sample certifies).
    pub fn default_looks(p_min: f64, confidence: f64) -> Option<Vec<usize>> {
        if !(p_min > 0.0 && p_min < 1.0) {
            return None;
        }
        let alpha = (1.0 - confidence) / 2.0;
        let n1 = (alpha.ln() / p_min.ln()).ceil().max(1.0) as usize;
        Some(vec![n1, 2 * n1])
    }

    /// Why this plan cannot certify any object at `p_min` (None: it can): at its last look
    /// an object that stayed in every scenario must reject H₀ at α/L, i.e. p_minⁿ ≤ α/L.
    pub fn check(&self, p_min: f64) -> Result<(), String> {
        let Some(&n) = self.looks.last() else {
            return Err("must name at least one look".into());
        };
        let a = (1.0 - self.confidence) / self.looks.len() as f64;
        if p_min >= 1.0 || p_min.powi(n as i32) > a {
            let need = if p_min < 1.0 { format!("{}", (a.ln() / p_min.ln()).ceil()) } else { "infinitely many".into() };
            return Err(format!(
                "cannot certify any design at p_min {p_min}: even {n} of {n} staying leaves P(stay) < p_min possible at level {a:.4} (α {:.3} split over {} looks); the last look needs at least {need} scenarios (or set [robust.certify] enabled = false)",
                1.0 - self.confidence,
                self.looks.len()
            ));
        }
        Ok(())
    }
}

/// How the scenarios are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sampling {
    /// K random draws per object (common random numbers).
    Random,
    /// The centre and every corner of the uncertain inputs' box (1 + 2^d scenarios).
    Corners,
}

/// How one objective is aggregated over an object set's scenarios (in minimisation form,
/// "worse" = larger).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Aggregation {
    /// The worst value.
    Worst,
    /// The arithmetic mean.
    Mean,
    /// The q-quantile in the worse direction (inverted empirical CDF: the smallest value v
    /// such that at least a fraction q of the values are ≤ v; q = 1 is the worst).
    Quantile(f64),
}

impl Aggregation {
    /// Aggregate `v` (minimisation form: larger is worse); NaN for an empty set.
    pub fn apply(&self, v: &[f64]) -> f64 {
        if v.is_empty() {
            return f64::NAN;
        }
        match *self {
            Aggregation::Worst => v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            Aggregation::Mean => v.iter().sum::<f64>() / v.len() as f64,
            Aggregation::Quantile(q) => {
                let mut s = v.to_vec();
                s.sort_by(f64::total_cmp);
                // inverted empirical CDF: the smallest s[j] with (j + 1)/n ≥ q
                let n = s.len();
                let j = (0..n).find(|&j| (j + 1) as f64 >= q * n as f64).unwrap_or(n - 1);
                s[j]
            }
        }
    }
    /// As written in a problem file: "worst", "mean" or the quantile.
    pub fn label(&self) -> String {
        match self {
            Aggregation::Worst => "worst".into(),
            Aggregation::Mean => "mean".into(),
            Aggregation::Quantile(q) => format!("quantile {q}"),
        }
    }
}

/// `[robust]` of a problem file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Robust {
    /// The objects (at least one).
    pub objects: Vec<ObjectCase>,
    /// The uncertain inputs.
    pub uncertainty: Uncertainty,
    /// How the scenarios are chosen.
    pub sampling: Sampling,
    /// K: scenarios per object.
    pub scenarios: usize,
    /// Seed of the scenario streams.
    pub seed: u64,
    /// Aggregation of max_offset, α, F̃, t_stab.
    pub aggregate: [Aggregation; 4],
    /// The constraint P(barely moves) ≥ p_min per object.
    pub p_min: f64,
    /// Level of the P(stay) confidence interval (Clopper–Pearson).
    pub confidence: f64,
    /// Stop a design's scenarios once an object's constraint can no longer be met.
    pub early_stop: bool,
    /// Scenarios per object of `gripopt verify`'s out-of-sample draw.
    pub verify_scenarios: usize,
    /// How the front is certified on fresh scenarios.
    pub certify: Certify,
}

/// One scenario: an object and the values of every uncertain input (nominal where fixed).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Scenario {
    /// Object index (in `objects`).
    pub object: usize,
    /// Scenario index k within the object.
    pub k: usize,
    /// The stream it was drawn from (0: optimisation, 1: verify).
    pub stream: u64,
    /// Each input's value, in the order of [`INPUTS`].
    pub values: [f64; N_INPUTS],
}

impl Scenario {
    /// The scene parameters of this scenario for object `o` of problem scene `base`: the
    /// free scene at the drawn offset, the object's cylinder filled and raised as drawn, the
    /// frictions scaled, the restitution and the grip torque as drawn.
    pub fn scene(&self, base: &SceneParams, o: &ObjectCase) -> SceneParams {
        let mut s = base.clone();
        s.object = o.object;
        s.setup = s.setup.to_free();
        for (row, v) in INPUTS.iter().zip(self.values) {
            (row.apply)(&mut s, o, v);
        }
        s
    }

    /// The value of input `name` (a row of [`INPUTS`]).
    pub fn value(&self, name: &str) -> Option<f64> {
        super::input_slot(name).map(|i| self.values[i])
    }
}

impl Robust {
    /// The nominal value of each input for problem scene `base` (x_off from `[scene]`,
    /// restitution from `[contact]`, no height offset, factors 1: each row's own).
    pub fn nominal_values(base: &SceneParams) -> [f64; N_INPUTS] {
        INPUTS.map(|row| (row.nominal)(base))
    }

    /// Number of scenarios per object of `stream` (the optimisation's K, or verify's count).
    pub fn count(&self, stream: u64) -> usize {
        match (self.sampling, stream) {
            (Sampling::Corners, STREAM_OPTIMISE) => corner_count(self.uncertainty.uncertain().len()),
            (_, STREAM_OPTIMISE) => self.scenarios,
            (_, STREAM_CERTIFY) => self.certify.looks.last().copied().unwrap_or(0),
            _ => self.verify_scenarios,
        }
    }

    /// Scenario `k` of object `object` drawn from `stream` (verify always draws at random).
    pub fn scenario(&self, base: &SceneParams, object: usize, k: usize, stream: u64) -> Scenario {
        let mut values = Self::nominal_values(base);
        if self.sampling == Sampling::Corners && stream == STREAM_OPTIMISE {
            let unc = self.uncertainty.uncertain();
            for (bit, &i) in unc.iter().enumerate() {
                let d = self.uncertainty.inputs[i].as_ref().expect("uncertain");
                let (lo, hi) = d.support();
                values[i] = if k == 0 {
                    d.centre()
                } else if (k - 1) >> bit & 1 == 0 {
                    lo
                } else {
                    hi
                };
            }
        } else {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(self.seed);
            rng.set_stream((stream << 56) ^ ((object as u64) << 32) ^ k as u64);
            for (i, slot) in self.uncertainty.inputs.iter().enumerate() {
                let u: f64 = rng.random();
                if let Some(d) = slot {
                    values[i] = d.at(u);
                }
            }
        }
        Scenario { object, k, stream, values }
    }

    /// Every scenario of `stream`, object-major (object 0's K, then object 1's, …).
    pub fn all_scenarios(&self, base: &SceneParams, stream: u64) -> Vec<Scenario> {
        let n = self.count(stream);
        (0..self.objects.len())
            .flat_map(|o| (0..n).map(move |k| (o, k)))
            .map(|(o, k)| self.scenario(base, o, k, stream))
            .collect()
    }

    /// Largest number of scenarios of an object that may fail while P̂ = stays/K ≥ p_min
    /// still holds (K = `n`).
    pub fn failures_allowed(&self, n: usize) -> usize {
        (0..=n).rev().find(|&f| (n - f) as f64 / n as f64 >= self.p_min).unwrap_or(0)
    }
}

/// Scenarios of a centre-plus-corners design with `d` uncertain inputs.
pub fn corner_count(d: usize) -> usize {
    1 + (1usize << d)
}

/// A distribution's description as written (`uniform [lo, hi]`, …) for messages.
pub fn describe(d: &Dist) -> String {
    match d {
        Dist::Uniform { lo, hi } => format!("uniform [{lo}, {hi}]"),
        Dist::Normal { mean, sd, lo, hi } => format!("normal(mean {mean}, sd {sd}) in [{lo}, {hi}]"),
        Dist::List(v) => format!("list {v:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantile_is_the_inverted_empirical_cdf() {
        let v = [4.0, 1.0, 3.0, 2.0];
        assert_eq!(Aggregation::Quantile(0.5).apply(&v), 2.0);
        assert_eq!(Aggregation::Quantile(0.51).apply(&v), 3.0);
        assert_eq!(Aggregation::Quantile(0.75).apply(&v), 3.0);
        assert_eq!(Aggregation::Quantile(1.0).apply(&v), 4.0);
        assert_eq!(Aggregation::Worst.apply(&v), 4.0);
        assert_eq!(Aggregation::Mean.apply(&v), 2.5);
        assert!(Aggregation::Mean.apply(&[]).is_nan());
    }
}
