//! The problem and design arguments every command shares: `PROBLEM` loaded with its path in
//! the error, `--design` (default: the problem's nominal) with a warning for values outside
//! the bounds.

use anyhow::Result;
use gripopt::app::{Design, Problem};
use std::path::PathBuf;

/// Load a problem, with the path in the error.
pub fn load_problem(p: &PathBuf) -> Result<Problem> {
    Ok(Problem::load(p)?)
}

/// The design of `--design` (default: the problem's nominal). A design outside the problem's
/// bounds is evaluated (the bounds are the optimiser's search box, not validity), with a
/// warning on stderr naming each variable outside.
pub fn design_of(p: &Problem, d: &Option<String>) -> Result<Design> {
    let x = match d {
        None => p.nominal,
        Some(s) => Design::parse_assignments(s)?,
    };
    let a = x.to_array();
    for k in 0..6 {
        let (lo, hi) = (p.bounds.lo[k], p.bounds.hi[k]);
        if !(a[k] >= lo && a[k] <= hi) {
            eprintln!(
                "warning: {} = {} is outside the problem's bounds [{}, {}]; evaluating it anyway",
                gripopt::app::DESIGN_NAMES[k],
                compact(a[k]),
                compact(lo),
                compact(hi)
            );
        }
    }
    if let Some(why) = x.invalid_length() {
        // stage 0 says "a length is not positive": which one, and why (stderr only)
        eprintln!("warning: --design: {why}; the design has no finger (discarded at stage 0)");
    }
    Ok(x)
}

/// A number in its shorter form, `{}` or `{:e}` (1e300, not 301 digits; 0.05, not 5e-2);
/// both read back to the same value.
pub fn compact(v: f64) -> String {
    let (plain, exp) = (format!("{v}"), format!("{v:e}"));
    if exp.len() < plain.len() {
        exp
    } else {
        plain
    }
}
