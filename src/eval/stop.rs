//! The sequential stopping rule of a design's scenarios: stop as soon as the verdict is
//! known.

use super::record_robust::ScenarioRecord;
use super::study::Study;

/// What decides a design's stage 3, scanning its scenarios in their order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decided {
    /// The solver aborted the scenario at this position (in the order run): the design is a
    /// solver-failure discard, as the single-object pipeline's aborted simulation.
    Aborted(usize),
    /// The scenario at this position gave its object more failures than its constraint
    /// allows over K.
    PStay(usize),
}

/// The sequential stopping rule: fed a design's scenarios in their order, it says when the
/// verdict is known — at the first aborted scenario (its object's motion was never measured,
/// so it is not counted as a failure) or at the first measured failure that makes some
/// object's constraint impossible.
#[derive(Debug, Clone)]
pub struct StopRule {
    fmax: usize,
    fails: Vec<usize>,
    seen: usize,
}

impl StopRule {
    /// The rule for the designs of `study`.
    pub fn new(study: &Study) -> Self {
        StopRule { fmax: study.failures_allowed(), fails: vec![0; study.objects()], seen: 0 }
    }

    /// The next scenario; Some once this one decides the verdict.
    pub fn push(&mut self, r: &ScenarioRecord) -> Option<Decided> {
        let j = self.seen;
        self.seen += 1;
        if r.aborted() {
            return Some(Decided::Aborted(j));
        }
        if !r.stays {
            self.fails[r.object] += 1;
            if self.fails[r.object] > self.fmax {
                return Some(Decided::PStay(j));
            }
        }
        None
    }
}

/// What decides the verdict of a design with scenarios `scen` (in their order), if anything
/// does: the first event of [`StopRule`].
pub fn decided(study: &Study, scen: &[ScenarioRecord]) -> Option<Decided> {
    let mut rule = StopRule::new(study);
    scen.iter().find_map(|r| rule.push(r))
}
