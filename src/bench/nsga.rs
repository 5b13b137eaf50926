//! `gripopt bench nsga`: non-dominated sorting and the optimiser's own overhead.

use super::{min_med, say, Out};
use crate::optim::rank_and_crowding;
use crate::optim::{reference_settings, TestProblem};
use crate::optim::{Infeasibility, MooProblem};
use crate::{Error, Result};
use rand::{Rng, SeedableRng};

/// Non-dominated sort + crowding distance on uniform random sets (2 and 4 objectives, 200 to
/// 10 000 points), and NSGA-II's overhead per generation on ZDT1 (everything but
/// evaluation), `reps` repetitions each (at least 3); writes min / median times to `out`
/// and returns them as JSON.
pub fn nsga(reps: usize, out: Out) -> Result<serde_json::Value> {
    let reps = reps.max(3);
    let mut sorts = vec![];
    say!(
        out,
        "non-dominated sort + crowding distance, uniform random points, 1 thread, {reps} repetitions (min / median)"
    );
    for m in [2usize, 4] {
        for n in [200usize, 1000, 10000] {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(n as u64 + m as u64);
            let pts: Vec<Vec<f64>> = (0..n).map(|_| (0..m).map(|_| rng.random::<f64>()).collect()).collect();
            let f: Vec<&[f64]> = pts.iter().map(|p| p.as_slice()).collect();
            let cv = vec![Infeasibility::FEASIBLE; n];
            let mut ts = vec![];
            for _ in 0..reps {
                let t0 = std::time::Instant::now();
                std::hint::black_box(rank_and_crowding(&f, &cv));
                ts.push(t0.elapsed().as_secs_f64());
            }
            let (a, b) = min_med(ts);
            sorts.push(serde_json::json!({ "objectives": m, "points": n, "min_ms": a * 1e3, "median_ms": b * 1e3 }));
            say!(out, "  {m} objectives, {n:>5} points: {:.3} / {:.3} ms", a * 1e3, b * 1e3);
        }
    }
    // optimiser overhead on ZDT1: whole run minus evaluation time, per generation
    let which = TestProblem::Zdt1;
    let gens = 250u64;
    let mut per_gen = vec![];
    let inst = which.instance();
    let x: Vec<f64> = vec![0.5; 30];
    let t0 = std::time::Instant::now();
    let k = 100_000;
    for _ in 0..k {
        std::hint::black_box(inst.evaluate(std::hint::black_box(&x)));
    }
    let eval_s = t0.elapsed().as_secs_f64() / k as f64;
    for rep in 0..reps.min(10) {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .map_err(|e| Error::bench_from("bench nsga: thread pool", e))?;
        let t0 = std::time::Instant::now();
        pool.install(|| {
            use argmin::core::State;
            let st = crate::optim::Nsga2State::new().with_max_generations(gens);
            let mut s = reference_settings(which, rep as u64 + 1, 100);
            s.hv_ref.clear();
            crate::optim::execute(which.instance(), crate::optim::Nsga2::new(s).nsga2(), st, |e| e)
        })
        .map_err(|e| Error::Optimiser(e.to_string()))?;
        let total = t0.elapsed().as_secs_f64();
        per_gen.push((total - eval_s * 100.0 * gens as f64) / gens as f64);
    }
    let (a, b) = min_med(per_gen);
    say!(out, "NSGA-II overhead per generation on ZDT1 (pop 100, 250 generations, 1 thread, evaluation time {:.2} us/eval subtracted): {:.3} / {:.3} ms", eval_s * 1e6, a * 1e3, b * 1e3);
    let hv = hypervolume_selection(reps, out)?;
    Ok(serde_json::json!({
        "bench": "nsga", "repetitions": reps, "sort_and_crowding": sorts,
        "generation_overhead_zdt1_ms": { "min": a * 1e3, "median": b * 1e3, "eval_us_subtracted": eval_s * 1e6 },
        "hypervolume_selection": hv,
    }))
}

/// The hypervolume survival of a generation (parents and offspring, 4 objectives, all
/// non-dominated: the gripper problem once its population is feasible) and the thinning of
/// an archive to the reported front, on points of the unit sphere's positive part, one
/// thread, `reps` repetitions (min / median).
fn hypervolume_selection(reps: usize, out: Out) -> Result<serde_json::Value> {
    use crate::optim::{greedy_subset, survive, Normalisation, Survival};
    let sphere = |n: usize, seed: u64| -> Vec<Vec<f64>> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                let p: Vec<f64> = (0..4).map(|_| rng.random_range(0.01..1.0)).collect();
                let s = p.iter().map(|v| v * v).sum::<f64>().sqrt();
                p.iter().map(|v| v / s).collect()
            })
            .collect()
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| Error::bench_from("bench nsga: thread pool", e))?;
    let (ideal, reference) = (vec![0.0; 4], vec![1.0; 4]);
    let norm = Normalisation { ideal: &ideal, reference: &reference };
    let mut rows = vec![];
    say!(out, "hypervolume selection, 4 objectives, non-dominated points, 1 thread (min / median):");
    for (what, n, keep) in [("survival", 200usize, 100usize), ("thinning", 1500, 100), ("thinning", 5000, 100)] {
        let pts = sphere(n, n as u64);
        let f: Vec<&[f64]> = pts.iter().map(|p| p.as_slice()).collect();
        let cv = vec![Infeasibility::FEASIBLE; n];
        let mut ts = vec![];
        for _ in 0..reps.min(10) {
            let t0 = std::time::Instant::now();
            pool.install(|| {
                if what == "survival" {
                    std::hint::black_box(survive(Survival::Hypervolume, &f, &cv, keep, norm));
                } else {
                    std::hint::black_box(greedy_subset(&pts, &reference, keep));
                }
            });
            ts.push(t0.elapsed().as_secs_f64());
        }
        let (a, b) = min_med(ts);
        say!(out, "  {what} {n} -> {keep}: {:.2} / {:.2} ms", a * 1e3, b * 1e3);
        rows.push(
            serde_json::json!({ "what": what, "points": n, "keep": keep, "min_ms": a * 1e3, "median_ms": b * 1e3 }),
        );
    }
    Ok(serde_json::Value::Array(rows))
}
