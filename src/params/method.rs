//! The integration method of the grasp simulation, chosen by a problem file's
//! `[solver] method` (and `gripopt simulate --method`). Owned here, below the simulator, so
//! that a problem can name it; the simulator re-exports it (`gripopt::sim::Method`).

use serde::{Deserialize, Serialize};

/// Integration method. A problem without `solver.method` runs [`Method::PROBLEM_DEFAULT`]
/// (auto, since session 38); the `Default` of the type is RADAU5, what a checkpoint, record
/// or serialised problem that names no method was run with (the default before session 38).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Radau IIA order 5 (stiff, L-stable, stiffly accurate; the default before session 38).
    #[default]
    Radau5,
    /// TR-BDF2 (stiff, L-stable, order 2; the thesis' method).
    TrBdf2,
    /// Dormand–Prince 5(4) (explicit; for comparison only).
    Dopri5,
    /// Dormand–Prince 5(4) where its steps are held by accuracy, RADAU5 where they would be
    /// held by stability (automatic stiffness switching).
    Auto,
}

impl Method {
    /// The method of a problem without `solver.method`: the stiffness-switching method
    /// (docs/benchmarks.md, "The default solver"; the simulator reads its tolerances with
    /// the default's scaling, `sim::Scaling::DEFAULT`).
    pub const PROBLEM_DEFAULT: Method = Method::Auto;

    /// Every method, in the order the docs and errors list them.
    pub const ALL: [Method; 4] = [Method::Radau5, Method::Auto, Method::TrBdf2, Method::Dopri5];

    /// The method's first step size (s): the implicit methods start at 10 µs, the explicit
    /// one at 1 µs (a stiff contact would reject a longer first step several times).
    pub fn first_step(self) -> f64 {
        match self {
            Method::Radau5 | Method::TrBdf2 => 1e-5,
            Method::Dopri5 | Method::Auto => 1e-6,
        }
    }
    /// The spelling in problem files, on the command line and in JSON (`radau5`, `trbdf2`,
    /// `dopri5`, `auto`).
    pub fn as_str(self) -> &'static str {
        match self {
            Method::Radau5 => "radau5",
            Method::TrBdf2 => "trbdf2",
            Method::Dopri5 => "dopri5",
            Method::Auto => "auto",
        }
    }
    /// Other accepted spellings of a method (as `gripopt simulate --method` takes them):
    /// `tr-bdf2` for `trbdf2`.
    pub const ALIASES: [(&'static str, Method); 1] = [("tr-bdf2", Method::TrBdf2)];

    /// The method spelled `s` ([`Method::as_str`] or one of [`Method::ALIASES`]), or None.
    pub fn parse(s: &str) -> Option<Method> {
        Method::ALL
            .into_iter()
            .find(|m| m.as_str() == s)
            .or_else(|| Method::ALIASES.iter().find(|a| a.0 == s).map(|a| a.1))
    }
    /// The accepted spellings as a sentence: `"radau5", "auto", "trbdf2" (or "tr-bdf2") or
    /// "dopri5"`.
    pub fn accepted() -> String {
        let q: Vec<String> = Method::ALL
            .iter()
            .map(|m| {
                let aliases: Vec<String> =
                    Method::ALIASES.iter().filter(|a| a.1 == *m).map(|a| format!("{:?}", a.0)).collect();
                if aliases.is_empty() {
                    format!("{:?}", m.as_str())
                } else {
                    format!("{:?} (or {})", m.as_str(), aliases.join(", "))
                }
            })
            .collect();
        format!("{} or {}", q[..q.len() - 1].join(", "), q[q.len() - 1])
    }
    /// The least absolute tolerance the method takes: 1e-11 for TR-BDF2, whose order-2 error
    /// estimate meets rounding below it (hostile pass 34: at 1e-13 the offset scene took
    /// millions of steps, at 1e-15 its steps collapsed at t = 0, at 3e-12 `offset:0.003`
    /// spent the default step budget; at 1e-11 every scene takes 3–6 k steps); `solver.atol`'s
    /// own floor, 1e-15, for the others.
    pub fn min_atol(self) -> f64 {
        match self {
            Method::TrBdf2 => 1e-11,
            Method::Radau5 | Method::Dopri5 | Method::Auto => 1e-15,
        }
    }
    /// `Err(rule)` where `atol` lies below [`Method::min_atol`].
    pub fn check_atol(self, atol: f64) -> Result<(), String> {
        if atol >= self.min_atol() {
            return Ok(());
        }
        Err(format!(
            "must be >= {:e} with method \"{}\" (its error estimate meets rounding below it)",
            self.min_atol(),
            self.as_str()
        ))
    }
    /// Whether this is RADAU5, the type's default: what a checkpoint's options, a record or a
    /// serialised problem that names no method ran with (a problem file without
    /// `solver.method` got it before session 38; such a record or checkpoint is written as
    /// before the key existed).
    pub fn is_default(&self) -> bool {
        *self == Method::Radau5
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_spelling_parses_and_the_sentence_lists_them() {
        for m in Method::ALL {
            assert_eq!(Method::parse(m.as_str()), Some(m));
        }
        assert_eq!(Method::parse("tr-bdf2"), Some(Method::TrBdf2));
        assert_eq!(Method::parse("euler"), None);
        assert_eq!(Method::parse("TRBDF2"), None, "spellings are lower case, as on the command line");
        assert_eq!(Method::accepted(), r#""radau5", "auto", "trbdf2" (or "tr-bdf2") or "dopri5""#);
    }

    #[test]
    fn only_tr_bdf2_refuses_an_atol_above_the_file_floor() {
        assert!(Method::TrBdf2.check_atol(1e-11).is_ok());
        let rule = Method::TrBdf2.check_atol(3e-12).unwrap_err();
        assert!(rule.contains(">= 1e-11") && rule.contains("trbdf2"), "{rule}");
        for m in [Method::Radau5, Method::Dopri5, Method::Auto] {
            assert!(m.check_atol(1e-15).is_ok(), "{m}");
        }
    }
}
