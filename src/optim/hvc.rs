//! Exclusive hypervolume contributions and the greedy least-contributor selection built on
//! them: the survival of [`Survival::Hypervolume`](super::Survival) and the thinning of a
//! run's reported front.
//!
//! The contribution of a point `p` of a set `S` (minimisation, reference point `r`) is the
//! volume only `p` dominates: the box `[p, r]` less the region the other points dominate
//! inside it, which is the hypervolume of the points `max(p, q)` (componentwise, `q ∈ S`,
//! `q ≠ p`) with respect to `r` (the "limited" points of WFG and of moocore's exclusive
//! contributions). Only the limited points that no other one weakly dominates shape that
//! region: after `q` leaves `S`, only the contributions of the points whose non-dominated
//! limited set held `q`'s point change, and only those are computed again. Each
//! contribution is a function of the set alone (taken in index order), so a value computed
//! again is the value computed from scratch, bit for bit, whatever the order of removals
//! and the thread count.

use super::hv::hv_inside;
#[cfg(test)]
use super::hv::hypervolume;
use rayon::prelude::*;
use std::cmp::Ordering;

/// From this many points on, the contributions are computed in parallel (in the caller's
/// rayon pool; each one is independent of the others, so the results do not depend on it).
const PARALLEL_POINTS: usize = 64;

/// The exclusive hypervolume contribution of each of `points` with respect to `r`
/// (minimisation): 0 for a point not strictly inside the box of `r`, for a point another
/// one weakly dominates, and for repeated points (each covers the other).
pub fn contributions(points: &[Vec<f64>], r: &[f64]) -> Vec<f64> {
    let alive: Vec<usize> = (0..points.len()).collect();
    compute(points, &alive, &alive, r).into_iter().map(|(c, _)| c).collect()
}

/// The contribution of `points[p]` among the points `alive` (indices, ascending), and the
/// points whose limited point is in its non-dominated limited set (the ones whose removal
/// can change it).
fn contribution(points: &[Vec<f64>], alive: &[usize], p: usize, r: &[f64]) -> (f64, Vec<usize>) {
    let others = alive.iter().copied().filter(|&q| q != p).map(|q| (q, points[q].as_slice()));
    exclusive(&points[p], others, r)
}

/// The volume `x` dominates within the box of `r` that none of `others` (tagged points)
/// dominates, and the tags of the others whose limited points shape it (ascending).
fn exclusive<'a>(x: &[f64], others: impl Iterator<Item = (usize, &'a [f64])>, r: &[f64]) -> (f64, Vec<usize>) {
    if x.iter().zip(r).any(|(a, b)| a >= b) {
        return (0.0, vec![]);
    }
    let d = x.len();
    // the limited points inside the box that no other one weakly dominates (of equal ones
    // the first), flat (d values each) in `buf`, with their tags: one pass, each point
    // compared with those kept so far (few: most limited points are dominated)
    let mut buf: Vec<f64> = Vec::new();
    let mut tags: Vec<usize> = Vec::new();
    let mut l = vec![0.0; d];
    for (q, y) in others {
        for ((l, a), b) in l.iter_mut().zip(x).zip(y) {
            *l = a.max(*b);
        }
        if l.iter().zip(r).any(|(a, b)| a >= b) {
            continue;
        }
        let weakly = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(u, v)| u <= v);
        if buf.chunks_exact(d).any(|k| weakly(k, &l)) {
            continue;
        }
        // drop the kept points the new one dominates, keeping the others' order
        let mut w = 0;
        for k in 0..tags.len() {
            if !weakly(&l, &buf[k * d..(k + 1) * d]) {
                buf.copy_within(k * d..(k + 1) * d, w * d);
                tags[w] = tags[k];
                w += 1;
            }
        }
        buf.truncate(w * d);
        tags.truncate(w);
        buf.extend_from_slice(&l);
        tags.push(q);
    }
    let box_volume: f64 = x.iter().zip(r).map(|(a, b)| b - a).product();
    let covered = if tags.is_empty() { 0.0 } else { hv_inside(buf.chunks_exact(d).collect(), r) };
    let mut deps = tags;
    deps.sort_unstable();
    ((box_volume - covered).max(0.0), deps)
}

/// The contributions (and dependencies) of the points `which` among `alive`.
fn compute(points: &[Vec<f64>], alive: &[usize], which: &[usize], r: &[f64]) -> Vec<(f64, Vec<usize>)> {
    if which.len() >= PARALLEL_POINTS {
        which.par_iter().map(|&p| contribution(points, alive, p, r)).collect()
    } else {
        which.iter().map(|&p| contribution(points, alive, p, r)).collect()
    }
}

/// Greedy least-contributor selection: remove from `points` one point at a time, the one
/// whose exclusive contribution (with respect to `r`) is least, until `keep` are left
/// (SMS-EMOA's reduction, Beume et al. 2007, repeated). Ties, e.g. points outside the box of
/// `r` that contribute nothing, go by `tie` (the point with the larger value leaves first),
/// then by index (the later point leaves first). Returns the kept indices, ascending, and
/// each one's contribution among the kept points.
pub fn least_contributor_selection(points: &[Vec<f64>], r: &[f64], keep: usize, tie: &[f64]) -> (Vec<usize>, Vec<f64>) {
    let n = points.len();
    let mut alive: Vec<usize> = (0..n).collect();
    if keep >= n {
        let c = contributions(points, r);
        return (alive, c);
    }
    let mut contrib = vec![0.0; n];
    let mut deps: Vec<Vec<usize>> = vec![vec![]; n];
    for (p, (c, d)) in compute(points, &alive, &alive, r).into_iter().enumerate() {
        contrib[p] = c;
        deps[p] = d;
    }
    while alive.len() > keep {
        let worst = *alive
            .iter()
            .min_by(|&&a, &&b| contrib[a].total_cmp(&contrib[b]).then(tie[b].total_cmp(&tie[a])).then(b.cmp(&a)))
            .expect("a point left");
        alive.retain(|&i| i != worst);
        let stale: Vec<usize> = alive.iter().copied().filter(|&p| deps[p].binary_search(&worst).is_ok()).collect();
        for (p, (c, d)) in stale.iter().zip(compute(points, &alive, &stale, r)) {
            contrib[*p] = c;
            deps[*p] = d;
        }
    }
    let c = alive.iter().map(|&i| contrib[i]).collect();
    (alive, c)
}

/// Greedy hypervolume subset selection: `k` of `points` chosen one at a time, each time the
/// one that adds the most hypervolume (with respect to `r`) to those chosen (ties: the lower
/// index), which keeps at least (1 − 1/e) of the best `k`-subset's hypervolume (the
/// hypervolume is submodular). Lazy: a point's gain can only fall as the chosen set grows,
/// so a gain computed earlier bounds it and only the best bound is computed again. Returns
/// the chosen indices, ascending; all of them when there are at most `k`.
pub fn greedy_subset(points: &[Vec<f64>], r: &[f64], k: usize) -> Vec<usize> {
    use std::collections::BinaryHeap;
    if points.len() <= k {
        return (0..points.len()).collect();
    }
    /// A point's gain, the chosen-set size it was computed at, and the point.
    struct Bound(f64, usize, usize);
    impl PartialEq for Bound {
        fn eq(&self, o: &Self) -> bool {
            self.cmp(o) == Ordering::Equal
        }
    }
    impl Eq for Bound {}
    impl PartialOrd for Bound {
        fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
            Some(self.cmp(o))
        }
    }
    impl Ord for Bound {
        // the greatest gain first, then the lowest index
        fn cmp(&self, o: &Self) -> Ordering {
            self.0.total_cmp(&o.0).then(o.2.cmp(&self.2))
        }
    }
    let mut heap: BinaryHeap<Bound> =
        points.iter().enumerate().map(|(i, p)| Bound(exclusive(p, std::iter::empty(), r).0, 0, i)).collect();
    let mut chosen: Vec<usize> = Vec::with_capacity(k);
    while chosen.len() < k {
        let Bound(gain, at, i) = heap.pop().expect("more points than k");
        if at == chosen.len() {
            chosen.push(i);
            continue;
        }
        let others = chosen.iter().map(|&q| (q, points[q].as_slice()));
        let fresh = exclusive(&points[i], others, r).0;
        heap.push(Bound(fresh.min(gain), chosen.len(), i));
    }
    chosen.sort_unstable();
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Exclusive contributions by inclusion–exclusion over every subset of the set: the
    /// volume of the union's part only `p` covers is Σ over subsets T ∌ p of
    /// (−1)^|T| · vol(box of {p} ∪ T), an independent formula (no slicing, no limiting).
    fn inclusion_exclusion(points: &[Vec<f64>], r: &[f64], p: usize) -> f64 {
        let others: Vec<usize> = (0..points.len()).filter(|&q| q != p).collect();
        let mut total = 0.0;
        for mask in 0u32..(1 << others.len()) {
            let mut corner = points[p].clone();
            let mut size = 0;
            for (k, &q) in others.iter().enumerate() {
                if mask & (1 << k) != 0 {
                    size += 1;
                    for (c, v) in corner.iter_mut().zip(&points[q]) {
                        *c = c.max(*v);
                    }
                }
            }
            let vol: f64 = corner.iter().zip(r).map(|(a, b)| (b - a).max(0.0)).product();
            total += if size % 2 == 0 { vol } else { -vol };
        }
        total
    }

    fn random_front(rng: &mut rand_chacha::ChaCha8Rng, n: usize, d: usize, grid: bool) -> Vec<Vec<f64>> {
        (0..n)
            .map(|_| {
                let p: Vec<f64> = (0..d).map(|_| rng.random_range(0.05..1.0)).collect();
                if grid {
                    return p.iter().map(|v| (v * 4.0).round() / 4.0).collect();
                }
                let s = p.iter().map(|v| v * v).sum::<f64>().sqrt();
                p.iter().map(|v| v / s * 1.05 - 0.05).collect()
            })
            .collect()
    }

    #[test]
    fn contributions_equal_inclusion_exclusion() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(42);
        for d in 2..=5 {
            for case in 0..12 {
                // points near a front (mostly non-dominated), or on a coarse grid (ties,
                // repeats, dominated points, points on the reference's faces)
                let pts = random_front(&mut rng, 3 + case % 9, d, case % 3 == 0);
                let r = vec![1.0; d];
                let c = contributions(&pts, &r);
                for (p, got) in c.iter().enumerate() {
                    let want = inclusion_exclusion(&pts, &r, p);
                    assert!((got - want).abs() <= 1e-12, "d {d} case {case} point {p}: {got} vs {want}");
                }
            }
        }
    }

    /// The lazy greedy chooses as the plain greedy does (every gain computed again at every
    /// step, as a difference of hypervolumes), and keeps most of the set's hypervolume.
    #[test]
    fn greedy_subset_equals_the_plain_greedy() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for case in 0..4 {
            let pts = random_front(&mut rng, 80, 4, case % 2 == 1);
            let r = vec![1.0; 4];
            let lazy = greedy_subset(&pts, &r, 25);
            let mut chosen: Vec<usize> = vec![];
            for _ in 0..25 {
                let base: Vec<Vec<f64>> = chosen.iter().map(|&i| pts[i].clone()).collect();
                let hv0 = hypervolume(&base, &r);
                let gain = |i: usize| {
                    let mut with = base.clone();
                    with.push(pts[i].clone());
                    hypervolume(&with, &r) - hv0
                };
                let best = (0..pts.len())
                    .filter(|i| !chosen.contains(i))
                    .max_by(|&a, &b| gain(a).total_cmp(&gain(b)).then(b.cmp(&a)))
                    .unwrap();
                chosen.push(best);
            }
            chosen.sort_unstable();
            assert_eq!(lazy, chosen, "case {case}");
            let sub: Vec<Vec<f64>> = lazy.iter().map(|&i| pts[i].clone()).collect();
            let plain: Vec<Vec<f64>> = chosen.iter().map(|&i| pts[i].clone()).collect();
            assert!((hypervolume(&sub, &r) - hypervolume(&plain, &r)).abs() < 1e-12);
            assert!(hypervolume(&sub, &r) > 0.7 * hypervolume(&pts, &r));
        }
    }

    #[test]
    fn contributions_are_hypervolume_differences_on_larger_sets() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let pts = random_front(&mut rng, 120, 4, false);
        let r = vec![1.0; 4];
        let all = hypervolume(&pts, &r);
        let c = contributions(&pts, &r);
        for p in 0..pts.len() {
            let rest: Vec<Vec<f64>> = pts.iter().enumerate().filter(|(q, _)| *q != p).map(|(_, v)| v.clone()).collect();
            let want = all - hypervolume(&rest, &r);
            assert!((c[p] - want).abs() <= 1e-12, "point {p}: {} vs {want}", c[p]);
        }
    }

    /// The selection recomputes only the contributions a removal can change: its result is
    /// the plain greedy's, which recomputes every contribution after every removal.
    #[test]
    fn selection_equals_the_plain_greedy_and_does_not_depend_on_threads() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for case in 0..6 {
            let pts = random_front(&mut rng, 90, 4, case % 2 == 1);
            let r = vec![1.0; 4];
            let tie: Vec<f64> = (0..pts.len()).map(|i| (i % 7) as f64).collect();
            let (kept, c) = least_contributor_selection(&pts, &r, 40, &tie);
            let mut alive: Vec<usize> = (0..pts.len()).collect();
            while alive.len() > 40 {
                let sub: Vec<Vec<f64>> = alive.iter().map(|&i| pts[i].clone()).collect();
                let cs = contributions(&sub, &r);
                let k = (0..alive.len())
                    .min_by(|&a, &b| {
                        cs[a].total_cmp(&cs[b]).then(tie[alive[b]].total_cmp(&tie[alive[a]])).then(b.cmp(&a))
                    })
                    .unwrap();
                alive.remove(k);
            }
            assert_eq!(kept, alive, "case {case}");
            let sub: Vec<Vec<f64>> = kept.iter().map(|&i| pts[i].clone()).collect();
            assert_eq!(c, contributions(&sub, &r));
            let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
            let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
            let a = one.install(|| least_contributor_selection(&pts, &r, 40, &tie));
            let b = three.install(|| least_contributor_selection(&pts, &r, 40, &tie));
            assert_eq!(a, b);
        }
    }
}
