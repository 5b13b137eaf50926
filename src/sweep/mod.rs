//! Parameter studies (`gripopt sweep`): a grid of 1–3 varied names — design variables,
//! the derived relations the thesis's chapter 4 uses, or any numeric problem-file field —
//! evaluated in parallel through the staged pipeline, written as one CSV row per point (the
//! varied values, a verdict class and every key of the evaluation [`Record`]), plotted
//! ([`plot`]), and optionally refined by bisection to the boundaries where the verdict flips.
//!
//! Names (see [`Knob`]):
//! * design variables `l21`, `b`, `t22`, `r`, `p`, `psi_deg` (ψ in degrees);
//! * derived (thesis §4.1.2–4.2.2): `l11` sets p = l11/l21 and ψ = 140 − 25.6 p
//!   (eq. 4.15; varying `psi_deg` as well is refused); `l22` sets r = l22/l11; `l_hand` sets
//!   t22 = (l_hand − b − 2 l21)/2 (b and l21 as set at that point);
//! * `mu_scale`: a factor on the phalanx friction μ_s and μ_d of the simulated grasp
//!   together (stage 3 only; 0 allowed);
//! * scene and solver fields by dotted name (`hand.tau`, `object.density`) or by the last
//!   component when it is unique (`tau`, `density`, `grasp_height`, `radius`, `restitution`).
//!   A `[scene]` field the problem's scene kind does not simulate is refused
//!   ([`crate::params::scene_kinds_using`]: `scene.x_off` needs the offset or free scene, `scene.t_obs` and
//!   the ground's fields the free scene), as every point would be the same design in the same
//!   scene.
//!
//! Results do not depend on the number of threads: every point is evaluated on its own and
//! rows are written in grid order.

mod boundaries;
pub mod out;
pub mod plot;
mod spec;

pub use boundaries::{bisect, boundaries_csv, write_boundaries, Boundary};
pub(crate) use spec::ARRAY_KEYS;
pub use spec::{
    psi_thesis, resolve, set_field, stage3_only_names, Knob, Stage, SweepSpec, Vary, INTEGER_FIELDS, MAX_N, MAX_POINTS,
};

use crate::cells::{cells, Floats};
use crate::error::{Error, Result};
use crate::eval::{evaluate, evaluate_kinematics, Cause, EvalOptions, Evaluation, Record};
use crate::fsutil::write_atomic;
use crate::params::{Design, Problem};
use out::{record_unit, EarlierFile, SWEEP_FILE, SWEEP_TITLE};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::Path;

/// The verdict class of an evaluation: `pass` or what discarded it, as a short word (the
/// record's [`Cause`]: `singular_open`, `singular_closing`, `mode_change`, `impact`, `force`, …).
pub fn verdict(ev: &Evaluation) -> &'static str {
    ev.discard.and_then(|d| d.reason.cause()).map_or("pass", Cause::as_str)
}

/// Evaluate one design of one problem through the chosen stages.
pub fn evaluate_point(p: &Problem, x: &Design, stage: Stage) -> Evaluation {
    match stage {
        // with what stage 1 computed before a discard, as the later stages report it
        Stage::Kinematics => evaluate_kinematics(x, &p.scene),
        Stage::Static => evaluate(x, &p.scene, &EvalOptions::statics_only()),
        Stage::Dynamic => evaluate(x, &p.scene, &EvalOptions::full(p)),
    }
}

/// One evaluated grid point.
#[derive(Debug, Clone)]
pub struct Row {
    /// Values of the varied names.
    pub values: Vec<f64>,
    /// Verdict class ([`verdict`]).
    pub verdict: &'static str,
    /// The evaluation record, flattened: (key, CSV text); numbers are `None` when null.
    pub cells: Vec<(String, String)>,
}

impl Row {
    /// A numeric record value by key (None when null, absent or not a number).
    pub fn num(&self, key: &str) -> Option<f64> {
        self.cells.iter().find(|(k, _)| k == key).and_then(|(_, v)| v.parse().ok())
    }
}

/// The evaluation record (the JSON of `gripopt evaluate --json`) as CSV cells, in record
/// order, numbers as in the JSON; arrays become `key_0`, `key_1`, … (a null one keeps its
/// columns, so every row has the header's width).
pub fn record_cells(ev: &Evaluation) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for (k, v) in cells(&Record::from_eval(ev), Floats::Json) {
        match ARRAY_KEYS.iter().find(|a| a.0 == k) {
            Some(&(_, n)) => out.extend((0..n).map(|i| (format!("{k}_{i}"), String::new()))),
            None => out.push((k, v)),
        }
    }
    out
}

/// Evaluate one point of the sweep.
pub fn eval_row(spec: &SweepSpec, values: &[f64]) -> Result<Row> {
    let (p, x) = spec.apply(values)?;
    let mu = spec.vary.iter().zip(values).find(|(v, _)| v.knob == Knob::MuScale).map(|(_, &m)| m);
    let ev = match (mu, spec.stage) {
        (Some(m), Stage::Dynamic) => {
            // the grasp's friction scaled, the design statics at the problem's
            let mut s3 = p.scene.clone();
            s3.contact.mu_s *= m;
            s3.contact.mu_d *= m;
            crate::eval::evaluate_dynamics(
                crate::eval::evaluate_statics(&x, &p.scene),
                &s3,
                &EvalOptions::full(&p),
                &mut (),
            )
        }
        _ => evaluate_point(&p, &x, spec.stage),
    };
    Ok(Row { values: values.to_vec(), verdict: verdict(&ev), cells: record_cells(&ev) })
}

/// Evaluate the whole grid in parallel (rows in grid order); `tick` is called once per point.
pub fn run(spec: &SweepSpec, tick: &(dyn Fn() + Sync)) -> Result<Vec<Row>> {
    spec.validate()?;
    // every point is set up before any is evaluated, so a bad value fails fast
    let points: Vec<Vec<f64>> = (0..spec.len()).map(|k| spec.point(k)).collect();
    for v in &points {
        spec.apply(v)?;
    }
    points
        .par_iter()
        .map(|v| {
            let r = eval_row(spec, v);
            tick();
            r
        })
        .collect()
}

/// The record keys of `rows` that are columns (every key of any row, in record order; keys
/// equal to a varied name are not repeated): a row whose record lacks a scene's keys (stage
/// 3 did not run) has empty cells there, so every row has the header's width.
fn columns<'a>(spec: &SweepSpec, rows: &'a [Row]) -> Vec<&'a str> {
    let names: Vec<&str> = spec.vary.iter().map(|v| v.name.as_str()).collect();
    let mut keys: Vec<&str> = vec![];
    for r in rows {
        for (i, (k, _)) in r.cells.iter().enumerate() {
            if names.contains(&k.as_str()) || keys.contains(&k.as_str()) {
                continue;
            }
            // after the key that precedes it in this row (record order)
            let at = r.cells[..i].iter().rev().find_map(|(p, _)| keys.iter().position(|q| q == p)).map_or(0, |p| p + 1);
            keys.insert(at.min(keys.len()), k);
        }
    }
    keys
}

/// The CSV table (header and rows, without the `#` lines): varied names, `verdict`, then
/// every record key (`columns`).
pub fn to_csv(spec: &SweepSpec, rows: &[Row]) -> String {
    let mut s = String::new();
    let names: Vec<&str> = spec.vary.iter().map(|v| v.name.as_str()).collect();
    let keys = columns(spec, rows);
    let _ = writeln!(s, "{},verdict,{}", names.join(","), keys.join(","));
    for r in rows {
        let vals: Vec<String> = r.values.iter().map(|v| format!("{v}")).collect();
        let cells: Vec<&str> =
            keys.iter().map(|k| r.cells.iter().find(|(c, _)| c == k).map_or("", |(_, v)| v.as_str())).collect();
        let _ = writeln!(s, "{},{},{}", vals.join(","), r.verdict, cells.join(","));
    }
    s
}

/// sweep.csv's text: its `#` lines (title, the units of every column, the files the sweep
/// writes) and [`to_csv`].
pub fn sweep_csv(spec: &SweepSpec, rows: &[Row], files: &[String]) -> String {
    let mut s = format!("{SWEEP_TITLE}: one row per grid point: the varied names, the verdict (pass or what discarded the point) and the evaluation record's keys (docs/outputs.md); empty: not computed\n# units:");
    for v in &spec.vary {
        let _ = write!(s, " {} [{}]", v.name, v.unit());
    }
    s.push_str(" verdict [text]");
    for k in columns(spec, rows) {
        let _ = write!(s, " {k} [{}]", record_unit(k));
    }
    let _ = writeln!(s, "\n# files: {}", files.join(", "));
    s.push_str(&to_csv(spec, rows));
    s
}

/// Write DIR/sweep.csv alone (see [`write_outputs`]), holding the folder's lock.
pub fn write_csv(dir: &Path, spec: &SweepSpec, rows: &[Row]) -> Result<()> {
    let (_lock, earlier) = out::open_out_folder(dir)?;
    write_outputs(dir, spec, rows, &earlier, &[])?;
    seal(dir, spec, rows, &[])
}

/// Start a sweep's output folder `dir` (the caller holds its lock: [`out::open_out_folder`]):
/// of the `earlier` sweep's files, set aside those whose content is not provably what that
/// sweep wrote, remove the proven ones this sweep does not write again, and write sweep.csv
/// (atomically) listing itself and `files` (names in `dir`), which the caller writes next,
/// then [`seal`]s.
pub fn write_outputs(
    dir: &Path,
    spec: &SweepSpec,
    rows: &[Row],
    earlier: &[EarlierFile],
    files: &[String],
) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, "cannot create the output folder", e))?;
    let mut all = vec![SWEEP_FILE.to_string()];
    all.extend(files.iter().cloned());
    for f in earlier {
        let name = f.path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if !f.proven {
            // edited since, or never sealed: kept for the user, out of the new sweep's way
            crate::fsutil::set_aside(dir, &name)?;
        } else if !all.contains(&name) {
            std::fs::remove_file(&f.path)
                .map_err(|e| Error::io(&f.path, "cannot remove the earlier sweep's file", e))?;
        }
    }
    write_atomic(&dir.join(SWEEP_FILE), sweep_csv(spec, rows, &all).as_bytes())
}

/// Seal a finished sweep: rewrite sweep.csv with the SHA-256 of every file it lists
/// (`files`: the names the caller wrote besides sweep.csv), so that a later sweep into the
/// folder knows which files are still what this one wrote.
pub fn seal(dir: &Path, spec: &SweepSpec, rows: &[Row], files: &[String]) -> Result<()> {
    let mut all = vec![SWEEP_FILE.to_string()];
    all.extend(files.iter().cloned());
    let mut text = sweep_csv(spec, rows, &all);
    let mut sums = vec![];
    for f in files {
        let p = dir.join(f);
        let bytes = crate::fsutil::read_regular(&p, crate::fsutil::caps::TABLE)
            .map_err(|e| Error::io(&p, "cannot read back", e))?;
        sums.push(format!("{f}={}", crate::fsutil::sha256_hex(&bytes)));
    }
    // after the `# files:` line (its `#` lines come before the table)
    let at = text.find("\n# files: ").and_then(|i| text[i + 1..].find('\n').map(|j| i + 1 + j + 1)).unwrap_or(0);
    text.insert_str(at, &format!("{}{}\n", out::SHA256_LINE, sums.join(", ")));
    write_atomic(&dir.join(SWEEP_FILE), text.as_bytes())
}
