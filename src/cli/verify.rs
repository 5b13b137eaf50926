//! `gripopt verify RUN_DIR`: the free scene against the centred criteria's prediction.

use crate::cli::out::path as quoted;
use anyhow::{bail, Context, Result};
use gripopt::app::{Confusion, Verified, VerifyRequest, VerifySource, VerifySummary};
use std::path::PathBuf;

/// Arguments of `gripopt verify`.
#[derive(clap::Args)]
pub struct VerifyArgs {
    /// Run folder (written by `gripopt optimise`).
    pub run_dir: PathBuf,
    /// Scene to measure in: free or free:X (object offset X metres; default: the problem's
    /// x_off). Not for a robust run (its scenarios set the offsets).
    #[arg(long)]
    pub scene: Option<String>,
    /// Every feasible design of the run's population and archive (from its checkpoint)
    /// instead of its front (not for a robust run, which verifies its front).
    #[arg(long)]
    pub all: bool,
    /// Worker threads (default: all cores; results do not depend on it).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Record the free scene to MCAP (RUN_DIR/verify.mcap; open in Foxglove with
    /// RUN_DIR/foxglove-verify-layout.json): all (default), or none. Not for a robust run.
    #[arg(long, value_enum)]
    pub record: Option<VerifyRecordArg>,
    /// Study: N designs drawn from the run's problem bounds that pass stage 2 (writes verify_sample.csv).
    #[arg(long, hide = true)]
    pub sample: Option<usize>,
    /// Seed of `--sample` (default 1).
    #[arg(long, hide = true)]
    pub seed: Option<u64>,
}

/// What `verify` records.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum VerifyRecordArg {
    /// Every verified design's free scene (the object's pose and the fingers).
    All,
    /// Nothing.
    None,
}

/// Refuse the flags a robust run's verify does not apply: it verifies its front on fresh
/// scenarios (docs/robust.md), so there is no design set, scene or recording to choose
/// (`--record none` says what happens anyway).
fn check_robust_flags(a: &VerifyArgs) -> Result<()> {
    let given = [
        (a.all, "--all"),
        (a.scene.is_some(), "--scene"),
        (a.record == Some(VerifyRecordArg::All), "--record all"),
        (a.sample.is_some(), "--sample"),
        (a.seed.is_some(), "--seed"),
    ];
    if let Some((_, flag)) = given.iter().find(|g| g.0) {
        bail!(
            "{flag}: {} is a robust run: verify re-evaluates its front on fresh scenarios of every object, with the offsets its scenarios draw, and records nothing (docs/robust.md), so this flag does not apply",
            a.run_dir.display()
        );
    }
    Ok(())
}

fn x_off_of(scene: &str) -> Result<Option<f64>> {
    match scene.split_once(':') {
        None if scene == "free" => Ok(None),
        Some(("free", x)) => {
            let v: f64 = x.parse().with_context(|| format!("--scene free:{x}: not a number"))?;
            gripopt::app::limit("scene.x_off").check(v).map_err(|r| anyhow::anyhow!("--scene free:{x}: {r}"))?;
            Ok(Some(v))
        }
        _ => bail!("--scene {scene}: verify measures in the free scene: free or free:X (metres)"),
    }
}

/// Print the 2×2 table.
fn print_table(c: &Confusion) {
    outln!("                     measured moved   measured stayed");
    outln!("  predicted moves    {:>14}   {:>15}", c.pred_moved, c.pred_stayed);
    outln!("  predicted stays    {:>14}   {:>15}", c.ok_moved, c.ok_stayed);
}

/// Run `gripopt verify`.
pub fn run(a: VerifyArgs) -> Result<()> {
    let robust = gripopt::app::is_robust_run(&a.run_dir);
    if robust {
        check_robust_flags(&a)?;
    }
    let x_off = x_off_of(a.scene.as_deref().unwrap_or("free"))?;
    let record = a.record != Some(VerifyRecordArg::None);
    if a.sample.is_some() && a.all {
        bail!("--sample and --all: give one");
    }
    if a.seed.is_some() && a.sample.is_none() {
        bail!("--seed: only with --sample N (the designs of the run are not drawn)");
    }
    let source = match a.sample {
        Some(n) => VerifySource::Sample { n, seed: a.seed.unwrap_or(1) },
        None if a.all => VerifySource::All,
        None => VerifySource::Pareto,
    };
    // (a robust run's verify reports no progress)
    let pb = if std::io::IsTerminal::is_terminal(&std::io::stderr()) && !robust {
        indicatif::ProgressBar::new(0)
    } else {
        indicatif::ProgressBar::hidden()
    };
    pb.set_style(
        indicatif::ProgressStyle::with_template("verify [{bar:30}] {pos}/{len} designs, ETA {eta}").expect("template"),
    );
    let req = VerifyRequest { source, x_off, record, threads: a.threads };
    let verified = gripopt::app::verify(&a.run_dir, &req, &|n| pb.set_length(n as u64), &|| pb.inc(1))?;
    pb.finish_and_clear();
    let s = match verified {
        // a robust run: the front out of sample (docs/robust.md)
        Verified::Robust(s) => {
            out!("{}", s.report());
            return Ok(());
        }
        Verified::Designs(s) => s,
    };
    report(&a, source, &s);
    Ok(())
}

/// What a single-object run's verify found: the file, the recording, the 2×2 table and the
/// counts.
fn report(a: &VerifyArgs, source: VerifySource, s: &VerifySummary) {
    let c = s.confusion;
    let agree = c.pred_moved + c.ok_stayed;
    let plural = |n: usize| if n == 1 { "" } else { "s" };
    outln!("verified {} design{} in the free scene → {}", s.rows.len(), plural(s.rows.len()), quoted(&s.file));
    if let VerifySource::Sample { n, .. } = source {
        if s.designs < n {
            eprintln!(
                "warning: --sample {n}: only {} drawn design{} pass stages 0–2 (the draw gives up after {} designs)",
                s.designs,
                plural(s.designs),
                1000 * n + 10_000
            );
        }
    }
    if let Some(r) = &s.recording {
        outln!(
            "recorded to {} (open in Foxglove with {}, see docs/recording.md)",
            quoted(r),
            quoted(&a.run_dir.join(gripopt::app::VERIFY_LAYOUT_FILE))
        );
    }
    if !s.skipped.is_empty() {
        eprintln!(
            "warning: {} design(s) are discarded at stages 0–2 on re-evaluation and left out: ids {:?}",
            s.skipped.len(),
            s.skipped
        );
    }
    print_table(&c);
    if c.not_observed > 0 {
        let mut why = std::collections::BTreeMap::<String, usize>::new();
        for r in s.rows.iter().filter(|r| !r.observed()) {
            *why.entry(r.free_end()).or_default() += 1;
        }
        let why: Vec<String> = why.into_iter().map(|(w, k)| format!("{k} {w}")).collect();
        outln!(
            "  not observed (the free scene ended before t_obs; left out of the table): {} ({})",
            c.not_observed,
            why.join(", ")
        );
    }
    if c.total() > 0 {
        outln!("  agreement {agree}/{} ({:.1} %); too strict (predicted moves, stayed) {}; too lax (predicted stays, moved) {}", c.total(), 100.0 * agree as f64 / c.total() as f64, c.pred_stayed, c.ok_moved);
    }
    let n = |f: &dyn Fn(&gripopt::app::VerifyRow) -> bool| s.rows.iter().filter(|r| f(r)).count();
    outln!(
        "  toppled {}  escaped {}  rim_contact {}  impact criterion fails {}  force criterion fails {}",
        n(&|r| r.toppled == Some(true)),
        n(&|r| r.escaped == Some(true)),
        n(&|r| r.rim_contact),
        n(&|r| r.impact_ratio.is_some_and(|x| x > 1.0)),
        n(&|r| r.force_margin < 0.0)
    );
    if let Some((t, r)) = s.median_energy_ratio {
        outln!("  object peak kinetic energy during the first contact / §9.1: median E_trans ratio {t:.3}, E_rot ratio {r:.3}");
    }
}
