//! Bisection of the boundaries where a sweep's verdict flips along a varied name, and
//! boundaries.csv: one row per boundary, `bisected` (the name), every varied name's value
//! (the bisected name's own cell empty: `lo` and `hi` bracket it), `lo`, `hi`,
//! `verdict_lo`, `verdict_hi`; its units line names the same columns in the same order.

use super::{eval_row, out::BOUNDARIES_FILE, Row, SweepSpec};
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::Path;

/// A boundary found by bisection: along `name`, between two values whose verdicts differ.
#[derive(Debug, Clone)]
pub struct Boundary {
    /// The bisected name.
    pub name: String,
    /// Values of the other varied names (in --vary order, the bisected one omitted).
    pub others: Vec<f64>,
    /// Last value with `verdict_lo`.
    pub lo: f64,
    /// First value with `verdict_hi`.
    pub hi: f64,
    /// Verdict at `lo`.
    pub verdict_lo: &'static str,
    /// Verdict at `hi`.
    pub verdict_hi: &'static str,
}

/// For every line of the grid along the varied name `name`, every pair of neighbours with
/// different verdicts is narrowed by `steps` bisections (in parallel).
pub fn bisect(spec: &SweepSpec, rows: &[Row], name: &str, steps: u32) -> Result<Vec<Boundary>> {
    let axis = spec.vary.iter().position(|v| v.name == name).ok_or_else(|| {
        Error::Input(format!(
            "--bisect {name}: not one of the varied names ({})",
            spec.vary.iter().map(|v| v.name.as_str()).collect::<Vec<_>>().join(", ")
        ))
    })?;
    if steps > 60 {
        return Err(Error::Input(format!("--bisect-steps {steps}: at most 60")));
    }
    let stride: usize = spec.vary[..axis].iter().map(|v| v.n).product();
    let mut pairs = Vec::new();
    for k in 0..rows.len() {
        let i = (k / stride) % spec.vary[axis].n;
        if i + 1 < spec.vary[axis].n && rows[k].verdict != rows[k + stride].verdict {
            pairs.push((k, k + stride));
        }
    }
    pairs
        .par_iter()
        .map(|&(a, b)| {
            let (mut lo, mut hi) = (rows[a].values[axis], rows[b].values[axis]);
            let (vlo, vhi) = (rows[a].verdict, rows[b].verdict);
            let mut point = rows[a].values.clone();
            let integer = spec.vary[axis].is_integer();
            for _ in 0..steps {
                // a whole-number field is bisected over whole values, down to neighbours
                let mid = if integer { (0.5 * (lo + hi)).floor() } else { 0.5 * (lo + hi) };
                if integer && (mid <= lo || mid >= hi) {
                    break;
                }
                point[axis] = mid;
                let v = eval_row(spec, &point)?.verdict;
                if v == vlo {
                    lo = mid;
                } else if v == vhi {
                    hi = mid;
                } else {
                    // a third verdict in between: keep the side next to the lower verdict
                    hi = mid;
                }
            }
            let mut others = rows[a].values.clone();
            others.remove(axis);
            Ok(Boundary { name: name.to_string(), others, lo, hi, verdict_lo: vlo, verdict_hi: vhi })
        })
        .collect()
}

/// boundaries.csv's columns with their units, the one list both the header and the units
/// line are written from: `lo` and `hi` in the bisected name's unit (`as bisected` when
/// names of different units were bisected).
fn columns(spec: &SweepSpec, b: &[Boundary]) -> Vec<(String, String)> {
    let mut units: Vec<&str> =
        b.iter().filter_map(|bd| spec.vary.iter().find(|v| v.name == bd.name)).map(|v| v.unit()).collect();
    units.dedup();
    let bracket = match units[..] {
        [one] => one.to_string(),
        _ => "as bisected".to_string(),
    };
    let mut c = vec![("bisected".to_string(), "text".to_string())];
    c.extend(spec.vary.iter().map(|v| (v.name.clone(), v.unit().to_string())));
    c.push(("lo".into(), bracket.clone()));
    c.push(("hi".into(), bracket));
    c.push(("verdict_lo".into(), "text".into()));
    c.push(("verdict_hi".into(), "text".into()));
    c
}

/// boundaries.csv text: the header and one row per boundary (every varied name's value, the
/// bisected name's own cell empty).
pub fn boundaries_csv(spec: &SweepSpec, b: &[Boundary]) -> String {
    let names: Vec<String> = columns(spec, b).into_iter().map(|(n, _)| n).collect();
    let mut s = names.join(",") + "\n";
    for bd in b {
        let mut others = bd.others.iter();
        let values: Vec<String> = spec
            .vary
            .iter()
            .map(
                |v| if v.name == bd.name { String::new() } else { others.next().map_or(String::new(), f64::to_string) },
            )
            .collect();
        let _ = writeln!(s, "{},{},{},{},{},{}", bd.name, values.join(","), bd.lo, bd.hi, bd.verdict_lo, bd.verdict_hi);
    }
    s
}

/// Write DIR/boundaries.csv (its `#` title and units lines, then [`boundaries_csv`]).
pub fn write_boundaries(dir: &Path, spec: &SweepSpec, b: &[Boundary]) -> Result<()> {
    let mut s = String::from("# gripopt boundaries.csv: where the verdict flips along a bisected name, between the values lo and hi (the other varied names as given; the bisected name's own cell empty)\n# units:");
    for (name, unit) in columns(spec, b) {
        let _ = write!(s, " {name} [{unit}]");
    }
    s.push('\n');
    s.push_str(&boundaries_csv(spec, b));
    write_atomic(&dir.join(BOUNDARIES_FILE), s.as_bytes())
}
