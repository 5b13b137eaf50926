//! Optimisation runs: started or resumed through the [`Optimiser`] builder (a progress
//! callback, a stop flag, another batch evaluator); a run of a problem held in memory
//! ([`ProblemRun`]: which file it starts from and records as its source); recording options
//! given as a mapping of run.json's `recording` fields over the defaults.

use crate::error::{Error, Result};
use crate::optim::Evaluator;
use crate::params::Problem;
use crate::record::RecordOptions;
use crate::run::{GripperProblem, Progress, RunHooks, RunSpec, RunSummary, PROBLEM_FILE, RUN_FILE};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// An optimisation run, set up step by step: a new run ([`Optimiser::new`]) or the resume
/// of one ([`Optimiser::resume`]), then [`Optimiser::run`].
pub struct Optimiser {
    spec: RunSpec,
    resume: Option<Resume>,
    hooks: RunHooks,
}

/// What a resume changes.
struct Resume {
    generations: Option<u64>,
    force: bool,
}

impl Optimiser {
    /// A new run of the problem file `problem` in the run folder `out` (new or empty): by
    /// default a population of 100 for 50 generations, seed 1, all cores, every design and
    /// grasp recorded.
    pub fn new(problem: impl Into<PathBuf>, out: impl Into<PathBuf>) -> Self {
        let spec = RunSpec {
            problem_path: problem.into(),
            out: out.into(),
            pop: 100,
            generations: 50,
            seed: 1,
            threads: None,
            record: RecordOptions::default(),
        };
        Optimiser { spec, resume: None, hooks: RunHooks::default() }
    }
    /// The resume of the run in `dir` (stopped, killed or finished).
    pub fn resume(dir: impl Into<PathBuf>) -> Self {
        let mut o = Self::new(PathBuf::new(), dir);
        o.resume = Some(Resume { generations: None, force: false });
        o
    }
    /// Population size (a new run).
    pub fn pop(mut self, n: usize) -> Self {
        self.spec.pop = n;
        self
    }
    /// Total generations (1 = the initial population; for a resume, the new total).
    pub fn generations(mut self, g: u64) -> Self {
        self.spec.generations = g;
        if let Some(r) = &mut self.resume {
            r.generations = Some(g);
        }
        self
    }
    /// Seed (a new run): it fixes the run.
    pub fn seed(mut self, s: u64) -> Self {
        self.spec.seed = s;
        self
    }
    /// Worker threads (a number, or None: all cores; results do not depend on them).
    pub fn threads(mut self, n: impl Into<Option<usize>>) -> Self {
        self.spec.threads = n.into();
        self
    }
    /// What to record to MCAP (a new run).
    pub fn record(mut self, r: RecordOptions) -> Self {
        self.spec.record = r;
        self
    }
    /// Resume even if the problem file or the checkpoint's checksum changed.
    pub fn force(mut self, yes: bool) -> Self {
        if let Some(r) = &mut self.resume {
            r.force = yes;
        }
        self
    }
    /// Report every generation (and notes) to `p`.
    pub fn progress(mut self, p: impl Progress + 'static) -> Self {
        self.hooks.progress = Some(Box::new(p));
        self
    }
    /// Stop after the current generation's checkpoint once `flag` is set.
    pub fn stop_flag(mut self, flag: Arc<AtomicBool>) -> Self {
        self.hooks.stop = Some(flag);
        self
    }
    /// Evaluate each generation with `e` instead of the default scheduler.
    pub fn evaluator(mut self, e: impl Evaluator<GripperProblem> + 'static) -> Self {
        self.hooks.evaluator = Some(Box::new(e));
        self
    }
    /// Run it.
    pub fn run(self) -> Result<RunSummary> {
        match self.resume {
            None => crate::run::optimise_with(&self.spec, self.hooks),
            Some(r) => crate::run::resume_with(&self.spec.out, r.generations, r.force, self.spec.threads, self.hooks),
        }
    }
}

/// Recording options: the defaults with the fields of `fields` (run.json's `recording`
/// fields: `enabled`, `trajectories`, `every`, `scene_dt`, `resolution`, `zstd_level`,
/// `zstd_threads`) over them, checked as the command line's are. An unknown field, or a value
/// of the wrong type, is an input error naming it.
pub fn record_options(fields: &serde_json::Map<String, serde_json::Value>) -> Result<RecordOptions> {
    let bad = |m: String| Error::Input(format!("record: {m}"));
    let mut v = serde_json::to_value(RecordOptions::default()).map_err(|e| bad(e.to_string()))?;
    let known = v.as_object_mut().expect("options are an object");
    for (k, x) in fields {
        if !known.contains_key(k) {
            let names: Vec<&str> = known.keys().map(String::as_str).filter(|k| *k != "epoch_s").collect();
            return Err(bad(format!("unknown option `{k}` (known: {})", names.join(", "))));
        }
        known.insert(k.clone(), x.clone());
    }
    let options: RecordOptions = serde_json::from_value(v).map_err(|e| bad(e.to_string()))?;
    options.validate()?;
    Ok(options)
}

/// A run of a problem held in memory (loaded from a file, or made from its text): the
/// problem file it starts from and records as its source. That is the file the problem was
/// loaded from where the file still holds exactly the problem's text (as `gripopt optimise
/// FILE`: run.json names the file, a resume follows its edits); otherwise (text, a name with
/// no such file, a file edited since, or other text named after a file) the problem's own
/// text written into the run folder as problem.toml, which must then be new or empty: the
/// run records that copy as its source, never a file whose content it did not run.
#[derive(Debug)]
pub struct ProblemRun {
    file: PathBuf,
    out: PathBuf,
    text: String,
    /// The copy of the text was written by this run (taken back if the run writes nothing).
    copied: bool,
    /// The run folder was created by this run.
    created: bool,
    /// Where a file was set aside (its content is not the problem's text): why, for the
    /// caller to tell.
    pub note: Option<String>,
}

impl ProblemRun {
    /// Decide the file of a run of `problem` (loaded from `loaded_from`, None: text) in `out`,
    /// writing the problem's text there where it must be.
    pub fn prepare(problem: &Problem, loaded_from: Option<&Path>, out: &Path) -> Result<Self> {
        let text = &problem.source_text;
        let created = !out.exists();
        let mut note = None;
        if let Some(p) = loaded_from {
            match std::fs::read(p) {
                Ok(bytes) if bytes == text.as_bytes() => {
                    let file = p.to_path_buf();
                    let (out, text) = (out.to_path_buf(), text.clone());
                    return Ok(ProblemRun { file, out, text, copied: false, created, note: None });
                }
                Ok(_) => {
                    note = Some(format!(
                        "{}: the file's content is not the problem's text (edited since the problem was loaded, or the text was only named after it); the run uses the problem's text, written to {} as its source",
                        p.display(),
                        out.join(PROBLEM_FILE).display()
                    ))
                }
                Err(_) => {}
            }
        }
        let empty = match std::fs::read_dir(out) {
            Ok(mut rd) => rd.next().is_none(),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => true,
            Err(e) => return Err(Error::io(out, "cannot list the run folder", e)),
        };
        if !empty {
            let why = match loaded_from {
                None => "a problem given as text".to_string(),
                Some(p) => format!(
                    "a problem whose text is not the content of {} (no such file, or another text)",
                    p.display()
                ),
            };
            return Err(Error::RunDir {
                path: out.to_path_buf(),
                message: format!("not empty: {why} starts a run only in a new or empty folder (its text is written there as problem.toml); load the problem from its file instead"),
            });
        }
        std::fs::create_dir_all(out).map_err(|e| Error::io(out, "cannot create the run folder", e))?;
        let file = out.join(PROBLEM_FILE);
        std::fs::write(&file, text).map_err(|e| Error::io(&file, "cannot write", e))?;
        Ok(ProblemRun { file, out: out.to_path_buf(), text: text.clone(), copied: true, created, note })
    }

    /// The run did not happen (it failed, or the caller stopped before it): where it wrote
    /// no run.json, the problem's copy written for it is taken back, and the folder where
    /// this run created it, so that the same call can be made again.
    pub fn abandon(self) {
        if self.copied && !self.out.join(RUN_FILE).exists() {
            let _ = std::fs::remove_file(&self.file);
            if self.created {
                let _ = std::fs::remove_dir(&self.out); // only if empty
            }
        }
    }

    /// The problem file the run starts from.
    pub fn file(&self) -> &Path {
        &self.file
    }

    /// The run's outcome `ran`, made safe: a run that stopped before it wrote run.json (a
    /// problem refused by the run, say) leaves nothing of its own in the folder (the copy
    /// written for it is taken back, and the folder where this run created it), so that the
    /// same call can be made again; a run from the problem's own file is checked to have read
    /// the problem's text (a file replaced between the check and the run's start is named,
    /// so that a run of other text is never returned as the problem's).
    pub fn finish(self, ran: Result<RunSummary>) -> Result<RunSummary> {
        let s = match ran {
            Ok(s) => s,
            Err(e) => {
                self.abandon();
                return Err(e);
            }
        };
        if !self.copied {
            let copy = self.out.join(PROBLEM_FILE);
            if std::fs::read(&copy).ok().as_deref() != Some(self.text.as_bytes()) {
                return Err(Error::RunDir {
                    path: self.out.clone(),
                    message: format!(
                        "{} changed while the run started: the run (attributed to that file, as its run.json says) is not of the problem given",
                        self.file.display()
                    ),
                });
            }
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Options over the defaults by field name; an unknown one, or one of the wrong type, is
    /// named.
    #[test]
    fn record_options_are_fields_over_the_defaults() {
        let map = |v: serde_json::Value| v.as_object().unwrap().clone();
        let o = record_options(&map(serde_json::json!({"every": 3, "resolution": "full"}))).unwrap();
        assert_eq!(o, RecordOptions { every: 3, resolution: crate::record::Resolution::Full, ..Default::default() });
        let e = record_options(&map(serde_json::json!({"evry": 3}))).unwrap_err().to_string();
        assert!(e.contains("unknown option `evry`") && e.contains("every"), "{e}");
        assert!(!e.contains("epoch_s"), "{e}");
        let e = record_options(&map(serde_json::json!({"every": "x"}))).unwrap_err().to_string();
        assert!(e.starts_with("record: "), "{e}");
    }
}
