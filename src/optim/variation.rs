//! Variation: how a mating's two tournament winners become two offspring.
//!
//! - [`Variation::Sbx`] (NSGA-II's, as in the reference implementation): simulated binary
//!   crossover of the two winners, then polynomial mutation of each child;
//! - [`Variation::DifferentialEvolution`] (the default): each winner `x` becomes one child
//!   `x + F·(x_r1 − x_r2)`, `r1 ≠ r2` two other members drawn from the population, each
//!   variable taken from that vector with probability CR (one variable, drawn, always: the
//!   binomial crossover of DE/rand/1/bin with `x` as target and base), a value beyond a
//!   bound replaced by one drawn between the bound and `x`'s value; then polynomial
//!   mutation. The difference of two members scales the step to the population's spread
//!   and follows its correlations (the gripper's variables are strongly coupled), where SBX
//!   acts on each variable alone.
//!
//! Every draw comes from the mating's own stream, so offspring are fixed by the seed, the
//! generation and the mating index.

use super::operators::{polynomial_mutation, sbx, Operators};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// How offspring are made (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Variation {
    /// SBX then polynomial mutation, with the settings' [`Operators`] (NSGA-II's; gripopt's
    /// variation before issue 42).
    Sbx,
    /// Differential evolution (DE/rand/1/bin with the winner as target and base), then
    /// polynomial mutation with the settings' [`Operators`].
    DifferentialEvolution {
        /// Scale factor F of the difference vector.
        f: f64,
        /// Crossover rate CR: the probability that a variable is taken from the mutant.
        cr: f64,
    },
}

impl Default for Variation {
    /// Differential evolution with F = 0.5, CR = 0.5 (docs/benchmarks.md: "Optimiser:
    /// selection and variation").
    fn default() -> Self {
        Variation::DifferentialEvolution { f: 0.5, cr: 0.5 }
    }
}

impl Variation {
    /// Its name in reports.
    pub fn describe(&self) -> String {
        match self {
            Variation::Sbx => "SBX + polynomial mutation".into(),
            Variation::DifferentialEvolution { f, cr } => {
                format!("DE/rand/1/bin (F {f}, CR {cr}) + polynomial mutation")
            }
        }
    }

    /// The two children of the winners `a` and `b` (indices into `pop`, the decision vectors
    /// of the population), within the bounds `lo`, `hi`.
    pub fn offspring(
        &self,
        rng: &mut ChaCha8Rng,
        pop: &[&[f64]],
        (a, b): (usize, usize),
        (lo, hi): (&[f64], &[f64]),
        op: &Operators,
    ) -> [Vec<f64>; 2] {
        let (mut c1, mut c2) = match *self {
            Variation::Sbx => sbx(rng, pop[a], pop[b], lo, hi, op),
            Variation::DifferentialEvolution { f, cr } => {
                (de_child(rng, pop, a, lo, hi, f, cr), de_child(rng, pop, b, lo, hi, f, cr))
            }
        };
        polynomial_mutation(rng, &mut c1, lo, hi, op);
        polynomial_mutation(rng, &mut c2, lo, hi, op);
        [c1, c2]
    }
}

/// One DE child of member `t` (see the module documentation).
fn de_child(rng: &mut ChaCha8Rng, pop: &[&[f64]], t: usize, lo: &[f64], hi: &[f64], f: f64, cr: f64) -> Vec<f64> {
    let n = pop.len();
    let x = pop[t];
    // two other members (fewer than three members: the difference is zero)
    let (r1, r2) = if n >= 3 {
        let r1 = loop {
            let r = rng.random_range(0..n);
            if r != t {
                break r;
            }
        };
        let r2 = loop {
            let r = rng.random_range(0..n);
            if r != t && r != r1 {
                break r;
            }
        };
        (r1, r2)
    } else {
        (t, t)
    };
    let always = rng.random_range(0..x.len().max(1));
    (0..x.len())
        .map(|j| {
            let take = rng.random::<f64>() < cr;
            if !(take || j == always) {
                return x[j];
            }
            let v = x[j] + f * (pop[r1][j] - pop[r2][j]);
            if v < lo[j] {
                lo[j] + rng.random::<f64>() * (x[j] - lo[j])
            } else if v > hi[j] {
                x[j] + rng.random::<f64>() * (hi[j] - x[j])
            } else {
                v
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// Without mutation a DE child differs from its target by F times the difference of two
    /// other members in the variables it took (CR = 1: all of them), and stays in bounds.
    #[test]
    fn de_children_are_difference_steps_within_bounds() {
        // within [0.4, 0.6]: half a difference never leaves the unit box
        let members: Vec<Vec<f64>> = (0..6).map(|k| vec![0.4 + 0.04 * k as f64, 0.5, 0.6 - 0.04 * k as f64]).collect();
        let pop: Vec<&[f64]> = members.iter().map(|m| m.as_slice()).collect();
        let (lo, hi) = (vec![0.0; 3], vec![1.0; 3]);
        let no_mutation = Operators { p_mut: 0.0, ..Operators::default() };
        let de = Variation::DifferentialEvolution { f: 0.5, cr: 1.0 };
        for seed in 0..50 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let [c, _] = de.offspring(&mut rng, &pop, (2, 3), (&lo, &hi), &no_mutation);
            let step: Vec<f64> = c.iter().zip(&members[2]).map(|(a, b)| (a - b) / 0.5).collect();
            // the step is a difference of two members: (0.04 (i − j), 0, −0.04 (i − j)), i ≠ j
            assert!(step[1].abs() < 1e-12, "{step:?}");
            assert!((step[0] + step[2]).abs() < 1e-12 && step[0].abs() > 0.03, "{step:?}");
            assert!(c.iter().zip(&lo).zip(&hi).all(|((v, l), h)| v >= l && v <= h));
        }
        // CR = 0: exactly one variable moves
        let de0 = Variation::DifferentialEvolution { f: 0.5, cr: 0.0 };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let [c, _] = de0.offspring(&mut rng, &pop, (0, 1), (&lo, &hi), &no_mutation);
        let moved = c.iter().zip(&members[0]).filter(|(a, b)| a != b).count();
        assert!(moved <= 1, "{c:?}");
    }
}
