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
    /// Folder of the synthetic run (cleared first).
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
/// random ids; writes min / median times to `out_text` and returns them as JSON. An existing
/// `b.out` is cleared only if it is an earlier synthetic run (its run.json says so).
pub fn replay(
    problem: &Problem,
    b: &ReplayBench,
    out_text: super::Out,
    progress: &dyn super::BenchProgress,
) -> Result<serde_json::Value> {
    let (p, n, out, per_shard) = (problem, b.designs, b.out.as_path(), b.per_shard);
    for (flag, v) in [("--designs", n), ("--per-shard", per_shard)] {
        if v == 0 {
            return Err(Error::Input(format!("bench replay: {flag} 0: at least 1 design is needed")));
        }
    }
    if out.exists() {
        // never delete a folder this benchmark did not write (a real run, say)
        let synthetic = crate::fsutil::read_regular_string(&out.join("run.json"), crate::fsutil::caps::RUN_JSON)
            .ok()
            .and_then(|t| serde_json::from_str::<SyntheticRun>(&t).ok())
            .is_some_and(|v| v.synthetic);
        let empty = std::fs::read_dir(out).map(|mut d| d.next().is_none()).unwrap_or(false);
        if !synthetic && !empty {
            return Err(Error::RunDir { path: out.to_path_buf(), message: "exists and is not a synthetic run of `gripopt bench replay`: choose another --out (nothing was deleted)".into() });
        }
        std::fs::remove_dir_all(out).map_err(|e| Error::io(out, "cannot clear", e))?;
    }
    // the synthetic run is removed afterwards without --keep, also when the benchmark fails
    let result = write_and_replay(p, n, per_shard, out, out_text, progress);
    if !b.keep && out.exists() {
        let removed = std::fs::remove_dir_all(out).map_err(|e| Error::io(out, "cannot remove", e));
        return result.and_then(|v| removed.map(|()| v));
    }
    result
}

/// Write the synthetic run of `n` designs (`per_shard` a shard) into `out` and time finding,
/// reading and replaying 50 random ids (`replay`'s work).
fn write_and_replay(
    p: &Problem,
    n: u64,
    per_shard: u64,
    out: &Path,
    out_text: super::Out,
    progress: &dyn super::BenchProgress,
) -> Result<serde_json::Value> {
    let rec_dir = out.join("recording");
    std::fs::create_dir_all(&rec_dir).map_err(|e| Error::io(&rec_dir, "cannot create", e))?;
    let problem_toml = out.join("problem.toml");
    std::fs::write(&problem_toml, &p.source_text).map_err(|e| Error::io(&problem_toml, "cannot write", e))?;
    let opts = crate::record::RecordOptions { scene_dt: 0.0, ..Default::default() };
    let run_json = out.join("run.json");
    let problem_sha256 = crate::fsutil::sha256_hex(p.source_text.as_bytes());
    let synthetic = SyntheticRun { synthetic: true, recording: opts, problem_sha256: problem_sha256.clone() };
    let text = serde_json::to_string_pretty(&synthetic).map_err(json_err(&run_json))?;
    std::fs::write(&run_json, text).map_err(|e| Error::io(&run_json, "cannot write", e))?;
    // the nominal design's real evaluation and recorded grasp, under every id
    let mut gp = GripperProblem::new(p.clone());
    gp.recording = opts;
    let x = p.nominal.to_array().to_vec();
    let eval = gp.evaluate(&x);
    let samples = eval.info.trajectory.as_ref().map_or(0, |t| t.simulated);
    let meta = crate::record::RunMetadata {
        synthetic: Some("gripopt bench replay".into()),
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
    std::fs::write(&index_path, index).map_err(|e| Error::io(&index_path, "cannot write", e))?;
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
        let rp = crate::record::replay(out, id)
            .map_err(|e| Error::bench_from(format!("bench replay: replaying design {id}"), e))?;
        t_full.push(a.elapsed().as_secs_f64());
        if !rp.verified {
            return Err(Error::Recording { path: rp.recorded.file, message: format!("design {id} did not verify") });
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
