//! `gripopt bench accuracy`'s outcomes and statistics: what each setting gives per design,
//! and per candidate the verdicts that differ from the reference and each quantity's
//! relative errors (median, p90, max), whether the rule holds, and the CSV files.

use super::ensemble::quantile;
use super::{median, say};
use crate::params::{Design, DESIGN_NAMES};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::Path;

/// The rule's bound on each objective's 90th-percentile relative error.
pub const RULE_P90: f64 = 5e-5;
/// The rule's bound on each objective's largest relative error.
pub const RULE_MAX: f64 = 2e-3;

/// A grasp-ensemble design's outcome under one setting.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct GraspOutcome {
    /// The pipeline's verdict (feasible, failed stage, reason) in the problem's scene.
    pub verdict: (bool, Option<u8>, Option<String>),
    /// The pipeline's objectives.
    pub objectives: [Option<f64>; 4],
    /// t_stab of the diagnostic grasp (the objective where the pipeline stops earlier).
    pub t_stab: Option<f64>,
    /// E_cyl of the diagnostic grasp (diagnostic).
    pub e_cyl: Option<f64>,
    /// The free scene's verdict (x_off 0): feasible, failed stage, reason.
    pub free_verdict: (bool, Option<u8>, Option<String>),
    /// The free scene's largest displacement (m) and tilt (°) (diagnostic).
    pub free_motion: (Option<f64>, Option<f64>),
    /// Accepted steps and RHS evaluations of the three simulations.
    pub work: [u64; 2],
    /// Seconds.
    pub seconds: f64,
}

/// One robust scenario's outcome.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ScenarioOutcome {
    /// The object barely moved.
    pub stays: bool,
    /// Its t_stab (s).
    pub t_stab: Option<f64>,
    /// Largest displacement (m) and tilt (°) of the object (diagnostic).
    pub motion: (Option<f64>, Option<f64>),
}

/// A robust-ensemble design's outcome under one setting (every scenario run).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RobustOutcome {
    /// The design's verdict: feasible, failed stage.
    pub verdict: (bool, Option<u8>),
    /// The aggregated objectives.
    pub objectives: [Option<f64>; 4],
    /// Per object: its objectives and whether it meets p_min.
    pub objects: Vec<([Option<f64>; 4], Option<bool>)>,
    /// Every scenario, object-major.
    pub scenarios: Vec<ScenarioOutcome>,
    /// Accepted steps and RHS evaluations of all its simulations.
    pub work: [u64; 2],
    /// Seconds.
    pub seconds: f64,
}

/// Every design's outcome under one setting.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Outcomes {
    /// The grasp ensemble.
    pub grasp: Vec<GraspOutcome>,
    /// The robust ensemble.
    pub robust: Vec<RobustOutcome>,
}

/// What a quantity is to the rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A verdict: every one must be the reference's.
    Verdict,
    /// An objective: p90 and max relative error within the rule's bounds.
    Objective,
    /// Reported, not held.
    Diagnostic,
}

impl Kind {
    fn as_str(self) -> &'static str {
        match self {
            Kind::Verdict => "verdict",
            Kind::Objective => "objective",
            Kind::Diagnostic => "diagnostic",
        }
    }
}

/// One quantity's comparison with the reference.
#[derive(Debug, Clone)]
pub struct Quantity {
    /// Its name (`grasp.t_stab`, `robust.objective.t_stab`, …).
    pub name: String,
    /// Verdict, objective or diagnostic.
    pub kind: Kind,
    /// Cases compared.
    pub n: usize,
    /// Verdicts differing, or values present on one side only.
    pub differing: usize,
    /// Median, p90 and largest relative error (NaN for verdicts).
    pub errors: [f64; 3],
}

impl Quantity {
    /// Does the rule hold for it?
    pub fn holds(&self) -> bool {
        match self.kind {
            Kind::Verdict => self.differing == 0,
            Kind::Objective => self.differing == 0 && !(self.errors[1] > RULE_P90) && !(self.errors[2] > RULE_MAX),
            Kind::Diagnostic => true,
        }
    }
}

/// One candidate's comparison.
#[derive(Debug, Clone)]
pub struct CandidateSummary {
    /// The candidate (`default`, `auto:1e-6`).
    pub label: String,
    /// Every quantity.
    pub quantities: Vec<Quantity>,
    /// Accepted steps and RHS evaluations, all simulations.
    pub work: [u64; 2],
    /// Wall seconds of the candidate's run (both ensembles, in parallel).
    pub wall_s: f64,
}

impl CandidateSummary {
    /// Does the rule hold for every quantity?
    pub fn holds(&self) -> bool {
        self.quantities.iter().all(Quantity::holds)
    }

    /// Its text lines.
    pub fn say(&self, out: super::Out) -> Result<()> {
        let verdict = if self.holds() { "the rule holds" } else { "the rule does NOT hold" };
        say!(
            out,
            "{}: {verdict}; {} steps, {} RHS evaluations, {:.1} s wall",
            self.label,
            self.work[0],
            self.work[1],
            self.wall_s
        );
        for q in &self.quantities {
            let mark = if q.holds() { "" } else { "  <- beyond the rule" };
            match q.kind {
                Kind::Verdict => say!(out, "  {:<34} {:>5} verdicts, {} differ{mark}", q.name, q.n, q.differing),
                _ => say!(
                    out,
                    "  {:<34} {:>5} {:<10} median {:.2e}  p90 {:.2e}  max {:.2e}{}{mark}",
                    q.name,
                    q.n,
                    q.kind.as_str(),
                    q.errors[0],
                    q.errors[1],
                    q.errors[2],
                    if q.differing > 0 { format!(" ({} on one side only)", q.differing) } else { String::new() }
                ),
            }
        }
        Ok(())
    }

    /// As JSON.
    pub fn to_json(&self) -> serde_json::Value {
        let qs: Vec<serde_json::Value> = self
            .quantities
            .iter()
            .map(|q| {
                let num = |v: f64| if v.is_finite() { serde_json::json!(v) } else { serde_json::Value::Null };
                serde_json::json!({
                    "name": q.name, "kind": q.kind.as_str(), "n": q.n, "differing": q.differing,
                    "median": num(q.errors[0]), "p90": num(q.errors[1]), "max": num(q.errors[2]), "holds": q.holds(),
                })
            })
            .collect();
        serde_json::json!({
            "candidate": self.label, "holds": self.holds(), "steps": self.work[0], "rhs_evals": self.work[1],
            "wall_s": self.wall_s, "quantities": qs,
        })
    }
}

/// Relative error of `a` against the reference `r`: 0 when both are absent, infinite when
/// one is.
fn rel(a: Option<f64>, r: Option<f64>) -> f64 {
    match (a, r) {
        (Some(a), Some(r)) if a == r => 0.0,
        (Some(a), Some(r)) => ((a - r) / r).abs(),
        (None, None) => 0.0,
        _ => f64::INFINITY,
    }
}

/// Builds the quantities of one candidate.
#[derive(Default)]
struct Collect {
    quantities: Vec<Quantity>,
}

impl Collect {
    fn verdicts(&mut self, name: &str, same: impl Iterator<Item = bool>) {
        let (mut n, mut differing) = (0, 0);
        for s in same {
            n += 1;
            differing += usize::from(!s);
        }
        self.quantities.push(Quantity { name: name.into(), kind: Kind::Verdict, n, differing, errors: [f64::NAN; 3] });
    }

    fn errors(&mut self, name: &str, kind: Kind, pairs: impl Iterator<Item = (Option<f64>, Option<f64>)>) {
        let mut e = vec![];
        let mut differing = 0;
        for (a, r) in pairs {
            if a.is_none() && r.is_none() {
                continue;
            }
            let x = rel(a, r);
            differing += usize::from(x.is_infinite());
            e.push(x);
        }
        let n = e.len();
        let max = e.iter().copied().fold(0.0, f64::max);
        let finite: Vec<f64> = e.iter().copied().filter(|x| x.is_finite()).collect();
        let errors = if n == 0 { [f64::NAN; 3] } else { [median(finite.clone()), quantile(e, 0.9), max] };
        self.quantities.push(Quantity { name: name.into(), kind, n, differing, errors });
    }
}

const OBJECTIVES: [&str; 4] = ["max_offset", "alpha", "mean_force", "t_stab"];

/// The comparison of `o` (candidate `label`, `wall_s` seconds) with the reference `r`.
pub fn summarise(label: &str, r: &Outcomes, o: &Outcomes, wall_s: f64) -> CandidateSummary {
    let mut c = Collect::default();
    let g = || r.grasp.iter().zip(&o.grasp);
    c.verdicts("grasp.verdict", g().map(|(r, o)| r.verdict == o.verdict));
    c.verdicts("grasp.free_scene.verdict", g().map(|(r, o)| r.free_verdict == o.free_verdict));
    c.errors("grasp.t_stab", Kind::Objective, g().map(|(r, o)| (o.t_stab, r.t_stab)));
    for (i, name) in OBJECTIVES.iter().enumerate() {
        c.errors(
            &format!("grasp.objective.{name}"),
            Kind::Objective,
            g().map(|(r, o)| (o.objectives[i], r.objectives[i])),
        );
    }
    c.errors("grasp.e_cyl", Kind::Diagnostic, g().map(|(r, o)| (o.e_cyl, r.e_cyl)));
    c.errors("grasp.free_scene.displacement", Kind::Diagnostic, g().map(|(r, o)| (o.free_motion.0, r.free_motion.0)));
    c.errors("grasp.free_scene.tilt", Kind::Diagnostic, g().map(|(r, o)| (o.free_motion.1, r.free_motion.1)));
    let rb = || r.robust.iter().zip(&o.robust);
    c.verdicts("robust.verdict", rb().map(|(r, o)| r.verdict == o.verdict));
    c.verdicts(
        "robust.object.meets_p_min",
        rb().flat_map(|(r, o)| r.objects.iter().zip(&o.objects).map(|(a, b)| a.1 == b.1)),
    );
    let sc = || rb().flat_map(|(r, o)| r.scenarios.iter().zip(&o.scenarios));
    c.verdicts("robust.scenario.stays", sc().map(|(r, o)| r.stays == o.stays));
    for (i, name) in OBJECTIVES.iter().enumerate() {
        c.errors(
            &format!("robust.objective.{name}"),
            Kind::Objective,
            rb().map(|(r, o)| (o.objectives[i], r.objectives[i])),
        );
    }
    for (i, name) in OBJECTIVES.iter().enumerate() {
        let pairs = rb().flat_map(|(r, o)| r.objects.iter().zip(&o.objects).map(move |(a, b)| (b.0[i], a.0[i])));
        c.errors(&format!("robust.object.{name}"), Kind::Objective, pairs);
    }
    c.errors("robust.scenario.t_stab", Kind::Diagnostic, sc().map(|(r, o)| (o.t_stab, r.t_stab)));
    c.errors("robust.scenario.displacement", Kind::Diagnostic, sc().map(|(r, o)| (o.motion.0, r.motion.0)));
    c.errors("robust.scenario.tilt", Kind::Diagnostic, sc().map(|(r, o)| (o.motion.1, r.motion.1)));
    let work = o
        .grasp
        .iter()
        .map(|g| g.work)
        .chain(o.robust.iter().map(|r| r.work))
        .fold([0, 0], |a, w| [a[0] + w[0], a[1] + w[1]]);
    CandidateSummary { label: label.into(), quantities: c.quantities, work, wall_s }
}

/// accuracy.csv: one row per candidate and quantity.
pub fn write_summaries(path: &Path, s: &[CandidateSummary]) -> Result<()> {
    let io = |e| Error::io(path, "cannot write", e);
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).map_err(|e| Error::io(path, "cannot create", e))?);
    writeln!(w, "candidate,quantity,kind,n,differing,err_median,err_p90,err_max,holds,steps,rhs_evals,wall_s")
        .map_err(io)?;
    for c in s {
        for q in &c.quantities {
            let [m, p, x] = q.errors;
            writeln!(
                w,
                "{},{},{},{},{},{m:e},{p:e},{x:e},{},{},{},{:.3}",
                c.label,
                q.name,
                q.kind.as_str(),
                q.n,
                q.differing,
                q.holds(),
                c.work[0],
                c.work[1],
                c.wall_s
            )
            .map_err(io)?;
        }
    }
    w.flush().map_err(io)
}

/// accuracy_cases.csv: every case's verdict and values, the reference's and each
/// candidate's (`all`), one row per (setting, case).
pub fn write_cases(
    path: &Path,
    gd: &[Design],
    rd: &[Design],
    reference: &Outcomes,
    all: &[(String, Outcomes)],
) -> Result<()> {
    let io = |e| Error::io(path, "cannot write", e);
    let mut w = std::io::BufWriter::new(std::fs::File::create(path).map_err(|e| Error::io(path, "cannot create", e))?);
    writeln!(w, "setting,ensemble,design,object,scenario,verdict,t_stab,displacement,tilt_deg,e_cyl,steps,rhs_evals")
        .map_err(io)?;
    let arg = |d: &Design| {
        let v: Vec<String> = DESIGN_NAMES.iter().zip(d.to_array()).map(|(n, x)| format!("{n}={x}")).collect();
        format!("\"{}\"", v.join(","))
    };
    let f = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:e}"));
    let settings = std::iter::once(("reference".to_string(), reference)).chain(all.iter().map(|(l, o)| (l.clone(), o)));
    for (label, o) in settings {
        for (d, g) in gd.iter().zip(&o.grasp) {
            let v = format!("{}/{}", g.verdict.0, g.free_verdict.0);
            let (t, e, m) = (f(g.t_stab), f(g.e_cyl), (f(g.free_motion.0), f(g.free_motion.1)));
            writeln!(w, "{label},grasp,{},,,{v},{t},{},{},{e},{},{}", arg(d), m.0, m.1, g.work[0], g.work[1])
                .map_err(io)?;
        }
        for (d, r) in rd.iter().zip(&o.robust) {
            let t = f(r.objectives[3]);
            writeln!(w, "{label},robust,{},,,{},{t},,,,{},{}", arg(d), r.verdict.0, r.work[0], r.work[1])
                .map_err(io)?;
            let k = r.scenarios.len() / r.objects.len().max(1);
            for (i, s) in r.scenarios.iter().enumerate() {
                let (t, m0, m1) = (f(s.t_stab), f(s.motion.0), f(s.motion.1));
                writeln!(
                    w,
                    "{label},scenario,{},{},{},{},{t},{m0},{m1},,,",
                    arg(d),
                    i / k.max(1),
                    i % k.max(1),
                    s.stays
                )
                .map_err(io)?;
            }
        }
    }
    w.flush().map_err(io)
}
