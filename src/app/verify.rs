//! `gripopt verify`: a run's designs evaluated on another study and compared with what the
//! run found. A single-object run's designs on the 1 × 1 study of the free scene, diagnosed
//! to its end, against the centred criteria's prediction (verify.csv, `run::verify`); a
//! robust run's front on its verify study — fresh scenarios drawn from the verify stream of
//! each design's generation's problem — against its in-sample P(stay)
//! (verify_robust.csv, `run::verify_robust`).

use super::evaluate::in_pool;
use crate::error::Result;
use crate::params::Problem;
use crate::run::{check_sample, is_robust_run, RobustVerifySummary, VerifySource, VerifySummary};
use std::path::Path;

/// What `verify` is asked for (a single-object run; a robust run verifies its front on
/// fresh scenarios whatever is asked).
#[derive(Debug, Clone, Copy)]
pub struct VerifyRequest {
    /// The designs: the front, every feasible design of the checkpoint, or a sample.
    pub source: VerifySource,
    /// The object's offset in the free scene (None: the problem's).
    pub x_off: Option<f64>,
    /// Record the free scene to MCAP.
    pub record: bool,
    /// Worker threads (None: all cores; results do not depend on them).
    pub threads: Option<usize>,
}

/// What a verify found.
#[derive(Debug, Clone)]
pub enum Verified {
    /// A single-object run's designs in the free scene.
    Designs(VerifySummary),
    /// A robust run's front out of sample.
    Robust(RobustVerifySummary),
}

/// Verify the run in `dir` as `req` asks (`tick_len`: the number of designs to verify, once
/// known; `tick`: one more verified).
pub fn verify(
    dir: &Path,
    req: &VerifyRequest,
    tick_len: &(dyn Fn(usize) + Sync),
    tick: &(dyn Fn() + Sync),
) -> Result<Verified> {
    if is_robust_run(dir) {
        // a robust run: the front out of sample (docs/robust.md)
        return in_pool(req.threads, || crate::run::verify_robust(dir))?.map(Verified::Robust);
    }
    if let VerifySource::Sample { n, .. } = req.source {
        // the recording's share follows the free scene's duration (a problem.toml that does
        // not load is the library's error to report, after this check), before the lock
        let problem = Problem::load(dir.join("problem.toml")).ok();
        let t_obs = problem.map(|p| p.scene.setup.t_obs.min(p.scene.criteria.t_max));
        check_sample(n, t_obs.filter(|_| req.record))?;
    }
    in_pool(req.threads, || crate::run::verify(dir, req.source, req.x_off, req.record, tick_len, tick))?
        .map(Verified::Designs)
}
