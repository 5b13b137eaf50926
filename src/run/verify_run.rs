//! `gripopt verify RUN_DIR`: the run folder's designs (or a sample of its problem's box)
//! verified in the free scene ([`super::verify`]), written to verify.csv under the folder's
//! lock, and recorded (`verify_rec`). Each design is verified with the problem its
//! generation was evaluated with (run.json's `problems`, checked against their hashes: an
//! edited problem file is refused, naming it), and verify.csv's `# run:` line says which
//! run state it checked (the generation, the checkpoint's and the problems' hashes), so
//! that `gripopt show` can tell when it no longer matches the run.

use super::folder::RunFolder;
use super::info::RunInfo;
use super::limits::check_sample;
use super::lock::RunLock;
use super::verify::{
    run_line, sample_designs, verify_csv, verify_designs_poses, CheckedState, Confusion, VerifiedGeneration, VerifyRow,
    VerifySource, VerifySummary, CHECKPOINT_FILE, VERIFY_COLUMNS, VERIFY_FILE, VERIFY_SAMPLE_FILE,
};
use super::verify_rec::VerifyRecording;
use super::verify_robust::VERIFY_ROBUST_FILE;
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
use crate::params::{Design, Problem, SceneChoice};
use crate::record::ProblemUse;
use std::collections::BTreeMap;
use std::path::Path;

/// The run state run.json names (a sample's verify.csv: the run the sample belongs to).
fn attribution_of(info: &RunInfo) -> VerifiedGeneration {
    VerifiedGeneration {
        generation: info.completed_generations,
        checkpoint_sha256: info.checkpoint_sha256.clone().unwrap_or_else(|| "none".into()),
    }
}

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
/// loads the run's problems (each checked against the hash run.json recorded), switches
/// them to the free scene (at `x_off`, default the problem's), simulates the designs of
/// `source` each with its generation's problem and writes the CSV atomically; with
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
        // absent; anything else there (a pipe, a folder) is refused by its read, naming it
        if std::fs::symlink_metadata(dir.join(f)).is_err() {
            let message = if f == "problem.toml" {
                "problem.toml is missing from the run folder (run.json is there): restore it (a copy of the \
                 problem file the run started from, run.json's problem_path; its SHA-256 is run.json's \
                 problem_sha256)"
                    .to_string()
            } else {
                format!("not a run folder (no {f}); give a folder written by `gripopt optimise`")
            };
            return Err(Error::RunDir { path: dir.to_path_buf(), message });
        }
    }
    let _lock = RunLock::acquire(dir)?;
    let info = RunInfo::load(dir)?;
    let folder = RunFolder::open(dir)?;
    let files = info.problem_files();
    // every problem file the designs need, checked, in the free scene
    let free = |f: &ProblemUse| -> Result<Problem> {
        let file = dir.join(&f.file);
        folder.problem_of_generation(f.first_generation)?.in_scene(SceneChoice::free(x_off), &file)
    };
    let current = free(files.last().expect("a problem file"))?;
    // the run's designs come from its checkpoint (the state verify.csv is attributed to)
    let checked = match source {
        VerifySource::Sample { .. } => None,
        _ => Some(CheckedState::load(dir, &info)?),
    };
    let from_checkpoint = |all| checked.as_ref().map_or(Ok(vec![]), |c| c.designs(all));
    let (found, file) = match source {
        VerifySource::Pareto => (from_checkpoint(false)?, VERIFY_FILE),
        VerifySource::All => (from_checkpoint(true)?, VERIFY_FILE),
        VerifySource::Sample { n, seed } => {
            let setup = &current.scene;
            check_sample(n, record.then(|| setup.setup.t_obs.min(setup.criteria.t_max)))?;
            (sample_designs(&current, n, seed).into_iter().map(|(id, x)| (id, 0, x)).collect(), VERIFY_SAMPLE_FILE)
        }
    };
    // a folder or pipe where the table goes would fail its write only after the work
    crate::fsutil::check_rewritable(dir, &[file])?;
    let designs: Vec<(u64, Design)> = found.iter().map(|&(id, _, x)| (id, x)).collect();
    if designs.is_empty() {
        let message = match source {
            VerifySource::Sample { n, seed } => format!("--sample {n} --seed {seed}: no drawn design passes stages 0–2 of problem.toml; nothing to verify, nothing written"),
            _ => match info.discards.explain() {
                Some(why) => format!("nothing to verify, nothing written; {}", why.join("\n")),
                None => "no feasible design to verify; nothing written".into(),
            },
        };
        let path = match source {
            VerifySource::Sample { .. } => dir.join("problem.toml"),
            _ => dir.join(CHECKPOINT_FILE),
        };
        return Err(Error::RunDir { path, message });
    }
    // the designs by the problem file their generation was evaluated with (a sample: the
    // current problem)
    let mut groups: BTreeMap<usize, Vec<(u64, Design)>> = BTreeMap::new();
    for &(id, g, x) in &found {
        let k = match source {
            VerifySource::Sample { .. } => files.len() - 1,
            _ => files.iter().rposition(|f| f.first_generation <= g).unwrap_or(0),
        };
        groups.entry(k).or_default().push((id, x));
    }
    let mut problems = BTreeMap::new();
    for k in groups.keys() {
        problems.insert(*k, if *k == files.len() - 1 { current.clone() } else { free(&files[*k])? });
    }
    tick_len(designs.len());
    let rec = if record { Some(VerifyRecording::new(dir, &source)?) } else { None };
    let scene_dt = rec.as_ref().map(|r| r.opts.scene_dt);
    let mut with_poses = vec![];
    for (k, ds) in &groups {
        with_poses.extend(verify_designs_poses(&problems[k], ds, scene_dt, tick));
    }
    with_poses.sort_by_key(|(r, _)| designs.iter().position(|d| d.0 == r.id));
    let rows: Vec<VerifyRow> = with_poses.iter().map(|(r, _)| r.clone()).collect();
    let skipped: Vec<u64> = designs.iter().map(|d| d.0).filter(|id| !rows.iter().any(|r| r.id == *id)).collect();
    if rows.is_empty() {
        return Err(Error::RunDir {
            path: dir.to_path_buf(),
            message: format!(
                "{} discarded at stages 0–2 on re-evaluation; nothing to verify, nothing written",
                if designs.len() == 1 {
                    "the one design is".to_string()
                } else {
                    format!("all {} designs are", designs.len())
                }
            ),
        });
    }
    let file = dir.join(file);
    let used: Vec<&ProblemUse> = groups.keys().map(|k| &files[*k]).collect();
    let state = checked.as_ref().map(|c| c.attribution()).unwrap_or_else(|| attribution_of(&info));
    write_atomic(
        &file,
        attributed(&verify_csv(&rows, current.scene.setup.x_off), &info.run_id, &state, &used).as_bytes(),
    )?;
    let recording = match rec {
        Some(r) => Some(r.write(&current, with_poses)?),
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

/// verify.csv's text with its `# run:` line after the title: the run state it checked (the
/// completed generations, the checkpoint's content checksum) and the problem files used.
fn attributed(csv: &str, run_id: &str, state: &VerifiedGeneration, used: &[&ProblemUse]) -> String {
    let line = run_line(run_id, state, used);
    // the unit of every column, as in every CSV gripopt writes (docs/outputs.md)
    let units: Vec<String> = VERIFY_COLUMNS.iter().map(|(c, u)| format!("{c} [{u}]")).collect();
    let line = format!("{line}# units: {}\n", units.join(" "));
    match csv.split_once('\n') {
        Some((title, rest)) => format!("{title}\n{line}{rest}"),
        None => format!("{line}{csv}"),
    }
}

impl RunFolder {
    /// The verification file the folder holds: verify.csv, or a robust run's
    /// verify_robust.csv (None: not verified).
    pub fn verify_file(&self) -> Option<&'static str> {
        // whatever stands there: a pipe or folder is then refused by the read, naming it
        [VERIFY_FILE, VERIFY_ROBUST_FILE].into_iter().find(|f| std::fs::symlink_metadata(self.dir().join(f)).is_ok())
    }
    /// The run state the folder's `verify.csv` (or `verify_robust.csv`) checked (None: no verify.csv, or one
    /// written by a gripopt before issue 24, without a `# run:` line).
    pub fn verified_generation(&self) -> Result<Option<VerifiedGeneration>> {
        let Some(file) = self.verify_file() else { return Ok(None) };
        let p = self.dir().join(file);
        let text = crate::fsutil::read_regular_string(&p, crate::fsutil::caps::TABLE)
            .map_err(|e| Error::io(&p, "cannot read", e))?;
        let Some(line) = text.lines().take_while(|l| l.starts_with('#')).find(|l| l.starts_with("# run:")) else {
            return Ok(None);
        };
        let word_after =
            |key: &str| line.split(key).nth(1).and_then(|r| r.split([' ', ',', ';']).find(|w| !w.is_empty()));
        let generation = word_after("generation ").and_then(|w| w.parse().ok());
        let sha = word_after("checkpoint sha256 ");
        match (generation, sha) {
            (Some(generation), Some(s)) => {
                Ok(Some(VerifiedGeneration { generation, checkpoint_sha256: s.to_string() }))
            }
            _ => Err(Error::RunDir { path: p, message: format!("its `# run:` line is damaged: {line:?}") }),
        }
    }
}
