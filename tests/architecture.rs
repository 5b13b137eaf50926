//! The layering of docs/architecture.md, checked on the source text: each layer imports only
//! the layers below it; no source file is over 700 lines; the library reads no
//! environment variable and uses no anyhow (CLI only).

use std::path::{Path, PathBuf};

/// The layers, lowest first. `math`, `error` and `fsutil` are shared utilities below all.
const LAYERS: &[&str] =
    &["params", "model", "sim", "eval", "export", "optim", "record", "run", "sweep", "bench", "cli"];
/// Layers that sit side by side and must not import each other (same rank).
const PEERS: &[(&str, &str)] =
    &[("sweep", "run"), ("sweep", "record"), ("sweep", "optim"), ("sweep", "bench"), ("bench", "sweep")];

fn rs_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            rs_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

fn src() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/src"))
}

/// The code of a file without its `#[cfg(test)]` module and comments.
fn code(p: &Path) -> String {
    let text = std::fs::read_to_string(p).unwrap();
    let text = text.split("#[cfg(test)]").next().unwrap_or("");
    text.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n")
}

#[test]
fn layers_only_point_down() {
    let mut violations = Vec::new();
    for (rank, layer) in LAYERS.iter().enumerate() {
        let mut files = Vec::new();
        rs_files(&src().join(layer), &mut files);
        let single = src().join(format!("{layer}.rs"));
        if single.exists() {
            files.push(single);
        }
        for f in files {
            let c = code(&f);
            let above = LAYERS[rank + 1..].iter().copied();
            let peers = PEERS.iter().filter(|(a, _)| a == layer).map(|(_, b)| *b);
            for higher in above.chain(peers) {
                for pat in [format!("crate::{higher}::"), format!("crate::{higher}}}"), format!("crate::{higher};")] {
                    if c.contains(&pat) {
                        violations.push(format!("{} imports `{higher}` (above `{layer}`)", f.display()));
                    }
                }
            }
        }
    }
    assert!(violations.is_empty(), "layering violations:\n{}", violations.join("\n"));
}

#[test]
fn no_source_file_over_700_lines() {
    let mut files = Vec::new();
    rs_files(&src(), &mut files);
    rs_files(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests")), &mut files);
    rs_files(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/benches")), &mut files);
    let long: Vec<_> = files
        .iter()
        .map(|f| (f, std::fs::read_to_string(f).unwrap().lines().count()))
        .filter(|(_, n)| *n > 700)
        .map(|(f, n)| format!("{}: {n} lines", f.display()))
        .collect();
    assert!(long.is_empty(), "{}", long.join("\n"));
}

#[test]
fn the_library_reads_no_environment_and_uses_no_anyhow() {
    let mut files = Vec::new();
    rs_files(&src(), &mut files);
    let mut bad = Vec::new();
    for f in files.iter().filter(|f| !f.starts_with(src().join("cli")) && !f.ends_with("main.rs")) {
        let c = code(f);
        if c.contains("env::var") {
            bad.push(format!("{} reads an environment variable", f.display()));
        }
        if c.contains("anyhow") {
            bad.push(format!("{} uses anyhow", f.display()));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// The module path of a source file (`src/sim/scene/mod.rs` → sim::scene).
fn module_of(p: &Path) -> Vec<String> {
    let rel = p.strip_prefix(src()).unwrap().with_extension("");
    let mut m: Vec<String> = rel.iter().map(|c| c.to_string_lossy().to_string()).collect();
    if m.last().is_some_and(|l| l == "mod" || l == "lib") {
        m.pop();
    }
    m
}

/// No two source files import each other (`use super::x` / `crate::a::b` both ways): a
/// lower module owns what both need.
#[test]
fn no_two_files_import_each_other() {
    let mut files = Vec::new();
    rs_files(&src(), &mut files);
    let modules: std::collections::HashMap<Vec<String>, &PathBuf> = files.iter().map(|f| (module_of(f), f)).collect();
    let mut edges = std::collections::HashSet::new();
    for f in &files {
        let me = module_of(f);
        let c = code(f);
        let bytes: Vec<char> = c.chars().collect();
        // every path `crate::…` or `super::…` (with `{a, b}` groups), as segments
        let text: String = bytes.iter().collect();
        for (start, _) in text.match_indices("crate::").chain(text.match_indices("super::")) {
            let rest = &text[start..];
            let path: String = rest.chars().take_while(|ch| ch.is_alphanumeric() || *ch == '_' || *ch == ':').collect();
            let mut segs: Vec<&str> = path.split("::").filter(|s| !s.is_empty()).collect();
            let mut base: Vec<String> =
                if segs.first() == Some(&"crate") { vec![] } else { me[..me.len().saturating_sub(1)].to_vec() };
            segs.remove(0);
            while segs.first() == Some(&"super") {
                base.pop();
                segs.remove(0);
            }
            let mut target = modules.contains_key(&base).then(|| base.clone());
            for s in segs {
                base.push(s.to_string());
                if modules.contains_key(&base) {
                    target = Some(base.clone());
                }
            }
            if let Some(t) = target.filter(|t| *t != me) {
                edges.insert((me.clone(), t));
            }
        }
    }
    let circles: Vec<String> = edges
        .iter()
        .filter(|(a, b)| a < b && edges.contains(&(b.clone(), a.clone())))
        .map(|(a, b)| format!("{} <-> {}", a.join("::"), b.join("::")))
        .collect();
    assert!(circles.is_empty(), "files that import each other:\n{}", circles.join("\n"));
}
