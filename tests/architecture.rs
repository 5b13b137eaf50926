//! The layering of docs/architecture.md, checked on the source text: each layer imports only
//! the layers below it; no two files import each other; no source file is over 700 lines;
//! the library reads no environment variable, uses no anyhow and never prints (CLI only);
//! the CLI and the Python binding reach the library through its application layer only.

use std::path::{Path, PathBuf};

/// The layers, lowest first. `math`, `error` and `fsutil` are shared utilities below all.
const LAYERS: &[&str] =
    &["params", "model", "sim", "eval", "export", "optim", "record", "run", "sweep", "bench", "app", "cli"];
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

/// Files of the library allowed to print, each with its reason: none. What a user sees of the
/// library's work (a run's progress, a benchmark's bars, warnings, a trace) reaches the
/// caller through a callback, a sink or a writer it is given; printing and progress bars are
/// the CLI's (src/main.rs, src/cli/).
const MAY_PRINT: &[(&str, &str)] = &[];

/// The library never prints and draws no progress bar: no `println!`, `eprintln!`, `print!`,
/// `eprint!`, `dbg!`, no write to the process's stdout or stderr, no indicatif outside
/// src/main.rs and src/cli/.
#[test]
fn the_library_never_prints() {
    let mut files = Vec::new();
    rs_files(&src(), &mut files);
    let mut bad = Vec::new();
    let cli = |f: &PathBuf| f.starts_with(src().join("cli")) || *f == src().join("main.rs");
    let excepted = |f: &PathBuf| MAY_PRINT.iter().any(|(p, _)| *f == src().join(p));
    for f in files.iter().filter(|f| !cli(f) && !excepted(f)) {
        let c = code(f);
        for what in ["println!", "eprintln!", "print!", "eprint!", "dbg!", "io::stdout", "io::stderr", "indicatif"] {
            if c.contains(what) {
                bad.push(format!("{} uses {what}", f.display()));
            }
        }
    }
    assert!(bad.is_empty(), "the library prints (give the caller a callback, a sink or a writer):\n{}", bad.join("\n"));
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

/// A token of Rust source, as far as paths need: a word, `::`, a brace, a comma, or any
/// other character (string and char literals and comments are skipped).
#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Word(String),
    Sep,
    Open,
    Close,
    Comma,
    Other(char),
}

fn tokens(code: &str) -> Vec<Tok> {
    let c: Vec<char> = code.chars().collect();
    let (mut out, mut i) = (Vec::new(), 0);
    let skip_string = |mut i: usize, hashes: usize| {
        // `i` is just past the opening quote; returns the index past the closing one
        while i < c.len() {
            if hashes == 0 && c[i] == '\\' {
                i += 2;
                continue;
            }
            if c[i] == '"' && c[i + 1..].iter().take(hashes).filter(|&&h| h == '#').count() == hashes {
                return i + 1 + hashes;
            }
            i += 1;
        }
        i
    };
    while i < c.len() {
        let ch = c[i];
        if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && c.get(i + 1) == Some(&'/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && c.get(i + 1) == Some(&'*') {
            i += 2;
            while i + 1 < c.len() && !(c[i] == '*' && c[i + 1] == '/') {
                i += 1;
            }
            i += 2;
        } else if ch == '"' {
            i = skip_string(i + 1, 0);
        } else if ch == 'r' && (c.get(i + 1) == Some(&'"') || c.get(i + 1) == Some(&'#')) && !out_word_continues(&c, i)
        {
            let hashes = c[i + 1..].iter().take_while(|&&h| h == '#').count();
            if c.get(i + 1 + hashes) == Some(&'"') {
                i = skip_string(i + 2 + hashes, hashes);
            } else {
                out.push(Tok::Word("r".into()));
                i += 1;
            }
        } else if ch == '\'' {
            // a char literal ('x', '\n', '\u{..}') or a lifetime ('a)
            if c.get(i + 1) == Some(&'\\') {
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                i += 1;
            }
        } else if ch.is_alphanumeric() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push(Tok::Word(c[start..i].iter().collect()));
        } else if ch == ':' && c.get(i + 1) == Some(&':') {
            out.push(Tok::Sep);
            i += 2;
        } else {
            out.push(match ch {
                '{' => Tok::Open,
                '}' => Tok::Close,
                ',' => Tok::Comma,
                _ => Tok::Other(ch),
            });
            i += 1;
        }
    }
    out
}

/// Whether the character before `i` continues a word (the `r` of `for"` is no raw string).
fn out_word_continues(c: &[char], i: usize) -> bool {
    i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_')
}

/// One path of a `use` tree or an expression, `{a, b::c}` groups expanded; with the name it
/// binds (`as` alias or last segment).
#[derive(Debug, Clone)]
struct UsePath {
    segs: Vec<String>,
    name: String,
}

/// The paths starting at token `i` (`a::b::{c, d::e as f}`), and the index after them.
fn parse_path(t: &[Tok], mut i: usize) -> (Vec<UsePath>, usize) {
    let mut segs: Vec<String> = Vec::new();
    let mut out = Vec::new();
    loop {
        match t.get(i) {
            Some(Tok::Word(w)) => {
                segs.push(w.clone());
                i += 1;
            }
            Some(Tok::Other('*')) => {
                segs.push("*".into());
                i += 1;
                break;
            }
            Some(Tok::Open) => {
                i += 1;
                loop {
                    let (sub, j) = parse_path(t, i);
                    i = j;
                    for s in sub {
                        let segs = segs.iter().cloned().chain(s.segs).collect();
                        out.push(UsePath { segs, name: s.name });
                    }
                    match t.get(i) {
                        Some(Tok::Comma) => i += 1,
                        Some(Tok::Close) => {
                            i += 1;
                            break;
                        }
                        _ => break,
                    }
                    if t.get(i) == Some(&Tok::Close) {
                        i += 1;
                        break;
                    }
                }
                return (out, i);
            }
            _ => break,
        }
        if t.get(i) == Some(&Tok::Sep) {
            i += 1;
        } else {
            break;
        }
    }
    let mut name = segs.last().cloned().unwrap_or_default();
    if name == "self" && segs.len() > 1 {
        name = segs[segs.len() - 2].clone();
    }
    if let (Some(Tok::Word(a)), Some(Tok::Word(alias))) = (t.get(i), t.get(i + 1)) {
        if a == "as" {
            name = alias.clone();
            i += 2;
        }
    }
    if !segs.is_empty() {
        out.push(UsePath { segs, name });
    }
    (out, i)
}

/// What one source file says about paths: the modules it declares (`mod x;`), the paths of
/// its `use` declarations (which also name what it re-exports) and every other path in its
/// code that starts at the crate, `super`, `self` or one of its own modules.
#[derive(Default)]
struct FileRefs {
    children: Vec<String>,
    uses: Vec<UsePath>,
    /// Paths of `pub use` declarations: a module's face, not a use of the module it names.
    reexports: Vec<UsePath>,
    other: Vec<UsePath>,
}

fn file_refs(code: &str) -> FileRefs {
    let t = tokens(code);
    let mut r = FileRefs::default();
    for i in 0..t.len() {
        if let (Some(Tok::Word(m)), Some(Tok::Word(name)), Some(Tok::Other(';'))) =
            (t.get(i), t.get(i + 1), t.get(i + 2))
        {
            if m == "mod" {
                r.children.push(name.clone());
            }
        }
    }
    let children = r.children.clone();
    let starts = |w: &str| matches!(w, "crate" | "super" | "self") || children.iter().any(|c| c == w);
    let mut i = 0;
    while i < t.len() {
        let after_sep = i > 0 && (t[i - 1] == Tok::Sep || t[i - 1] == Tok::Other('.'));
        match &t[i] {
            Tok::Word(w) if w == "use" => {
                let public = i > 0 && (t[i - 1] == Tok::Word("pub".into()) || t[i - 1] == Tok::Other(')'));
                let (paths, j) = parse_path(&t, i + 1);
                for p in paths.into_iter().filter(|p| starts(&p.segs[0])) {
                    r.uses.push(p.clone());
                    if public {
                        r.reexports.push(p);
                    }
                }
                i = j.max(i + 1);
            }
            Tok::Word(w) if !after_sep && t.get(i + 1) == Some(&Tok::Sep) && starts(w) => {
                let (paths, j) = parse_path(&t, i);
                r.other.extend(paths);
                i = j.max(i + 1);
            }
            _ => i += 1,
        }
    }
    r
}

/// The source tree as modules, for resolving paths to the file that defines what they name.
struct Tree {
    refs: std::collections::HashMap<Vec<String>, FileRefs>,
}

impl Tree {
    fn new(files: &[(Vec<String>, String)]) -> Self {
        Tree { refs: files.iter().map(|(m, c)| (m.clone(), file_refs(c))).collect() }
    }

    /// The file module that defines what `p`, written in module `me`, names: its modules
    /// followed as far as they go, then a name resolved through the `use` declarations of the
    /// module it is in (a `pub use` list of a mod.rs leads to the defining file).
    fn resolve(&self, me: &[String], p: &UsePath, depth: usize) -> Option<Vec<String>> {
        let mut segs = p.segs.iter().map(String::as_str).peekable();
        let mut base: Vec<String> = match segs.peek() {
            Some(&"crate") => {
                segs.next();
                vec![]
            }
            Some(&"self") => {
                segs.next();
                me.to_vec()
            }
            Some(&"super") => me.to_vec(),
            _ => me.to_vec(), // one of `me`'s own modules
        };
        for s in segs {
            match s {
                "super" => {
                    base.pop();
                }
                "self" | "*" => {}
                _ => {
                    let mut child = base.clone();
                    child.push(s.to_string());
                    if self.refs.contains_key(&child) {
                        base = child;
                    } else {
                        return Some(self.item(&base, s, depth).unwrap_or(base));
                    }
                }
            }
        }
        self.refs.contains_key(&base).then_some(base)
    }

    /// The file that defines item `name` seen in module `m` through one of its `use`s.
    fn item(&self, m: &[String], name: &str, depth: usize) -> Option<Vec<String>> {
        let u = self.refs.get(m)?.uses.iter().find(|u| u.name == name)?;
        if depth > 8 {
            return None;
        }
        self.resolve(m, u, depth + 1)
    }

    /// Every (importer, imported file) pair: paths in code and private `use`s, not re-exports
    /// (a mod.rs's own use of a name it re-exports is not seen: a bare name is not a path).
    fn edges(&self) -> std::collections::BTreeSet<(Vec<String>, Vec<String>)> {
        let mut edges = std::collections::BTreeSet::new();
        for (me, r) in &self.refs {
            let face_only = |u: &UsePath| r.reexports.iter().any(|x| x.segs == u.segs);
            let used = r.uses.iter().filter(|u| !face_only(u)).chain(&r.other);
            for p in used {
                if let Some(t) = self.resolve(me, p, 0).filter(|t| t != me) {
                    edges.insert((me.clone(), t));
                }
            }
        }
        edges
    }

    /// The pairs of files that import each other, as `a <-> b` (a before b).
    fn circles(&self) -> Vec<String> {
        let edges = self.edges();
        edges
            .iter()
            .filter(|(a, b)| a < b && edges.contains(&(b.clone(), a.clone())))
            .map(|(a, b)| format!("{} <-> {}", a.join("::"), b.join("::")))
            .collect()
    }
}

/// No two source files import each other (`use super::x`, `crate::a::b`, a module's own
/// `x::…`, a name re-exported by a mod.rs — all resolved to the file that defines what they
/// name): a lower module owns what both need.
#[test]
fn no_two_files_import_each_other() {
    let mut files = Vec::new();
    rs_files(&src(), &mut files);
    let tree = Tree::new(&files.iter().map(|f| (module_of(f), code(f))).collect::<Vec<_>>());
    let circles = tree.circles();
    assert!(circles.is_empty(), "files that import each other:\n{}", circles.join("\n"));
}

/// The circle finder sees each way a file can name another: a name re-exported by the parent
/// (`super::Problem` is load.rs's), a mod.rs's path with no prefix (`out::f`), `use` groups
/// (`super::{a::X, b::Y}`), `crate::` paths, and none in strings, comments or re-exports.
#[test]
fn the_circle_finder_sees_every_kind_of_path() {
    let m = |s: &str| s.split("::").filter(|x| !x.is_empty()).map(String::from).collect::<Vec<_>>();
    let files = [
        (m(""), "pub mod p; pub mod q;".to_string()),
        (m("p"), "mod load; mod robust; mod a; mod b; mod c; pub use load::Problem; pub use robust::Robust;".into()),
        (m("p::load"), "use super::robust::Robust; pub struct Problem;".into()),
        (m("p::robust"), "impl super::Problem { fn f() {} } pub struct Robust;".into()),
        (m("p::a"), "use super::{b::B, c::C}; pub struct A;".into()),
        (m("p::b"), "pub struct B; fn f() -> crate::p::a::A { todo!() }".into()),
        (m("p::c"), "pub struct C; // super::a::A\nconst S: &str = \"super::a::A\";".into()),
        (m("q"), "mod out; mod spec; pub use out::write; fn g() { out::check() }".into()),
        (m("q::out"), "pub fn check() { super::g() } pub fn write() {}".into()),
        (m("q::spec"), "pub fn h() { super::write() }".into()),
    ];
    let tree = Tree::new(&files);
    assert_eq!(tree.circles(), ["p::a <-> p::b", "p::load <-> p::robust", "q <-> q::out"]);
    assert!(tree.edges().contains(&(m("q::spec"), m("q::out"))), "a re-exported name leads to its file");
    assert!(!tree.edges().contains(&(m("p::c"), m("p::a"))), "no path in a comment or string");
}

/// The layers inside the library: what a front end (the CLI, the Python binding) reaches only
/// through the application layer (`gripopt::app::…`) or the crate root's re-exports of it.
const INNER: &[&str] =
    &["params", "model", "sim", "eval", "export", "optim", "record", "run", "sweep", "bench", "math"];

/// Paths a front end may name inside the layers, each with why (docs/architecture.md, "The
/// application layer"): none.
const FRONT_END_EXCEPTIONS: &[(&str, &str)] = &[];

/// The paths `gripopt::…` a front end's file names (in `use` lists and in code, groups
/// expanded), strings and comments aside.
fn gripopt_paths(code: &str) -> Vec<Vec<String>> {
    let t = tokens(code);
    let mut out = vec![];
    let mut i = 0;
    while i < t.len() {
        let after_sep = i > 0 && (t[i - 1] == Tok::Sep || t[i - 1] == Tok::Other('.'));
        match &t[i] {
            Tok::Word(w) if w == "gripopt" && !after_sep && t.get(i + 1) == Some(&Tok::Sep) => {
                let (paths, j) = parse_path(&t, i);
                out.extend(paths.into_iter().map(|p| p.segs));
                i = j.max(i + 1);
            }
            _ => i += 1,
        }
    }
    out
}

/// The CLI (src/cli, src/main.rs) and the Python binding (crates/gripopt-py/src) name no path
/// inside the layers: `gripopt::app::…` and the crate root's items only (issue 39 item 3:
/// they parse and render, convert and own the GIL; the library decides).
#[test]
fn front_ends_reach_only_the_application_layer() {
    let mut files = Vec::new();
    rs_files(&src().join("cli"), &mut files);
    files.push(src().join("main.rs"));
    rs_files(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/crates/gripopt-py/src")), &mut files);
    let mut bad = vec![];
    for f in &files {
        for p in gripopt_paths(&code(f)) {
            let Some(layer) = p.get(1) else { continue };
            let path = p.join("::");
            if INNER.contains(&layer.as_str()) && !FRONT_END_EXCEPTIONS.iter().any(|(e, _)| path.starts_with(e)) {
                bad.push(format!("{}: {path}", f.display()));
            }
        }
    }
    assert!(bad.is_empty(), "front ends naming paths inside the layers (use gripopt::app):\n{}", bad.join("\n"));
    // the finder sees groups, nested paths and code paths, not strings or comments
    let seen =
        gripopt_paths("use gripopt::{app::X, run::Y};\nfn f() { gripopt::eval::g(); let s = \"gripopt::sim::Z\"; }");
    let seen: Vec<String> = seen.iter().map(|p| p.join("::")).collect();
    assert_eq!(seen, ["gripopt::app::X", "gripopt::run::Y", "gripopt::eval::g"]);
}
