//! `gripopt bench static`: throughput of the static pipeline (stages 0–2).

use super::{say, BenchProgress, Out};
use crate::eval::{evaluate, EvalOptions};
use crate::params::{Design, Problem};
use crate::Result;
use rand::SeedableRng;
use std::path::Path;

/// Static pipeline (stages 0–2) throughput on one core: `n` random designs in the bounds of
/// `problem` (seed `seed`), five repetitions; prints designs/s and the discard counts per
/// stage to `out` and returns them as JSON. `path` is the problem file, for the printout.
pub fn static_pipeline(
    problem: &Problem,
    path: &Path,
    n: usize,
    seed: u64,
    out: Out,
    progress: &dyn BenchProgress,
) -> Result<serde_json::Value> {
    let p = problem;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let designs: Vec<Design> = (0..n).map(|_| p.bounds.sample(&mut rng)).collect();
    let opts = EvalOptions::statics_only();
    let mut counts = [0usize; 4];
    let mut feasible = 0usize;
    let mut times = Vec::new();
    progress.begin("bench static", 5, "repetitions");
    for rep in 0..5 {
        let t0 = std::time::Instant::now();
        for x in &designs {
            let ev = evaluate(x, &p.scene, &opts);
            if rep == 0 {
                match ev.discard {
                    Some(d) => counts[d.stage as usize] += 1,
                    None => feasible += 1,
                }
            }
            std::hint::black_box(&ev);
        }
        times.push(t0.elapsed().as_secs_f64());
        progress.step();
    }
    progress.end();
    let (tmin, tmed) = super::min_med(times);
    say!(
        out,
        "static pipeline (stages 0-2), {} random designs in the bounds of {}, seed {seed}, 1 thread, 5 repetitions",
        n,
        path.display()
    );
    say!(
        out,
        "  designs/s: min-time {:.0}  median-time {:.0}   ({:.2} us/design at min)",
        n as f64 / tmin,
        n as f64 / tmed,
        tmin / n as f64 * 1e6
    );
    for (s, c) in counts.iter().enumerate() {
        say!(out, "  discarded at stage {s}: {c} ({:.1} %)", 100.0 * *c as f64 / n as f64);
    }
    say!(out, "  passed stage 2: {feasible} ({:.1} %)", 100.0 * feasible as f64 / n as f64);
    Ok(serde_json::json!({
        "bench": "static", "problem": path.display().to_string(), "designs": n, "seed": seed, "threads": 1, "repetitions": 5,
        "designs_per_s_min_time": n as f64 / tmin, "designs_per_s_median_time": n as f64 / tmed, "us_per_design_min": tmin / n as f64 * 1e6,
        "discarded_by_stage": counts, "passed_stage_2": feasible,
    }))
}
