//! `gripopt moo-test`, `optimise`, `resume`.

use crate::cli::out::EXIT_CHECK_FAILED;
use anyhow::{bail, Context, Result};
use gripopt::app::FreeRecording;
use gripopt::app::moo::{run_test, TestProblem};

/// The most seeds one `moo-test --seeds A-B` runs (each is a whole NSGA-II run; the list is
/// held in memory).
const MAX_SEEDS: u64 = 100_000;

/// `gripopt moo-test NAME --seed S | --seeds A-B [--json]`: the exit code is
/// [`EXIT_CHECK_FAILED`] when a problem's hypervolume median over the seeds lies outside the
/// reference band (the text line says OUTSIDE; with `--json` a line on stderr says so), 0
/// when every median is inside.
pub fn moo_test(
    name: &str,
    seed: Option<u64>,
    seeds: Option<String>,
    json: bool,
    pop: usize,
    generations: Option<u64>,
) -> Result<i32> {
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
            if b - a >= MAX_SEEDS {
                bail!(
                    "--seeds `{r}`: {} seeds, at most {MAX_SEEDS} (each seed is a whole NSGA-II run)",
                    (b - a).saturating_add(1)
                );
            }
            (a..=b).collect()
        }
        (None, None) => vec![1],
        (Some(_), Some(_)) => bail!("give --seed or --seeds, not both"),
    };
    let mut code = 0;
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
                outln!("{}", serde_json::to_string(&r)?);
            }
            runs.push(r);
            pb.inc(1);
        }
        pb.finish_and_clear();
        let hv = median_and_range(runs.iter().map(|r| r.hv).collect());
        let (rm, lo, hi) = p.hv_band();
        let inside = hv.median >= lo && hv.median <= hi;
        if !inside {
            code = EXIT_CHECK_FAILED;
        }
        if json {
            if !inside {
                eprintln!(
                    "{}: hypervolume median {} over {} is OUTSIDE the reference band [{lo}, {hi}] (exit {EXIT_CHECK_FAILED})",
                    p.name(),
                    hv.median,
                    gripopt::app::counted(runs.len() as u64, "seed", "seeds")
                );
            }
            continue;
        }
        let igd_med = median_and_range(runs.iter().map(|r| r.igd).collect()).median;
        let wall: f64 = runs.iter().map(|r| r.wall_s).sum::<f64>() / runs.len() as f64;
        let verdict = if inside { "inside" } else { "OUTSIDE" };
        let seeds = gripopt::app::counted(runs.len() as u64, "seed", "seeds");
        outln!(
            "{:<8} {seeds:>8}: HV median {:.5} [min {:.5}, max {:.5}]  reference median {} [{}, {}]: {verdict}; IGD median {:.3e}; {} evals, {:.3} s/run",
            p.name(), hv.median, hv.min, hv.max, rm, lo, hi, igd_med, runs[0].evaluations, wall
        );
    }
    Ok(code)
}

/// The median (the upper middle value of an even count), least and greatest of a non-empty
/// list of values.
struct MedianRange {
    median: f64,
    min: f64,
    max: f64,
}

fn median_and_range(mut v: Vec<f64>) -> MedianRange {
    v.sort_by(f64::total_cmp);
    MedianRange { median: v[v.len() / 2], min: v[0], max: v[v.len() - 1] }
}

/// `optimise --json` / `resume --json`: the run's summary.
#[derive(serde::Serialize)]
struct SummaryJson<'a> {
    status: &'a str,
    run_dir: String,
    generations: u64,
    evaluations: u64,
    feasible: usize,
    front_size: usize,
    hypervolume: Option<f64>,
    wall_s: f64,
    exit_code: i32,
    /// Why no design is feasible (null when one is).
    no_feasible_design: Option<Vec<String>>,
}

/// Print where the results are (text, or one JSON object with `--json`), and when no design
/// was feasible, why (the discard causes); the exit code: 130 when the run was interrupted
/// (after the checkpoint of the current generation), else 0.
pub fn summary(s: &gripopt::app::RunSummary, json: bool) -> Result<i32> {
    let d = crate::cli::out::path(&s.out);
    let code = if s.interrupted { 130 } else { 0 };
    if json {
        let v = SummaryJson {
            status: if s.interrupted { "interrupted" } else { "finished" },
            run_dir: s.out.display().to_string(),
            generations: s.generations,
            evaluations: s.evaluations,
            feasible: s.feasible,
            front_size: s.front_size,
            hypervolume: s.hv.is_finite().then_some(s.hv),
            wall_s: s.wall_s,
            exit_code: code,
            no_feasible_design: s.discards.explain(),
        };
        outln!("{}", serde_json::to_string(&v)?);
        return Ok(code);
    }
    if s.interrupted {
        outln!(
            "interrupted after generation {} ({} evaluation{}); resume with `gripopt resume {d}`",
            s.generations,
            s.evaluations,
            if s.evaluations == 1 { "" } else { "s" }
        );
    } else {
        let n = gripopt::app::counted;
        outln!(
            "finished: {}, {} in {:.1} s; {} in the final population, {} on the Pareto front (hypervolume {:.4})",
            n(s.generations, "generation", "generations"),
            n(s.evaluations, "evaluation", "evaluations"),
            s.wall_s,
            n(s.feasible as u64, "feasible design", "feasible designs"),
            s.front_size,
            s.hv
        );
    }
    if let Some(lines) = s.discards.explain() {
        // the run's step budget, for an aborted simulation's line
        let max_steps =
            gripopt::app::RunFolder::open(&s.out).and_then(|f| f.problem()).ok().map(|p| p.solver.max_steps);
        for l in lines {
            outln!("{}", crate::cli::report::with_steps_hint(&l, max_steps));
        }
        outln!("every value of a design: `gripopt show {d} --design ID`");
    }
    outln!("results in {d}: pareto.csv (front), archive.csv, population.csv, history.csv, pareto_matrix.svg, hypervolume.svg, run.json, checkpoint.json; best designs: `gripopt show {d}`");
    Ok(code)
}

/// `replay --json`: the recorded `/designs` record and what the replay found.
#[derive(serde::Serialize)]
struct ReplayJson<'a> {
    #[serde(flatten)]
    recorded: &'a gripopt::app::DesignMessage,
    verified: bool,
    /// Why it cannot verify (a problem file edited since the run), else null.
    problem_note: Option<&'a str>,
    verdict_agrees: bool,
    max_difference: Option<f64>,
    /// A recording by another simulator revision: the comparison within the integration
    /// tolerance (null for the same revision, or when the replay verified bit for bit).
    across_revisions: Option<AcrossRevisionsJson>,
    compared_samples: usize,
    compared_values: usize,
    file: String,
    replay_s: f64,
    /// A single-object free-kind run: the design's free scene recorded here (`free-ID.mcap`).
    #[serde(skip_serializing_if = "Option::is_none")]
    free_recording: Option<String>,
    /// A single-object free-kind run: why the free scene was not recorded.
    #[serde(skip_serializing_if = "Option::is_none")]
    free_not_recorded: Option<String>,
}

/// `replay --json`'s `across_revisions`.
#[derive(serde::Serialize)]
struct AcrossRevisionsJson {
    recorded_revision: u32,
    current_revision: u32,
    agrees: bool,
    max_difference: f64,
    differs: Option<String>,
}

/// `gripopt replay`.
/// Exit code 3 when the recording is not verified, which includes a design with no recorded
/// trajectory (nothing was compared); 0 when it is, or when another simulator revision
/// recorded it and the re-evaluation agrees with it within the integration tolerance.
pub fn replay(
    dir: &std::path::Path,
    id: u64,
    json: bool,
    csv: Option<&std::path::Path>,
    plot: Option<&std::path::Path>,
) -> Result<i32> {
    let t0 = std::time::Instant::now();
    let r = gripopt::app::replay(dir, id)?;
    let secs = t0.elapsed().as_secs_f64();
    let samples = &r.recorded.samples;
    // verified means something was re-computed and compared: the trajectory, or (recorded
    // without one) the record's stage, reason, violation, objectives and simulation work
    let verified = r.verified && (r.compared > 0 || r.values_compared > 0);
    let across = r.across_revisions.as_ref();
    let code = if verified || across.is_some_and(|a| a.agrees()) { 0 } else { EXIT_CHECK_FAILED };
    if let Some(path) = csv {
        let kept = match r.recorded.resolution {
            gripopt::Resolution::Compact => "the compact subset, values at f32 precision",
            gripopt::Resolution::Full => "every recorded sample at full precision",
        };
        let fingers =
            if samples.iter().any(|s| s.finger2.is_some()) { "finger 1, then finger 2 (finger2_)" } else { "finger 1" };
        let title = format!("trajectory: {fingers} of design {id} as recorded ({kept}; docs/recording.md)");
        crate::cli::scenes::write_samples_csv(path, &title, samples, |v| format!("{v}"))?;
    }
    if let Some(path) = plot {
        let title = format!("design {id}");
        crate::cli::out::write_file_with(path, |tmp| Ok(gripopt::app::grasp_plot(tmp, &title, samples)?))?;
    }
    let rec = &r.recorded.record;
    // a single-object free-kind run: the design's free scene to MCAP (docs/recording.md)
    let (free_recording, free_not_recorded) = match gripopt::app::record_free_scene(dir, &r)? {
        Some(FreeRecording::Recorded(p)) => (Some(p.display().to_string()), None),
        Some(FreeRecording::NotRecorded(why)) => (None, Some(why)),
        None => (None, None),
    };
    if json {
        let v = ReplayJson {
            recorded: rec,
            verified,
            problem_note: r.problem_note.as_deref(),
            verdict_agrees: r.recomputed_feasible == rec.feasible,
            max_difference: r.max_difference.is_finite().then_some(r.max_difference),
            across_revisions: across.map(|a| AcrossRevisionsJson {
                recorded_revision: a.recorded,
                current_revision: a.current,
                agrees: a.agrees(),
                max_difference: a.max_difference,
                differs: a.differs.clone(),
            }),
            compared_samples: r.compared,
            compared_values: r.values_compared,
            file: r.recorded.file.display().to_string(),
            replay_s: secs,
            free_recording,
            free_not_recorded,
        };
        outln!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(code);
    }
    let text = |v: serde_json::Result<String>| v.unwrap_or_default();
    outln!("design {id} (generation {}) from {}", rec.generation, crate::cli::out::path(&r.recorded.file));
    if let Some(n) = &r.problem_note {
        outln!("  NOT verified: {n}; restore the run's problem file to verify the recording");
    }
    outln!("  parameters {}", text(serde_json::to_string(&rec.parameters)));
    outln!("  derived    {}", text(serde_json::to_string(&rec.derived)));
    match rec.failed_stage {
        Some(s) => outln!(
            "  DISCARDED at stage {s}: {} (violation {})",
            rec.reason.as_deref().unwrap_or(""),
            rec.violation.map_or("null".into(), |v| v.to_string())
        ),
        None => outln!("  feasible; objectives {}", text(serde_json::to_string(&rec.objectives))),
    }
    outln!(
        "  trajectory: {} samples{}",
        samples.len(),
        samples.last().map(|s| format!(", t = 0 … {:.3} ms", s.t * 1e3)).unwrap_or_default()
    );
    if r.problem_note.is_some() {
        // its one verdict, printed above: the comparison is moot
    } else if let Some(a) = across {
        let (rtol, rec, cur) = (gripopt::app::ACROSS_REVISIONS_RTOL, a.recorded, a.current);
        match &a.differs {
            None => outln!("  verified across simulator revisions (recorded by revision {rec}, this build is revision {cur}): the same verdict, objectives and violation within {rtol:e} relative (largest difference {:e}); trajectories of two revisions are not compared sample by sample", a.max_difference),
            Some(d) => outln!("  NOT verified: recorded by simulator revision {rec}, this build is revision {cur}, and beyond {rtol:e} relative: {d}"),
        }
    } else if r.compared == 0 && verified {
        outln!("  verified (no trajectory recorded for this design): the re-evaluation reproduces the record's stage, reason, violation, objectives and simulation work ({} values)", r.values_compared);
    } else if r.compared == 0 {
        outln!("  NOT verified: no trajectory was recorded, and the re-evaluation differs from the record (recomputed feasible: {})", r.recomputed_feasible);
    } else if verified {
        let precision = if r.recorded.resolution == gripopt::app::Resolution::Full {
            "every sample, f64"
        } else {
            "compact subset, to the recorded f32 precision"
        };
        outln!("  verified ({precision}): re-simulation reproduces the recorded trajectory (max relative difference {:e}, {} samples)", r.max_difference, r.compared);
    } else {
        outln!(
            "  NOT verified: max relative difference {:e} over {} samples (recomputed feasible: {})",
            r.max_difference,
            r.compared,
            r.recomputed_feasible
        );
    }
    if let Some(why) = &free_not_recorded {
        outln!("  {why}");
    }
    if let Some(m) = &free_recording {
        outln!(
            "  free scene recorded to {m} (open in Foxglove with {})",
            dir.join(gripopt::app::VERIFY_LAYOUT_FILE).display()
        );
    }
    outln!("  ({:.1} ms)", secs * 1e3);
    Ok(code)
}
