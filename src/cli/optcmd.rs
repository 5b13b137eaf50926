//! `gripopt moo-test`, `optimise`, `resume`.

use anyhow::{bail, Context, Result};
use gripopt::optim::{run_test, TestProblem};

/// `gripopt moo-test NAME --seed S | --seeds A-B [--json]`.
pub fn moo_test(
    name: &str,
    seed: Option<u64>,
    seeds: Option<String>,
    json: bool,
    pop: usize,
    generations: Option<u64>,
) -> Result<()> {
    let probs: Vec<TestProblem> = if name.eq_ignore_ascii_case("all") {
        TestProblem::ALL.to_vec()
    } else {
        vec![TestProblem::parse(name).with_context(|| {
            format!(
                "unknown test problem `{name}` (expected one of {} or all)",
                TestProblem::ALL.map(|p| p.name()).join(", ")
            )
        })?]
    };
    let seed_list: Vec<u64> = match (seed, seeds) {
        (Some(s), None) => vec![s],
        (None, Some(r)) => {
            let (a, b) = r.split_once('-').with_context(|| format!("--seeds `{r}`: expected a range A-B"))?;
            let a: u64 = a.trim().parse().with_context(|| format!("--seeds `{r}`: `{a}` is not a whole number"))?;
            let b: u64 = b.trim().parse().with_context(|| format!("--seeds `{r}`: `{b}` is not a whole number"))?;
            if a > b {
                bail!("--seeds `{r}`: empty range");
            }
            (a..=b).collect()
        }
        (None, None) => vec![1],
        (Some(_), Some(_)) => bail!("give --seed or --seeds, not both"),
    };
    for p in probs {
        let pb = indicatif::ProgressBar::new(seed_list.len() as u64);
        pb.set_style(indicatif::ProgressStyle::with_template("{msg} [{bar:25}] {pos}/{len} seeds").expect("template"));
        pb.set_message(p.name().to_string());
        if json {
            pb.set_draw_target(indicatif::ProgressDrawTarget::hidden());
        }
        let mut runs = vec![];
        for &s in &seed_list {
            let r = run_test(p, s, pop, generations);
            if json {
                println!("{}", serde_json::to_string(&r)?);
            }
            runs.push(r);
            pb.inc(1);
        }
        pb.finish_and_clear();
        if !json {
            let mut hv: Vec<f64> = runs.iter().map(|r| r.hv).collect();
            hv.sort_by(f64::total_cmp);
            let med = hv[hv.len() / 2];
            let (rm, lo, hi) = p.hv_band();
            let igd_med = {
                let mut v: Vec<f64> = runs.iter().map(|r| r.igd).collect();
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            let wall: f64 = runs.iter().map(|r| r.wall_s).sum::<f64>() / runs.len() as f64;
            let verdict = if med >= lo && med <= hi { "inside" } else { "OUTSIDE" };
            println!(
                "{:<8} seeds {:>2}: HV median {:.5} [min {:.5}, max {:.5}]  reference median {} [{}, {}]: {verdict}; IGD median {:.3e}; {} evals, {:.3} s/run",
                p.name(), runs.len(), med, hv[0], hv[hv.len() - 1], rm, lo, hi, igd_med, runs[0].evaluations, wall
            );
        }
    }
    Ok(())
}

/// Print where the results are (text, or one JSON object with `--json`); the exit code:
/// 130 when the run was interrupted (after the checkpoint of the current generation), else 0.
pub fn summary(s: &gripopt::run::RunSummary, json: bool) -> Result<i32> {
    let d = s.out.display();
    let code = if s.interrupted { 130 } else { 0 };
    if json {
        let v = serde_json::json!({
            "status": if s.interrupted { "interrupted" } else { "finished" },
            "run_dir": d.to_string(),
            "generations": s.generations,
            "evaluations": s.evaluations,
            "feasible": s.feasible,
            "front_size": s.front_size,
            "hypervolume": if s.hv.is_finite() { Some(s.hv) } else { None },
            "wall_s": s.wall_s,
            "exit_code": code,
        });
        println!("{}", serde_json::to_string(&v)?);
        return Ok(code);
    }
    if s.interrupted {
        println!(
            "interrupted after generation {} ({} evaluations); resume with `gripopt resume {d}`",
            s.generations, s.evaluations
        );
    } else {
        println!("finished: {} generations, {} evaluations in {:.1} s; {} feasible designs in the final population, {} on the Pareto front (hypervolume {:.4})", s.generations, s.evaluations, s.wall_s, s.feasible, s.front_size, s.hv);
    }
    println!("results in {d}/: pareto.csv (front), archive.csv, population.csv, history.csv, pareto_matrix.svg, hypervolume.svg, run.json, checkpoint.json; best designs: `gripopt show {d}`");
    Ok(code)
}

/// `gripopt replay`.
/// Exit code 3 when the recording is not verified, which includes a design with no recorded
/// trajectory (nothing was compared).
pub fn replay(
    dir: &std::path::Path,
    id: u64,
    json: bool,
    csv: Option<&std::path::Path>,
    plot: Option<&std::path::Path>,
) -> Result<i32> {
    use std::io::Write;
    let t0 = std::time::Instant::now();
    let r = gripopt::record::replay(dir, id)?;
    let secs = t0.elapsed().as_secs_f64();
    let samples = &r.recorded.samples;
    // verified means something was re-computed and compared: the trajectory, or (recorded
    // without one) the record's stage, reason, violation, objectives and simulation work
    let verified = r.verified && (r.compared > 0 || r.values_compared > 0);
    let code = if verified { 0 } else { 3 };
    if let Some(path) = csv {
        let mut w = std::io::BufWriter::new(
            std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?,
        );
        writeln!(w, "t,q11,q21,q11_dot,q21_dot,theta2,delta_1,delta_2,fn_1,fn_2,ft_1,ft_2,hand_fy,filtered_fy,energy,energy_excess")?;
        for s in samples {
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                s.t,
                s.q[0],
                s.q[1],
                s.qd[0],
                s.qd[1],
                s.theta2,
                s.delta[0],
                s.delta[1],
                s.normal[0],
                s.normal[1],
                s.friction[0],
                s.friction[1],
                s.hand_fy,
                s.filtered_fy,
                s.energy,
                s.energy_excess
            )?;
        }
        w.flush()?;
    }
    if let Some(path) = plot {
        gripopt::run::grasp_plot(path, &format!("design {id}"), samples)?;
    }
    if json {
        let mut v = r.recorded.record.clone();
        v["verified"] = serde_json::json!(verified);
        v["verdict_agrees"] = serde_json::json!(r.recomputed_feasible == v["feasible"].as_bool().unwrap_or(false));
        v["max_difference"] =
            serde_json::json!(if r.max_difference.is_finite() { Some(r.max_difference) } else { None });
        v["compared_samples"] = serde_json::json!(r.compared);
        v["compared_values"] = serde_json::json!(r.values_compared);
        v["file"] = serde_json::json!(r.recorded.file.display().to_string());
        v["replay_s"] = serde_json::json!(secs);
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(code);
    }
    let rec = &r.recorded.record;
    println!("design {id} (generation {}) from {}", rec["generation"], r.recorded.file.display());
    println!("  parameters {}", rec["parameters"]);
    println!("  derived    {}", rec["derived"]);
    match rec["failed_stage"].as_u64() {
        Some(s) => println!(
            "  DISCARDED at stage {s}: {} (violation {})",
            rec["reason"].as_str().unwrap_or(""),
            rec["violation"]
        ),
        None => println!("  feasible; objectives {}", rec["objectives"]),
    }
    println!(
        "  trajectory: {} samples{}",
        samples.len(),
        samples.last().map(|s| format!(", t = 0 … {:.3} ms", s.t * 1e3)).unwrap_or_default()
    );
    if r.compared == 0 && verified {
        println!("  verified (no trajectory recorded for this design): the re-evaluation reproduces the record's stage, reason, violation, objectives and simulation work ({} values)", r.values_compared);
    } else if r.compared == 0 {
        println!("  NOT verified: no trajectory was recorded, and the re-evaluation differs from the record (recomputed feasible: {})", r.recomputed_feasible);
    } else if verified {
        let precision = if r.recorded.resolution == gripopt::record::Resolution::Full {
            "every sample, f64"
        } else {
            "compact subset, to the recorded f32 precision"
        };
        println!("  verified ({precision}): re-simulation reproduces the recorded trajectory (max relative difference {:e}, {} samples)", r.max_difference, r.compared);
    } else {
        println!(
            "  NOT verified: max relative difference {:e} over {} samples (recomputed feasible: {})",
            r.max_difference, r.compared, r.recomputed_feasible
        );
    }
    println!("  ({:.1} ms)", secs * 1e3);
    Ok(code)
}
