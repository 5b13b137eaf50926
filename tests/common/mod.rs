//! Shared helpers for the integration tests.
#![allow(dead_code)]

use gripopt::params::{Design, Problem, SceneParams};

/// The default problem, loaded from the repository file.
pub fn bottle() -> Problem {
    Problem::load(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).expect("bottle-1l.toml loads")
}

/// The nominal scene.
pub fn scene() -> SceneParams {
    bottle().scene
}

/// The nominal design.
pub fn nominal() -> Design {
    Design::nominal()
}

/// Assert |a − b| ≤ rel·|b| with a message.
#[track_caller]
pub fn close_rel(a: f64, b: f64, rel: f64, what: &str) {
    assert!(
        (a - b).abs() <= rel * b.abs(),
        "{what}: got {a:.15e}, expected {b:.15e} (rel {:.2e})",
        (a - b).abs() / b.abs()
    );
}

/// Assert |a − b| ≤ abs.
#[track_caller]
pub fn close_abs(a: f64, b: f64, abs: f64, what: &str) {
    assert!((a - b).abs() <= abs, "{what}: got {a:.15e}, expected {b:.15e} (diff {:.2e})", (a - b).abs());
}

/// A design drawn uniformly in the default box of bottle-1l.toml.
pub fn random_design<R: rand::Rng>(rng: &mut R) -> Design {
    bottle().bounds.sample(rng)
}

/// A tiny recorded run of `problem` (seed 16, one thread; on bottle-1l pop 8 × 2 generations
/// has 4 designs on its front) in `target/mcap-check/NAME` (or `$GRIPOPT_MCAP_CHECK_DIR`),
/// so that `make test` checks its recording with the independent reader.
pub fn tiny_run(name: &str, problem: &std::path::Path, pop: usize, generations: u64) -> std::path::PathBuf {
    tiny_run_in(check_dir(name), problem, pop, generations)
}

/// [`tiny_run`] written to the folder `d` (which must not hold a run).
pub fn tiny_run_in(
    d: std::path::PathBuf,
    problem: &std::path::Path,
    pop: usize,
    generations: u64,
) -> std::path::PathBuf {
    let spec = gripopt::run::RunSpec {
        problem_path: problem.to_path_buf(),
        out: d.clone(),
        pop,
        generations,
        seed: 16,
        threads: Some(1),
        record: gripopt::record::RecordOptions::default(),
    };
    gripopt::run::optimise(&spec).unwrap();
    d
}

/// The default problem file, bottle-1l.
pub const BOTTLE_FILE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml");

/// The robust kitchen problem file (four objects, the free scene).
pub const KITCHEN_FILE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml");

/// The centred grasp of finger `f` (statics `st`) with `integ` under the controls `ctl`,
/// and its trajectory (through the library's one simulation call).
pub fn grasp_traj(
    f: &gripopt::model::Finger,
    s: &SceneParams,
    st: &gripopt::eval::StaticsResult,
    integ: &gripopt::sim::Integration,
    ctl: &gripopt::sim::Controls,
) -> (gripopt::sim::DynamicsResult, gripopt::sim::Trajectory) {
    let mut tr = gripopt::sim::Trajectory::default();
    let r = gripopt::sim::simulate(f, s, st, &gripopt::sim::SceneSpec::Centred, integ, ctl, &mut tr);
    (*r.grasp().expect("a grasp"), tr)
}

/// `optimise` with a progress observer that fails at generation `k`, as a crash would (a
/// failing observer stops the run; the checkpoint of generation `k` is kept): how tests
/// crash a run without a hook in the library's types.
pub fn optimise_crashing_after(spec: &gripopt::run::RunSpec, k: u64) -> gripopt::Result<gripopt::run::RunSummary> {
    struct Crash(u64);
    impl gripopt::run::Progress for Crash {
        fn generation(&mut self, g: &gripopt::run::GenerationReport) -> Result<(), String> {
            if g.generation >= self.0 {
                return Err(format!("simulated crash after generation {}", g.generation));
            }
            Ok(())
        }
    }
    let hooks = gripopt::run::RunHooks { progress: Some(Box::new(Crash(k))), ..Default::default() };
    gripopt::run::optimise_with(spec, hooks)
}

/// A fresh, empty folder `target/tests/FILE/NAME` for a test's files (removed first if left
/// over), FILE the stem of the test file that asks for it (`replay` for tests/replay.rs): the
/// one scratch-folder helper of the tests. Each folder is handed out once per test binary, so
/// that tests running in parallel never share one: a second request for the same folder
/// panics (give the test its own NAME).
#[track_caller]
pub fn scratch(name: &str) -> std::path::PathBuf {
    use std::sync::Mutex;
    static HANDED_OUT: Mutex<Vec<std::path::PathBuf>> = Mutex::new(Vec::new());
    let file = std::path::Path::new(std::panic::Location::caller().file());
    let area = file.file_stem().and_then(|s| s.to_str()).expect("a test file's name");
    let d = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/tests")).join(area).join(name);
    {
        let mut given = HANDED_OUT.lock().unwrap_or_else(|e| e.into_inner());
        assert!(!given.contains(&d), "scratch folder {} requested twice: give each test its own name", d.display());
        given.push(d.clone());
    }
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A fresh folder `name` under `target/mcap-check` (or `$GRIPOPT_MCAP_CHECK_DIR`), whose
/// MCAP files `make test` checks with the independent reader.
pub fn check_dir(name: &str) -> std::path::PathBuf {
    use std::path::PathBuf;
    let base = std::env::var_os("GRIPOPT_MCAP_CHECK_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/mcap-check")));
    let d = base.join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&base).unwrap();
    d
}

/// A run of bottle-1l into `out`: population 12, every design recorded.
pub fn bottle_spec(out: &std::path::Path, generations: u64, seed: u64, threads: usize) -> gripopt::run::RunSpec {
    gripopt::run::RunSpec {
        problem_path: BOTTLE_FILE.into(),
        out: out.to_path_buf(),
        pop: 12,
        generations,
        seed,
        threads: Some(threads),
        record: gripopt::record::RecordOptions::default(),
    }
}

/// The gripopt binary that cargo built for the tests.
pub const GRIPOPT_BIN: &str = env!("CARGO_BIN_EXE_gripopt");

/// Run the gripopt binary with `args` and wait for its output.
pub fn run_gripopt(args: &[&str]) -> std::process::Output {
    std::process::Command::new(GRIPOPT_BIN).args(args).output().unwrap()
}

/// A command's stdout followed by its stderr, as text.
pub fn output_text(o: &std::process::Output) -> String {
    format!("{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr))
}

/// A copy of folder `from` at `to` (as `cp -a`; `to` replaced).
pub fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
    let _ = std::fs::remove_dir_all(to);
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let (p, q) = (e.path(), to.join(e.file_name()));
        if p.is_dir() {
            copy_dir(&p, &q);
        } else {
            std::fs::copy(&p, &q).unwrap();
        }
    }
}

/// Every file under `dir` (but the lock's pid file) with its bytes.
pub fn folder_bytes(dir: &std::path::Path) -> std::collections::BTreeMap<std::path::PathBuf, Vec<u8>> {
    let mut m = std::collections::BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            m.extend(folder_bytes(&p));
        } else if e.file_name() != ".lock" {
            m.insert(p.clone(), std::fs::read(&p).unwrap());
        }
    }
    m
}

/// A command's stdout as one JSON object (the panic shows its output when it is not).
pub fn json_stdout(o: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", output_text(o)))
}

/// A JSON value without its CPU times (`cpu_s` at any depth: the only values that differ
/// between two runs of the same evaluation).
pub fn untimed(mut v: serde_json::Value) -> serde_json::Value {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.remove("cpu_s");
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    strip(&mut v);
    v
}

/// A design (found by searching the box, seed 3) whose finger, closing on nothing, drives the
/// five-bar into its parallel singularity (MODEL.md §13 item 1).
pub fn singular_closing_design() -> Design {
    Design::from_array(&[
        0.04549204603835802,
        0.05890255558786177,
        0.0307206768455294,
        0.6474382809963541,
        0.6134575256373511,
        126.19868905695499,
    ])
}

/// bottle-1l with `[scene] kind = "offset"`, x_off = 2 mm, in `dir`.
pub fn offset_problem(dir: &std::path::Path) -> std::path::PathBuf {
    let src = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    let src = src.replacen("kind = \"centred\"", "kind = \"offset\"", 1).replacen("x_off = 0.0 ", "x_off = 0.002 ", 1);
    assert!(src.contains("x_off = 0.002"), "the problem's [scene] changed: fix the test");
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join("offset.toml");
    std::fs::write(&p, src).unwrap();
    p
}

/// The folder `name` of the runs recorded by the gripopt of 5d2a08e (tests/fixtures).
pub fn recorded_fixture(name: &str) -> std::path::PathBuf {
    std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/recorded-5d2a08e")).join(name)
}

/// Run the gripopt binary with `args`, assert its exit code is `code`, and return its output
/// as text.
#[track_caller]
pub fn gripopt_exits(args: &[&str], code: i32) -> String {
    let o = run_gripopt(args);
    let text = output_text(&o);
    assert_eq!(o.status.code(), Some(code), "{args:?}: {text}");
    text
}

/// Run the gripopt binary with `args`, assert its exit code is `code`, and parse its stdout
/// as one JSON object.
#[track_caller]
pub fn json_exits(args: &[&str], code: i32) -> serde_json::Value {
    let o = run_gripopt(args);
    assert_eq!(o.status.code(), Some(code), "{args:?}: {}", output_text(&o));
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{args:?}: stdout is one JSON object: {e}"))
}

/// [`json_exits`] of a command that succeeds (exit 0).
#[track_caller]
pub fn json_of(args: &[&str]) -> serde_json::Value {
    json_exits(args, 0)
}

/// A tiny run through the command line (bottle-1l, population 4, one generation: ids 0 to 3)
/// in `dir/run`.
pub fn cli_tiny_run(dir: &std::path::Path) -> std::path::PathBuf {
    let run = dir.join("run");
    let o = run_gripopt(&["optimise", BOTTLE_FILE, "--out", run.to_str().unwrap(), "--pop", "4", "--generations", "1"]);
    assert!(o.status.success(), "{}", output_text(&o));
    run
}

/// `text` with its line starting with `key =` replaced by `line` (exactly one such line).
pub fn set_line(text: impl AsRef<str>, key: &str, line: &str) -> String {
    let text = text.as_ref();
    let hits = text.lines().filter(|l| l.starts_with(&format!("{key} ="))).count();
    assert_eq!(hits, 1, "one `{key} =` line");
    text.lines().map(|l| if l.starts_with(&format!("{key} =")) { line } else { l }).collect::<Vec<_>>().join("\n")
        + "\n"
}

/// kitchen.toml's text with `edit` applied, written to `dir/name`; its path.
pub fn kitchen_with(dir: &std::path::Path, name: &str, edit: impl Fn(String) -> String) -> String {
    let path = dir.join(name);
    std::fs::write(&path, edit(std::fs::read_to_string(KITCHEN_FILE).unwrap())).unwrap();
    path.display().to_string()
}

/// `text` without its `[robust]` sections (they close kitchen.toml): a single-object problem.
pub fn without_robust(text: String) -> String {
    let at = text.find("\n[robust]").expect("kitchen.toml has [robust]");
    let rest = text[at + 1..].lines().filter(|l| l.starts_with('['));
    assert!(
        rest.clone().all(|l| l.starts_with("[robust") || l.starts_with("[[robust")),
        "{:?}",
        rest.collect::<Vec<_>>()
    );
    text[..at + 1].to_string()
}

/// kitchen.toml with `[solver] max_steps = steps` and, with `small`, only its first object
/// (bottle-full), K = 4, 4 verify scenarios, p_min 0.5 and no certification stage (a quick
/// run with a feasible front: verify then checks the search's front, which certification on
/// fresh scenarios a small step budget cuts short would empty).
pub fn kitchen_with_max_steps(steps: u64, small: bool) -> String {
    let mut t = std::fs::read_to_string(KITCHEN_FILE).unwrap();
    if small {
        let first = t.find("[[robust.objects]]").unwrap();
        let second = first + 1 + t[first + 1..].find("[[robust.objects]]").unwrap();
        let uncertainty = t.find("[robust.uncertainty]").unwrap();
        t = format!("{}{}", &t[..second], &t[uncertainty..]);
        t = set_line(&t, "scenarios", "scenarios = 4");
        t = set_line(&t, "verify_scenarios", "verify_scenarios = 4");
        t = set_line(&t, "p_min", "p_min = 0.5");
        t.push_str("\n[robust.certify]\nenabled = false\n");
    }
    set_line(&t, "max_steps", &format!("max_steps = {steps}"))
}

/// `file` with `method = METHOD` added to its `[solver]`, written to `dir/name`; its path.
pub fn with_solver_method(file: &str, dir: &std::path::Path, name: &str, method: &str) -> String {
    let text = std::fs::read_to_string(file).unwrap();
    assert!(text.contains("\n[solver]\n"), "{file} has a [solver] section");
    let path = dir.join(name);
    std::fs::write(&path, text.replacen("\n[solver]\n", &format!("\n[solver]\nmethod = \"{method}\"\n"), 1)).unwrap();
    path.display().to_string()
}

/// A named pipe at `path` (false: `mkfifo` is not available here; the caller skips).
pub fn fifo(path: &std::path::Path) -> bool {
    let made = std::process::Command::new("mkfifo").arg(path).status().is_ok_and(|s| s.success());
    if !made {
        eprintln!("skipped: mkfifo is not available");
    }
    made
}

/// Whether `path` is a named pipe (not followed if a link).
pub fn is_fifo(path: &std::path::Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}

/// Run gripopt with `args`, its memory limited to 2 GiB and its time to 120 s (killed then:
/// the test fails, it does not hang); stdout and stderr through files in `dir`.
pub fn run_limited(dir: &std::path::Path, args: &[&str]) -> std::process::Output {
    use std::process::{Command, Output, Stdio};
    use std::time::{Duration, Instant};
    let (out, err) = (dir.join(".stdout"), dir.join(".stderr"));
    let mut child = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 2097152; exec \"$0\" \"$@\"")
        .arg(GRIPOPT_BIN)
        .args(args)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("gripopt {args:?} did not end in 120 s (killed): {}", std::fs::read_to_string(&err).unwrap());
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    Output { status, stdout: std::fs::read(&out).unwrap(), stderr: std::fs::read(&err).unwrap() }
}
