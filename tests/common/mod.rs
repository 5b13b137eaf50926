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

/// A fresh, empty folder `target/AREA/NAME` for a test's files (removed first if left over).
pub fn scratch_dir(area: &str, name: &str) -> std::path::PathBuf {
    let d = std::path::PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target")).join(area).join(name);
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
