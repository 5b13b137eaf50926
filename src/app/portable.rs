//! A problem as text that makes the same problem wherever and whenever it is read (a pickle,
//! a Dask worker): a robust object given by `file = "…"` written inline, its cylinder as
//! loaded, so the object files are not read again (they may be elsewhere, or edited since).

use crate::error::{Error, Result};
use crate::params::Problem;
use std::path::Path;

/// The object tables of `[[robust.objects]]` in a problem's TOML (parsed as written).
fn object_tables(doc: &mut toml::Table) -> Option<&mut Vec<toml::Value>> {
    doc.get_mut("robust")?.as_table_mut()?.get_mut("objects")?.as_array_mut()
}

/// `text` parsed as a TOML table (it parsed when the problem was loaded).
fn toml_table(text: &str) -> Result<toml::Table> {
    text.parse::<toml::Table>().map_err(|e| Error::Input(format!("problem text: {e}")))
}

/// The problem's text with each robust object given by `file = "…"` written inline, its
/// cylinder as loaded (None: no object is given by a file, the text is portable as it is).
pub fn inlined_text(problem: &Problem) -> Result<Option<String>> {
    let Some(robust) = &problem.robust else { return Ok(None) };
    if robust.objects.iter().all(|o| o.file.is_none()) {
        return Ok(None);
    }
    let mut doc = toml_table(&problem.source_text)?;
    let tables = object_tables(&mut doc).ok_or_else(|| Error::Input("problem text: no [[robust.objects]]".into()))?;
    for (case, t) in robust.objects.iter().zip(tables.iter_mut()) {
        let Some(t) = t.as_table_mut().filter(|_| case.file.is_some()) else { continue };
        t.remove("file");
        let o = &case.object;
        for (key, v) in
            [("radius", o.radius), ("length", o.length), ("density", o.density), ("grasp_height", o.grasp_height)]
        {
            t.insert(key.into(), toml::Value::Float(v));
        }
    }
    toml::to_string(&doc).map(Some).map_err(|e| Error::Input(format!("problem text: {e}")))
}

/// The problem of [`inlined_text`]'s `inlined`, with `text` (the problem's own) as its text
/// and each object's `file` as `text` names it: the object files are not read. `shown`: what
/// errors name.
pub fn from_inlined(text: &str, inlined: &str, shown: &Path) -> Result<Problem> {
    let mut problem = Problem::from_toml_str(inlined, shown)?;
    let mut doc = toml_table(text)?;
    if let (Some(robust), Some(tables)) = (problem.robust.as_mut(), object_tables(&mut doc)) {
        for (case, t) in robust.objects.iter_mut().zip(tables.iter()) {
            case.file = t.get("file").and_then(|f| f.as_str()).map(String::from);
        }
    }
    problem.source_text = text.to_string();
    Ok(problem)
}
