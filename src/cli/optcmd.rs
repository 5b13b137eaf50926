//! `gripopt moo-test`, `optimise`, `resume`.

use anyhow::{bail, Context, Result};
use gripopt::optim::{run_test, TestProblem};

/// `gripopt moo-test NAME --seed S | --seeds A-B [--json]`.
pub fn moo_test(name: &str, seed: Option<u64>, seeds: Option<String>, json: bool, pop: usize, generations: Option<u64>) -> Result<()> {
    let probs: Vec<TestProblem> = if name.eq_ignore_ascii_case("all") {
        TestProblem::ALL.to_vec()
    } else {
        vec![TestProblem::parse(name).with_context(|| format!("unknown test problem `{name}` (expected one of {} or all)", TestProblem::ALL.map(|p| p.name()).join(", ")))?]
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

/// Print where the results are.
pub fn summary(s: &gripopt::run::RunSummary) {
    let d = s.out.display();
    if s.interrupted {
        println!("interrupted after generation {} ({} evaluations); resume with `gripopt resume {d}`", s.generations, s.evaluations);
    } else {
        println!("finished: {} generations, {} evaluations in {:.1} s; {} feasible designs in the final population, {} on the Pareto front (hypervolume {:.4})", s.generations, s.evaluations, s.wall_s, s.feasible, s.front_size, s.hv);
    }
    println!("results in {d}/: pareto.csv (front), population.csv, history.csv, pareto_matrix.svg, hypervolume.svg, run.json, checkpoint.json");
}

/// `gripopt replay`.
pub fn replay(dir: &std::path::Path, id: u64, json: bool, csv: Option<&std::path::Path>, plot: Option<&std::path::Path>) -> Result<()> {
    use std::io::Write;
    let t0 = std::time::Instant::now();
    let r = gripopt::record::replay(dir, id)?;
    let secs = t0.elapsed().as_secs_f64();
    let samples = &r.recorded.samples;
    if let Some(path) = csv {
        let mut w = std::io::BufWriter::new(std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?);
        writeln!(w, "t,q11,q21,q11_dot,q21_dot,theta2,delta_1,delta_2,fn_1,fn_2,ft_1,ft_2,hand_fy,filtered_fy,energy,energy_excess")?;
        for s in samples {
            writeln!(w, "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}", s.t, s.q[0], s.q[1], s.qd[0], s.qd[1], s.theta2, s.delta[0], s.delta[1], s.normal[0], s.normal[1], s.friction[0], s.friction[1], s.hand_fy, s.filtered_fy, s.energy, s.energy_excess)?;
        }
        w.flush()?;
    }
    if let Some(path) = plot {
        plot_trajectory(path, id, samples)?;
    }
    if json {
        let mut v = r.recorded.record.clone();
        v["verified"] = serde_json::json!(r.verified);
        v["max_difference"] = serde_json::json!(if r.max_difference.is_finite() { Some(r.max_difference) } else { None });
        v["compared_samples"] = serde_json::json!(r.compared);
        v["file"] = serde_json::json!(r.recorded.file.display().to_string());
        v["replay_s"] = serde_json::json!(secs);
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    let rec = &r.recorded.record;
    println!("design {id} (generation {}) from {}", rec["generation"], r.recorded.file.display());
    println!("  parameters {}", rec["parameters"]);
    println!("  derived    {}", rec["derived"]);
    match rec["failed_stage"].as_u64() {
        Some(s) => println!("  DISCARDED at stage {s}: {} (violation {})", rec["reason"].as_str().unwrap_or(""), rec["violation"]),
        None => println!("  feasible; objectives {}", rec["objectives"]),
    }
    println!("  trajectory: {} samples{}", samples.len(), samples.last().map(|s| format!(", t = 0 … {:.3} ms", s.t * 1e3)).unwrap_or_default());
    if r.verified {
        let precision = if r.recorded.resolution == gripopt::record::Resolution::Full { "every sample, f64" } else { "compact subset, to the recorded f32 precision" };
        println!("  verified ({precision}): re-simulation reproduces the recorded trajectory (max relative difference {:e}, {} samples)", r.max_difference, r.compared);
    } else {
        println!("  NOT verified: max relative difference {:e} over {} samples (recomputed feasible: {})", r.max_difference, r.compared, r.recomputed_feasible);
    }
    println!("  ({:.1} ms)", secs * 1e3);
    Ok(())
}

fn plot_trajectory(path: &std::path::Path, id: u64, s: &[gripopt::sim::Sample]) -> Result<()> {
    use plotters::prelude::*;
    let e = |x: Box<dyn std::fmt::Display>| anyhow::anyhow!("plot {}: {x}", path.display());
    let root = SVGBackend::new(path, (900, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(Box::new(x)))?;
    let (top, bottom) = root.split_vertically(350);
    let tmax = s.last().map_or(1e-3, |x| x.t).max(1e-6) * 1e3;
    let ang: Vec<(f64, f64, f64, f64)> = s.iter().map(|x| (x.t * 1e3, x.q[0].to_degrees(), x.q[1].to_degrees(), x.theta2.to_degrees())).collect();
    let (amin, amax) = ang.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v.1.min(v.2).min(v.3)), b.max(v.1.max(v.2).max(v.3))));
    let (amin, amax) = if amin.is_finite() { (amin - 1.0, amax + 1.0) } else { (0.0, 1.0) };
    let mut c = ChartBuilder::on(&top).caption(format!("design {id}: joint angles"), ("sans-serif", 18)).margin(10).x_label_area_size(30).y_label_area_size(50).build_cartesian_2d(0.0..tmax, amin..amax).map_err(|x| e(Box::new(x)))?;
    c.configure_mesh().x_desc("t (ms)").y_desc("deg").draw().map_err(|x| e(Box::new(x)))?;
    for (k, col, name) in [(1, RED, "q11"), (2, BLUE, "q21 = theta1"), (3, GREEN, "theta2")] {
        c.draw_series(LineSeries::new(ang.iter().map(|v| (v.0, [v.1, v.2, v.3][k - 1])), col)).map_err(|x| e(Box::new(x)))?.label(name).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], col));
    }
    c.configure_series_labels().background_style(WHITE).border_style(BLACK).draw().map_err(|x| e(Box::new(x)))?;
    let fmax = s.iter().map(|x| x.normal[0].max(x.normal[1])).fold(1.0, f64::max).min(200.0);
    let mut c = ChartBuilder::on(&bottom).caption("contact normal forces (N, clipped at 200)", ("sans-serif", 18)).margin(10).x_label_area_size(30).y_label_area_size(50).build_cartesian_2d(0.0..tmax, 0.0..fmax * 1.05).map_err(|x| e(Box::new(x)))?;
    c.configure_mesh().x_desc("t (ms)").y_desc("N").draw().map_err(|x| e(Box::new(x)))?;
    for (k, col, name) in [(0usize, RED, "proximal"), (1, BLUE, "distal")] {
        c.draw_series(LineSeries::new(s.iter().map(|x| (x.t * 1e3, x.normal[k].min(fmax * 1.05))), col)).map_err(|x| e(Box::new(x)))?.label(name).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], col));
    }
    c.configure_series_labels().background_style(WHITE).border_style(BLACK).draw().map_err(|x| e(Box::new(x)))?;
    root.present().map_err(|x| e(Box::new(x)))?;
    Ok(())
}
