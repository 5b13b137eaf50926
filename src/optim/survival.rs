//! Survival: which of a generation's parents and offspring form the next population, and
//! the measure each survivor carries into the next generation's tournaments.
//!
//! Both selections keep whole fronts of the constrained non-dominated sort, best first
//! (feasible fronts by Pareto rank, then infeasible designs by their infeasibility key, so
//! constraint domination decides among infeasible designs). They differ in the front that
//! does not fit whole, and in the measure:
//! - [`Survival::Crowding`] (NSGA-II, Deb et al. 2002): the split front's members with the
//!   largest crowding distance survive; the measure is the crowding distance;
//! - [`Survival::Hypervolume`] (SMS-EMOA's reduction, Beume et al. 2007, applied to a
//!   generation at a time): the split front loses its least hypervolume contributor, one at
//!   a time, contributions computed again after each removal; the measure is the member's
//!   exclusive hypervolume contribution within its front. Objectives are normalised as the
//!   progress hypervolume is (ideal → 0, reference → 1), the contributions taken with
//!   reference point ([`SURVIVAL_REFERENCE`], …): a little beyond the reported
//!   hypervolume's (1, …, 1), so that the survival keeps what the reported hypervolume
//!   measures and the members near a face of its box keep a share. A member outside the
//!   reference box contributes nothing; among those, the one farthest outside leaves first.

use super::hvc::least_contributor_selection;
use super::sort::{constrained_ranks, rank_and_crowding, survivors_with_attributes};
use super::Infeasibility;
use serde::{Deserialize, Serialize};

/// How a generation's survivors are chosen (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Survival {
    /// NSGA-II: the split front by crowding distance (gripopt's selection before issue 42).
    Crowding,
    /// The split front by greedy least hypervolume contribution (the default).
    #[default]
    Hypervolume,
}

impl Survival {
    /// Its name in options and reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Survival::Crowding => "crowding",
            Survival::Hypervolume => "hypervolume",
        }
    }
}

/// The survival's reference point in normalised objectives, (1.1, …, 1.1): beyond the
/// reported hypervolume's (1, …, 1), so that a member near a face of the box keeps a share
/// of its contribution (docs/benchmarks.md: 1.0, 1.1, 1.25, 1.5 measured).
pub const SURVIVAL_REFERENCE: f64 = 1.1;

/// How objectives are normalised for hypervolume contributions: `(f − ideal) / (reference −
/// ideal)` per objective (reference point [`SURVIVAL_REFERENCE`] in every objective).
/// Empty: each front normalised by its own least and greatest values.
#[derive(Debug, Clone, Copy)]
pub struct Normalisation<'a> {
    /// Ideal point (raw objectives).
    pub ideal: &'a [f64],
    /// Reference point (raw objectives).
    pub reference: &'a [f64],
}

impl Normalisation<'_> {
    /// The members `members` of `f` normalised, and the reference point.
    fn apply(&self, f: &[&[f64]], members: &[usize]) -> (Vec<Vec<f64>>, Vec<f64>) {
        let m = members.first().map_or(0, |&i| f[i].len());
        let (lo, hi, r): (Vec<f64>, Vec<f64>, f64) = if self.reference.len() == m && self.ideal.len() == m {
            (self.ideal.to_vec(), self.reference.to_vec(), SURVIVAL_REFERENCE)
        } else {
            let lo = (0..m).map(|k| members.iter().map(|&i| f[i][k]).fold(f64::INFINITY, f64::min)).collect();
            let hi = (0..m).map(|k| members.iter().map(|&i| f[i][k]).fold(f64::NEG_INFINITY, f64::max)).collect();
            (lo, hi, SURVIVAL_REFERENCE)
        };
        let pts = members
            .iter()
            .map(|&i| {
                (0..m)
                    .map(|k| {
                        let span = hi[k] - lo[k];
                        if span > 0.0 {
                            (f[i][k] - lo[k]) / span
                        } else {
                            0.0
                        }
                    })
                    .collect()
            })
            .collect();
        (pts, vec![r; m])
    }
}

/// How far outside the box of `r` a point lies (0 inside).
fn excess(p: &[f64], r: &[f64]) -> f64 {
    p.iter().zip(r).map(|(a, b)| (a - b).max(0.0)).sum()
}

/// The `n` survivors of the points `f` with infeasibility `cv`: their indices, and for each
/// its rank in the merged set and its measure (crowding distance or hypervolume
/// contribution; ∞ for infeasible members).
pub fn survive(
    how: Survival,
    f: &[&[f64]],
    cv: &[Infeasibility],
    n: usize,
    norm: Normalisation<'_>,
) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    if how == Survival::Crowding {
        return survivors_with_attributes(f, cv, n);
    }
    let rank = constrained_ranks(f, cv);
    let (mut out, mut orank, mut measure) = (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
    for (r, fr) in fronts(&rank).iter().enumerate() {
        let slots = n - out.len();
        if fr.first().is_some_and(|&i| cv[i].is_feasible()) {
            let (kept, contrib) = hv_keep(f, fr, slots, norm);
            for (k, c) in kept.into_iter().zip(contrib) {
                out.push(fr[k]);
                orank.push(r);
                measure.push(c);
            }
        } else {
            for &i in fr.iter().take(slots) {
                out.push(i);
                orank.push(r);
                measure.push(f64::INFINITY);
            }
        }
        if out.len() == n {
            break;
        }
    }
    (out, orank, measure)
}

/// The members of each front, in index order.
fn fronts(rank: &[usize]) -> Vec<Vec<usize>> {
    let nf = rank.iter().copied().max().map_or(0, |m| m + 1);
    let mut by_front: Vec<Vec<usize>> = vec![vec![]; nf];
    for (i, &r) in rank.iter().enumerate() {
        by_front[r].push(i);
    }
    by_front
}

/// The positions in `front` of its `slots` members kept by hypervolume (all of them when
/// they fit), and their contributions among the kept.
fn hv_keep(f: &[&[f64]], front: &[usize], slots: usize, norm: Normalisation<'_>) -> (Vec<usize>, Vec<f64>) {
    let (pts, r) = norm.apply(f, front);
    let tie: Vec<f64> = pts.iter().map(|p| excess(p, &r)).collect();
    least_contributor_selection(&pts, &r, slots.min(front.len()), &tie)
}

/// Rank and measure of every member of a population, in its order (the initial population's).
pub fn attributes(
    how: Survival,
    f: &[&[f64]],
    cv: &[Infeasibility],
    norm: Normalisation<'_>,
) -> (Vec<usize>, Vec<f64>) {
    if how == Survival::Crowding {
        return rank_and_crowding(f, cv);
    }
    let rank = constrained_ranks(f, cv);
    let mut measure = vec![f64::INFINITY; f.len()];
    for fr in fronts(&rank) {
        if fr.first().is_some_and(|&i| cv[i].is_feasible()) {
            let (kept, contrib) = hv_keep(f, &fr, fr.len(), norm);
            for (k, c) in kept.into_iter().zip(contrib) {
                measure[fr[k]] = c;
            }
        }
    }
    (rank, measure)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::hypervolume;

    /// When the whole merged set is one feasible front, the hypervolume survival keeps a
    /// subset with at least the hypervolume of the crowding survival's (on points near a
    /// concave front), and every survivor's measure is its exclusive contribution.
    #[test]
    fn hypervolume_survival_keeps_more_hypervolume_than_crowding() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let pts: Vec<Vec<f64>> = (0..200)
            .map(|_| {
                let p: Vec<f64> = (0..4).map(|_| rng.random_range(0.05..1.0)).collect();
                let s = p.iter().map(|v| v * v).sum::<f64>().sqrt();
                p.iter().map(|v| v / s).collect()
            })
            .collect();
        let f: Vec<&[f64]> = pts.iter().map(|p| p.as_slice()).collect();
        let cv = vec![Infeasibility::FEASIBLE; pts.len()];
        let (ideal, reference) = (vec![0.0; 4], vec![1.0; 4]);
        let norm = Normalisation { ideal: &ideal, reference: &reference };
        let hv_of = |keep: &[usize]| hypervolume(&keep.iter().map(|&i| pts[i].clone()).collect::<Vec<_>>(), &reference);
        let (hv_keep, _, measure) = survive(Survival::Hypervolume, &f, &cv, 100, norm);
        let (crowd_keep, _, _) = survive(Survival::Crowding, &f, &cv, 100, norm);
        assert!(hv_of(&hv_keep) > hv_of(&crowd_keep), "{} vs {}", hv_of(&hv_keep), hv_of(&crowd_keep));
        // the measure: the contribution at the survival's reference point
        let r = [SURVIVAL_REFERENCE; 4];
        let hv_r = |keep: &[usize]| hypervolume(&keep.iter().map(|&i| pts[i].clone()).collect::<Vec<_>>(), &r);
        let all = hv_r(&hv_keep);
        for (k, &i) in hv_keep.iter().enumerate() {
            let rest: Vec<usize> = hv_keep.iter().copied().filter(|&j| j != i).collect();
            assert!((measure[k] - (all - hv_r(&rest))).abs() < 1e-12);
        }
    }

    /// Constraint domination decides among infeasible designs: feasible fronts first, then
    /// the infeasible ones by their key, as with the crowding survival.
    #[test]
    fn infeasible_designs_go_by_constraint_domination() {
        let pts = [[0.95, 0.95], [0.2, 0.9], [0.1, 0.1], [0.9, 0.2], [0.0, 0.0]];
        let f: Vec<&[f64]> = pts.iter().map(|p| p.as_slice()).collect();
        let bad = |s: u8, v: f64| Infeasibility { stages_short: s, violation: v };
        let cv = [Infeasibility::FEASIBLE, Infeasibility::FEASIBLE, bad(1, 0.5), Infeasibility::FEASIBLE, bad(2, 0.1)];
        let (ideal, reference) = (vec![0.0; 2], vec![1.0; 2]);
        let norm = Normalisation { ideal: &ideal, reference: &reference };
        let (keep, rank, _) = survive(Survival::Hypervolume, &f, &cv, 4, norm);
        assert_eq!(keep, vec![1, 3, 0, 2]);
        assert_eq!(rank, vec![0, 0, 1, 2]);
        // of the first front's three members, the one contributing least (0.5, 0.5) leaves
        let cv2 = [Infeasibility::FEASIBLE; 5];
        let pts2 = [[0.5, 0.5], [0.1, 0.9], [0.45, 0.55], [0.9, 0.1], [0.55, 0.45]];
        let f2: Vec<&[f64]> = pts2.iter().map(|p| p.as_slice()).collect();
        let (keep, _, _) = survive(Survival::Hypervolume, &f2, &cv2, 4, norm);
        assert_eq!(keep, vec![1, 2, 3, 4]);
    }
}
