//! Limits of a run's size: a population (and run length) that fits in memory and in the
//! recording's id space, checked before anything is allocated, with the estimate in the
//! error (docs/cli.md, "Limits of the command-line flags").

use crate::error::{Error, Result};

/// Memory per design of the population, without trajectories (bytes): parents, offspring,
/// the merged population while sorting, the last evaluated generation, the checkpoint's
/// serialisation (measured ≈ 6 KiB when it was still built as a JSON tree; rounded up).
pub const BYTES_PER_DESIGN: u64 = 16 << 10;

/// Memory per design while its stage-3 trajectory waits for the recorder (bytes): what is
/// kept of it ([`crate::record::KeptTrajectory`]) is a few KB at the default compact
/// resolution, but every sample (a few hundred to a few thousand accepted steps of 136
/// bytes) with `--record-full`; the estimate keeps that worst case.
pub const BYTES_PER_TRAJECTORY: u64 = 512 << 10;

/// Largest design id a recording can hold: design k's messages live at [k s, k s + 1 s) of
/// a u64 nanosecond clock.
pub const MAX_EVALUATIONS: u64 = u64::MAX / 1_000_000_000 - 1;

/// Most worker threads a run may ask for.
pub const MAX_THREADS: usize = 1024;

/// Check a thread count (`--threads`): 1 to [`MAX_THREADS`].
pub fn check_threads(threads: Option<usize>) -> Result<()> {
    let bad = |n: usize, rule: String| Error::InvalidField {
        file: "command line".into(),
        field: "--threads".into(),
        value: n.to_string(),
        rule,
    };
    match threads {
        Some(0) => Err(bad(0, "must be at least 1".into())),
        Some(n) if n > MAX_THREADS => Err(bad(n, format!("at most {MAX_THREADS}"))),
        _ => Ok(()),
    }
}

/// Fewer designs per thread than this draw a note: with 2 per thread (pop 128 on 64
/// threads) `bench scaling` predicts about 50 % efficiency, with 8 (on 16) about 90 %.
pub const MIN_DESIGNS_PER_THREAD: usize = 4;

/// A note for a population that gives fewer than [`MIN_DESIGNS_PER_THREAD`] designs per
/// thread (each generation waits for its slowest design); `None` when it gives enough.
pub fn threads_note(pop: usize, threads: usize) -> Option<String> {
    (threads > 1 && pop < MIN_DESIGNS_PER_THREAD * threads).then(|| {
        format!(
            "note: a population of {pop} on {threads} threads is {:.1} designs per thread per generation; each generation waits for its slowest design, so threads idle at the end of every generation (a population of at least {} uses them better; `gripopt bench scaling --pop {pop}` predicts the efficiency at 16 and 64 threads)",
            pop as f64 / threads as f64,
            MIN_DESIGNS_PER_THREAD * threads
        )
    })
}

/// Memory the system can give (MemAvailable of /proc/meminfo), if known.
fn available_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn gib(b: f64) -> String {
    if b >= (1u64 << 30) as f64 {
        format!("{:.1} GiB", b / (1u64 << 30) as f64)
    } else if b >= (1u64 << 20) as f64 {
        format!("{:.0} MiB", b / (1u64 << 20) as f64)
    } else {
        // a design's share (a few kB without trajectories), never "0 MiB"
        format!("{:.0} kiB", (b / 1024.0).max(1.0))
    }
}

/// Check `--pop` and `--generations` before a run allocates anything: pop ≥ 4, generations
/// ≥ 1, pop × generations within the recording's id space, and the memory estimate
/// (pop × [`BYTES_PER_DESIGN`], plus 2 × pop × `BYTES_PER_TRAJECTORY` when recording)
/// within half of the available memory (64 GiB when unknown).
pub fn check_population(pop: usize, generations: u64, recording: bool) -> Result<()> {
    let field = |f: &str, v: String, rule: String| Error::InvalidField {
        file: "command line".into(),
        field: f.into(),
        value: v,
        rule,
    };
    if pop < 4 {
        return Err(field("--pop", pop.to_string(), "must be at least 4".into()));
    }
    if generations < 1 {
        return Err(field("--generations", generations.to_string(), "must be at least 1".into()));
    }
    let per = BYTES_PER_DESIGN as f64 + if recording { 2.0 * BYTES_PER_TRAJECTORY as f64 } else { 0.0 };
    let need = pop as f64 * per;
    let (avail, known) = match available_memory() {
        Some(a) => (a as f64, true),
        None => (64.0 * (1u64 << 30) as f64, false),
    };
    let budget = avail / 2.0;
    if need > budget {
        let max = (budget / per).floor() as u64;
        return Err(field(
            "--pop",
            pop.to_string(),
            format!(
                "needs about {} of memory ({} per design{}), more than half of the {} {}; at most {max} here",
                gib(need),
                gib(per).replace(".0 ", " "),
                if recording { ", trajectories included while they wait for the recorder" } else { "" },
                gib(avail),
                if known { "available" } else { "assumed (memory unknown)" }
            ),
        ));
    }
    let evals = (pop as u128) * (generations as u128);
    if evals > MAX_EVALUATIONS as u128 {
        return Err(field("--pop × --generations", format!("{pop} × {generations}"), format!("at most {MAX_EVALUATIONS} evaluations (design ids are the recording's time windows of 1 s on a u64 nanosecond clock)")));
    }
    Ok(())
}

/// Bytes a robust design's record takes in the checkpoint (and a shard's design record) per
/// scenario it holds: one compact scenario record as JSON, its numbers at full precision
/// (the longest there can be: 559 bytes, tests/robust.rs; a typical one ~320 bytes).
pub const BYTES_PER_SCENARIO_JSON: u64 = 576;

/// Copies of a design's record a run holds in memory at once: parents, offspring, the
/// last generation for the recorder, the archive.
const RECORD_COPIES: u64 = 4;

/// A checkpoint's bytes per design besides its scenarios (the record, the vector, rank and
/// crowding: ~3 kB, rounded up).
const CHECKPOINT_BYTES_PER_DESIGN: u64 = 4 << 10;

/// The scenario records each design of `problem`'s run holds: objects × scenarios per
/// object (0 for a problem without `[robust]`).
pub fn scenario_records(problem: &crate::params::Problem) -> u64 {
    problem.robust.as_ref().map_or(0, |r| r.objects.len() as u64 * r.count(crate::params::STREAM_OPTIMISE) as u64)
}

/// Check, before a run (or resume) of `problem` with population `pop` starts, that what its
/// designs' records hold fits: a robust record grows with objects × scenarios (K = 4096 ×
/// 16 objects: ~26 MB a design). The memory for the records ([`RECORD_COPIES`] in memory
/// and twice as JSON: the checkpoint's and the shard's text) within half of the available
/// memory, and the checkpoint of the population and an archive as large, within the size
/// a checkpoint is read back at ([`crate::fsutil::caps::CHECKPOINT`]): a run is never
/// started that cannot be resumed. The error gives the estimates and the largest population
/// that fits. A note (for the caller to show) when that checkpoint would take more than half
/// of the cap: an archive that grows to several times the population would reach it, and a
/// checkpoint past the cap is never written (the run stops at the last one that fits).
pub fn check_record_size(problem: &crate::params::Problem, pop: usize, recording: bool) -> Result<Option<String>> {
    let n = scenario_records(problem);
    if n == 0 {
        return Ok(None);
    }
    let per_record =
        n * (RECORD_COPIES * std::mem::size_of::<crate::eval::ScenarioRecord>() as u64 + 2 * BYTES_PER_SCENARIO_JSON);
    let per =
        BYTES_PER_DESIGN as f64 + if recording { 2.0 * BYTES_PER_TRAJECTORY as f64 } else { 0.0 } + per_record as f64;
    let (avail, known) = available_memory().map_or((64.0 * (1u64 << 30) as f64, false), |a| (a as f64, true));
    let checkpoint_per = (CHECKPOINT_BYTES_PER_DESIGN + n * BYTES_PER_SCENARIO_JSON) as f64;
    let cap = crate::fsutil::caps::CHECKPOINT as f64;
    let checkpoint = 2.0 * pop as f64 * checkpoint_per;
    let robust = problem.robust.as_ref().expect("a robust problem");
    let what = format!(
        "a robust record holds {n} scenario records ({} objects × {} scenarios), about {} a design",
        robust.objects.len(),
        robust.count(crate::params::STREAM_OPTIMISE),
        gib(checkpoint_per)
    );
    let bad = |rule: String| Error::InvalidField {
        file: "command line".into(),
        field: "--pop".into(),
        value: pop.to_string(),
        rule,
    };
    if checkpoint > cap {
        let max = (cap / (2.0 * checkpoint_per)).floor() as u64;
        return Err(bad(format!(
            "{what}: the checkpoint of the population and an archive as large would take about {}, more than the {} a checkpoint is read back at (the run could not be resumed); at most {max} here, or fewer scenarios or objects",
            gib(checkpoint),
            gib(cap)
        )));
    }
    if pop as f64 * per > avail / 2.0 {
        let max = (avail / 2.0 / per).floor() as u64;
        return Err(bad(format!(
            "{what}: the population needs about {} of memory, more than half of the {} {}; at most {max} here, or fewer scenarios or objects",
            gib(pop as f64 * per),
            gib(avail),
            if known { "available" } else { "assumed (memory unknown)" }
        )));
    }
    Ok((checkpoint > cap / 2.0).then(|| {
        format!(
            "note: {what}: the checkpoint of the population and an archive as large takes about {}; an archive {:.1} times the population would pass the {} a checkpoint is read back at, and the run would stop at its last checkpoint that fits (fewer scenarios or objects, or a smaller --pop, leave room)",
            gib(checkpoint),
            cap / (pop as f64 * checkpoint_per) - 1.0,
            gib(cap)
        )
    }))
}

/// Memory per design of `--sample N` (bytes), without a recording: the drawn batch, the
/// designs, their rows and verify_sample.csv's text (measured ≈ 1 KiB: peak RSS of
/// `verify RUN --sample 400 --record none` less that of `--sample 100`, over 300; rounded up).
pub const SAMPLE_BYTES_PER_DESIGN: u64 = 4 << 10;

/// Memory per design that recording a sample adds (bytes) when its free scene lasts
/// `t_obs` seconds: its poses every 2 ms (`record::DEFAULT_SCENE_DT`) kept until the MCAP
/// is written, twice (the poses and the framed file), and 4 KiB of messages (bottle-1l,
/// t_obs 0.1 s: 16.6 KiB; measured as above with `--record all`: 14.4 KiB).
pub fn sample_bytes_recorded(t_obs: f64) -> u64 {
    let poses = (t_obs.max(0.0) / crate::record::DEFAULT_SCENE_DT).ceil() as u64 + 2;
    2 * poses * std::mem::size_of::<crate::sim::PoseSample>() as u64 + (4 << 10)
}

/// Check `--sample N` before anything is drawn (as `optimise` checks `--pop`): at least 1,
/// and its memory estimate within half of the available memory (64 GiB when unknown);
/// `recorded_t_obs`: the free scene's duration when the sample is recorded.
pub fn check_sample(n: usize, recorded_t_obs: Option<f64>) -> Result<()> {
    let bad = |rule: String| Error::InvalidField {
        file: "command line".into(),
        field: "--sample".into(),
        value: n.to_string(),
        rule,
    };
    if n == 0 {
        return Err(bad("must be at least 1".into()));
    }
    let per = SAMPLE_BYTES_PER_DESIGN + recorded_t_obs.map_or(0, sample_bytes_recorded);
    let (avail, known) = available_memory().map_or((64u64 << 30, false), |a| (a, true));
    let budget = avail / 2;
    if (n as u128) * per as u128 > budget as u128 {
        let gib = |b: f64| format!("{:.1} GiB", b / (1u64 << 30) as f64);
        return Err(bad(format!(
            "needs about {} of memory ({:.1} KiB per design{}), more than half of the {} {}; at most {} here",
            gib(n as f64 * per as f64),
            per as f64 / 1024.0,
            if recorded_t_obs.is_some() { ", its recorded poses included; --record none needs less" } else { "" },
            gib(avail as f64),
            if known { "available" } else { "assumed (memory unknown)" },
            budget / per
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    /// A design's few kilobytes read as kiB, not "0 MiB" (the moo-test --pop message).
    #[test]
    fn memory_sizes_read_in_their_own_unit() {
        assert_eq!(super::gib(16_384.0), "16 kiB");
        assert_eq!(super::gib(10.0), "1 kiB");
        assert_eq!(super::gib(3.0 * (1u64 << 20) as f64), "3 MiB");
        assert_eq!(super::gib(1.5 * (1u64 << 30) as f64), "1.5 GiB");
    }
}
