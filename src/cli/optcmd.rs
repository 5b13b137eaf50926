//! `gripopt moo-test`, `optimise`, `resume`.

use crate::cli::args::{check_output, with_hooks, RecordArg};
use crate::cli::out::EXIT_CHECK_FAILED;
use anyhow::{bail, Context, Result};
use gripopt::app::moo::{run_test, TestProblem};
use gripopt::app::{FreeRecording, Optimiser, RecordOptions, Replay, Resolution, TrajectoryKeep};
use std::path::PathBuf;

/// Arguments of `gripopt optimise`.
#[derive(clap::Args)]
pub struct OptimiseArgs {
    /// Problem file (TOML).
    pub problem: PathBuf,
    /// Run folder (created; must not hold a run already).
    #[arg(long)]
    pub out: PathBuf,
    /// Population size.
    #[arg(long, default_value_t = 100)]
    pub pop: usize,
    /// Generations (1 = the random initial population).
    #[arg(long, default_value_t = 50)]
    pub generations: u64,
    /// Seed (fixes the run).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores; results do not depend on it).
    #[arg(long)]
    pub threads: Option<usize>,
    /// What to record to MCAP in RUN_DIR/recording: every design with its grasp
    /// (all), trajectories of feasible designs only (feasible), design records only
    /// (designs), or nothing (none).
    #[arg(long, value_enum, default_value = "all")]
    pub record: RecordArg,
    /// Keep every n-th trajectory sample (1 = every accepted step).
    #[arg(long, default_value_t = 1)]
    pub record_every: u32,
    /// Interval of the 3D scene updates in milliseconds of simulated time (0 = none).
    #[arg(long, default_value_t = gripopt::app::DEFAULT_SCENE_DT * 1e3)]
    pub scene_ms: f64,
    /// Record every trajectory sample in full f64 (default: the compact subset).
    #[arg(long)]
    pub record_full: bool,
    /// zstd compression level of the recording (changes file sizes, never content).
    #[arg(long, default_value_t = gripopt::app::DEFAULT_ZSTD_LEVEL)]
    pub zstd_level: u32,
    /// zstd worker threads per recording shard (0 = compress on the writing thread).
    #[arg(long, default_value_t = gripopt::app::DEFAULT_ZSTD_THREADS)]
    pub zstd_threads: u32,
    /// Print the summary as one JSON object (for scripts).
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `gripopt replay`.
#[derive(clap::Args)]
pub struct ReplayArgs {
    /// Run folder.
    pub run_dir: PathBuf,
    /// Design id (see pareto.csv / population.csv).
    #[arg(long)]
    pub design: u64,
    /// Print the record plus `verified` and `max_difference` as JSON.
    #[arg(long)]
    pub json: bool,
    /// Write the recorded trajectory to this CSV file.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Plot the recorded trajectory to this SVG file.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Replay in this scene: centred, offset:X or free[:X] (metres). The run's own scene
    /// (default) verifies the recording; another one re-simulates the design there and
    /// reports it like `simulate --scene` (it cannot be verified against the recording).
    #[arg(long)]
    pub scene: Option<String>,
    /// A robust run: replay scenario K of OBJECT (e.g. can:3) of the design, compare it
    /// with the recording and record it to RUN_DIR/scenario-ID-OBJECT-K.mcap.
    #[arg(long, conflicts_with_all = ["scene", "plot"])]
    pub scenario: Option<String>,
    /// Overwrite the --csv / --plot files if they exist (refused otherwise).
    #[arg(long)]
    pub force: bool,
}

/// The recording options of `optimise --record … --record-*`.
fn record_options(a: &OptimiseArgs) -> RecordOptions {
    let (enabled, trajectories) = match a.record {
        RecordArg::All => (true, TrajectoryKeep::All),
        RecordArg::Feasible => (true, TrajectoryKeep::Feasible),
        RecordArg::Designs => (true, TrajectoryKeep::None),
        RecordArg::None => (false, TrajectoryKeep::None),
    };
    RecordOptions {
        enabled,
        trajectories,
        every: a.record_every,
        scene_dt: a.scene_ms * 1e-3,
        zstd_level: a.zstd_level,
        zstd_threads: a.zstd_threads,
        resolution: if a.record_full { Resolution::Full } else { Resolution::Compact },
        epoch_s: 0,
    }
}

/// `gripopt optimise`: the run, with the progress bar and ctrl-c; its summary.
pub fn optimise(a: OptimiseArgs) -> Result<i32> {
    let rec = record_options(&a);
    let run = Optimiser::new(a.problem, a.out).pop(a.pop).generations(a.generations).seed(a.seed);
    let s = with_hooks(run.threads(a.threads).record(rec)).run()?;
    summary(&s, a.json)
}

/// `gripopt replay`: the outputs checked (never into the run folder), then one scenario of
/// a robust design, the design in another scene, or the design replayed and verified.
pub fn replay_cmd(a: ReplayArgs) -> Result<i32> {
    let (csv, plot) = (a.csv.as_deref(), a.plot.as_deref());
    check_output("--csv", csv, a.force, &[&a.run_dir])?;
    check_output("--plot", plot, a.force, &[&a.run_dir])?;
    if let Some(sc) = &a.scenario {
        return crate::cli::robust::replay_scenario(&a.run_dir, a.design, sc, a.json, csv);
    }
    if let Some(sc) = &a.scene {
        if let Some(code) = crate::cli::scenes::replay_in_scene(&a.run_dir, a.design, sc, a.json, csv, plot)? {
            return Ok(code);
        }
    }
    replay(&a.run_dir, a.design, a.json, csv, plot)
}

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
    if pop < 2 {
        bail!("--pop {pop}: must be at least 2");
    }
    if generations == Some(0) {
        bail!("--generations 0: must be at least 1");
    }
    gripopt::app::check_population(pop.max(4), generations.unwrap_or(250), false)?;
    let probs = test_problems(name)?;
    let seed_list = seed_list(seed, seeds)?;
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

/// The test problems `name` names (`all`: every one).
fn test_problems(name: &str) -> Result<Vec<TestProblem>> {
    if name.eq_ignore_ascii_case("all") {
        return Ok(TestProblem::ALL.to_vec());
    }
    let p = TestProblem::parse(name).with_context(|| {
        format!(
            "unknown test problem `{name}` (expected one of {} or all)",
            TestProblem::ALL.map(|p| p.name()).join(", ")
        )
    })?;
    Ok(vec![p])
}

/// The seeds of `--seed S` or `--seeds A-B` (default: seed 1).
fn seed_list(seed: Option<u64>, seeds: Option<String>) -> Result<Vec<u64>> {
    Ok(match (seed, seeds) {
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
    })
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
    /// A robust run's certification: designs tested, certified, the reported front's ids and
    /// why none is certified (null: the problem does not certify, or the run was interrupted).
    certification: Option<CertificationJson>,
}

/// `optimise --json`'s certification stage.
#[derive(serde::Serialize)]
struct CertificationJson {
    tested: usize,
    certified: usize,
    front: Vec<u64>,
    why_none: Option<String>,
}

/// The certification stage's line of the text summary.
fn certification_line(c: &gripopt::app::CertificationSummary) -> String {
    let n = gripopt::app::counted;
    let head = format!(
        "certified on fresh scenarios: {} of {} tested; {} on the certified front (pareto.csv; the search's front: search_pareto.csv; certification.json)",
        c.certified,
        n(c.tested as u64, "design", "designs"),
        c.front.len()
    );
    match &c.why_none {
        Some(why) => format!("{head}\n{why}"),
        None => head,
    }
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
            certification: s.certification.as_ref().map(|c| CertificationJson {
                tested: c.tested,
                certified: c.certified,
                front: c.front.clone(),
                why_none: c.why_none.clone(),
            }),
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
            "finished: {}, {} in {:.1} s; {} in the final population, {} on the reported front, pareto.csv (hypervolume {:.4})",
            n(s.generations, "generation", "generations"),
            n(s.evaluations, "evaluation", "evaluations"),
            s.wall_s,
            n(s.feasible as u64, "feasible design", "feasible designs"),
            s.front_size,
            s.hv
        );
    }
    if let Some(c) = &s.certification {
        outln!("{}", certification_line(c));
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
    // verified means something was re-computed and compared: the trajectory, or (recorded
    // without one) the record's stage, reason, violation, objectives and simulation work
    let verified = r.verified && (r.compared > 0 || r.values_compared > 0);
    let across = r.across_revisions.as_ref();
    let code = if verified || across.is_some_and(|a| a.agrees()) { 0 } else { EXIT_CHECK_FAILED };
    write_recorded(&r, id, csv, plot)?;
    // a single-object free-kind run: the design's free scene to MCAP (docs/recording.md)
    let free = match gripopt::app::record_free_scene(dir, &r)? {
        Some(FreeRecording::Recorded(p)) => (Some(p.display().to_string()), None),
        Some(FreeRecording::NotRecorded(why)) => (None, Some(why)),
        None => (None, None),
    };
    if json {
        replay_json(&r, verified, secs, free)?;
    } else {
        replay_text(dir, &r, verified, secs, free);
    }
    Ok(code)
}

/// `replay --csv`, `--plot`: the recorded trajectory.
fn write_recorded(r: &Replay, id: u64, csv: Option<&std::path::Path>, plot: Option<&std::path::Path>) -> Result<()> {
    let samples = &r.recorded.samples;
    if let Some(path) = csv {
        let kept = match r.recorded.resolution {
            Resolution::Compact => "the compact subset, values at f32 precision",
            Resolution::Full => "every recorded sample at full precision",
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
    Ok(())
}

/// `replay --json`.
fn replay_json(r: &Replay, verified: bool, secs: f64, free: (Option<String>, Option<String>)) -> Result<()> {
    let rec = &r.recorded.record;
    let v = ReplayJson {
        recorded: rec,
        verified,
        problem_note: r.problem_note.as_deref(),
        verdict_agrees: r.recomputed_feasible == rec.feasible,
        max_difference: r.max_difference.is_finite().then_some(r.max_difference),
        across_revisions: r.across_revisions.as_ref().map(|a| AcrossRevisionsJson {
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
        free_recording: free.0,
        free_not_recorded: free.1,
    };
    outln!("{}", serde_json::to_string_pretty(&v)?);
    Ok(())
}

/// `replay`'s text: the recorded design, the verdict, the free scene's recording.
fn replay_text(dir: &std::path::Path, r: &Replay, verified: bool, secs: f64, free: (Option<String>, Option<String>)) {
    let (rec, samples) = (&r.recorded.record, &r.recorded.samples);
    let text = |v: serde_json::Result<String>| v.unwrap_or_default();
    outln!("design {} (generation {}) from {}", rec.id, rec.generation, crate::cli::out::path(&r.recorded.file));
    if let Some(n) = &r.problem_note {
        outln!("  NOT verified: {n}; restore the run's problem file to verify the recording");
    }
    outln!("  parameters {}", text(serde_json::to_string(&rec.parameters)));
    outln!("  derived    {}", text(serde_json::to_string(&rec.derived)));
    match rec.failed_stage {
        Some(s) => outln!(
            "  DISCARDED at stage {s}: {} (violation {})",
            rec.reason.as_deref().unwrap_or(""),
            rec.violation.map_or("null".into(), gripopt::app::exact_num)
        ),
        None => outln!("  feasible; objectives {}", text(serde_json::to_string(&rec.objectives))),
    }
    outln!(
        "  trajectory: {} samples{}",
        samples.len(),
        samples.last().map(|s| format!(", t = 0 … {:.3} ms", s.t * 1e3)).unwrap_or_default()
    );
    // with a problem note, its one verdict, printed above: the comparison is moot
    if r.problem_note.is_none() {
        outln!("  {}", verdict_line(r, verified));
    }
    let (free_recording, free_not_recorded) = free;
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
}

/// What the comparison found, in one line.
fn verdict_line(r: &Replay, verified: bool) -> String {
    if let Some(a) = &r.across_revisions {
        let (rtol, rec, cur) = (gripopt::app::ACROSS_REVISIONS_RTOL, a.recorded, a.current);
        return match &a.differs {
            None => format!("verified across simulator revisions (recorded by revision {rec}, this build is revision {cur}): the same verdict, objectives and violation within {rtol:e} relative (largest difference {:e}); trajectories of two revisions are not compared sample by sample", a.max_difference),
            Some(d) => format!("NOT verified: recorded by simulator revision {rec}, this build is revision {cur}, and beyond {rtol:e} relative: {d}"),
        };
    }
    if r.compared == 0 && verified {
        format!("verified (no trajectory recorded for this design): the re-evaluation reproduces the record's stage, reason, violation, objectives and simulation work ({} values)", r.values_compared)
    } else if r.compared == 0 {
        format!("NOT verified: no trajectory was recorded, and the re-evaluation differs from the record (recomputed feasible: {})", r.recomputed_feasible)
    } else if verified {
        let precision = if r.recorded.resolution == Resolution::Full {
            "every sample, f64"
        } else {
            "compact subset, to the recorded f32 precision"
        };
        format!("verified ({precision}): re-simulation reproduces the recorded trajectory (max relative difference {:e}, {} samples)", r.max_difference, r.compared)
    } else {
        format!(
            "NOT verified: max relative difference {:e} over {} samples (recomputed feasible: {})",
            r.max_difference, r.compared, r.recomputed_feasible
        )
    }
}
