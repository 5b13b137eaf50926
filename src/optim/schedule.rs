//! Ordering a generation's work for list scheduling. Each design's evaluation starts with
//! a cheap part ([`MooProblem::start`](super::MooProblem::start)) that says whether the
//! rest is cheap or costly and, for a costly one, gives features of the design. The
//! [`CostModel`] learns the problem's deterministic work measure
//! ([`MooProblem::work`](super::MooProblem::work)) from those features over the
//! generations already evaluated, so that the designs predicted to take longest are
//! finished first and no thread is left with a long one at the end. The order never changes
//! a result: evaluations are pure and go back in index order.

use super::evaluator::{Batch, Evaluations, Evaluator, GenTiming};
use super::{Evaluated, MooProblem};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::collections::VecDeque;

/// What the cheap first part of an evaluation says of the rest's cost.
#[derive(Debug, Clone, PartialEq)]
pub enum CostHint {
    /// Little or nothing is left (the design was discarded early).
    Cheap,
    /// The expensive part runs; the features describe the design for the cost model
    /// (empty: no features, such designs keep their index order among themselves).
    Costly(Vec<f64>),
}

/// Training rows kept: the most recent ones (a few generations of a large population).
const MAX_ROWS: usize = 4096;
/// Ridge penalty on the standardised features' coefficients (the intercept is free): with
/// it a fit from a few rows is already usable (measured on the bottle problem: 8 rows and
/// λ = 1 ordered better than 2 (d + 1) rows or λ = 0.1).
const RIDGE: f64 = 1.0;
/// Fewest rows for a fit.
const MIN_ROWS: usize = 8;
/// Rows whose work is below this fraction of the median are not fitted: a costly design
/// that ended early (e.g. discarded at the first impact) would bend the log-linear law.
const LOW_WORK: f64 = 0.25;

/// Online log-linear model of a design's work from its features: least squares with a
/// small ridge penalty on standardised features, fitted to the rows of earlier generations.
/// Deterministic: the same rows give the same order.
#[derive(Debug, Clone, Default)]
pub struct CostModel {
    rows: VecDeque<(Vec<f64>, f64)>,
    fit: Option<Fit>,
}

#[derive(Debug, Clone)]
struct Fit {
    mean: Vec<f64>,
    scale: Vec<f64>,
    coef: Vec<f64>,
    intercept: f64,
}

impl Fit {
    fn predict(&self, f: &[f64]) -> Option<f64> {
        if f.len() != self.coef.len() {
            return None;
        }
        let z = f
            .iter()
            .zip(&self.mean)
            .zip(&self.scale)
            .zip(&self.coef)
            .map(|(((v, m), s), c)| (v - m) / s * c)
            .sum::<f64>();
        Some(self.intercept + z).filter(|v| v.is_finite())
    }
}

impl CostModel {
    /// An empty model (orders costly designs by index until it has learnt enough).
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of training rows held.
    pub fn rows(&self) -> usize {
        self.rows.len()
    }

    /// Whether the model has been fitted (enough rows with features of one length).
    pub fn is_fitted(&self) -> bool {
        self.fit.is_some()
    }

    /// Add one evaluated design: its features and its measured work (> 0; others ignored).
    pub fn add(&mut self, features: &[f64], work: f64) {
        if features.is_empty() || !(work > 0.0) || !work.is_finite() || features.iter().any(|v| !v.is_finite()) {
            return;
        }
        if self.rows.len() == MAX_ROWS {
            self.rows.pop_front();
        }
        self.rows.push_back((features.to_vec(), work));
    }

    /// Predicted work of a design with these features (`None` before a fit).
    pub fn predict(&self, features: &[f64]) -> Option<f64> {
        self.fit.as_ref()?.predict(features).map(f64::exp)
    }

    /// Refit on the rows held: ln(work) against the features, rows with work below
    /// `LOW_WORK` × median left out. Needs `MIN_ROWS` rows of the latest feature length;
    /// otherwise the model stays unfitted.
    pub fn refit(&mut self) {
        self.fit = None;
        let Some(d) = self.rows.back().map(|r| r.0.len()) else { return };
        let mut w: Vec<f64> = self.rows.iter().filter(|r| r.0.len() == d).map(|r| r.1).collect();
        if w.is_empty() {
            return;
        }
        w.sort_by(f64::total_cmp);
        let cut = LOW_WORK * w[w.len() / 2];
        let rows: Vec<&(Vec<f64>, f64)> = self.rows.iter().filter(|r| r.0.len() == d && r.1 >= cut).collect();
        let n = rows.len();
        if n < MIN_ROWS.max(2) {
            return;
        }
        let mean: Vec<f64> = (0..d).map(|j| rows.iter().map(|r| r.0[j]).sum::<f64>() / n as f64).collect();
        let scale: Vec<f64> = (0..d)
            .map(|j| {
                let v = rows.iter().map(|r| (r.0[j] - mean[j]).powi(2)).sum::<f64>() / n as f64;
                if v > 0.0 {
                    v.sqrt()
                } else {
                    1.0
                }
            })
            .collect();
        // normal equations of [Z 1] c = ln w with λ on the feature coefficients
        let a = DMatrix::from_fn(n, d + 1, |i, j| if j == d { 1.0 } else { (rows[i].0[j] - mean[j]) / scale[j] });
        let y = DVector::from_iterator(n, rows.iter().map(|r| r.1.ln()));
        let mut m = a.tr_mul(&a);
        for j in 0..d {
            m[(j, j)] += RIDGE;
        }
        let Some(ch) = m.cholesky() else { return };
        let c = ch.solve(&a.tr_mul(&y));
        if c.iter().all(|v| v.is_finite()) {
            self.fit = Some(Fit { mean, scale, coef: c.rows(0, d).iter().copied().collect(), intercept: c[d] });
        }
    }

    /// The order in which to evaluate designs with these hints: costly ones first, those
    /// with the largest predicted work first (unpredicted costly ones after the predicted,
    /// in index order), then the cheap ones; ties in index order.
    pub fn order(&self, hints: &[CostHint]) -> Vec<usize> {
        let key: Vec<(u8, f64)> = hints
            .iter()
            .map(|h| match h {
                CostHint::Cheap => (2, 0.0),
                CostHint::Costly(f) => match self.predict(f) {
                    Some(w) => (0, -w),
                    None => (1, 0.0),
                },
            })
            .collect();
        let mut order: Vec<usize> = (0..hints.len()).collect();
        order.sort_by(|&a, &b| key[a].0.cmp(&key[b].0).then(key[a].1.total_cmp(&key[b].1)).then(a.cmp(&b)));
        order
    }
}

/// The default [`Evaluator`]: a batch in two passes in the current rayon pool. First
/// every design's cheap start ([`MooProblem::start`]), in parallel (fine-grained); then the
/// rest ([`MooProblem::finish`]) by list scheduling in the [`CostModel`]'s order, the
/// designs predicted to take longest first: each worker takes the next design from a shared
/// counter, so no thread idles while another still has a queue. Each evaluation is a pure
/// function of its vector and the results are put back in index order, so they do not
/// depend on the thread count or the schedule. Afterwards the model learns the batch's
/// work ([`MooProblem::work`]).
#[derive(Debug, Clone, Default)]
pub struct Scheduled {
    model: CostModel,
}

impl Scheduled {
    /// What the evaluator has learnt of the designs' costs.
    pub fn model(&self) -> &CostModel {
        &self.model
    }
}

impl<P: MooProblem> Evaluator<P> for Scheduled {
    fn evaluate(&mut self, p: &P, batch: &Batch<'_>) -> Evaluations<P::Info> {
        use std::sync::atomic::{AtomicUsize, Ordering};
        use std::sync::Mutex;
        let t0 = std::time::Instant::now();
        let xs = batch.xs;
        let n = xs.len();
        let started: Vec<(P::Started, CostHint, f64)> = xs
            .par_iter()
            .map(|x| {
                let t = std::time::Instant::now();
                let (s, h) = p.start(x);
                (s, h, t.elapsed().as_secs_f64())
            })
            .collect();
        let mut hints = Vec::with_capacity(n);
        let mut start_costs = Vec::with_capacity(n);
        let slots: Vec<Mutex<Option<P::Started>>> = started
            .into_iter()
            .map(|(s, h, c)| {
                hints.push(h);
                start_costs.push(c);
                Mutex::new(Some(s))
            })
            .collect();
        let order = self.model.order(&hints);
        let costly = hints.iter().filter(|h| matches!(h, CostHint::Costly(_))).count();
        let order_s = t0.elapsed().as_secs_f64();
        let next = AtomicUsize::new(0);
        let workers = rayon::current_num_threads().min(n).max(1);
        let done: Vec<(usize, Evaluated<P::Info>, f64)> = (0..workers)
            .into_par_iter()
            .with_max_len(1)
            .flat_map_iter(|_| {
                let mut mine = vec![];
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    if k >= n {
                        break;
                    }
                    let i = order[k];
                    let t = std::time::Instant::now();
                    let st = slots[i].lock().map(|mut g| g.take()).ok().flatten().expect("each design finished once");
                    let e = p.finish(&xs[i], st);
                    mine.push((i, e, t.elapsed().as_secs_f64()));
                }
                mine
            })
            .collect();
        let mut results: Vec<Option<(Evaluated<P::Info>, f64)>> = (0..n).map(|_| None).collect();
        for (i, e, s) in done {
            results[i] = Some((e, s));
        }
        let mut costs = Vec::with_capacity(n);
        let evaluated: Vec<Evaluated<P::Info>> = results
            .into_iter()
            .enumerate()
            .map(|(k, slot)| {
                let (eval, s) = slot.expect("every design evaluated once");
                costs.push(start_costs[k] + s);
                eval
            })
            .collect();
        for (h, e) in hints.iter().zip(&evaluated) {
            if let (CostHint::Costly(f), Some(w)) = (h, p.work(e)) {
                self.model.add(f, w);
            }
        }
        self.model.refit();
        let timing = GenTiming::of_two_passes(t0, order_s, (costs, start_costs), order, costly);
        Evaluations { evaluated, timing }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// A known log-linear law is recovered from noisy rows, and the order follows it.
    #[test]
    fn learns_a_log_linear_law_and_orders_by_it() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let law = |f: &[f64]| (8.0 + 0.5 * f[0] - 0.3 * f[1] + 0.0 * f[2]).exp();
        let mut m = CostModel::new();
        for _ in 0..400 {
            let f: Vec<f64> = (0..3).map(|_| rng.random::<f64>() * 2.0 - 1.0).collect();
            let noise = 1.0 + 0.02 * (rng.random::<f64>() - 0.5);
            m.add(&f, law(&f) * noise);
        }
        assert!(!m.is_fitted());
        m.refit();
        assert!(m.is_fitted());
        for f in [[0.5, -0.5, 0.9], [-0.9, 0.9, -0.2], [0.0, 0.0, 0.0]] {
            let (p, t) = (m.predict(&f).unwrap(), law(&f));
            assert!((p / t - 1.0).abs() < 0.02, "{p} vs {t}");
        }
        let hints = vec![
            CostHint::Cheap,
            CostHint::Costly(vec![-1.0, 1.0, 0.0]),
            CostHint::Costly(vec![]),
            CostHint::Costly(vec![1.0, -1.0, 0.0]),
            CostHint::Costly(vec![0.0, 0.0, 0.0]),
        ];
        assert_eq!(m.order(&hints), vec![3, 4, 1, 2, 0]);
    }

    /// Too few rows: no fit; costly designs keep index order, before the cheap ones.
    #[test]
    fn unfitted_model_keeps_index_order() {
        let mut m = CostModel::new();
        for k in 0..MIN_ROWS - 1 {
            m.add(&[k as f64, 1.0], 100.0 + k as f64);
        }
        m.refit();
        assert!(!m.is_fitted());
        let hints =
            vec![CostHint::Cheap, CostHint::Costly(vec![1.0, 1.0]), CostHint::Cheap, CostHint::Costly(vec![2.0, 1.0])];
        assert_eq!(m.order(&hints), vec![1, 3, 0, 2]);
    }
}
