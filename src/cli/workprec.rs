//! `gripopt bench work-precision`: CPU time against error for each integrator.

use anyhow::{Context, Result};
use gripopt::eval::{evaluate, stage_kinematics, stage_statics, EvalOptions};
use gripopt::params::{Design, Problem};
use gripopt::sim::{simulate_grasp, DynamicsResult, Method, SimOptions};
use std::io::Write;
use std::path::Path;
use std::time::Instant;

/// One row of the work-precision table.
struct Row {
    method: &'static str,
    rtol: f64,
    cpu_min: f64,
    cpu_med: f64,
    steps: u64,
    rhs: u64,
    err_t_first: f64,
    err_e_cyl: f64,
    err_t_stab: f64,
    err_force: f64,
    verdict_same: bool,
}

fn rel(a: Option<f64>, b: Option<f64>) -> f64 {
    match (a, b) {
        (Some(a), Some(b)) if b != 0.0 => ((a - b) / b).abs(),
        _ => f64::NAN,
    }
}

fn time_it<F: FnMut() -> DynamicsResult>(mut f: F, budget_s: f64, max_reps: usize) -> (DynamicsResult, f64, f64) {
    let mut ts = vec![];
    let start = Instant::now();
    let mut last = None;
    while ts.len() < 3 || (start.elapsed().as_secs_f64() < budget_s && ts.len() < max_reps) {
        let t0 = Instant::now();
        let r = f();
        ts.push(t0.elapsed().as_secs_f64());
        last = Some(r);
    }
    ts.sort_by(f64::total_cmp);
    (last.expect("ran"), ts[0], ts[ts.len() / 2])
}

/// Run the benchmark and write CSV + SVG into `out_dir`.
pub fn run(problem: &Path, design: Design, out_dir: &Path, reps: usize, atol: Option<f64>) -> Result<()> {
    let p = Problem::load(problem)?;
    let s = &p.scene;
    let k = stage_kinematics(&design, s).map_err(|d| anyhow::anyhow!("design discarded at stage {}: {}", d.stage, d.reason))?;
    let st = stage_statics(&k.finger, s).map_err(|d| anyhow::anyhow!("design discarded at stage {}: {}", d.stage, d.reason))?;
    let f = k.finger;
    let atol_of = |rtol: f64| atol.unwrap_or(rtol * 1e-3);
    let diag = |m: Method, rtol: f64| SimOptions { method: m, ..SimOptions::diagnostic(rtol, atol_of(rtol), 5_000_000) };
    // the reference is tight whatever --atol says
    let tight = |m: Method| SimOptions { method: m, ..SimOptions::diagnostic(1e-12, 1e-15, 5_000_000) };
    let reference = simulate_grasp(&f, s, &st, &tight(Method::Radau5));
    let check = simulate_grasp(&f, s, &st, &tight(Method::Dopri5));
    println!("atol: {}", atol.map_or("1e-3·rtol".to_string(), |a| format!("{a:e} at every rtol")));
    let t_ref = reference.t_stab.context("the reference run did not reach stability")?;
    println!("reference: Radau IIA rtol 1e-12: t_first {:.12e} s, E_cyl {:.12e} J, t_stab {:.12e} s, f_stab ({:.9}, {:.9}) N", reference.first.map(|x| x.t).unwrap_or(f64::NAN), reference.first.map(|x| x.impact.e_cyl).unwrap_or(f64::NAN), t_ref, reference.f_end[0], reference.f_end[1]);
    println!("           Dormand–Prince rtol 1e-12 differs by {:.1e} relative in t_stab", rel(check.t_stab, reference.t_stab));
    let methods = [Method::Radau5, Method::TrBdf2, Method::Dopri5];
    let rtols = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10];
    let pb = indicatif::ProgressBar::new((methods.len() * rtols.len()) as u64);
    pb.set_style(indicatif::ProgressStyle::with_template("work-precision [{bar:30}] {pos}/{len} {msg}").expect("template"));
    let mut rows = vec![];
    for m in methods {
        for &rtol in &rtols {
            pb.set_message(format!("{m:?} rtol {rtol:e}"));
            let o = diag(m, rtol);
            let (r, tmin, tmed) = time_it(|| simulate_grasp(&f, s, &st, &o), 1.0, reps);
            let ef = r.f_end.iter().zip(reference.f_end.iter()).map(|(a, b)| ((a - b) / b).abs()).fold(0.0, f64::max);
            rows.push(Row {
                method: label(m),
                rtol,
                cpu_min: tmin,
                cpu_med: tmed,
                steps: r.stats.steps,
                rhs: r.rhs_evals,
                err_t_first: rel(r.first.map(|x| x.t), reference.first.map(|x| x.t)),
                err_e_cyl: rel(r.first.map(|x| x.impact.e_cyl), reference.first.map(|x| x.impact.e_cyl)),
                err_t_stab: rel(r.t_stab, reference.t_stab),
                err_force: if r.t_stab.is_some() { ef } else { f64::NAN },
                verdict_same: r.outcome == reference.outcome,
            });
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    rows.extend(diffsol_rows(&f, s, &st, &reference, reps, atol)?);
    std::fs::create_dir_all(out_dir).with_context(|| format!("cannot create {}", out_dir.display()))?;
    let csv = out_dir.join("work_precision.csv");
    let mut w = std::io::BufWriter::new(std::fs::File::create(&csv).with_context(|| format!("cannot create {}", csv.display()))?);
    writeln!(w, "method,rtol,cpu_min_s,cpu_median_s,steps,rhs_evals,err_t_first_contact,err_e_cyl,err_t_stab,err_final_forces,same_verdict")?;
    println!("{:<8} {:>7} {:>10} {:>10} {:>7} {:>8} {:>10} {:>10} {:>10} {:>10} {}", "method", "rtol", "cpu min", "cpu med", "steps", "rhs", "e(t_fc)", "e(E_cyl)", "e(t_stab)", "e(f_stab)", "verdict");
    for r in &rows {
        writeln!(w, "{},{:e},{:e},{:e},{},{},{:e},{:e},{:e},{:e},{}", r.method, r.rtol, r.cpu_min, r.cpu_med, r.steps, r.rhs, r.err_t_first, r.err_e_cyl, r.err_t_stab, r.err_force, r.verdict_same)?;
        println!("{:<8} {:>7.0e} {:>8.3}ms {:>8.3}ms {:>7} {:>8} {:>10.2e} {:>10.2e} {:>10.2e} {:>10.2e} {}", r.method, r.rtol, r.cpu_min * 1e3, r.cpu_med * 1e3, r.steps, r.rhs, r.err_t_first, r.err_e_cyl, r.err_t_stab, r.err_force, if r.verdict_same { "same" } else { "DIFFERS" });
    }
    w.flush()?;
    // cheapest run meeting 1e-5 on t_stab, per method
    let mut labels: Vec<&str> = rows.iter().map(|r| r.method).collect();
    labels.dedup();
    for m in labels {
        let best = rows.iter().filter(|r| r.method == m && r.err_t_stab <= 1e-5).min_by(|a, b| a.cpu_med.total_cmp(&b.cpu_med));
        match best {
            Some(r) => println!("{m}: t_stab within 1e-5 at rtol {:e} in {:.3} ms (min {:.3} ms)", r.rtol, r.cpu_med * 1e3, r.cpu_min * 1e3),
            None => println!("{m}: no tolerance reached 1e-5 on t_stab"),
        }
    }
    // whole staged evaluation (stages 0–3, pipeline mode, max_offset scan included)
    let opts = EvalOptions::full(&p);
    let mut ts = vec![];
    for _ in 0..reps.max(20) {
        let t0 = Instant::now();
        std::hint::black_box(evaluate(&design, s, &opts));
        ts.push(t0.elapsed().as_secs_f64());
    }
    ts.sort_by(f64::total_cmp);
    let ev = evaluate(&design, s, &opts);
    println!("whole staged evaluation (stages 0-3, pipeline mode, rtol {:e}): min {:.3} ms, median {:.3} ms; verdict: {}", p.solver.rtol, ts[0] * 1e3, ts[ts.len() / 2] * 1e3, ev.discard.map(|d| format!("stage {} {}", d.stage, d.reason)).unwrap_or("feasible".into()));
    plot(&rows, &out_dir.join("work_precision.svg"))?;
    println!("wrote {} and {}", csv.display(), out_dir.join("work_precision.svg").display());
    let _ = t_ref;
    Ok(())
}

/// Label of one of gripopt's own methods in the table.
fn label(m: Method) -> &'static str {
    match m {
        Method::Radau5 => "Radau5",
        Method::TrBdf2 => "TrBdf2",
        Method::Dopri5 => "Dopri5",
    }
}

/// The same grasp through diffsol's solvers, against the same reference (feature `diffsol`).
#[cfg(feature = "diffsol")]
fn diffsol_rows(f: &gripopt::model::geometry::Finger, s: &gripopt::params::SceneParams, st: &gripopt::eval::StaticsResult, reference: &DynamicsResult, reps: usize, atol: Option<f64>) -> Result<Vec<Row>> {
    use super::diffsol_cmp::{simulate, DsMethod};
    let mut rows = vec![];
    let pb = indicatif::ProgressBar::new((DsMethod::ALL.len() * 6) as u64);
    pb.set_style(indicatif::ProgressStyle::with_template("diffsol [{bar:30}] {pos}/{len} {msg}").expect("template"));
    for m in DsMethod::ALL {
        for rtol in [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
            pb.set_message(format!("{} rtol {rtol:e}", m.label()));
            pb.inc(1);
            let mut ts = vec![];
            let start = Instant::now();
            let mut last = None;
            while ts.len() < 3 || (start.elapsed().as_secs_f64() < 1.0 && ts.len() < reps) {
                let t0 = Instant::now();
                let r = simulate(f, s, st, m, rtol, atol.unwrap_or(rtol * 1e-3));
                ts.push(t0.elapsed().as_secs_f64());
                last = Some(r);
            }
            ts.sort_by(f64::total_cmp);
            let r = match last.expect("ran") {
                Ok(r) => r,
                Err(e) => {
                    pb.suspend(|| eprintln!("{} rtol {rtol:e}: failed ({e})", m.label()));
                    continue;
                }
            };
            let ef = r.f_end.iter().zip(reference.f_end.iter()).map(|(a, b)| ((a - b) / b).abs()).fold(0.0, f64::max);
            rows.push(Row {
                method: m.label(),
                rtol,
                cpu_min: ts[0],
                cpu_med: ts[ts.len() / 2],
                steps: r.steps,
                rhs: r.rhs,
                err_t_first: rel(r.t_first, reference.first.map(|x| x.t)),
                err_e_cyl: rel(r.e_cyl, reference.first.map(|x| x.impact.e_cyl)),
                err_t_stab: rel(r.t_stab, reference.t_stab),
                err_force: if r.t_stab.is_some() { ef } else { f64::NAN },
                verdict_same: r.t_stab.is_some() == reference.t_stab.is_some(),
            });
        }
    }
    pb.finish_and_clear();
    Ok(rows)
}

/// Without the `diffsol` feature there is nothing to compare against.
#[cfg(not(feature = "diffsol"))]
fn diffsol_rows(_: &gripopt::model::geometry::Finger, _: &gripopt::params::SceneParams, _: &gripopt::eval::StaticsResult, _: &DynamicsResult, _: usize, _: Option<f64>) -> Result<Vec<Row>> {
    println!("(diffsol rows: build with `--features diffsol`, as `make bench` does)");
    Ok(vec![])
}

fn plot(rows: &[Row], path: &Path) -> Result<()> {
    use plotters::prelude::*;
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e}"))?;
    let pts: Vec<_> = rows.iter().filter(|r| r.err_t_stab.is_finite() && r.err_t_stab > 0.0).collect();
    let (xmin, xmax) = pts.iter().fold((1e-14f64, 1.0f64), |(a, b), r| (a.min(r.err_t_stab), b.max(r.err_t_stab)));
    let (ymin, ymax) = pts.iter().fold((1e-4f64, 1e-3f64), |(a, b), r| (a.min(r.cpu_med), b.max(r.cpu_med)));
    let mut chart = ChartBuilder::on(&root)
        .caption("work-precision: nominal grasp to t_stab", ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((xmin * 0.5..xmax * 2.0).log_scale(), (ymin * 0.8..ymax * 1.25).log_scale())
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    chart
        .configure_mesh()
        .x_desc("relative error in t_stab")
        .y_desc("CPU time, median (s)")
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut labels: Vec<&str> = rows.iter().map(|r| r.method).collect();
    labels.dedup();
    let palette = [RED, BLUE, GREEN, MAGENTA, CYAN, BLACK, RGBColor(255, 140, 0)];
    for (j, m) in labels.into_iter().enumerate() {
        let color = palette[j % palette.len()];
        let series: Vec<(f64, f64)> = pts.iter().filter(|r| r.method == m).map(|r| (r.err_t_stab, r.cpu_med)).collect();
        chart
            .draw_series(LineSeries::new(series.clone(), color.stroke_width(2)))
            .map_err(|e| anyhow::anyhow!("{e}"))?
            .label(m.to_string())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        chart.draw_series(series.iter().map(|&(x, y)| Circle::new((x, y), 4, color.filled()))).map_err(|e| anyhow::anyhow!("{e}"))?;
    }
    chart.configure_series_labels().border_style(BLACK).background_style(WHITE).draw().map_err(|e| anyhow::anyhow!("{e}"))?;
    root.present().map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(())
}

/// Work-precision over an ensemble of `n` random designs of the box that pass stage 2
/// (seed `seed`): for each method and rtol, the median CPU time per simulation and the
/// median / 90th-percentile relative errors in t_stab and E_cyl against Radau IIA at rtol
/// 1e-11, and how many verdicts differ. Writes work_precision_ensemble.csv.
pub fn run_ensemble(problem: &Path, n: usize, seed: u64, out_dir: &Path, atol: Option<f64>) -> Result<()> {
    use rand::{Rng, SeedableRng};
    let p = Problem::load(problem)?;
    let s = &p.scene;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let diag = |m: Method, rtol: f64| SimOptions { method: m, ..SimOptions::diagnostic(rtol, atol.unwrap_or(rtol * 1e-3), 5_000_000) };
    let tight = SimOptions::diagnostic(1e-11, 1e-14, 5_000_000);
    let mut cases = vec![];
    let mut drawn = 0usize;
    let pb = indicatif::ProgressBar::new(n as u64);
    pb.set_style(indicatif::ProgressStyle::with_template("designs + references [{bar:30}] {pos}/{len}").expect("template"));
    while cases.len() < n && drawn < 1000 * n {
        drawn += 1;
        let mut x = [0.0; 6];
        for i in 0..6 {
            x[i] = rng.random_range(p.bounds.lo[i]..=p.bounds.hi[i]);
        }
        let d = Design::from_array(&x);
        let Ok(k) = stage_kinematics(&d, s) else { continue };
        let Ok(st) = stage_statics(&k.finger, s) else { continue };
        let reference = simulate_grasp(&k.finger, s, &st, &tight);
        if reference.t_stab.is_none() {
            continue;
        }
        cases.push((k.finger, st, reference));
        pb.inc(1);
    }
    pb.finish_and_clear();
    if cases.is_empty() {
        anyhow::bail!("{}: no random design of the box passed stage 2 and reached stability in {drawn} draws", problem.display());
    }
    println!("ensemble: {} designs passing stage 2 and reaching stability (drawn {drawn}, seed {seed}); reference Radau IIA rtol 1e-11", cases.len());
    let q = |mut v: Vec<f64>, f: f64| -> f64 {
        v.retain(|x| !x.is_nan());
        if v.is_empty() {
            return f64::NAN;
        }
        v.sort_by(f64::total_cmp);
        v[((v.len() - 1) as f64 * f).round() as usize]
    };
    std::fs::create_dir_all(out_dir).with_context(|| format!("cannot create {}", out_dir.display()))?;
    let csv = out_dir.join("work_precision_ensemble.csv");
    let mut w = std::io::BufWriter::new(std::fs::File::create(&csv).with_context(|| format!("cannot create {}", csv.display()))?);
    writeln!(w, "method,rtol,designs,cpu_median_s,steps_median,rhs_median,err_t_stab_median,err_t_stab_p90,err_e_cyl_median,err_e_cyl_p90,verdicts_differing")?;
    println!("{:<8} {:>7} {:>10} {:>7} {:>7} {:>11} {:>11} {:>11} {:>11} {}", "method", "rtol", "cpu med", "steps", "rhs", "t_stab med", "t_stab p90", "E_cyl med", "E_cyl p90", "verdicts differ");
    for m in [Method::Radau5, Method::Dopri5, Method::TrBdf2] {
        for rtol in [1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
            if m == Method::TrBdf2 && rtol < 1e-7 {
                continue;
            }
            let o = diag(m, rtol);
            let (mut cpu, mut steps, mut rhs, mut ets, mut ee) = (vec![], vec![], vec![], vec![], vec![]);
            let mut differ = 0;
            for (f, st, reference) in &cases {
                let (r, _, tmed) = time_it(|| simulate_grasp(f, s, st, &o), 0.05, 7);
                cpu.push(tmed);
                steps.push(r.stats.steps as f64);
                rhs.push(r.rhs_evals as f64);
                ets.push(rel(r.t_stab, reference.t_stab));
                ee.push(rel(r.first.map(|x| x.impact.e_cyl), reference.first.map(|x| x.impact.e_cyl)));
                differ += usize::from(r.outcome != reference.outcome);
            }
            let row = (q(cpu, 0.5), q(steps, 0.5), q(rhs, 0.5), q(ets.clone(), 0.5), q(ets, 0.9), q(ee.clone(), 0.5), q(ee, 0.9));
            writeln!(w, "{m:?},{rtol:e},{},{:e},{},{},{:e},{:e},{:e},{:e},{differ}", cases.len(), row.0, row.1, row.2, row.3, row.4, row.5, row.6)?;
            println!("{:<8} {:>7.0e} {:>8.3}ms {:>7} {:>7} {:>11.2e} {:>11.2e} {:>11.2e} {:>11.2e} {differ}", format!("{m:?}"), rtol, row.0 * 1e3, row.1, row.2, row.3, row.4, row.5, row.6);
        }
    }
    w.flush()?;
    println!("wrote {}", csv.display());
    Ok(())
}
