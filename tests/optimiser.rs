//! Optimiser runs: determinism, exact resume (crash, kill -9, extension), refusal of
//! changed inputs, corrupt checkpoints, and the reference hypervolume bands.
use gripopt::optim::{run_test, TestProblem};
use gripopt::run::{optimise, resume, RunSpec};
use std::path::{Path, PathBuf};

/// Run folders go under target/mcap-check/ so that `make test` checks their recordings
/// with the independent reader.
fn tmp(name: &str) -> PathBuf {
    crate::common::check_dir(&format!("optimiser-{name}"))
}

fn spec(out: &Path, generations: u64, threads: usize) -> RunSpec {
    crate::common::bottle_spec(out, generations, 7, threads)
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The population without the wall-clock timings (the only non-deterministic fields:
/// the stage seconds and the simulations' cpu seconds of each record).
fn population_json(dir: &Path) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_str(&read(&dir.join("checkpoint.json"))).unwrap();
    let mut pop = v["state"]["population"].take();
    for ind in pop.as_array_mut().unwrap() {
        let info = &mut ind["eval"]["info"];
        info["stage_seconds"] = serde_json::Value::Null;
        info["record"]["cpu_s"] = serde_json::Value::Null;
        if let Some(f) = info["record"].get_mut("free_scene").and_then(|f| f.as_object_mut()) {
            f.remove("cpu_s");
        }
    }
    pop
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let (a, b) = (tmp("t1"), tmp("t2"));
    optimise(&spec(&a, 4, 1)).unwrap();
    optimise(&spec(&b, 4, 2)).unwrap();
    assert_eq!(read(&a.join("pareto.csv")), read(&b.join("pareto.csv")));
    assert_eq!(population_json(&a), population_json(&b));
    assert!(read(&a.join("pareto.csv")).len() > 200, "the front is not empty");
}

#[test]
fn crash_and_resume_is_bit_identical() {
    let (full, cut) = (tmp("full"), tmp("cut"));
    optimise(&spec(&full, 6, 2)).unwrap();
    let s = spec(&cut, 6, 2);
    let e = crate::common::optimise_crashing_after(&s, 3).unwrap_err().to_string();
    assert!(e.contains("resume"), "{e}");
    let run: serde_json::Value = serde_json::from_str(&read(&cut.join("run.json"))).unwrap();
    assert_eq!(run["status"], "interrupted");
    // run.json says what the checkpoint holds
    let cp: serde_json::Value = serde_json::from_str(&read(&cut.join("checkpoint.json"))).unwrap();
    assert_eq!(run["completed_generations"], 3);
    assert_eq!(run["completed_generations"], cp["state"]["generation"]);
    assert_eq!(run["evaluations"], cp["state"]["evaluations"]);
    let r = resume(&cut, None, false, Some(1)).unwrap();
    assert_eq!(r.generations, 6);
    assert_eq!(read(&full.join("pareto.csv")), read(&cut.join("pareto.csv")));
    assert_eq!(read(&full.join("population.csv")), read(&cut.join("population.csv")));
    assert_eq!(population_json(&full), population_json(&cut));
    let run: serde_json::Value = serde_json::from_str(&read(&cut.join("run.json"))).unwrap();
    assert_eq!(run["status"], "finished");
    assert_eq!(run["resumes"][0]["at_generation"], 3);
}

#[test]
fn a_finished_run_can_be_extended() {
    let (long, short) = (tmp("long"), tmp("short"));
    optimise(&spec(&long, 7, 2)).unwrap();
    optimise(&spec(&short, 4, 2)).unwrap();
    let r = resume(&short, Some(7), false, Some(2)).unwrap();
    assert_eq!(r.generations, 7);
    assert_eq!(read(&long.join("pareto.csv")), read(&short.join("pareto.csv")));
    // shrinking below the completed generations is refused
    let e = resume(&short, Some(3), false, None).unwrap_err().to_string();
    assert!(e.contains("already has 7 generations"), "{e}");
}

#[test]
fn kill_minus_9_and_resume_via_the_cli() {
    let bin = env!("CARGO_BIN_EXE_gripopt");
    let problem = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml");
    let (full, cut) = (tmp("cli-full"), tmp("cli-cut"));
    let args = |out: &Path| {
        vec![
            "optimise".to_string(),
            problem.into(),
            "--out".into(),
            out.display().to_string(),
            "--pop".into(),
            "16".into(),
            "--generations".into(),
            "12".into(),
            "--seed".into(),
            "3".into(),
        ]
    };
    let st = std::process::Command::new(bin).args(args(&full)).output().unwrap();
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    // start again and kill it once a few generations are checkpointed
    let mut child = std::process::Command::new(bin)
        .args(args(&cut))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    loop {
        let g = std::fs::read(cut.join("checkpoint.json"))
            .ok()
            .and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok())
            .and_then(|v| v["state"]["generation"].as_u64())
            .unwrap_or(0);
        if g >= 3 || t0.elapsed().as_secs() > 60 {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let _ = child.kill(); // SIGKILL
    let _ = child.wait();
    let out = std::process::Command::new(bin).args(["resume", &cut.display().to_string()]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(read(&full.join("pareto.csv")), read(&cut.join("pareto.csv")));
}

#[test]
fn changed_problem_file_is_refused_unless_forced() {
    let dir = tmp("changed");
    let prob = dir.with_extension("toml");
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).unwrap();
    std::fs::write(&prob, &text).unwrap();
    let mut s = spec(&dir, 3, 2);
    s.problem_path = prob.clone();
    optimise(&s).unwrap();
    std::fs::write(&prob, text.replace("tau = 0.5 ", "tau = 0.45 ")).unwrap();
    let e = resume(&dir, Some(4), false, None).unwrap_err().to_string();
    assert!(e.contains("changed") && e.contains("--force") && e.contains(&prob.display().to_string()), "{e}");
    resume(&dir, Some(4), true, None).unwrap();
    let run: serde_json::Value = serde_json::from_str(&read(&dir.join("run.json"))).unwrap();
    assert_eq!(run["resumes"][0]["forced"], true);
    // a second start into the same folder is refused
    let e = optimise(&s).unwrap_err().to_string();
    assert!(e.contains("already holds a run"), "{e}");
}

#[test]
fn corrupt_checkpoints_give_clear_errors() {
    let dir = tmp("corrupt");
    optimise(&spec(&dir, 2, 2)).unwrap();
    let cp = dir.join("checkpoint.json");
    let good = std::fs::read(&cp).unwrap();
    // truncated
    std::fs::write(&cp, &good[..good.len() / 2]).unwrap();
    let e = resume(&dir, None, false, None).unwrap_err().to_string();
    assert!(e.contains("checkpoint.json") && e.contains("truncated"), "{e}");
    // wrong format tag
    let mut v: serde_json::Value = serde_json::from_slice(&good).unwrap();
    v["format"] = "something-else".into();
    std::fs::write(&cp, serde_json::to_vec(&v).unwrap()).unwrap();
    let e = resume(&dir, None, false, None).unwrap_err().to_string();
    assert!(e.contains("checkpoint.json") && e.contains("format"), "{e}");
    // inconsistent state
    let mut v: serde_json::Value = serde_json::from_slice(&good).unwrap();
    v["state"]["generation"] = 9.into();
    std::fs::write(&cp, serde_json::to_vec(&v).unwrap()).unwrap();
    let e = resume(&dir, None, false, None).unwrap_err().to_string();
    assert!(e.contains("checkpoint.json") && e.contains("inconsistent"), "{e}");
    // missing
    std::fs::remove_file(&cp).unwrap();
    let e = resume(&dir, None, false, None).unwrap_err().to_string();
    assert!(e.contains("checkpoint.json"), "{e}");
    // the results written before stay readable
    assert!(read(&dir.join("pareto.csv")).lines().find(|l| !l.starts_with('#')).unwrap().starts_with("id,"));
}

#[test]
fn reference_hypervolume_bands() {
    // median over seeds 1..11 inside the band of the reference NSGA-II (the table)
    for p in TestProblem::ALL {
        let mut hv: Vec<f64> = (1..=11).map(|s| run_test(p, s, 100, None).hv).collect();
        hv.sort_by(f64::total_cmp);
        let (_, lo, hi) = p.hv_band();
        assert!(hv[5] >= lo && hv[5] <= hi, "{}: median {} outside [{lo}, {hi}]", p.name(), hv[5]);
    }
}

/// The solver's order of work (issue 15): every design's start says whether the rest is
/// costly, costly designs go first, the order is the same for any thread count, and once
/// the cost model has learnt from earlier generations it orders the simulated designs by
/// their work (right-hand-side evaluations, deterministic) better than chance: the Spearman
/// rank correlation between position and work is clearly negative (longest first).
#[test]
fn work_is_ordered_by_the_learnt_cost_model() {
    use argmin::core::observers::Observe;
    use argmin::core::State;
    use gripopt::optim::{execute, observe, Nsga2, Nsga2Settings, Nsga2State, Operators};
    use gripopt::run::{GripperInfo, GripperProblem};
    use std::sync::{Arc, Mutex};
    type Gens = Arc<Mutex<Vec<(Vec<usize>, usize, Vec<Option<u64>>)>>>;
    struct Obs(Gens);
    impl Observe<Nsga2State<GripperInfo>> for Obs {
        fn observe_init(
            &mut self,
            _: &str,
            st: &Nsga2State<GripperInfo>,
            _: &argmin::core::KV,
        ) -> Result<(), argmin::core::Error> {
            self.observe_iter(st, &argmin::core::KV::new())
        }
        fn observe_iter(
            &mut self,
            st: &Nsga2State<GripperInfo>,
            _: &argmin::core::KV,
        ) -> Result<(), argmin::core::Error> {
            let work = st.last_evaluated.iter().map(|i| i.eval.info.record.grasp.work.rhs_evals).collect();
            self.0.lock().unwrap().push((st.timing.order.clone(), st.timing.costly, work));
            Ok(())
        }
    }
    let run = |threads: usize| {
        let problem =
            gripopt::params::Problem::load(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).unwrap();
        let gp = GripperProblem::new(problem);
        let (ideal, r) = gp.hv_points();
        let settings = Nsga2Settings {
            pop_size: 64,
            seed: 5,
            operators: Operators::default(),
            eliminate_duplicates: true,
            hv_ideal: ideal,
            hv_ref: r,
        };
        let gens: Gens = Arc::default();
        let obs = Obs(gens.clone());
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            execute(gp, Nsga2::new(settings), Nsga2State::new().with_max_generations(8), move |e| observe(e, obs))
        })
        .unwrap();
        Arc::try_unwrap(gens).unwrap().into_inner().unwrap()
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one, two, "the order and the work do not depend on the thread count");
    let mut rho_sum = (0.0, 0);
    for (g, (order, costly, work)) in one.iter().enumerate() {
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..work.len()).collect::<Vec<_>>(), "generation {}: the order is a permutation", g + 1);
        // designs not simulated (or ended before the simulation) are cheap, and come last
        for &i in &order[*costly..] {
            assert!(work[i].unwrap_or(0) == 0, "generation {}: design {i} was called cheap but simulated", g + 1);
        }
        // generations after the model has rows: rank correlation of position and work
        let sims: Vec<(usize, f64)> = order[..*costly]
            .iter()
            .enumerate()
            .filter_map(|(pos, &i)| work[i].filter(|&w| w > 0).map(|w| (pos, w as f64)))
            .collect();
        if g >= 3 && sims.len() >= 10 {
            let rank = |v: Vec<f64>| {
                let mut idx: Vec<usize> = (0..v.len()).collect();
                idx.sort_by(|&a, &b| v[a].total_cmp(&v[b]));
                let mut r = vec![0.0; v.len()];
                for (k, &i) in idx.iter().enumerate() {
                    r[i] = k as f64;
                }
                r
            };
            let (a, b) = (rank(sims.iter().map(|s| s.0 as f64).collect()), rank(sims.iter().map(|s| s.1).collect()));
            let n = a.len() as f64;
            let m = (n - 1.0) / 2.0;
            let cov: f64 = a.iter().zip(&b).map(|(x, y)| (x - m) * (y - m)).sum();
            let var: f64 = a.iter().map(|x| (x - m) * (x - m)).sum();
            rho_sum.0 += cov / var;
            rho_sum.1 += 1;
        }
    }
    assert!(rho_sum.1 >= 3, "enough generations with simulated designs: {}", rho_sum.1);
    let rho = rho_sum.0 / rho_sum.1 as f64;
    assert!(rho < -0.3, "longest first: mean Spearman ρ(position, work) = {rho:.2}");
}

/// A folder left by a run killed before its first checkpoint (run.json, the layout, the
/// first views, a recording index, but no checkpoint) can be given to `optimise` again;
/// the same output names without a run.json are someone else's files and are refused.
#[test]
fn a_folder_left_before_the_first_checkpoint_is_reused() {
    let (done, left, other) = (tmp("left-src"), tmp("left"), tmp("left-other"));
    optimise(&spec(&done, 1, 1)).unwrap();
    std::fs::create_dir_all(left.join("recording")).unwrap();
    for f in ["run.json", "problem.toml", "foxglove-layout.json", "pareto.csv", "pareto_timings.csv", "history.csv"] {
        std::fs::copy(done.join(f), left.join(f)).unwrap();
    }
    // run.json as a run writes it at its start (no completed generation: a run.json that
    // records one is a run whose checkpoint is lost, which optimise refuses, issue 24 item 1)
    let mut run: serde_json::Value = serde_json::from_slice(&std::fs::read(left.join("run.json")).unwrap()).unwrap();
    run["completed_generations"] = 0.into();
    run["evaluations"] = 0.into();
    run["checkpoint_sha256"] = serde_json::Value::Null;
    run["status"] = "running".into();
    std::fs::write(left.join("run.json"), serde_json::to_string_pretty(&run).unwrap()).unwrap();
    let s = optimise(&spec(&left, 2, 2)).unwrap();
    assert_eq!(s.generations, 2);
    std::fs::create_dir_all(&other).unwrap();
    std::fs::copy(done.join("pareto.csv"), other.join("pareto.csv")).unwrap();
    let e = optimise(&spec(&other, 1, 1)).unwrap_err().to_string();
    assert!(e.contains("not a gripopt run") && e.contains("pareto.csv"), "{e}");
    assert!(other.join("pareto.csv").exists(), "a refused folder is left as it was");
}
