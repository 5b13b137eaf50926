//! `gripopt bench replay`: finding, reading and replaying designs in a large recorded run.

use super::min_med;
use super::say;
use crate::optim::{Individual, MooProblem};
use crate::params::Problem;
use crate::record::{write_shard, ShardEntry};
use crate::run::GripperProblem;
use crate::{Error, Result};
use rand::{Rng, SeedableRng};
use std::path::{Path, PathBuf};

/// Settings of the replay benchmark.
#[derive(Debug, Clone)]
pub struct ReplayBench {
    /// Recorded designs in the synthetic run (at least 1; 0 is refused).
    pub designs: u64,
    /// Designs per shard (at least 1; 0 is refused).
    pub per_shard: u64,
    /// Folder of the synthetic run (an earlier synthetic run's files in it removed first).
    pub out: PathBuf,
    /// Keep the synthetic run afterwards.
    pub keep: bool,
}

/// The run.json of a synthetic run (what marks the folder as this benchmark's).
#[derive(serde::Serialize, serde::Deserialize)]
struct SyntheticRun {
    /// Always true: the folder may be cleared by the next benchmark.
    #[serde(default)]
    synthetic: bool,
    /// The recording settings of the synthetic shards.
    recording: crate::record::RecordOptions,
    /// SHA-256 of its problem.toml (a replay checks the file against it).
    #[serde(default)]
    problem_sha256: String,
}

fn json_err(path: &Path) -> impl FnOnce(serde_json::Error) -> Error + '_ {
    move |source| Error::Json { path: path.to_path_buf(), what: "synthetic run file", source }
}

/// Replay speed: writes a synthetic run of `b.designs` copies of the nominal design's real
/// evaluation and recorded grasp (the problem's nominal), then finds, reads and replays 50
/// random ids with `replay_one` (the replay of the app layer, above this one: whether the
/// design of the run folder verified); writes min / median times to `out_text` and returns
/// them as JSON. `b.out` is locked while the benchmark runs; of what it holds only an
/// earlier synthetic run's files are removed (each proven by its content); anything else
/// refuses the benchmark.
pub fn replay(
    problem: &Problem,
    b: &ReplayBench,
    replay_one: &dyn Fn(&Path, u64) -> Result<bool>,
    out_text: super::Out,
    progress: &dyn super::BenchProgress,
) -> Result<serde_json::Value> {
    let (p, n, out, per_shard) = (problem, b.designs, b.out.as_path(), b.per_shard);
    for (flag, v) in [("--designs", n), ("--per-shard", per_shard)] {
        if v == 0 {
            return Err(Error::Input(format!("bench replay: {flag} 0: at least 1 design is needed")));
        }
    }
    if out.exists() && !out.is_dir() {
        return Err(Error::RunDir { path: out.to_path_buf(), message: "--out: not a folder".into() });
    }
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, "cannot create", e))?;
    // the folder's lock, held while the benchmark writes and clears it
    let lock = crate::fsutil::lock::RunLock::acquire(out)?;
    // only files whose content proves this benchmark wrote them are removed (an earlier
    // synthetic run's); anything else in the folder refuses it, nothing deleted
    remove_files(&synthetic_files(out)?)?;
    // the synthetic run is removed afterwards without --keep, also when the benchmark fails
    let result = write_and_replay(p, n, per_shard, out, replay_one, out_text, progress);
    if b.keep {
        return result;
    }
    let removed = synthetic_files(out).and_then(|f| remove_files(&f));
    drop(lock);
    let _ = std::fs::remove_dir(out); // only if now empty
    result.and_then(|v| removed.map(|()| v))
}

/// The files in `out` that this benchmark provably wrote (its synthetic run: run.json says
/// `synthetic`, problem.toml has its hash, the index lines name it, the shards' metadata
/// mark them `gripopt bench replay`), and the recording folder last; an error naming the
/// first file that is not (a user's file, another run's: nothing is removed).
fn synthetic_files(out: &Path) -> Result<Vec<PathBuf>> {
    let refuse = |path: PathBuf, why: &str| {
        Err(Error::RunDir { path, message: format!("{why}: not written by `gripopt bench replay`; choose another --out or move it away (nothing was deleted)") })
    };
    let names = |dir: &Path| -> Result<Vec<String>> {
        let rd = std::fs::read_dir(dir).map_err(|e| Error::io(dir, "cannot list", e))?;
        let mut v: Vec<String> = rd.flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        Ok(v)
    };
    let top = names(out)?;
    if top.iter().all(|n| n == crate::fsutil::lock::LOCK_FILE) {
        return Ok(vec![]);
    }
    let run_json = out.join("run.json");
    let run: Option<SyntheticRun> = crate::fsutil::read_regular_string(&run_json, crate::fsutil::caps::RUN_JSON)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .filter(|r: &SyntheticRun| r.synthetic && !r.problem_sha256.is_empty());
    let Some(run) = run else { return refuse(out.to_path_buf(), "not a synthetic run (it holds no run.json of one)") };
    let regular = |p: &Path| std::fs::symlink_metadata(p).is_ok_and(|m| m.is_file());
    let mut files = vec![];
    let mut recording = None;
    for n in top {
        let p = out.join(&n);
        match n.as_str() {
            crate::fsutil::lock::LOCK_FILE => continue,
            "run.json" => {}
            "problem.toml" if regular(&p) => {
                let text = crate::fsutil::read_regular(&p, crate::params::MAX_FILE_BYTES).unwrap_or_default();
                if crate::fsutil::sha256_hex(&text) != run.problem_sha256 {
                    return refuse(p, "not the synthetic run's problem (its hash differs from run.json's)");
                }
            }
            "recording" if std::fs::symlink_metadata(&p).is_ok_and(|m| m.is_dir()) => {
                recording = Some(p);
                continue;
            }
            _ => return refuse(p, "a file the synthetic run does not have"),
        }
        files.push(p);
    }
    if let Some(rec) = recording {
        for n in names(&rec)? {
            let p = rec.join(&n);
            let ours = regular(&p)
                && match n.as_str() {
                    "index.jsonl" => index_of(&p, &run.problem_sha256),
                    n if crate::record::shard_generation(n).is_some() => crate::record::shard_metadata(&p)
                        .is_ok_and(|m| m.is_some_and(|m| m.synthetic.as_deref() == Some(SYNTHETIC))),
                    _ => false,
                };
            if !ours {
                return refuse(p, "not a shard or index of the synthetic run");
            }
            files.push(p);
        }
        files.push(rec);
    }
    Ok(files)
}

/// Every line of the index `path` is a shard line of the synthetic run of problem hash `sha`.
fn index_of(path: &Path, sha: &str) -> bool {
    crate::fsutil::read_regular_string(path, crate::fsutil::caps::INDEX).is_ok_and(|t| {
        t.lines().all(|l| serde_json::from_str::<ShardEntry>(l).is_ok_and(|e| e.problem_sha256.as_deref() == Some(sha)))
    })
}

/// Remove `files` (a folder last, only when empty).
fn remove_files(files: &[PathBuf]) -> Result<()> {
    for f in files {
        if f.is_dir() {
            std::fs::remove_dir(f).map_err(|e| Error::io(f, "cannot remove", e))?;
        } else {
            std::fs::remove_file(f).map_err(|e| Error::io(f, "cannot remove", e))?;
        }
    }
    Ok(())
}

/// What marks a shard of the synthetic run (its metadata's `synthetic`).
const SYNTHETIC: &str = "gripopt bench replay";

/// Write the synthetic run of `n` designs (`per_shard` a shard) into `out` and time finding,
/// reading and replaying 50 random ids (`replay`'s work).
fn write_and_replay(
    p: &Problem,
    n: u64,
    per_shard: u64,
    out: &Path,
    replay_one: &dyn Fn(&Path, u64) -> Result<bool>,
    out_text: super::Out,
    progress: &dyn super::BenchProgress,
) -> Result<serde_json::Value> {
    let rec_dir = out.join("recording");
    std::fs::create_dir_all(&rec_dir).map_err(|e| Error::io(&rec_dir, "cannot create", e))?;
    let problem_toml = out.join("problem.toml");
    crate::fsutil::write_atomic(&problem_toml, p.source_text.as_bytes())?;
    let opts = crate::record::RecordOptions { scene_dt: 0.0, ..Default::default() };
    let run_json = out.join("run.json");
    let problem_sha256 = crate::fsutil::sha256_hex(p.source_text.as_bytes());
    let synthetic = SyntheticRun { synthetic: true, recording: opts, problem_sha256: problem_sha256.clone() };
    let text = serde_json::to_string_pretty(&synthetic).map_err(json_err(&run_json))?;
    crate::fsutil::write_atomic(&run_json, text.as_bytes())?;
    // the nominal design's real evaluation and recorded grasp, under every id
    let mut gp = GripperProblem::new(p.clone());
    gp.recording = opts;
    let x = p.nominal.to_array().to_vec();
    let eval = gp.evaluate(&x);
    let samples = eval.info.trajectory.as_ref().map_or(0, |t| t.simulated);
    let meta = crate::record::RunMetadata {
        synthetic: Some(SYNTHETIC.into()),
        // the revision whose settings replay re-evaluates with (as a run's shards state it)
        simulator_revision: Some(crate::sim::revision_of(&p.solver)),
        ..Default::default()
    };
    let t0 = std::time::Instant::now();
    let shards = n.div_ceil(per_shard);
    progress.begin("writing synthetic run", shards, "shards");
    let mut index = String::new();
    let mut bytes = 0u64;
    let index_path = rec_dir.join("index.jsonl");
    for k in 0..shards {
        let ids = (k * per_shard)..((k + 1) * per_shard).min(n);
        let inds: Vec<Individual<_>> =
            ids.clone().map(|id| Individual { id, generation: k + 1, x: x.clone(), eval: eval.clone() }).collect();
        let refs: Vec<&Individual<_>> = inds.iter().collect();
        let file = format!("gen-{:05}.mcap", k + 1);
        let shard = rec_dir.join(&file);
        let b = write_shard(&shard, p, &meta, &refs, &opts)
            .map_err(|e| Error::bench_from(format!("bench replay: writing {}", shard.display()), e))?;
        bytes += b;
        let entry = ShardEntry {
            generation: k + 1,
            file,
            first_id: ids.start,
            last_id: ids.end - 1,
            designs: ids.end - ids.start,
            bytes: b,
            run_id: None,
            problem_sha256: Some(problem_sha256.clone()),
        };
        index.push_str(&serde_json::to_string(&entry).map_err(json_err(&index_path))?);
        index.push('\n');
        progress.step();
    }
    progress.end();
    crate::fsutil::write_atomic(&index_path, index.as_bytes())?;
    let write_s = t0.elapsed().as_secs_f64();
    say!(out_text, "synthetic run: {n} designs ({samples} trajectory samples each) in {shards} shards, {:.1} MB, written in {:.1} s", bytes as f64 / 1e6, write_s);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let (mut t_read, mut t_full) = (vec![], vec![]);
    for _ in 0..50 {
        let id = rng.random_range(0..n);
        let a = std::time::Instant::now();
        let r = crate::record::read_design(out, id)
            .map_err(|e| Error::bench_from(format!("bench replay: reading design {id}"), e))?;
        t_read.push(a.elapsed().as_secs_f64());
        if r.record.id != id {
            return Err(Error::Recording {
                path: r.file,
                message: format!("asked for design {id}, wrong design returned"),
            });
        }
        let a = std::time::Instant::now();
        let verified =
            replay_one(out, id).map_err(|e| Error::bench_from(format!("bench replay: replaying design {id}"), e))?;
        t_full.push(a.elapsed().as_secs_f64());
        if !verified {
            return Err(Error::Recording { path: r.file, message: format!("design {id} did not verify") });
        }
    }
    let (r0, r1) = min_med(t_read);
    let (f0, f1) = min_med(t_full);
    say!(
        out_text,
        "find + read one design (index, MCAP summary, one chunk): {:.2} / {:.2} ms (min / median of 50 random ids)",
        r0 * 1e3,
        r1 * 1e3
    );
    say!(out_text, "replay (find, read, re-simulate, verify):               {:.2} / {:.2} ms", f0 * 1e3, f1 * 1e3);
    Ok(serde_json::json!({
        "bench": "replay", "designs": n, "samples_per_design": samples, "shards": shards, "bytes": bytes, "write_s": write_s,
        "find_read_ms": { "min": r0 * 1e3, "median": r1 * 1e3 }, "replay_ms": { "min": f0 * 1e3, "median": f1 * 1e3 },
    }))
}
