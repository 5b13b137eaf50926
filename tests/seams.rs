//! The library's seams (issue 21), each against an independent result: the facade against
//! the CLI's JSON, the sample sink against the recorded trajectory and against itself
//! (results do not depend on it), the batch evaluator (default at 1 and 2 threads, against
//! one design at a time; a custom one plugged in), the domain rules a library caller meets,
//! and a run's progress callback and stop flag.

use crate::common::{bottle, nominal, BOTTLE_FILE};
use gripopt::optim::{Batch, Evaluations, Evaluator, MooProblem, Scheduled};
use gripopt::run::{GenerationReport, GripperInfo, GripperProblem, Progress, RunSpec};
use gripopt::sim::{Controls, EventNote, Integration, Point, Sample, SceneSpec, Sink, Trajectory};
use gripopt::{Optimiser, Problem, Stages};
use std::path::PathBuf;
use std::process::Command;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/seams-tests")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(d.parent().unwrap()).unwrap();
    d
}

/// The evaluation record without its wall-clock seconds.
fn untimed(mut v: serde_json::Value) -> serde_json::Value {
    v.as_object_mut().unwrap().remove("cpu_s");
    if let Some(f) = v.get_mut("free_scene").and_then(|f| f.as_object_mut()) {
        f.remove("cpu_s");
    }
    v
}

/// Load → evaluate through the facade gives the numbers of `gripopt evaluate --json` (a
/// separate process), for the nominal and another design, static and full.
#[test]
fn facade_evaluate_equals_the_cli_json() {
    let p = Problem::load(BOTTLE_FILE).unwrap();
    let d = "l21=0.05,b=0.06,t22=0.035,r=0.5,p=0.4,psi_deg=130";
    for (design, x) in [(None, p.nominal), (Some(d), gripopt::Design::parse_assignments(d).unwrap())] {
        for (stages, flag) in [(Stages::All, None), (Stages::Static, Some("--static-only"))] {
            let mut args = vec!["evaluate", BOTTLE_FILE, "--json"];
            args.extend(flag);
            if let Some(d) = design {
                args.extend(["--design", d]);
            }
            let out = Command::new(env!("CARGO_BIN_EXE_gripopt")).args(&args).output().unwrap();
            assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
            let mut cli: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
            // the CLI names the method of a simulation that is not RADAU5's: the default, auto
            let method = cli.as_object_mut().unwrap().remove("method");
            assert_eq!(method, flag.is_none().then(|| "auto".into()), "{args:?}");
            let lib = serde_json::to_value(gripopt::evaluate(&p, &x, stages)).unwrap();
            assert_eq!(untimed(lib), untimed(cli), "{args:?}");
        }
    }
    // a batch, at 1 and 2 threads: the same records in the same order
    let designs: Vec<gripopt::Design> = (0..6).map(|k| crate::common::random_design(&mut rng(k))).collect();
    let one = gripopt::evaluate_batch(&p, &designs, Stages::All, Some(1)).unwrap();
    let two = gripopt::evaluate_batch(&p, &designs, Stages::All, Some(2)).unwrap();
    let strip =
        |r: &Vec<gripopt::Record>| r.iter().map(|r| untimed(serde_json::to_value(r).unwrap())).collect::<Vec<_>>();
    assert_eq!(strip(&one), strip(&two));
    for (x, r) in designs.iter().zip(&one) {
        assert_eq!(
            untimed(serde_json::to_value(gripopt::evaluate(&p, x, Stages::All)).unwrap()),
            strip(&vec![r.clone()])[0]
        );
    }
}

fn rng(k: u64) -> rand_chacha::ChaCha8Rng {
    use rand::SeedableRng;
    rand_chacha::ChaCha8Rng::seed_from_u64(100 + k)
}

/// Counts what a simulation reports.
#[derive(Default)]
struct Counter {
    steps: Vec<Sample>,
    grid: usize,
    events: usize,
}

impl Sink for Counter {
    fn wants_samples(&self) -> bool {
        true
    }
    fn finger(&mut self, at: Point, s: &Sample) {
        match at {
            Point::Grid => self.grid += 1,
            _ => self.steps.push(*s),
        }
    }
    fn event(&mut self, _e: &EventNote<'_>) {
        self.events += 1;
    }
}

/// The sink sees every sample and event of a run: a custom sink gets the samples a
/// `Trajectory` keeps, one event note per located event, grid samples when asked; and
/// the result does not depend on the sink (none, a trajectory, a counter).
#[test]
fn the_sink_sees_the_run_and_changes_nothing() {
    let p = bottle();
    let s = &p.scene;
    let k = gripopt::eval::stage_kinematics(&nominal(), s).unwrap();
    let st = gripopt::eval::stage_statics(&k.finger, s).unwrap();
    let integ = Integration::from_solver(&p.solver);
    let ctl = Controls { grid_dt: Some(1e-3), ..Controls::DIAGNOSTIC };
    for spec in [SceneSpec::Centred, SceneSpec::Offset { x_off: 0.002 }] {
        let none = gripopt::sim::simulate(&k.finger, s, &st, &spec, &integ, &ctl, &mut ());
        let mut tr = Trajectory::default();
        let with_tr = gripopt::sim::simulate(&k.finger, s, &st, &spec, &integ, &ctl, &mut tr);
        let mut c = Counter::default();
        let with_c = gripopt::sim::simulate(&k.finger, s, &st, &spec, &integ, &ctl, &mut c);
        let g = |r: gripopt::sim::SceneResult| gripopt::sim::DynamicsResult { cpu_s: 0.0, ..*r.grasp().unwrap() };
        let (a, b, cc) = (g(none), g(with_tr), g(with_c));
        assert_eq!(a, b, "{spec:?}");
        assert_eq!(a, cc, "{spec:?}");
        assert!(tr.samples.len() > 100, "{spec:?}: every scene records, the offset one too");
        assert_eq!(c.steps, tr.samples, "{spec:?}");
        assert_eq!(c.grid, tr.grid.len());
        assert_eq!(c.events as u32, a.events, "{spec:?}: one note per located event");
        // the last sample is the state the run ended at
        assert_eq!(tr.samples.last().unwrap().t, a.t_end);
        assert_eq!(tr.samples[0].t, 0.0);
        // the grid covers [0, t_end] every millisecond (its times summed, so ±1 at the end)
        let n = (a.t_end / 1e-3).floor() + 1.0;
        assert!((tr.grid.len() as f64 - n).abs() <= 1.0, "{spec:?}: {} grid samples for {n}", tr.grid.len());
    }
}

/// The default evaluator gives the same individuals at 1 and 2 threads, and each is what
/// the problem gives for its design alone (start then finish, on one thread).
#[test]
fn the_default_evaluator_is_thread_count_independent() {
    let gp = GripperProblem::new(bottle());
    let xs: Vec<Vec<f64>> = (0..12)
        .map(|k| {
            let d = crate::common::random_design(&mut rng(k));
            d.to_array().to_vec()
        })
        .collect();
    let batch = Batch { xs: &xs, first_id: 0, generation: 1 };
    let eval = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| Scheduled::default().evaluate(&gp, &batch)).evaluated
    };
    let clean = |e: Vec<gripopt::optim::Evaluated<GripperInfo>>| {
        e.into_iter()
            .map(|mut e| {
                e.info.stage_seconds = [0.0; 4];
                untimed(serde_json::to_value(&e).unwrap())
            })
            .collect::<Vec<_>>()
    };
    let (one, two) = (clean(eval(1)), clean(eval(2)));
    assert_eq!(one, two);
    let alone = clean(xs.iter().map(|x| gp.evaluate(x)).collect());
    let alone: Vec<_> = alone
        .into_iter()
        .map(|mut v| {
            v["info"]["record"]["cpu_s"] = one[0]["info"]["record"]["cpu_s"].clone();
            v
        })
        .collect();
    assert_eq!(one.len(), alone.len());
    for (a, b) in one.iter().zip(&alone) {
        assert_eq!(untimed(a["info"]["record"].clone()), untimed(b["info"]["record"].clone()));
        assert_eq!(a["f"], b["f"]);
        assert_eq!(a["cv"], b["cv"]);
    }
}

/// Wraps the default evaluator and notes each batch it is handed.
struct Noting {
    inner: Scheduled,
    batches: Arc<Mutex<Vec<(usize, u64, u64)>>>,
}

impl Evaluator<GripperProblem> for Noting {
    fn evaluate(&mut self, p: &GripperProblem, batch: &Batch<'_>) -> Evaluations<GripperInfo> {
        self.batches.lock().unwrap().push((batch.xs.len(), batch.first_id, batch.generation));
        self.inner.evaluate(p, batch)
    }
}

/// A custom evaluator plugged into a run through the builder is called with each
/// generation's batch (its size, first id and generation), and the run equals the default's.
#[test]
fn a_custom_evaluator_gets_each_generation() {
    let (a, b) = (tmp("evaluator-default"), tmp("evaluator-custom"));
    let run = |out: &PathBuf| {
        Optimiser::new(BOTTLE_FILE, out).pop(8).generations(3).seed(4).threads(2).record(gripopt::RecordOptions::none())
    };
    run(&a).run().unwrap();
    let batches = Arc::new(Mutex::new(vec![]));
    run(&b).evaluator(Noting { inner: Scheduled::default(), batches: batches.clone() }).run().unwrap();
    assert_eq!(*batches.lock().unwrap(), vec![(8, 0, 1), (8, 8, 2), (8, 16, 3)]);
    for f in ["pareto.csv", "population.csv", "history.csv"] {
        assert_eq!(std::fs::read(a.join(f)).unwrap(), std::fs::read(b.join(f)).unwrap(), "{f}");
    }
}

/// A library caller of `optimise` with a free-kind problem whose hand is not horizontal
/// gets the problem file's error (field environment.g_eq) before anything is written; so
/// do `Problem::load` and a scene switched to free (`in_scene`, the facade's simulate).
#[test]
fn the_free_scene_rule_holds_for_library_callers() {
    let dir = tmp("free-geq");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(BOTTLE_FILE).unwrap().replacen("kind = \"centred\"", "kind = \"free\"", 1);
    let text = text.replacen("g_eq = 0.0", "g_eq = 9.81", 1);
    assert!(text.contains("g_eq = 9.81") && text.contains("kind = \"free\""));
    let path = dir.join("free-geq.toml");
    std::fs::write(&path, &text).unwrap();
    let out = dir.join("run");
    let spec = RunSpec {
        problem_path: path.clone(),
        out: out.clone(),
        pop: 8,
        generations: 1,
        seed: 1,
        threads: Some(1),
        record: gripopt::RecordOptions::none(),
    };
    let e = gripopt::run::optimise(&spec).unwrap_err();
    assert!(matches!(&e, gripopt::Error::InvalidField { field, .. } if field == "environment.g_eq"), "{e}");
    assert!(e.to_string().contains("free-geq.toml") && e.is_input(), "{e}");
    assert!(!out.exists(), "nothing written");
    assert!(Problem::load(&path).is_err());
    let mut p = bottle();
    p.scene.env.g_eq = 9.81;
    let free = gripopt::SimulateRequest { scene: Some(gripopt::SceneChoice::free(None)), ..Default::default() };
    let e = gripopt::simulate(&p, &nominal(), &free).unwrap_err();
    assert!(e.to_string().contains("environment.g_eq"), "{e}");
    // and the run's settings: a zstd level outside 1..22, no thread
    let bad = RunSpec {
        problem_path: BOTTLE_FILE.into(),
        record: gripopt::RecordOptions { zstd_level: 30, ..Default::default() },
        ..spec.clone()
    };
    assert!(gripopt::run::optimise(&bad).unwrap_err().to_string().contains("zstd"));
    let bad = RunSpec { problem_path: BOTTLE_FILE.into(), threads: Some(0), ..spec };
    assert!(gripopt::run::optimise(&bad).unwrap_err().to_string().contains("--threads"));
}

/// Reports the generations and sets the stop flag after the second.
struct StopAfter2 {
    seen: Arc<Mutex<Vec<u64>>>,
    stop: Arc<AtomicBool>,
}

impl Progress for StopAfter2 {
    fn generation(&mut self, g: &GenerationReport) -> Result<(), String> {
        self.seen.lock().unwrap().push(g.generation);
        if g.generation == 2 {
            self.stop.store(true, Ordering::SeqCst);
        }
        Ok(())
    }
}

/// The progress callback hears every generation; the stop flag ends the run after the
/// current generation's checkpoint (interrupted, resumable), and the resumed run equals an
/// uninterrupted one.
#[test]
fn progress_and_stop_flag() {
    let (full, cut) = (tmp("stop-full"), tmp("stop-cut"));
    let run = |out: &PathBuf| {
        Optimiser::new(BOTTLE_FILE, out).pop(8).generations(4).seed(2).threads(1).record(gripopt::RecordOptions::none())
    };
    let count = Arc::new(AtomicUsize::new(0));
    struct Count(Arc<AtomicUsize>);
    impl Progress for Count {
        fn generation(&mut self, _: &GenerationReport) -> Result<(), String> {
            self.0.fetch_add(1, Ordering::SeqCst);
            Ok(())
        }
    }
    run(&full).progress(Count(count.clone())).run().unwrap();
    assert_eq!(count.load(Ordering::SeqCst), 4);
    let (seen, stop) = (Arc::new(Mutex::new(vec![])), Arc::new(AtomicBool::new(false)));
    let s = run(&cut).progress(StopAfter2 { seen: seen.clone(), stop: stop.clone() }).stop_flag(stop).run().unwrap();
    assert!(s.interrupted && s.generations == 2, "{s:?}");
    assert_eq!(*seen.lock().unwrap(), vec![1, 2]);
    let info = gripopt::RunFolder::open(&cut).unwrap().info().unwrap();
    assert_eq!(info.status, gripopt::run::RunStatus::Interrupted);
    let r = Optimiser::resume(&cut).run().unwrap();
    assert!(!r.interrupted && r.generations == 4);
    let (a, b) = (gripopt::RunFolder::open(&full).unwrap(), gripopt::RunFolder::open(&cut).unwrap());
    assert_eq!(a.front().unwrap(), b.front().unwrap());
    assert_eq!(a.history().unwrap().len(), 4);
    assert_eq!(
        a.history().unwrap().iter().map(|h| h.hypervolume).collect::<Vec<_>>(),
        b.history().unwrap().iter().map(|h| h.hypervolume).collect::<Vec<_>>()
    );
}

/// A checkpoint written before the typed record (format version 2, as the 5d2a08e binary
/// wrote it) is refused with a message naming its version, not a serde error.
#[test]
fn an_older_checkpoint_is_refused_by_name() {
    let dir = tmp("old-checkpoint");
    std::fs::create_dir_all(&dir).unwrap();
    let text = r#"{"format": "gripopt-checkpoint", "version": 2, "state": {}}"#;
    std::fs::write(dir.join("checkpoint.json"), text).unwrap();
    let e = gripopt::run::Checkpoint::<GripperInfo>::load(&dir.join("checkpoint.json")).unwrap_err().to_string();
    assert!(e.contains("version") && e.contains("before the typed evaluation record"), "{e}");
}
