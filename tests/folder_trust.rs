//! Run folders put together by hand (s31 hostile-user pass): run.json restored beside a
//! newer checkpoint is refused, never taken for the run's state; the CSV views keep up with
//! a persister that is behind; ctrl-c during a resume with nothing to do leaves a finished
//! run finished; `show` takes the designs from the checkpoint, not from a view copied in or
//! edited; a run recorded with `--record none` is shown and exported from its checkpoint; a
//! `.lock` that is a link is never written through.

use crate::common::folder_bytes;
use crate::robustness::{cli, code, read, stderr, tmp, PROBLEM};
use gripopt::run::{optimise, resume, resume_with, RunHooks, RunSpec};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

fn out(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string()
}

fn spec(out: &Path, generations: u64, record: bool) -> RunSpec {
    let mut s = crate::common::bottle_spec(out, generations, 5, 1);
    if !record {
        s.record = gripopt::record::RecordOptions::none();
    }
    s
}

/// Finding 1: `optimise b5 (5 generations); cp -a b5 w; resume w --generations 10; cp
/// b5/run.json w/`: `resume` and `verify` refuse, naming run.json and checkpoint.json, and
/// change no file; `show` says so. A run.json one generation behind a checkpoint of a run
/// killed between the two writes is the run's own and resumes.
#[test]
fn an_older_run_json_beside_a_newer_checkpoint_is_refused() {
    let (b5, w) = (tmp("trust-b5"), tmp("trust-w"));
    optimise(&spec(&b5, 5, true)).unwrap();
    crate::common::copy_dir(&b5, &w);
    resume(&w, Some(10), false, Some(1)).unwrap();
    std::fs::copy(b5.join("run.json"), w.join("run.json")).unwrap();
    let before = folder_bytes(&w);
    let d = w.display().to_string();
    for args in [vec!["resume", &d, "--generations", "12"], vec!["verify", &d, "--record", "none"]] {
        let o = cli(&args);
        let e = stderr(&o);
        assert_eq!(code(&o), 2, "{args:?}: {e}");
        assert!(e.contains("run.json") && e.contains("does not match checkpoint.json"), "{args:?}: {e}");
        assert!(e.contains("generation 10"), "{args:?}: {e}");
    }
    assert!(folder_bytes(&w) == before, "a refused resume or verify changes no file");
    let s = out(&cli(&["show", &d]));
    assert!(s.contains("run.json does not match checkpoint.json"), "{s}");
    // run.json one generation behind, status running (killed between checkpoint 10 and its
    // run.json): the run's own, resumed
    let mut v: serde_json::Value = serde_json::from_str(&read(&w.join("run.json"))).unwrap();
    v["generations"] = 10.into();
    v["completed_generations"] = 9.into();
    v["status"] = "running".into();
    std::fs::write(w.join("run.json"), serde_json::to_string_pretty(&v).unwrap()).unwrap();
    assert!(!out(&cli(&["show", &d])).contains("does not match"));
    let r = resume(&w, Some(11), false, Some(1)).unwrap();
    assert_eq!(r.generations, 11);
}

/// Finding 2: a persister that is behind (every commit slow, the next generation always
/// queued) still rewrites the views at least every 250 ms, not only at the end.
#[test]
fn the_views_keep_up_with_a_persister_that_is_behind() {
    use argmin::core::observers::Observe;
    use gripopt::run::{Archive, Checkpoint, CheckpointSpec, GripperInfo, OutputsObserver, PersistHooks, Persister};
    let src = tmp("trust-views-src");
    optimise(&spec(&src, 2, false)).unwrap();
    let cp = Checkpoint::<GripperInfo>::load(&src.join("checkpoint.json")).unwrap();
    let dir = tmp("trust-views");
    std::fs::create_dir_all(&dir).unwrap();
    let archive = Arc::new(std::sync::Mutex::new(Archive::default()));
    let outputs = OutputsObserver { out: dir.clone(), settings: cp.settings.clone(), archive };
    let ckpt = CheckpointSpec {
        path: dir.join("checkpoint.json"),
        problem_hash: cp.problem_hash.clone(),
        settings: cp.settings.clone(),
        options: cp.options.clone(),
        wall_before: 0.0,
        start: std::time::Instant::now(),
    };
    let slow = move |_: &gripopt::run::Committed| -> gripopt::Result<()> {
        std::thread::sleep(std::time::Duration::from_millis(60));
        Ok(())
    };
    let hooks = PersistHooks { on_commit: Some(Box::new(slow)), ..Default::default() };
    let mut p = Persister::start_with(Some(outputs), None, ckpt, 1, hooks).unwrap();
    let generations = 30;
    let mut st = cp.state.clone();
    let (hv, fe) = (st.hv_history[0], st.feasible_history[0]);
    for g in 1..=generations {
        st.generation = g;
        st.hv_history = vec![hv; g as usize];
        st.feasible_history = vec![fe; g as usize];
        p.observe_iter(&st, &argmin::core::KV::new()).unwrap();
    }
    // history.csv as the run goes on (before the final views): close to the last generation
    let history = crate::robustness::rows(&dir.join("history.csv"));
    let shown = history.len() as u64 - 1;
    let stats = p.finish_with(false).unwrap();
    assert!(stats.views_written >= 3, "{stats:?}");
    assert!(shown + 10 >= generations, "history.csv shows {shown} of {generations} generations; {stats:?}");
}

/// Finding 3: ctrl-c during a resume of a finished run with nothing left to do: still
/// finished, not interrupted.
#[test]
fn ctrl_c_during_a_resume_with_nothing_to_do_leaves_the_run_finished() {
    let dir = tmp("trust-noop");
    optimise(&spec(&dir, 2, false)).unwrap();
    let hooks = RunHooks { stop: Some(Arc::new(AtomicBool::new(true))), ..Default::default() };
    let s = resume_with(&dir, None, false, Some(1), hooks).unwrap();
    assert!(!s.interrupted);
    let v: serde_json::Value = serde_json::from_str(&read(&dir.join("run.json"))).unwrap();
    assert_eq!(v["status"], "finished", "{v}");
}

/// Finding 4: `show` takes the front from the checkpoint: an older pareto.csv copied in, or
/// a value edited by hand, is not shown as the run's, and `show` says the view differs.
#[test]
fn show_takes_the_designs_from_the_checkpoint_not_from_pareto_csv() {
    let (old, dir) = (tmp("trust-show-old"), tmp("trust-show"));
    // population 16, seed 5: 3 designs on the front after 5 generations, 5 after 6
    let sixteen = |d: &Path, g| RunSpec { pop: 16, ..spec(d, g, false) };
    optimise(&sixteen(&old, 5)).unwrap();
    optimise(&sixteen(&dir, 6)).unwrap();
    let d = dir.display().to_string();
    let json = |args: &[&str]| -> serde_json::Value { serde_json::from_slice(&cli(args).stdout).unwrap() };
    let truth = json(&["show", &d, "--json"]);
    let pareto = read(&dir.join("pareto.csv"));
    // an older pareto.csv copied in
    std::fs::copy(old.join("pareto.csv"), dir.join("pareto.csv")).unwrap();
    assert_ne!(read(&dir.join("pareto.csv")), pareto, "the test needs another front");
    let shown = json(&["show", &d, "--json"]);
    assert_eq!(shown["designs"], truth["designs"]);
    assert!(shown["warnings"][0].as_str().unwrap().contains("pareto.csv does not hold"), "{shown}");
    assert!(out(&cli(&["show", &d])).contains("pareto.csv does not hold the designs of checkpoint.json"));
    // a value edited by hand: the design's values are the evaluated ones
    let first = pareto.lines().filter(|l| !l.starts_with('#')).nth(1).unwrap();
    let id = first.split(',').next().unwrap().to_string();
    let cells: Vec<&str> = first.split(',').collect();
    let edited = first.replacen(cells[7], "0.123", 1);
    std::fs::write(dir.join("pareto.csv"), pareto.replacen(first, &edited, 1)).unwrap();
    let one = json(&["show", &d, "--design", &id, "--json"]);
    let original: f64 = cells[7].parse().unwrap();
    assert_eq!(one["l21"]["value"].as_f64(), Some(original), "{one}");
    assert_eq!(json(&["show", &d, "--json"])["designs"], truth["designs"]);
    assert_eq!(truth["warnings"], serde_json::json!([]), "{truth}");
}

/// Finding 5: a run with `--record none`: no layout is written, `show` offers no replay
/// command, and `export` writes a design of the checkpoint (the message for one not there says the run was not
/// recorded).
#[test]
fn a_run_without_recording_is_shown_and_exported_from_its_checkpoint() {
    let dir = tmp("trust-norec");
    optimise(&spec(&dir, 2, false)).unwrap();
    // no recording, so no layout naming channels that no file has
    assert!(!dir.join("foxglove-layout.json").exists() && !dir.join("recording").exists());
    let d = dir.display().to_string();
    let s = out(&cli(&["show", &d]));
    assert!(!s.contains("gripopt replay") && s.contains("--record none"), "{s}");
    let v: serde_json::Value = serde_json::from_slice(&cli(&["show", &d, "--json"]).stdout).unwrap();
    assert!(v["designs"].as_array().unwrap().iter().all(|r| r["replay"].is_null()), "{v}");
    let folder = gripopt::RunFolder::open(&dir).unwrap();
    let (pop, archive) = (folder.population().unwrap(), folder.archive().unwrap());
    let id = pop[0].id.to_string();
    let o = cli(&["export", &d, "--design", &id, "--format", "json", "--out", "-"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let sheet: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let (l21, psi) = (pop[0].design.to_array()[0], pop[0].design.to_array()[5]);
    let got = (sheet["design"]["l21_mm"].as_f64().unwrap(), sheet["design"]["psi_deg"].as_f64().unwrap());
    assert!((got.0 - l21 * 1e3).abs() < 1e-9 && (got.1 - psi).abs() < 1e-9, "{got:?} vs {l21} m, {psi}°");
    // a design the checkpoint no longer holds (generation 1's, replaced)
    let kept = |i: u64| pop.iter().chain(&archive).any(|r| r.id == i);
    let gone = (0..24u64).find(|i| !kept(*i)).unwrap().to_string();
    let o = cli(&["export", &d, "--design", &gone, "--format", "json", "--out", "-"]);
    assert_eq!(code(&o), 2);
    assert!(stderr(&o).contains("not recorded") && !stderr(&o).contains("was the run started"), "{}", stderr(&o));
}

/// Finding 6: a `.lock` that is a symbolic link is refused, and the file it points to is
/// never written.
#[test]
fn a_lock_file_that_is_a_link_is_never_written_through() {
    let dir = tmp("trust-link");
    optimise(&spec(&dir, 1, false)).unwrap();
    let victim = dir.with_extension("victim.txt");
    std::fs::write(&victim, "precious\n").unwrap();
    std::os::unix::fs::symlink(&victim, dir.join(".lock")).unwrap();
    let o = cli(&["resume", &dir.display().to_string(), "--generations", "2"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains(".lock") && stderr(&o).contains("symbolic link"), "{}", stderr(&o));
    assert_eq!(read(&victim), "precious\n");
    assert!(std::fs::symlink_metadata(dir.join(".lock")).unwrap().file_type().is_symlink());
}

/// A library caller's `optimise` into a path that is a file is refused naming it as a file,
/// and the file is kept (it used to fail with the OS's "File exists").
#[test]
fn optimise_into_a_file_is_refused_as_a_file() {
    let dir = tmp("trust-out-file");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("not-a-folder");
    std::fs::write(&file, b"keep").unwrap();
    let e = optimise(&spec(&file, 1, false)).unwrap_err().to_string();
    assert!(e.contains("not-a-folder") && e.contains("is a file, not a folder"), "{e}");
    assert_eq!(std::fs::read(&file).unwrap(), b"keep");
}

// Hostile pass 32: the recording shards a run folder reads are attributed to the run.

/// A run of 3 recorded generations in `name` (seed `seed`): its folder, the folder as a
/// string, and a design id of generation 2.
fn recorded_run(name: &str, seed: u64) -> (PathBuf, String, u64) {
    let dir = tmp(name);
    let mut s = spec(&dir, 3, true);
    s.seed = seed;
    optimise(&s).unwrap();
    let g2 = gripopt::record::read_index(&dir.join("recording")).unwrap()[1].clone();
    assert_eq!(g2.file, "gen-00002.mcap");
    let d = dir.display().to_string();
    (dir, d, g2.first_id)
}

/// Another program's MCAP (a ROS-style `/chatter` recording, no gripopt.run metadata) at
/// `path`; its bytes.
fn foreign_mcap(path: &Path) -> Vec<u8> {
    let mut w = mcap::Writer::new(std::io::Cursor::new(Vec::new())).unwrap();
    let ch = w.add_channel(0, "/chatter", "json", &BTreeMap::new()).unwrap();
    for k in 0..5u32 {
        let t = 1_700_000_000_000_000_000 + u64::from(k) * 1_000_000;
        let h = mcap::records::MessageHeader { channel_id: ch, sequence: k, log_time: t, publish_time: t };
        w.write_to_known_channel(&h, br#"{"data":"hello"}"#).unwrap();
    }
    w.finish().unwrap();
    let bytes = w.into_inner().into_inner();
    std::fs::write(path, &bytes).unwrap();
    bytes
}

/// Finding 1: a shard copied from run B into run A, or an index line naming B's shard by a
/// path out of A's recording folder, is never read as A's design: the library, `replay` and
/// `export` refuse it (exit 2), naming the file.
#[test]
fn a_shard_of_another_run_is_never_read_as_this_runs_design() {
    let (a, da, id) = recorded_run("trust-shard-a", 5);
    let (b, _, _) = recorded_run("trust-shard-b", 6);
    let (ra, rb) = (a.join("recording"), b.join("recording"));
    let ours = std::fs::read(ra.join("gen-00002.mcap")).unwrap();
    assert!(gripopt::record::read_design(&a, id).is_ok());
    let refused = |what: &str, file: &str| {
        let e = gripopt::record::read_design(&a, id).unwrap_err();
        assert!(e.is_input() && e.to_string().contains(file) && e.to_string().contains(what), "{e}");
        for args in [
            vec!["replay", &da, "--design", &id.to_string()],
            vec!["export", &da, "--design", &id.to_string(), "--format", "json", "--out", "-"],
        ] {
            let o = cli(&args);
            assert_eq!(code(&o), 2, "{args:?}: {}", stderr(&o));
            assert!(stderr(&o).contains(file) && stderr(&o).contains(what), "{args:?}: {}", stderr(&o));
            assert!(o.stdout.is_empty(), "{args:?}: another run's design written");
        }
    };
    std::fs::copy(rb.join("gen-00002.mcap"), ra.join("gen-00002.mcap")).unwrap();
    refused("written by another run", "gen-00002.mcap");
    // without a readable run.json (missing, cut short, no run id) the shard is not
    // attributed: the library refuses too, naming run.json, as replay and export do
    let run_json = std::fs::read(a.join("run.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_slice(&run_json).unwrap();
    v["run_id"] = serde_json::Value::Null;
    let null_id = serde_json::to_string_pretty(&v).unwrap();
    for damaged in [None, Some(run_json[..100].to_vec()), Some(null_id.into_bytes())] {
        match damaged {
            None => std::fs::remove_file(a.join("run.json")).unwrap(),
            Some(bytes) => std::fs::write(a.join("run.json"), bytes).unwrap(),
        }
        let e = gripopt::record::read_design(&a, id).unwrap_err();
        assert!(e.is_input() && e.to_string().contains("run.json"), "{e}");
        let e = gripopt::run::RunFolder::open(&a).unwrap().design(id).unwrap_err();
        assert!(e.to_string().contains("run.json"), "{e}");
    }
    std::fs::write(a.join("run.json"), &run_json).unwrap();
    // A's own shard back, and its index line pointing at B's shard (relative and absolute)
    std::fs::write(ra.join("gen-00002.mcap"), &ours).unwrap();
    let index = std::fs::read_to_string(ra.join("index.jsonl")).unwrap();
    let rel = format!("../../{}/recording/gen-00002.mcap", b.file_name().unwrap().to_string_lossy());
    let abs = rb.join("gen-00002.mcap").display().to_string();
    for path in [rel, abs] {
        let edited = index.replace("\"file\":\"gen-00002.mcap\"", &format!("\"file\":{}", serde_json::json!(path)));
        assert_ne!(edited, index);
        std::fs::write(ra.join("index.jsonl"), edited).unwrap();
        refused("never followed", "index.jsonl");
    }
    std::fs::write(ra.join("index.jsonl"), index).unwrap();
    assert!(gripopt::record::read_design(&a, id).is_ok());
}

/// Finding 2: when `resume` rebuilds a missing index, another program's MCAP lying as a
/// covered shard is not indexed as the run's: the resume stops (exit 2) naming it, as for
/// a shard of another run, and changes nothing; with the index intact, the same.
#[test]
fn resume_never_indexes_an_mcap_another_program_wrote() {
    let (dir, d, _) = recorded_run("trust-foreign-covered", 5);
    let rdir = dir.join("recording");
    foreign_mcap(&rdir.join("gen-00002.mcap"));
    for drop_index in [false, true] {
        if drop_index {
            std::fs::remove_file(rdir.join("index.jsonl")).unwrap();
        }
        let before = folder_bytes(&dir);
        let o = cli(&["resume", &d, "--generations", "4"]);
        assert_eq!(code(&o), 2, "{}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains("gen-00002.mcap") && e.contains("written by another run") && e.contains("gripopt.run"),
            "{e}"
        );
        assert!(folder_bytes(&dir) == before, "a refused resume changed the folder");
    }
    // the foreign file out of the folders tools/check_mcap.py reads
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Finding 3: a file of another program named like a shard after the checkpoint is set
/// aside with a warning, as a shard of another run is, never overwritten.
#[test]
fn resume_sets_aside_a_foreign_file_named_like_a_later_shard() {
    let (dir, d, _) = recorded_run("trust-foreign-later", 5);
    let rdir = dir.join("recording");
    let theirs = foreign_mcap(&rdir.join("gen-00004.mcap"));
    let o = cli(&["resume", &d, "--generations", "4"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(stderr(&o).contains("set aside as set-aside/gen-00004.mcap"), "{}", stderr(&o));
    assert!(std::fs::read(rdir.join("set-aside/gen-00004.mcap")).unwrap() == theirs, "the user's file was changed");
    let g4 = gripopt::record::read_index(&rdir).unwrap()[3].clone();
    assert!(g4.generation == 4 && g4.file == "gen-00004.mcap", "{g4:?}");
    assert!(gripopt::record::read_design(&dir, g4.first_id).is_ok());
    // the foreign file out of the folders tools/check_mcap.py reads
    std::fs::remove_dir_all(rdir.join("set-aside")).unwrap();
}

/// `gripopt ARGS…`, killed (and the test failed) if it runs for more than 60 s.
fn cli_within_a_minute(args: &[&str]) -> std::process::Output {
    let mut child = std::process::Command::new(crate::robustness::BIN)
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed().as_secs() > 60 {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("{args:?} still waits after 60 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    child.wait_with_output().unwrap()
}

/// Finding 10: a folder or a FIFO where a shard should be is refused (exit 2, "not a
/// regular file", naming it) by `replay` and by a `resume` that rebuilds the index, never
/// mapped (exit 1) or waited on forever.
#[test]
fn a_shard_that_is_not_a_regular_file_is_refused_not_mapped_or_waited_on() {
    let (dir, d, id) = recorded_run("trust-not-a-file", 5);
    let shard = dir.join("recording/gen-00002.mcap");
    let index = std::fs::read(dir.join("recording/index.jsonl")).unwrap();
    for kind in ["folder", "fifo"] {
        std::fs::write(dir.join("recording/index.jsonl"), &index).unwrap();
        std::fs::remove_file(&shard).or_else(|_| std::fs::remove_dir(&shard)).unwrap();
        if kind == "folder" {
            std::fs::create_dir(&shard).unwrap();
        } else {
            assert!(std::process::Command::new("mkfifo").arg(&shard).status().unwrap().success());
        }
        let o = cli_within_a_minute(&["replay", &d, "--design", &id.to_string()]);
        assert_eq!(code(&o), 2, "{kind}: {}", stderr(&o));
        assert!(stderr(&o).contains("not a regular file") && stderr(&o).contains("gen-00002.mcap"), "{}", stderr(&o));
        std::fs::remove_file(dir.join("recording/index.jsonl")).unwrap();
        let o = cli_within_a_minute(&["resume", &d, "--generations", "4"]);
        assert_eq!(code(&o), 2, "{kind}: {}", stderr(&o));
        assert!(stderr(&o).contains("not a regular file") && stderr(&o).contains("gen-00002.mcap"), "{}", stderr(&o));
    }
    // a FIFO would block tools/check_mcap.py, which reads every *.mcap the tests leave
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Finding 5: with the index intact, a covered shard whose metadata record is damaged stops
/// the resume (exit 2, naming it; nothing changed), as docs/cli.md says.
#[test]
fn resume_stops_on_a_covered_shard_with_damaged_metadata_even_when_indexed() {
    let (dir, d, _) = recorded_run("trust-damaged-meta", 5);
    let shard = dir.join("recording/gen-00002.mcap");
    let mut bytes = std::fs::read(&shard).unwrap();
    let summary = mcap::Summary::read(&bytes).unwrap().unwrap();
    let meta = summary.metadata_indexes.iter().find(|m| m.name == "gripopt.run").unwrap();
    // the record's name and contents (after its opcode and length) inverted
    for b in &mut bytes[meta.offset as usize + 9..(meta.offset + meta.length) as usize] {
        *b ^= 0xFF;
    }
    std::fs::write(&shard, bytes).unwrap();
    let before = folder_bytes(&dir);
    let o = cli(&["resume", &d, "--generations", "4"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("gen-00002.mcap") && stderr(&o).contains("metadata"), "{}", stderr(&o));
    assert!(folder_bytes(&dir) == before, "a refused resume changed the folder");
    // the damaged shard out of the folders tools/check_mcap.py reads
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every file and symbolic link under `dir` with its bytes (links: their target's name).
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut m = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        let meta = std::fs::symlink_metadata(&p).unwrap();
        if meta.file_type().is_symlink() {
            m.insert(p.clone(), std::fs::read_link(&p).unwrap().to_string_lossy().as_bytes().to_vec());
        } else if meta.is_dir() {
            m.extend(snapshot(&p));
        } else if e.file_name() != ".lock" {
            m.insert(p.clone(), std::fs::read(&p).unwrap());
        }
    }
    m
}

/// Issue 44 class 1: a symbolic link at a file `resume` rewrites (the plot
/// pareto_matrix.svg) made it write through the link into the file it names, outside the
/// folder; a hard link (a file another name shares, as in a `cp -al` backup) had its
/// content rewritten in both places. Now every file goes through one atomic, link-refusing
/// write, and the run refuses before any work (exit 2, naming the file): the folder, the
/// link's target and the backup keep every byte.
#[test]
fn a_link_at_a_file_the_run_rewrites_is_refused_before_any_work() {
    let base = tmp("i44-links");
    let dir = base.join("run");
    std::fs::create_dir_all(&base).unwrap();
    optimise(&spec(&dir, 2, false)).unwrap();
    let d = dir.display().to_string();
    let victim = base.join("victim.svg");
    for (file, link) in [("pareto_matrix.svg", "symbolic"), ("hypervolume.svg", "hard"), ("pareto.csv", "hard")] {
        std::fs::write(&victim, "the user's own file").unwrap();
        let p = dir.join(file);
        std::fs::remove_file(&p).unwrap();
        match link {
            "symbolic" => std::os::unix::fs::symlink(&victim, &p).unwrap(),
            _ => std::fs::hard_link(&victim, &p).unwrap(),
        }
        let before = snapshot(&dir);
        let o = cli(&["resume", &d, "--generations", "3"]);
        let e = stderr(&o);
        assert_eq!(code(&o), 2, "{file} ({link} link): {e}");
        assert!(e.contains(file) && e.contains(if link == "symbolic" { "symbolic link" } else { "2 names" }), "{e}");
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "the user's own file", "{file}: written through");
        assert!(snapshot(&dir) == before, "{file}: the refused resume changed the folder");
        std::fs::remove_file(&p).unwrap();
        std::fs::write(&p, "restored").unwrap();
    }
    // a `cp -al` backup: every file of the folder has two names; the run refuses, the
    // backup keeps every byte (it used to see its SVGs and views rewritten)
    let backup = base.join("backup");
    let link_all = |from: &Path, to: &Path| {
        fn walk(from: &Path, to: &Path) {
            std::fs::create_dir_all(to).unwrap();
            for e in std::fs::read_dir(from).unwrap().flatten() {
                if e.path().is_dir() {
                    walk(&e.path(), &to.join(e.file_name()));
                } else {
                    std::fs::hard_link(e.path(), to.join(e.file_name())).unwrap();
                }
            }
        }
        walk(from, to)
    };
    link_all(&dir, &backup);
    let kept = snapshot(&backup);
    let o = cli(&["resume", &d, "--generations", "3"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("names (hard links"), "{}", stderr(&o));
    assert!(snapshot(&backup) == kept, "the backup was changed");
}

/// Issue 44 class 2: `optimise --out` into the folder of a run stopped before its first
/// checkpoint took any gripopt-titled `pareto.csv` there for that run's own and deleted it
/// (another run's table copied in, say). A title line proves nothing: such a file is set
/// aside into `set-aside/` with a note, byte for byte, and the new run starts.
#[test]
fn optimise_sets_aside_a_view_it_cannot_prove_its_own() {
    let dir = tmp("i44-earlier-view");
    // the first checkpoint cannot be written: the run stops before it (run.json stays)
    std::fs::create_dir_all(dir.join(".checkpoint.json.tmp/x")).unwrap();
    assert!(optimise(&spec(&dir, 2, false)).is_err());
    std::fs::remove_dir_all(dir.join(".checkpoint.json.tmp")).unwrap();
    let theirs =
        "# gripopt pareto.csv: the population's feasible non-dominated designs, by id\n# another run's table\nid\n7\n";
    std::fs::write(dir.join("pareto.csv"), theirs).unwrap();
    let d = dir.display().to_string();
    let o = cli(&["optimise", PROBLEM, "--out", &d, "--pop", "8", "--generations", "1", "--record", "none"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert_eq!(read(&dir.join("set-aside/pareto.csv")), theirs, "the earlier table was not kept");
    assert!(stderr(&o).contains("set aside as"), "{}", stderr(&o));
    assert!(read(&dir.join("pareto.csv")).starts_with("# gripopt pareto.csv"));
}

/// Issue 44 class 1: every file gripopt writes goes through one atomic, link-refusing write
/// (src/fsutil/atomic.rs): the run's plots (they were drawn straight into their path, so a
/// link there was written through), a benchmark's tables (the same), and the library's
/// atomic write (it replaced a link) each refuse a symbolic link and a file with a second
/// name (a hard link), naming the file, and leave what the link names as it was.
#[test]
fn every_writer_refuses_a_link_at_its_file() {
    let d = tmp("i44-writers");
    std::fs::create_dir_all(&d).unwrap();
    let victim = d.join("victim.txt");
    type Writer = fn(&Path) -> gripopt::Result<()>;
    let writers: [(&str, Writer); 3] = [
        ("hypervolume plot", |p| gripopt::run::hypervolume(p, &[0.1, 0.2], &[0.1, 0.3], &[0.1, 0.3])),
        ("bench table", |p| gripopt::bench::write_csv(&[], p)),
        ("atomic write", |p| gripopt::write_atomic(p, b"new")),
    ];
    for (what, write) in writers {
        for hard in [false, true] {
            std::fs::write(&victim, "the user's own file").unwrap();
            let out = d.join("out.file");
            let _ = std::fs::remove_file(&out);
            if hard {
                std::fs::hard_link(&victim, &out).unwrap();
            } else {
                std::os::unix::fs::symlink(&victim, &out).unwrap();
            }
            let e = write(&out).expect_err(what).to_string();
            assert!(
                e.contains("out.file") && e.contains(if hard { "2 names" } else { "symbolic link" }),
                "{what}: {e}"
            );
            assert_eq!(std::fs::read_to_string(&victim).unwrap(), "the user's own file", "{what} (hard {hard})");
            assert_eq!(std::fs::read_to_string(&out).unwrap(), "the user's own file", "{what} (hard {hard})");
        }
        // and without a link it writes, leaving no temporary file
        let out = d.join("out.file");
        std::fs::remove_file(&out).unwrap();
        write(&out).unwrap();
        assert!(!d.join(".out.file.tmp").exists());
    }
}
