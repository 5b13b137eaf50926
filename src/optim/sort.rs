//! Non-dominated sorting with constrained domination, and crowding distance.
//!
//! Feasible points are sorted into Pareto fronts: for two objectives by the O(N log N)
//! sweep with a binary search over the fronts' last members; for more objectives by the
//! efficient non-dominated sort with sequential search (ENS-SS, Zhang et al. 2015).
//! Infeasible points follow all feasible fronts, ordered by their [`Infeasibility`] key;
//! equal keys share a front.

use super::{dominates, Infeasibility};
use std::cmp::Ordering;

/// Front index (0 = best) of every point.
pub fn constrained_ranks(f: &[&[f64]], cv: &[Infeasibility]) -> Vec<usize> {
    let n = f.len();
    let mut rank = vec![0usize; n];
    let feas: Vec<usize> = (0..n).filter(|&i| cv[i].is_feasible()).collect();
    let n_fronts = if feas.is_empty() {
        0
    } else {
        let sub: Vec<&[f64]> = feas.iter().map(|&i| f[i]).collect();
        let r = pareto_ranks(&sub);
        let mut m = 0;
        for (k, &i) in feas.iter().enumerate() {
            rank[i] = r[k];
            m = m.max(r[k] + 1);
        }
        m
    };
    let mut inf: Vec<usize> = (0..n).filter(|&i| !cv[i].is_feasible()).collect();
    inf.sort_by(|&a, &b| cv[a].cmp_key(&cv[b]).then(a.cmp(&b)));
    let mut r = n_fronts;
    for (k, &i) in inf.iter().enumerate() {
        if k > 0 && cv[inf[k - 1]].cmp_key(&cv[i]) != Ordering::Equal {
            r += 1;
        }
        rank[i] = r;
    }
    rank
}

fn lex(a: &[f64], b: &[f64]) -> Ordering {
    for (x, y) in a.iter().zip(b) {
        match x.total_cmp(y) {
            Ordering::Equal => continue,
            o => return o,
        }
    }
    Ordering::Equal
}

/// Pareto front index of every point (minimisation).
pub fn pareto_ranks(f: &[&[f64]]) -> Vec<usize> {
    let n = f.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| lex(f[a], f[b]).then(a.cmp(&b)));
    let mut rank = vec![0usize; n];
    if n == 0 {
        return rank;
    }
    let m = f[0].len();
    if m == 2 {
        // last (lowest f1) member of each front; fronts' last f1 increase with the index
        let mut last: Vec<usize> = vec![];
        for &p in &order {
            let dominated_by = |k: usize| {
                let q = last[k];
                f[q][1] < f[p][1] || (f[q][1] == f[p][1] && f[q][0] < f[p][0])
            };
            // first front that does not dominate p (monotone predicate)
            let (mut lo, mut hi) = (0usize, last.len());
            while lo < hi {
                let mid = (lo + hi) / 2;
                if dominated_by(mid) {
                    lo = mid + 1;
                } else {
                    hi = mid;
                }
            }
            if lo == last.len() {
                last.push(p);
            } else {
                last[lo] = p;
            }
            rank[p] = lo;
        }
    } else {
        let mut fronts: Vec<Vec<usize>> = vec![];
        for &p in &order {
            let mut placed = false;
            for (k, fr) in fronts.iter_mut().enumerate() {
                if !fr.iter().rev().any(|&q| dominates(f[q], f[p])) {
                    fr.push(p);
                    rank[p] = k;
                    placed = true;
                    break;
                }
            }
            if !placed {
                rank[p] = fronts.len();
                fronts.push(vec![p]);
            }
        }
    }
    rank
}

/// Crowding distance of the points `members` (indices into `f`); boundary points get ∞ and
/// repeated objective vectors get 0 (only their first occurrence is spread), as in pymoo.
pub fn crowding(f: &[&[f64]], members: &[usize]) -> Vec<f64> {
    if members.len() <= 2 {
        return vec![f64::INFINITY; members.len()];
    }
    // unique objective vectors (first occurrence)
    let mut order: Vec<usize> = (0..members.len()).collect();
    order.sort_by(|&a, &b| lex(f[members[a]], f[members[b]]).then(a.cmp(&b)));
    let mut unique = vec![true; members.len()];
    for w in order.windows(2) {
        if f[members[w[0]]] == f[members[w[1]]] {
            unique[w[1]] = false;
        }
    }
    let uniq: Vec<usize> = (0..members.len()).filter(|&i| unique[i]).map(|i| members[i]).collect();
    let du = crowding_unique(f, &uniq);
    let mut out = vec![0.0; members.len()];
    let mut k = 0;
    for i in 0..members.len() {
        if unique[i] {
            out[i] = du[k];
            k += 1;
        }
    }
    out
}

fn crowding_unique(f: &[&[f64]], members: &[usize]) -> Vec<f64> {
    let n = members.len();
    let mut d = vec![0.0f64; n];
    if n <= 2 {
        return vec![f64::INFINITY; n];
    }
    let m = f[members[0]].len();
    let mut idx: Vec<usize> = (0..n).collect();
    for k in 0..m {
        idx.sort_by(|&a, &b| f[members[a]][k].total_cmp(&f[members[b]][k]).then(a.cmp(&b)));
        let lo = f[members[idx[0]]][k];
        let hi = f[members[idx[n - 1]]][k];
        d[idx[0]] = f64::INFINITY;
        d[idx[n - 1]] = f64::INFINITY;
        let span = hi - lo;
        if span > 0.0 {
            for j in 1..n - 1 {
                d[idx[j]] += (f[members[idx[j + 1]]][k] - f[members[idx[j - 1]]][k]) / span;
            }
        }
    }
    d
}

/// Rank and crowding of a whole population (crowding computed per front).
pub fn rank_and_crowding(f: &[&[f64]], cv: &[Infeasibility]) -> (Vec<usize>, Vec<f64>) {
    let rank = constrained_ranks(f, cv);
    let nf = rank.iter().copied().max().map_or(0, |m| m + 1);
    let mut by_front: Vec<Vec<usize>> = vec![vec![]; nf];
    for (i, &r) in rank.iter().enumerate() {
        by_front[r].push(i);
    }
    let mut crowd = vec![0.0; f.len()];
    for fr in &by_front {
        let feasible = fr.first().is_some_and(|&i| cv[i].is_feasible());
        let c = if feasible { crowding(f, fr) } else { vec![f64::INFINITY; fr.len()] };
        for (k, &i) in fr.iter().enumerate() {
            crowd[i] = c[k];
        }
    }
    (rank, crowd)
}

/// Indices of the `n` survivors of `f` by (rank, crowding descending, index).
pub fn survivors(f: &[&[f64]], cv: &[Infeasibility], n: usize) -> Vec<usize> {
    survivors_with_attributes(f, cv, n).0
}

/// Survivors with the rank and crowding each got in the merged population (crowding of a
/// front computed over the whole front, also for the front that is split), as NSGA-II's
/// tournament uses them.
pub fn survivors_with_attributes(f: &[&[f64]], cv: &[Infeasibility], n: usize) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let rank = constrained_ranks(f, cv);
    let nf = rank.iter().copied().max().map_or(0, |m| m + 1);
    let mut by_front: Vec<Vec<usize>> = vec![vec![]; nf];
    for (i, &r) in rank.iter().enumerate() {
        by_front[r].push(i);
    }
    let (mut out, mut orank, mut ocrowd) = (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
    for (r, fr) in by_front.iter().enumerate() {
        let feasible = fr.first().is_some_and(|&i| cv[i].is_feasible());
        let c = if feasible { crowding(f, fr) } else { vec![f64::INFINITY; fr.len()] };
        let mut order: Vec<usize> = (0..fr.len()).collect();
        if out.len() + fr.len() > n && feasible {
            order.sort_by(|&a, &b| c[b].total_cmp(&c[a]).then(fr[a].cmp(&fr[b])));
        }
        for &k in order.iter().take(n - out.len()) {
            out.push(fr[k]);
            orank.push(r);
            ocrowd.push(c[k]);
        }
        if out.len() == n {
            break;
        }
    }
    (out, orank, ocrowd)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(f: &[&[f64]]) -> Vec<usize> {
        let n = f.len();
        let mut rank = vec![usize::MAX; n];
        let mut left: Vec<usize> = (0..n).collect();
        let mut r = 0;
        while !left.is_empty() {
            let front: Vec<usize> =
                left.iter().copied().filter(|&i| !left.iter().any(|&j| dominates(f[j], f[i]))).collect();
            for &i in &front {
                rank[i] = r;
            }
            left.retain(|i| !front.contains(i));
            r += 1;
        }
        rank
    }

    #[test]
    fn fast_sorts_match_brute_force() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        for m in [2usize, 3, 4] {
            for _ in 0..50 {
                let n = rng.random_range(1..120);
                // coarse grid values make ties and duplicates frequent
                let pts: Vec<Vec<f64>> =
                    (0..n).map(|_| (0..m).map(|_| rng.random_range(0..8) as f64).collect()).collect();
                let f: Vec<&[f64]> = pts.iter().map(|p| p.as_slice()).collect();
                assert_eq!(pareto_ranks(&f), brute(&f), "m = {m}");
            }
        }
    }

    #[test]
    fn hand_made_fronts_and_crowding() {
        let pts = [[1.0, 5.0], [2.0, 3.0], [3.0, 1.0], [2.0, 4.0], [4.0, 4.0], [1.0, 5.0]];
        let f: Vec<&[f64]> = pts.iter().map(|p| p.as_slice()).collect();
        assert_eq!(pareto_ranks(&f), vec![0, 0, 0, 1, 2, 0]);
        let c = crowding(&f, &[0, 1, 2]);
        assert!(c[0].is_infinite() && c[2].is_infinite());
        // (3 − 1)/2 + (1 − 5)/(1 − 5) … = 2/2 + 4/4 = 2
        assert!((c[1] - 2.0).abs() < 1e-15);
    }

    #[test]
    fn constrained_ranking() {
        let pts = [[1.0, 1.0], [0.0, 0.0], [5.0, 5.0], [0.0, 0.0]];
        let f: Vec<&[f64]> = pts.iter().map(|p| p.as_slice()).collect();
        let cv = [
            Infeasibility::FEASIBLE,
            Infeasibility { stages_short: 1, violation: 0.5 },
            Infeasibility::FEASIBLE,
            Infeasibility { stages_short: 2, violation: 0.1 },
        ];
        // feasible first (by Pareto), then later stage beats earlier stage regardless of violation
        assert_eq!(constrained_ranks(&f, &cv), vec![0, 2, 1, 3]);
        assert!(crate::optim::constrained_dominates(&pts[2], &cv[2], &pts[1], &cv[1]));
        assert!(crate::optim::constrained_dominates(&pts[1], &cv[1], &pts[3], &cv[3]));
        assert!(!crate::optim::constrained_dominates(&pts[3], &cv[3], &pts[1], &cv[1]));
        let s = survivors(&f, &cv, 3);
        assert_eq!(s, vec![0, 2, 1]);
    }
}
