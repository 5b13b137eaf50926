//! Run folders that never lose or fake data, inputs with limits, and a CLI that scripts can
//! trust (issue 12): the folder lock, index recovery, checkpoint checksums, exit codes, a
//! closed pipe, values before a discard, per-generation outputs, the archive and `show`.
use gripopt::record::{read_index, recover, RecordOptions, TrajectoryKeep};
use gripopt::run::{optimise, resume, RunSpec};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_gripopt");
const PROBLEM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml");

fn tmp(name: &str) -> PathBuf {
    let base = std::env::var_os("GRIPOPT_MCAP_CHECK_DIR").map(PathBuf::from).unwrap_or_else(|| PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/mcap-check")));
    let d = base.join(format!("robust-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&base).unwrap();
    d
}

fn spec(out: &Path, generations: u64) -> RunSpec {
    RunSpec { problem_path: PROBLEM.into(), out: out.to_path_buf(), pop: 12, generations, seed: 7, threads: Some(2), progress: false, crash_after: None, record: RecordOptions::default() }
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn cli(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

fn code(o: &Output) -> i32 {
    o.status.code().unwrap_or(-1)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).to_string()
}

fn checkpoint_generation(dir: &Path) -> u64 {
    std::fs::read(dir.join("checkpoint.json")).ok().and_then(|b| serde_json::from_slice::<serde_json::Value>(&b).ok()).and_then(|v| v["state"]["generation"].as_u64()).unwrap_or(0)
}

fn wait_for(what: &str, mut f: impl FnMut() -> bool) {
    let t0 = Instant::now();
    while !f() {
        assert!(t0.elapsed() < Duration::from_secs(120), "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Data rows of a gripopt CSV (without the `#` lines), header first.
fn rows(p: &Path) -> Vec<Vec<String>> {
    read(p).lines().filter(|l| !l.starts_with('#')).map(|l| l.split(',').map(String::from).collect()).collect()
}

#[test]
fn two_processes_on_one_folder_the_second_is_refused_with_the_holders_pid() {
    let dir = tmp("lock");
    let d = dir.display().to_string();
    let mut child = Command::new(BIN).args(["optimise", PROBLEM, "--out", &d, "--pop", "16", "--generations", "200", "--record", "none"]).stdout(Stdio::null()).stderr(Stdio::null()).spawn().unwrap();
    wait_for("the first checkpoint", || checkpoint_generation(&dir) >= 1);
    let second = cli(&["resume", &d]);
    let e = stderr(&second);
    assert_eq!(code(&second), 2, "{e}");
    assert!(e.contains(&format!("pid {}", child.id())) && e.contains("in use"), "{e}");
    // a second optimise into the same folder is refused too
    let o = cli(&["optimise", PROBLEM, "--out", &d, "--pop", "8", "--generations", "2"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    // the library says the same in-process (flock locks are per open file)
    let lib = resume(&dir, None, false, Some(1), false).unwrap_err();
    assert!(matches!(lib, gripopt::Error::Locked { pid: Some(p), .. } if p == child.id()), "{lib}");
    // kill -9 releases the lock: a resume then works
    child.kill().unwrap();
    child.wait().unwrap();
    let g = checkpoint_generation(&dir);
    let r = resume(&dir, Some(g + 1), false, Some(2), false).unwrap();
    assert_eq!(r.generations, g + 1);
}

#[test]
fn optimise_into_a_non_empty_folder_that_is_not_a_run_is_refused() {
    let dir = tmp("foreign");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("thesis.tex"), "precious").unwrap();
    let e = optimise(&spec(&dir, 1)).unwrap_err().to_string();
    assert!(e.contains("not empty") && e.contains("thesis.tex"), "{e}");
    assert_eq!(read(&dir.join("thesis.tex")), "precious");
    assert!(!dir.join("run.json").exists());
}

#[test]
fn kill_9_during_resume_loses_nothing_and_ends_bit_identical() {
    let (full, cut) = (tmp("k9-full"), tmp("k9-cut"));
    optimise(&spec(&full, 7)).unwrap();
    let mut s = spec(&cut, 7);
    s.crash_after = Some(2);
    optimise(&s).unwrap_err();
    let c = cut.display().to_string();
    let mut child = Command::new(BIN).args(["resume", &c, "--threads", "1"]).stdout(Stdio::null()).stderr(Stdio::null()).spawn().unwrap();
    wait_for("generation 4 of the resume", || checkpoint_generation(&cut) >= 4);
    child.kill().unwrap();
    child.wait().unwrap();
    let covered = checkpoint_generation(&cut);
    // every shard the checkpoint covers is still there and indexed after recovery
    let rec = recover(&cut.join("recording"), covered).unwrap();
    assert_eq!(rec.index.iter().map(|e| e.generation).collect::<Vec<_>>(), (1..=covered).collect::<Vec<_>>());
    resume(&cut, None, false, Some(2), false).unwrap();
    for f in ["pareto.csv", "population.csv", "history.csv", "archive.csv"] {
        assert_eq!(read(&full.join(f)), read(&cut.join(f)), "{f}");
    }
    // the same shards (sizes differ by the recorded wall-clock stage timings only)
    let ids = |d: &Path| read_index(&d.join("recording")).unwrap().into_iter().map(|e| (e.generation, e.file, e.first_id, e.last_id, e.designs)).collect::<Vec<_>>();
    assert_eq!(ids(&full), ids(&cut));
}

#[test]
fn an_emptied_truncated_or_missing_index_is_rebuilt_from_the_shards() {
    let dir = tmp("index");
    optimise(&spec(&dir, 4)).unwrap();
    let rdir = dir.join("recording");
    let original = read_index(&rdir).unwrap();
    assert_eq!(original.len(), 4);
    let text = read(&rdir.join("index.jsonl"));
    let first_line_and_a_half = format!("{}\n{}", text.lines().next().unwrap(), &text.lines().nth(1).unwrap()[..20]);
    for (case, content) in [("emptied", Some(String::new())), ("truncated", Some(first_line_and_a_half)), ("garbage", Some("{not json\n".into())), ("missing", None)] {
        match content {
            Some(c) => std::fs::write(rdir.join("index.jsonl"), c).unwrap(),
            None => std::fs::remove_file(rdir.join("index.jsonl")).unwrap(),
        }
        // leftovers of a generation after the checkpoint, and a temporary file
        std::fs::write(rdir.join("gen-00005.mcap"), b"partial").unwrap();
        std::fs::write(rdir.join("gen-00005.mcap.tmp"), b"partial").unwrap();
        let r = recover(&rdir, 4).unwrap();
        assert_eq!(r.index, original, "{case}: the index rebuilt from the shards equals the writer's");
        assert!(r.removed.contains(&"gen-00005.mcap".to_string()) && r.removed.contains(&"gen-00005.mcap.tmp".to_string()), "{case}: {:?}", r.removed);
        assert!(!rdir.join("gen-00005.mcap").exists());
        for e in &original {
            assert!(rdir.join(&e.file).exists(), "{case}: {} kept", e.file);
        }
    }
    // through a real resume (which used to delete every shard not listed)
    std::fs::write(rdir.join("index.jsonl"), "").unwrap();
    resume(&dir, Some(5), false, Some(2), false).unwrap();
    let after = read_index(&rdir).unwrap();
    assert_eq!(&after[..4], &original[..]);
    assert_eq!(after.len(), 5);
    let r = gripopt::record::replay(&dir, original[1].first_id).unwrap();
    assert_eq!(r.recorded.record["id"].as_u64(), Some(original[1].first_id));
}

#[test]
fn an_edited_checkpoint_is_refused_unless_forced() {
    let dir = tmp("edited");
    optimise(&spec(&dir, 3)).unwrap();
    let cp = dir.join("checkpoint.json");
    let text = read(&cp);
    // change one digit of the first design parameter of the population
    let at = text.find("\"x\":[").unwrap() + 6;
    let digit = text[at..].find(|c: char| c.is_ascii_digit() && c != '0').unwrap() + at;
    let old = text.as_bytes()[digit];
    let mut bytes = text.into_bytes();
    bytes[digit] = if old == b'9' { b'8' } else { old + 1 };
    std::fs::write(&cp, &bytes).unwrap();
    let e = resume(&dir, Some(4), false, Some(2), false).unwrap_err();
    assert!(e.to_string().contains("checksum") && e.to_string().contains("checkpoint.json"), "{e}");
    let o = cli(&["resume", &dir.display().to_string(), "--generations", "4"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    resume(&dir, Some(4), true, Some(2), false).unwrap();
    let run: serde_json::Value = serde_json::from_str(&read(&dir.join("run.json"))).unwrap();
    assert_eq!(run["resumes"][0]["forced"], true);
    assert!(run["resumes"][0]["note"].as_str().unwrap().contains("checksum"), "{}", run["resumes"][0]);
    // the checkpoint written by the forced resume carries a valid checksum again
    gripopt::run::Checkpoint::<gripopt::run::GripperInfo>::load(&cp).unwrap();
}

#[test]
fn absurd_inputs_are_refused_without_a_panic() {
    let out = tmp("absurd");
    let o = out.display().to_string();
    for (args, needle) in [
        (vec!["optimise", PROBLEM, "--out", &o, "--pop", "18446744073709551615"], "memory"),
        (vec!["optimise", PROBLEM, "--out", &o, "--pop", "1000000000"], "memory"),
        (vec!["optimise", PROBLEM, "--out", &o, "--pop", "3"], "at least 4"),
        (vec!["optimise", PROBLEM, "--out", &o, "--generations", "18446744073709551615"], "evaluations"),
        (vec!["optimise", PROBLEM, "--out", &o, "--threads", "1000000"], "at most"),
        (vec!["optimise", PROBLEM, "--out", &o, "--zstd-level", "99"], "1 to 22"),
        (vec!["moo-test", "zdt1", "--pop", "18446744073709551615"], "memory"),
        (vec!["simulate", PROBLEM, "--rtol", "1"], "rtol"),
    ] {
        let r = cli(&args);
        assert_eq!(code(&r), 2, "{args:?}: {}", stderr(&r));
        assert!(stderr(&r).contains(needle) && !stderr(&r).contains("panicked"), "{args:?}: {}", stderr(&r));
    }
    assert!(!out.join("checkpoint.json").exists());
    // a design outside the bounds is evaluated, with a warning
    let r = cli(&["evaluate", PROBLEM, "--json", "--design", "l21=0.09,b=0.056,t22=0.0376,r=0.46,p=0.4,psi_deg=129.76"]);
    assert_eq!(code(&r), 0, "{}", stderr(&r));
    assert!(stderr(&r).contains("warning: l21 = 0.09 is outside the problem's bounds"), "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(v["l21"], 0.09);
}

#[test]
fn a_closed_output_pipe_ends_the_program_quietly() {
    for args in [vec!["evaluate", PROBLEM], vec!["moo-test", "zdt1", "--seeds", "1-40", "--json", "--pop", "8", "--generations", "2"]] {
        // the reader is gone before the program starts (closing it after the spawn races
        // with a fast program on a loaded machine)
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let child = Command::new(BIN).args(&args).stdout(writer).stderr(Stdio::piped()).spawn().unwrap();
        let out = child.wait_with_output().unwrap();
        let e = stderr(&out);
        assert!(!e.contains("panicked") && !e.contains("Broken pipe") && e.is_empty(), "{args:?}: {e}");
        assert_eq!(code(&out), 141, "{args:?}");
    }
}

#[test]
fn exit_codes_follow_the_documented_table() {
    // 2: bad input (a problem file that does not exist, a malformed one)
    assert_eq!(code(&cli(&["evaluate", "/nonexistent/problem.toml"])), 2);
    let bad = tmp("bad-problem").with_extension("toml");
    std::fs::write(&bad, "[hand]\ntau = \"x\"\n").unwrap();
    assert_eq!(code(&cli(&["evaluate", bad.to_str().unwrap()])), 2);
    // 1: a failed run (the library's classification)
    assert_eq!(gripopt::Error::Optimiser("x".into()).exit_code(), 1);
    assert_eq!(gripopt::Error::Input("x".into()).exit_code(), 2);
    // 0 / 3: replay verified / not verified; 0 samples compared is never "verified"
    let dir = tmp("codes");
    let mut s = spec(&dir, 4);
    s.record = RecordOptions { trajectories: TrajectoryKeep::Feasible, ..RecordOptions::default() };
    optimise(&s).unwrap();
    let d = dir.display().to_string();
    let front = rows(&dir.join("pareto.csv"));
    let pop = rows(&dir.join("population.csv"));
    let feasible_id = &front[1][0];
    let r = cli(&["replay", &d, "--design", feasible_id]);
    assert_eq!(code(&r), 0, "{}", stderr(&r));
    let out = String::from_utf8_lossy(&r.stdout);
    assert!(out.contains("  verified (") && out.contains("re-simulation reproduces"), "{out}");
    let fcol = pop[0].iter().position(|h| h == "failed_stage").unwrap();
    let discarded = pop.iter().skip(1).find(|r| !r[fcol].is_empty() && r[fcol] != "3").expect("a design discarded before stage 3");
    // a design discarded before stage 3 has no trajectory: verified by its record's values
    let r = cli(&["replay", &d, "--design", &discarded[0]]);
    let text = String::from_utf8_lossy(&r.stdout).to_string();
    assert_eq!(code(&r), 0, "{text}");
    assert!(text.contains("verified (no trajectory recorded"), "{text}");
    // 3: the problem changed after the run (the torque): the front design no longer verifies
    let p = dir.join("problem.toml");
    let t0 = std::fs::read_to_string(&p).unwrap();
    let tau = t0.lines().find(|l| l.trim_start().starts_with("tau")).unwrap().to_string();
    std::fs::write(&p, t0.replacen(&tau, "tau = 0.45", 1)).unwrap();
    let r = cli(&["replay", &d, "--design", feasible_id]);
    let text = String::from_utf8_lossy(&r.stdout).to_string();
    assert_eq!(code(&r), 3, "{text}");
    assert!(text.contains("NOT verified") && !text.contains("  verified"), "{text}");
    let r = cli(&["replay", &d, "--design", feasible_id, "--json"]);
    assert_eq!(code(&r), 3);
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(v["verified"], false);
    // 130: interrupted by ctrl-c, after the checkpoint of the current generation
    let dir = tmp("sigint");
    let d = dir.display().to_string();
    let child = Command::new(BIN).args(["optimise", PROBLEM, "--out", &d, "--pop", "16", "--generations", "200", "--record", "none", "--json"]).stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    wait_for("the first checkpoint", || checkpoint_generation(&dir) >= 1);
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    let out = child.wait_with_output().unwrap();
    assert_eq!(code(&out), 130, "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["status"], "interrupted");
    assert_eq!(v["generations"].as_u64(), Some(checkpoint_generation(&dir)));
    let run: serde_json::Value = serde_json::from_str(&read(&dir.join("run.json"))).unwrap();
    assert_eq!(run["status"], "interrupted");
}

#[test]
fn discarded_designs_report_every_value_computed_before_the_discard() {
    use gripopt::eval::{evaluate, EvalOptions, Reason, Record};
    use gripopt::model::{grasp_at, spring_preload, Finger, OffsetFailure};
    use rand::SeedableRng;
    let p = crate::common::bottle();
    let s = &p.scene;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
    let (mut force, mut sweep) = (false, false);
    for _ in 0..20_000 {
        let x = crate::common::random_design(&mut rng);
        let ev = evaluate(&x, s, &EvalOptions::statics_only());
        let Some(d) = ev.discard else { continue };
        let r = Record::from_eval(&ev);
        let json = serde_json::to_value(&r).unwrap();
        match d.reason {
            Reason::Grasp(OffsetFailure::ForceNotPositive(_)) if !force => {
                // independent: the model's own functions, called directly
                let f = Finger::new(&x, s).unwrap();
                let (_, tau0) = spring_preload(&f, s).unwrap();
                let g = grasp_at(&f, s, tau0, 0.0).unwrap();
                assert_eq!(r.f0_1, Some(g.forces[0].f0[0]));
                assert_eq!(r.fmu_2, Some(g.forces[0].fmu[1]));
                assert_eq!(r.theta1, Some(g.cp[0].theta1));
                assert_eq!(r.tau_s0, Some(tau0));
                assert_eq!(r.fhandmu_y, Some(g.hand_mu.y));
                assert!(g.min_force() <= 0.0);
                // not computed: the objectives and form closure
                for k in ["alpha", "mean_force", "max_offset", "form_closed_0", "t_stab"] {
                    assert!(json[k].is_null(), "{k} = {}", json[k]);
                }
                force = true;
            }
            Reason::Sweep(_) if !sweep => {
                let f = Finger::new(&x, s).unwrap();
                assert_eq!(r.l12, Some(f.l12));
                assert_eq!(r.q11_0, Some(f.open.q11));
                assert_eq!(r.q12_0, Some(f.open.q12));
                assert_eq!(r.gamma, Some(f.gamma));
                assert!(json["min_margin_deg"].is_null() && json["tau_s0"].is_null());
                sweep = true;
            }
            _ => {}
        }
        if force && sweep {
            break;
        }
    }
    assert!(force && sweep, "found a force-positiveness discard: {force}, a sweep discard: {sweep}");
    // and the text report prints them, without Rust Debug text
    let o = cli(&["evaluate", PROBLEM]);
    let t = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(!t.contains("Some(") && !t.contains("None"), "{t}");
}

#[test]
fn outputs_are_written_every_generation_with_units_archive_and_totals() {
    let dir = tmp("outputs");
    let mut s = spec(&dir, 5);
    s.crash_after = Some(2);
    optimise(&s).unwrap_err();
    // a crashed (or running) run already has its tables, one history row per generation
    assert_eq!(rows(&dir.join("history.csv")).len(), 1 + 2);
    assert_eq!(rows(&dir.join("pareto.csv"))[0][0], "id");
    let bytes1 = serde_json::from_str::<serde_json::Value>(&read(&dir.join("run.json"))).unwrap()["recording_bytes"].as_u64().unwrap();
    assert!(bytes1 > 0);
    // not on a terminal: one log line per generation
    let o = cli(&["resume", &dir.display().to_string(), "--json"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let log = stderr(&o);
    for g in 3..=5 {
        assert!(log.lines().any(|l| l.starts_with(&format!("generation {g}/5")) && l.contains("evaluations/s") && l.contains("ETA") && l.contains("hypervolume")), "{log}");
    }
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(summary["generations"], 5);
    // totals across processes: the recorded bytes are every shard on disk
    let run: serde_json::Value = serde_json::from_str(&read(&dir.join("run.json"))).unwrap();
    let on_disk: u64 = read_index(&dir.join("recording")).unwrap().iter().map(|e| std::fs::metadata(dir.join("recording").join(&e.file)).unwrap().len()).sum();
    assert_eq!(run["recording_bytes"].as_u64(), Some(on_disk));
    // units and directions in a comment line; the same columns in pareto and population
    let p = read(&dir.join("pareto.csv"));
    assert!(p.starts_with("# gripopt pareto.csv") && p.contains("max_offset [m]") && p.contains("max_offset maximise"), "{p}");
    let (pa, po) = (rows(&dir.join("pareto.csv")), rows(&dir.join("population.csv")));
    assert_eq!(pa[0], po[0]);
    let col = |n: &str| po[0].iter().position(|h| h == n).unwrap();
    for r in &po[1..] {
        // no sentinel: a design not form closed has no max_offset
        if r[col("form_closed")] == "false" {
            assert!(r[col("max_offset")].is_empty(), "{r:?}");
        }
        if !r[col("max_offset")].is_empty() {
            assert!(r[col("max_offset")].parse::<f64>().unwrap() >= 0.0);
        }
    }
    // the archive's hypervolume never falls and is never below the population's
    let h = rows(&dir.join("history.csv"));
    let (hv, ahv) = (h[0].iter().position(|c| c == "hypervolume").unwrap(), h[0].iter().position(|c| c == "archive_hypervolume").unwrap());
    let mut last = 0.0;
    for r in &h[1..] {
        let (a, b): (f64, f64) = (r[hv].parse().unwrap(), r[ahv].parse().unwrap());
        assert!(b >= last && b >= a - 1e-15, "{r:?}");
        last = b;
    }
    // every front member is in the archive or dominated by an archive member
    let a = rows(&dir.join("archive.csv"));
    assert!(a.len() > 1 && pa.len() > 1, "a non-empty front and archive");
    // show: sorted by the objective, best first, each with its replay command
    let o = cli(&["show", &dir.display().to_string(), "--best", "alpha", "--json"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let alphas: Vec<f64> = v["designs"].as_array().unwrap().iter().map(|d| d["alpha"].as_f64().unwrap()).collect();
    assert_eq!(alphas.len(), pa.len() - 1);
    assert!(alphas.windows(2).all(|w| w[0] <= w[1]), "{alphas:?}");
    assert_eq!(v["units"]["mean_force"], "N");
    assert!(v["designs"][0]["replay"].as_str().unwrap().starts_with("gripopt replay "));
    let o = cli(&["show", &dir.display().to_string(), "--best", "mean_force"]);
    let t = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(t.contains("higher is better") && t.contains("mean_force N") && t.contains("--design"), "{t}");
    let id = &pa[1][0];
    let o = cli(&["show", &dir.display().to_string(), "--design", id]);
    assert_eq!(code(&o), 0);
    assert!(String::from_utf8_lossy(&o.stdout).contains(&format!("--design {id}")));
}

/// `gripopt bench … --json`: the figures as one JSON object on stdout (the text report on
/// stderr), with the discard counts adding up to the designs drawn.
#[test]
fn bench_json_summaries() {
    let bin = env!("CARGO_BIN_EXE_gripopt");
    let problem = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml");
    let out = std::process::Command::new(bin).args(["bench", "static", problem, "--n", "200", "--json"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON object");
    let discarded: u64 = v["discarded_by_stage"].as_array().unwrap().iter().map(|c| c.as_u64().unwrap()).sum();
    assert_eq!(discarded + v["passed_stage_2"].as_u64().unwrap(), 200, "{v}");
    assert!(v["designs_per_s_min_time"].as_f64().unwrap() > 0.0);
    assert!(String::from_utf8_lossy(&out.stderr).contains("static pipeline"));
}

/// `gripopt bench replay --out DIR` never deletes a folder it did not write itself.
#[test]
fn bench_replay_refuses_to_clear_a_folder_it_did_not_write() {
    let bin = env!("CARGO_BIN_EXE_gripopt");
    let problem = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml");
    let dir = tmp("bench-replay-guard");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("precious.csv"), "keep me").unwrap();
    let out = std::process::Command::new(bin).args(["bench", "replay", problem, "--designs", "10", "--out"]).arg(&dir).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a synthetic run"));
    assert_eq!(std::fs::read_to_string(dir.join("precious.csv")).unwrap(), "keep me");
}

/// Too few designs per thread draw a note on stderr (the run still succeeds, and its
/// results do not depend on the thread count); enough designs per thread draw none.
#[test]
fn few_designs_per_thread_draw_a_note() {
    let (a, b) = (tmp("note-few"), tmp("note-enough"));
    let few = cli(&["optimise", PROBLEM, "--pop", "8", "--generations", "1", "--threads", "4", "--record", "none", "--out", a.to_str().unwrap()]);
    assert_eq!(code(&few), 0, "{}", stderr(&few));
    assert!(stderr(&few).contains("a population of 8 on 4 threads is 2.0 designs per thread"), "{}", stderr(&few));
    // a bad value is refused first, without the note
    let bad = cli(&["optimise", PROBLEM, "--pop", "2", "--generations", "1", "--threads", "4", "--out", tmp("note-bad").to_str().unwrap()]);
    assert_eq!(code(&bad), 2, "{}", stderr(&bad));
    assert!(!stderr(&bad).contains("designs per thread"), "{}", stderr(&bad));
    let enough = cli(&["optimise", PROBLEM, "--pop", "8", "--generations", "1", "--threads", "2", "--record", "none", "--out", b.to_str().unwrap()]);
    assert_eq!(code(&enough), 0, "{}", stderr(&enough));
    assert!(!stderr(&enough).contains("designs per thread"), "{}", stderr(&enough));
    assert_eq!(read(&a.join("population.csv")), read(&b.join("population.csv")));
}

/// `bench scaling` names the one flag out of range, with its value and range (exit 2);
/// thread counts have the limit of `optimise --threads` (1024). Nothing is run.
#[test]
fn bench_scaling_names_the_flag_out_of_range() {
    let out = tmp("scaling-flags");
    let o = out.to_str().unwrap();
    for (flag, value, range) in [("--threads", "0", "1 to 1024"), ("--threads", "1025", "1 to 1024"), ("--max-threads", "0", "1 to 1024"), ("--max-threads", "1025", "1 to 1024"), ("--reps", "0", "at least 1"), ("--pop", "0", "at least 4"), ("--generations", "0", "at least 1")] {
        let r = cli(&["bench", "scaling", PROBLEM, flag, value, "--no-record", "--out", o]);
        let e = stderr(&r);
        assert_eq!(code(&r), 2, "{flag} {value}: {e}");
        assert!(e.contains(&format!("{flag} {value}:")) && e.contains(range), "{flag} {value}: {e}");
        // only the offending flag is named
        let others = ["--threads", "--max-threads", "--reps", "--pop", "--generations"].into_iter().filter(|f| *f != flag && !flag.ends_with(&f[2..]) && !f.ends_with(&flag[2..]));
        for f in others {
            assert!(!e.contains(&format!("{f} ")), "{flag} {value} names {f} too: {e}");
        }
        assert!(!out.exists(), "{flag} {value}: the benchmark ran");
    }
}

/// At 1 thread the hardware ceiling is 100 % by definition: not measured, "-" in the text
/// and null in JSON; at 2 threads it is measured (two independent runs' walls).
#[test]
fn bench_scaling_has_no_ceiling_at_one_thread() {
    let out = tmp("scaling-ceiling");
    let r = cli(&["bench", "--json", "scaling", PROBLEM, "--pop", "8", "--generations", "1", "--reps", "1", "--threads", "2", "--no-record", "--out", out.to_str().unwrap()]);
    assert_eq!(code(&r), 0, "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0]["threads"], 1);
    assert!(rows[0]["ceiling_efficiency"].is_null() && rows[0]["of_ceiling"].is_null(), "{}", rows[0]);
    assert_eq!(rows[0]["independent_wall_s"].as_array().map(Vec::len), Some(0), "the 1-thread ceiling was run: {}", rows[0]);
    assert_eq!(rows[1]["threads"], 2);
    assert!(rows[1]["ceiling_efficiency"].as_f64().is_some_and(|c| c > 0.0), "{}", rows[1]);
    assert_eq!(rows[1]["independent_wall_s"].as_array().map(Vec::len), Some(1));
    // the text row at 1 thread: eff 100.0 %, then "-" for ceiling and of ceil.
    let text = stderr(&r);
    let one = text.lines().find(|l| l.trim_start().starts_with("1 ")).unwrap_or_else(|| panic!("{text}"));
    let cells: Vec<&str> = one.split_whitespace().collect();
    assert_eq!(&cells[4..8], &["100.0", "%", "-", "-"], "{one}");
}

/// A small finished run (seed 4: three designs in the final front), without recording.
fn small_front_run(name: &str) -> PathBuf {
    let dir = tmp(name);
    let o = cli(&["optimise", PROBLEM, "--pop", "12", "--generations", "2", "--seed", "4", "--record", "none", "--out", dir.to_str().unwrap()]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    dir
}

/// `show` on a run folder lacking or with damaged files: an error naming the file (and the
/// line of a cut-short row), exit 2, never a half row or "(?, null generations)".
#[test]
fn show_refuses_a_missing_or_damaged_file_naming_it() {
    let dir = small_front_run("show-damaged");
    let d = dir.to_str().unwrap();
    let ok = cli(&["show", d]);
    assert_eq!(code(&ok), 0, "{}", stderr(&ok));
    let pareto = read(&dir.join("pareto.csv"));
    let run_json = read(&dir.join("run.json"));
    let data = pareto.lines().filter(|l| !l.starts_with('#')).count() - 1;
    assert!(data >= 2, "{pareto}");
    // pareto.csv cut in its last row
    std::fs::write(dir.join("pareto.csv"), &pareto[..pareto.len() - 40]).unwrap();
    let last = pareto.lines().count();
    for args in [vec!["show", d], vec!["show", d, "--json"]] {
        let r = cli(&args);
        let e = stderr(&r);
        assert_eq!(code(&r), 2, "{args:?}: {e}\n{}", String::from_utf8_lossy(&r.stdout));
        assert!(e.contains("pareto.csv") && e.contains(&format!("line {last}")), "{args:?}: {e}");
    }
    // pareto.csv missing
    std::fs::remove_file(dir.join("pareto.csv")).unwrap();
    let r = cli(&["show", d]);
    assert_eq!(code(&r), 2, "{}", stderr(&r));
    assert!(stderr(&r).contains("pareto.csv"), "{}", stderr(&r));
    std::fs::write(dir.join("pareto.csv"), &pareto).unwrap();
    // run.json not JSON, or JSON without the run's status
    for bad in [&run_json[..run_json.len() / 2], "[]", ""] {
        std::fs::write(dir.join("run.json"), bad).unwrap();
        let r = cli(&["show", d]);
        let out = String::from_utf8_lossy(&r.stdout).to_string();
        assert_eq!(code(&r), 2, "{bad:?}: {}\n{out}", stderr(&r));
        assert!(stderr(&r).contains("run.json") && !out.contains("null generations"), "{bad:?}: {}", stderr(&r));
    }
    std::fs::write(dir.join("run.json"), &run_json).unwrap();
    let again = cli(&["show", d]);
    assert_eq!((code(&again), again.stdout), (0, ok.stdout));
}

/// `show --best OBJ` puts designs without that value last, whether the objective is
/// maximised (max_offset) or minimised (t_stab), and breaks ties by numeric id.
#[test]
fn show_puts_missing_values_last() {
    let dir = small_front_run("show-missing");
    let d = dir.to_str().unwrap();
    // blank max_offset and t_stab of the front's first design
    let path = dir.join("pareto.csv");
    let text = read(&path);
    let header = text.lines().find(|l| l.starts_with("id,")).unwrap().split(',').map(str::to_string).collect::<Vec<_>>();
    let (mo, ts) = (header.iter().position(|c| c == "max_offset").unwrap(), header.iter().position(|c| c == "t_stab").unwrap());
    let mut blanked = None;
    let lines: Vec<String> = text
        .lines()
        .map(|l| {
            if blanked.is_none() && !l.starts_with('#') && !l.starts_with("id,") {
                let mut c: Vec<&str> = l.split(',').collect();
                blanked = Some(c[0].to_string());
                c[mo] = "";
                c[ts] = "";
                return c.join(",");
            }
            l.to_string()
        })
        .collect();
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    let id = blanked.expect("a front row");
    for best in ["max_offset", "t_stab"] {
        let r = cli(&["show", d, "--best", best, "--json"]);
        assert_eq!(code(&r), 0, "{}", stderr(&r));
        let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
        let designs = v["designs"].as_array().unwrap_or_else(|| panic!("{v}"));
        assert!(designs.len() >= 2, "{v}");
        // every design without the value comes after every design with one
        let has: Vec<bool> = designs.iter().map(|x| x[best].is_number()).collect();
        assert!(has.windows(2).all(|w| w[0] || !w[1]), "--best {best}: {has:?}");
        assert!(has.iter().any(|h| *h) && !has[has.len() - 1], "--best {best}: {has:?}");
        assert!(designs.iter().any(|x| x["id"].to_string().trim_matches('"') == id), "{v}");
    }
}

/// A run folder for damaged recordings, outside `target/mcap-check` (whose MCAP files
/// `make test` checks with the independent reader).
fn scratch(name: &str) -> PathBuf {
    let d = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/target/damaged-recordings")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(d.parent().unwrap()).unwrap();
    d
}

/// Invert every `step`-th byte of `path` from `from` on (`from` < 0: counted from the end).
fn flip(path: &Path, from: i64, step: usize) {
    let mut b = std::fs::read(path).unwrap();
    let start = if from < 0 { b.len() - (-from) as usize } else { from as usize };
    for i in (start..b.len()).step_by(step) {
        b[i] ^= 0xFF;
    }
    std::fs::write(path, b).unwrap();
}

/// One line on stderr that names `file`, without the mcap crate's backtrace block, ANSI
/// colours or source paths.
#[track_caller]
fn clean_error(o: &Output, file: &str) {
    let e = stderr(o);
    assert!(e.trim_end().lines().count() == 1 && e.contains(file), "{e}");
    assert!(!e.contains("Backtrace") && !e.contains('\u{1b}') && !e.contains(".cargo") && !e.contains("records.rs"), "{e}");
}

#[test]
fn a_damaged_shard_is_an_input_error_on_one_clean_line() {
    let dir = scratch("replay");
    optimise(&spec(&dir, 3)).unwrap();
    let rdir = dir.join("recording");
    let g2 = read_index(&rdir).unwrap()[1].clone();
    let shard = rdir.join(&g2.file);
    let pristine = std::fs::read(&shard).unwrap();
    let d = dir.display().to_string();
    let replay = |id: u64| cli(&["replay", &d, "--design", &id.to_string()]);
    // the summary damaged (the last 2 KiB, every 7th byte), or the file cut in half
    flip(&shard, -2048, 7);
    let o = replay(g2.first_id);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    clean_error(&o, &g2.file);
    std::fs::write(&shard, &pristine[..pristine.len() / 2]).unwrap();
    let o = replay(g2.first_id);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    clean_error(&o, &g2.file);
    // a chunk whose uncompressed size field says 2^63 - 1 bytes (the reader used to
    // allocate that, a panic): the chunk index gives the true size
    let buf = pristine.clone();
    let summary = mcap::Summary::read(&buf).unwrap().unwrap();
    let epoch_ns = summary.chunk_indexes.iter().map(|c| c.message_start_time).min().unwrap() - g2.first_id * 1_000_000_000;
    let ci = summary.chunk_indexes.iter().find(|c| c.message_start_time >= epoch_ns + g2.first_id * 1_000_000_000).unwrap();
    let at = ci.chunk_start_offset as usize + 25;
    assert_eq!(u64::from_le_bytes(buf[at..at + 8].try_into().unwrap()), ci.uncompressed_size, "chunk record layout");
    let mut bad = buf.clone();
    bad[at..at + 8].copy_from_slice(&(i64::MAX as u64).to_le_bytes());
    std::fs::write(&shard, &bad).unwrap();
    let o = replay(g2.first_id);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    clean_error(&o, &g2.file);
    assert!(stderr(&o).contains("uncompressed size"), "{}", stderr(&o));
    // bytes inverted every 3 KiB (the tester's damage): each design is an input error or
    // replays, never a panic or a backtrace
    std::fs::write(&shard, &pristine).unwrap();
    flip(&shard, 1000, 3072);
    for id in g2.first_id..=g2.last_id {
        let o = replay(id);
        assert!([0, 2, 3].contains(&code(&o)), "design {id}: exit {}: {}", code(&o), stderr(&o));
        if code(&o) == 2 {
            clean_error(&o, &g2.file);
        }
    }
}

/// Every file under `dir` with its content, sorted by name.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir).unwrap().flatten().filter(|f| f.path().is_file()).map(|f| (f.file_name().to_string_lossy().to_string(), std::fs::read(f.path()).unwrap())).collect();
    v.sort();
    v
}

#[test]
fn a_missing_index_and_an_unreadable_shard_stop_a_resume_and_a_moved_shard_is_named() {
    let dir = scratch("resume");
    optimise(&spec(&dir, 3)).unwrap();
    let rdir = dir.join("recording");
    let original = read_index(&rdir).unwrap();
    let g2 = original[1].clone();
    flip(&rdir.join(&g2.file), -2048, 7); // its summary and metadata unreadable
    std::fs::remove_file(rdir.join("index.jsonl")).unwrap();
    // leftovers a successful recovery removes: they must stay when it refuses
    std::fs::write(rdir.join("gen-00004.mcap"), b"partial").unwrap();
    std::fs::write(rdir.join("gen-00004.mcap.tmp"), b"partial").unwrap();
    let (rec_before, cp_before) = (snapshot(&rdir), std::fs::read(dir.join("checkpoint.json")).unwrap());
    let run_before = std::fs::read(dir.join("run.json")).unwrap();
    let e = recover(&rdir, 3).unwrap_err();
    assert!(e.is_input() && e.to_string().contains(&g2.file) && e.to_string().contains("restore"), "{e}");
    let o = cli(&["resume", &dir.display().to_string(), "--generations", "4"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    clean_error(&o, &g2.file);
    assert!(stderr(&o).contains("index cannot be rebuilt"), "{}", stderr(&o));
    assert!(snapshot(&rdir) == rec_before, "the recording folder was changed");
    assert!(std::fs::read(dir.join("checkpoint.json")).unwrap() == cp_before, "the checkpoint was changed");
    assert!(std::fs::read(dir.join("run.json")).unwrap() == run_before, "run.json was changed by a refused resume");
    // the shard moved away: the resume goes on, the generation is reported missing, and
    // replay names it for its ids instead of a range that contains them
    std::fs::rename(rdir.join(&g2.file), dir.join("moved-away.mcap")).unwrap();
    let r = recover(&rdir, 3).unwrap();
    assert_eq!(r.missing, vec![2]);
    assert!(r.warnings(&rdir).iter().any(|w| w.contains("generation 2") && w.contains(&g2.file)), "{:?}", r.warnings(&rdir));
    resume(&dir, Some(4), false, Some(2), false).unwrap();
    let gens: Vec<u64> = read_index(&rdir).unwrap().iter().map(|e| e.generation).collect();
    assert_eq!(gens, vec![1, 3, 4]);
    let e = gripopt::record::read_design(&dir, (g2.first_id + g2.last_id) / 2).unwrap_err().to_string();
    assert!(e.contains("generation 2") && e.contains(&g2.file) && e.contains(&format!("{}..={}", g2.first_id, g2.last_id)), "{e}");
    let o = cli(&["replay", &dir.display().to_string(), "--design", &g2.first_id.to_string()]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(!stderr(&o).contains(&format!("0..={}", read_index(&rdir).unwrap().last().unwrap().last_id)), "{}", stderr(&o));
}
