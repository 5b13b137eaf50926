//! `gripopt verify RUN_DIR`: the run folder's designs (or a sample of its problem's box)
//! verified in the free scene ([`super::verify`]), written to verify.csv under the folder's
//! lock, and recorded (`verify_rec`).

use super::lock::RunLock;
use super::verify::{
    run_designs, sample_designs, verify_csv, verify_designs_poses, Confusion, VerifyRow, VerifySource, VerifySummary,
    VERIFY_FILE, VERIFY_SAMPLE_FILE,
};
use super::verify_rec::VerifyRecording;
use crate::fsutil::write_atomic;
use crate::params::{Problem, SceneKind};
use crate::{Error, Result};
use std::path::Path;

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) })
}

/// Verify run folder `dir`: checks it is a run (run.json, problem.toml), takes its lock,
/// loads the run's problem, switches it to the free scene (at `x_off`, default the
/// problem's), simulates the designs of `source` and writes the CSV atomically; with
/// `record`, also the MCAP recording of the free scene (verify.mcap or verify_sample.mcap,
/// with the Foxglove layout `foxglove-verify-layout.json`).
pub fn verify(
    dir: &Path,
    source: VerifySource,
    x_off: Option<f64>,
    record: bool,
    tick_len: &dyn Fn(usize),
    tick: &(dyn Fn() + Sync),
) -> Result<VerifySummary> {
    if !dir.is_dir() {
        return Err(Error::RunDir { path: dir.to_path_buf(), message: "not a folder".into() });
    }
    for f in ["run.json", "problem.toml"] {
        if !dir.join(f).is_file() {
            return Err(Error::RunDir {
                path: dir.to_path_buf(),
                message: format!("not a run folder (no {f}); give a folder written by `gripopt optimise`"),
            });
        }
    }
    let _lock = RunLock::acquire(dir)?;
    let file = dir.join("problem.toml");
    let p = Problem::load(&file)?.in_scene(SceneKind::Free, x_off, &file)?;
    let (designs, file) = match source {
        VerifySource::Pareto => (run_designs(dir, false)?, VERIFY_FILE),
        VerifySource::All => (run_designs(dir, true)?, VERIFY_FILE),
        VerifySource::Sample { n, seed } => (sample_designs(&p, n, seed), VERIFY_SAMPLE_FILE),
    };
    if designs.is_empty() {
        let message = match source {
            VerifySource::Sample { n, seed } => format!("--sample {n} --seed {seed}: no drawn design passes stages 0–2 of problem.toml; nothing to verify, nothing written"),
            _ => "no feasible design to verify; nothing written".into(),
        };
        let path = match source {
            VerifySource::Pareto => dir.join("pareto.csv"),
            VerifySource::All => dir.join("population.csv"),
            VerifySource::Sample { .. } => dir.join("problem.toml"),
        };
        return Err(Error::RunDir { path, message });
    }
    tick_len(designs.len());
    let rec = if record { Some(VerifyRecording::new(dir, &source)?) } else { None };
    let with_poses = verify_designs_poses(&p, &designs, rec.as_ref().map(|r| r.opts.scene_dt), tick);
    let rows: Vec<VerifyRow> = with_poses.iter().map(|(r, _)| r.clone()).collect();
    let skipped: Vec<u64> = designs.iter().map(|d| d.0).filter(|id| !rows.iter().any(|r| r.id == *id)).collect();
    if rows.is_empty() {
        return Err(Error::RunDir {
            path: dir.to_path_buf(),
            message: format!(
                "all {} designs are discarded at stages 0–2 on re-evaluation; nothing to verify, nothing written",
                designs.len()
            ),
        });
    }
    let file = dir.join(file);
    write_atomic(&file, verify_csv(&rows, p.scene.setup.x_off).as_bytes())?;
    let recording = match rec {
        Some(r) => Some(r.write(&p, with_poses)?),
        None => None,
    };
    let et: Vec<f64> = rows.iter().filter_map(|r| r.energy_ratios().0).collect();
    let er: Vec<f64> = rows.iter().filter_map(|r| r.energy_ratios().1).collect();
    let median_energy_ratio = median(et).zip(median(er));
    Ok(VerifySummary {
        file,
        skipped,
        confusion: Confusion::of(&rows),
        rows,
        median_energy_ratio,
        recording,
        designs: designs.len(),
    })
}
