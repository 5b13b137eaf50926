//! A problem file's field checked against its limit, an error naming the file and the field
//! (shared by the loader and the `[robust]` section's checks).

use super::limits::{limit, num};
use crate::error::{Error, Result};
use std::path::Path;

/// Checks fields of the problem file `file`.
pub(super) struct Checker<'a> {
    pub(super) file: &'a Path,
}

impl Checker<'_> {
    /// `v` if it is within `field`'s limit, else an error naming the file and the field.
    pub(super) fn check(&self, field: &str, v: f64) -> Result<f64> {
        limit(field).check(v).map_err(|rule| Error::InvalidField {
            file: self.file.to_path_buf(),
            field: field.to_string(),
            value: num(v),
            rule,
        })
    }
    /// `v` checked as [`Checker::check`] does, and as a whole number (a count written `16`,
    /// `16.0` or `1.6e1`).
    pub(super) fn whole(&self, field: &str, v: f64) -> Result<f64> {
        let n = self.check(field, v)?;
        if n.fract() != 0.0 {
            return Err(self.fail(field, num(n), "must be a whole number"));
        }
        Ok(n)
    }
    /// The error for `field` holding `value` against `rule`.
    pub(super) fn fail(&self, field: &str, value: String, rule: &str) -> Error {
        Error::InvalidField { file: self.file.to_path_buf(), field: field.into(), value, rule: rule.into() }
    }
}

/// The rule for a hand plane lower than the fingers' half-thickness `w` (the [object]'s and
/// each robust object's `grasp_height`).
pub(super) fn below_finger_rule(w: f64) -> String {
    format!("must be at least hand.w ({w}): the fingers, capsules of radius hand.w in the hand plane, would cut the floor the object stands on")
}
