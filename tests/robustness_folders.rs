//! Run folders that cannot lose or misattribute results (issue 24, items 1–6): a run whose
//! checkpoint is lost is refused, never restarted over its shards; the lock holds against
//! `make run`, a removed or replaced lock file and a folder moved away; archive.json lost or
//! damaged changes nothing; a forced resume keeps each generation's problem; a folder left
//! before the first checkpoint is reused; `show` tells a killed run from a running one.

use crate::robustness::{checkpoint_generation, cli, code, read, spec, stderr, tmp, wait_for, BIN, PROBLEM};
use gripopt::record::read_index;
use gripopt::run::{optimise, resume};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The shard files of a run folder, sorted.
pub(crate) fn shards(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir.join("recording"))
        .map(|rd| {
            rd.flatten()
                .map(|e| e.file_name().to_string_lossy().to_string())
                .filter(|n| n.starts_with("gen-") && n.ends_with(".mcap"))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

pub(crate) fn run_json(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&read(&dir.join("run.json"))).unwrap()
}

pub(crate) fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).to_string()
}

/// `gripopt ARGS` in the background, output discarded but stderr kept.
pub(crate) fn spawn(args: &[&str]) -> Child {
    Command::new(BIN).args(args).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap()
}

/// `gripopt optimise` into folder `d` for 5 000 generations (stopped by the test), in the
/// background.
fn spawn_endless(d: &str) -> Child {
    let args = ["--pop", "16", "--generations", "5000", "--record", "none", "--threads", "1"];
    spawn(&[&["optimise", PROBLEM, "--out", d][..], &args[..]].concat())
}

/// `gripopt ARGS` in the background, output discarded, with the lines of its stderr
/// collected as they come.
pub(crate) fn spawn_collecting(args: &[&str]) -> (Child, Arc<Mutex<Vec<String>>>) {
    let mut child = spawn(args);
    let lines = Arc::new(Mutex::new(Vec::<String>::new()));
    let (l2, err) = (lines.clone(), child.stderr.take().unwrap());
    std::thread::spawn(move || {
        BufReader::new(err).lines().map_while(Result::ok).for_each(|l| l2.lock().unwrap().push(l))
    });
    (child, lines)
}

/// Wait for `child` at most `secs` seconds; its exit code (None: still running).
pub(crate) fn wait_at_most(child: &mut Child, secs: f64) -> Option<i32> {
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs_f64(secs) {
        if let Some(s) = child.try_wait().unwrap() {
            return Some(s.code().unwrap_or(-1));
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    None
}

/// Item 1: a finished run whose checkpoint.json is missing (a backup or sync tool skipped
/// it) is refused by `resume` with a message naming the file, and `optimise --out` into it
/// (or into a folder holding only a recording) is refused: no shard is deleted.
#[test]
fn item1_a_run_without_its_checkpoint_is_refused_never_restarted() {
    let dir = tmp("i1-lost-checkpoint");
    optimise(&spec(&dir, 3)).unwrap();
    let before = shards(&dir);
    assert_eq!(before.len(), 3);
    std::fs::remove_file(dir.join("checkpoint.json")).unwrap();
    let e = resume(&dir, None, false, Some(2)).unwrap_err().to_string();
    assert!(e.contains("checkpoint.json") && e.contains("missing") && e.contains("3 completed generations"), "{e}");
    let d = dir.display().to_string();
    let o = cli(&["optimise", PROBLEM, "--out", &d, "--pop", "8", "--generations", "1"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("checkpoint.json"), "{}", stderr(&o));
    assert_eq!(shards(&dir), before, "no shard deleted");
    // a folder holding only a recording (run.json and the checkpoint lost) is no empty folder
    let bare = tmp("i1-bare-recording");
    std::fs::create_dir_all(bare.join("recording")).unwrap();
    for s in &before {
        std::fs::copy(dir.join("recording").join(s), bare.join("recording").join(s)).unwrap();
    }
    let b = bare.display().to_string();
    let o = cli(&["optimise", PROBLEM, "--out", &b, "--pop", "8", "--generations", "1"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("gen-00001.mcap") || stderr(&o).contains("recording"), "{}", stderr(&o));
    assert_eq!(shards(&bare), before, "no shard deleted");
    let o = cli(&["resume", &b]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("run.json") && stderr(&o).contains("3 shards"), "{}", stderr(&o));
}

/// Item 2: a live run cannot be moved aside by `make run`, nor entered by removing or
/// replacing its lock file; a run whose folder is moved away stops without writing into
/// the folder that replaced it; a clean exit leaves no lock file behind.
#[test]
fn item2_the_lock_holds_against_make_run_a_lost_lock_file_and_a_moved_folder() {
    let dir = tmp("i2-live");
    let d = dir.display().to_string();
    let parent = dir.parent().unwrap();
    let moved_aside = || -> Vec<String> {
        std::fs::read_dir(parent)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().to_string())
            .filter(|n| n.starts_with("robust-i2-live."))
            .collect()
    };
    // folders an earlier test run's failure left aside
    for n in moved_aside() {
        std::fs::remove_dir_all(parent.join(n)).unwrap();
    }
    let mut child = spawn_endless(&d);
    wait_for("the first checkpoint", || checkpoint_generation(&dir) >= 1);
    let make = Command::new("make")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(["-s", "-o", "build", "run", &format!("OUT={d}"), &format!("BIN={BIN}"), "POP=4", "GENERATIONS=1"])
        .output()
        .unwrap();
    let said = format!("{}{}", stdout(&make), stderr(&make));
    assert!(!make.status.success(), "make run into a live run folder must fail: {said}");
    assert!(said.contains("in use"), "{said}");
    assert!(dir.join("run.json").exists() && dir.join("checkpoint.json").exists(), "the live folder stays");
    let moved = moved_aside();
    assert!(moved.is_empty(), "make run moved the live folder aside: {moved:?}");
    // the lock file removed, then replaced by another file: still refused
    let _ = std::fs::remove_file(dir.join(".lock"));
    let o = cli(&["resume", &d]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("in use"), "{}", stderr(&o));
    std::fs::write(dir.join(".lock"), "1\n").unwrap();
    let o = cli(&["optimise", PROBLEM, "--out", &d, "--pop", "8", "--generations", "1"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    // the folder moved away and replaced by a new one: the run stops, the new folder stays empty
    let away = parent.join("robust-i2-away");
    let _ = std::fs::remove_dir_all(&away);
    std::fs::rename(&dir, &away).unwrap();
    std::fs::create_dir_all(&dir).unwrap();
    let rc = wait_at_most(&mut child, 60.0);
    if rc.is_none() {
        child.kill().unwrap();
    }
    let err = {
        use std::io::Read;
        let mut s = String::new();
        child.stderr.take().unwrap().read_to_string(&mut s).unwrap();
        s
    };
    assert_eq!(rc, Some(1), "{err}");
    assert!(err.contains("moved"), "{err}");
    // writes go by path: the CSV views being written at the moment of the move may land
    // in the new folder (docs/cli.md); nothing that makes it look like a run does
    let left: Vec<String> =
        std::fs::read_dir(&dir).unwrap().flatten().map(|e| e.file_name().to_string_lossy().to_string()).collect();
    let runlike = ["run.json", "checkpoint.json", "recording", ".lock", "problem.toml", "foxglove-layout.json"];
    assert!(
        !left.iter().any(|n| runlike.contains(&n.as_str())),
        "the run wrote into the folder that replaced its own: {left:?}"
    );
    // the moved run resumes where it is; its clean end leaves no lock file
    let g = checkpoint_generation(&away);
    let r = resume(&away, Some(g + 1), false, Some(1)).unwrap();
    assert_eq!(r.generations, g + 1);
    assert!(!away.join(".lock").exists(), "a clean exit leaves no lock file");
}

/// Item 3: archive.json missing, emptied or damaged: the resumed run's archive is the
/// uninterrupted run's (it is restored from the checkpoint, never started empty).
#[test]
fn item3_a_lost_or_damaged_archive_json_changes_nothing() {
    // seed 16: from generation 4 on, the archive holds designs the population lost
    let spec16 = |d: &Path, g: u64| crate::common::bottle_spec(d, g, 16, 2);
    let full = tmp("i3-full");
    optimise(&spec16(&full, 7)).unwrap();
    for (case, damage) in
        [("missing", None), ("emptied", Some(r#"{"members":[],"hv_history":[]}"#)), ("garbage", Some("{not json"))]
    {
        let cut = tmp(&format!("i3-{case}"));
        optimise(&spec16(&cut, 4)).unwrap();
        let _ = std::fs::remove_file(cut.join("archive.json"));
        if let Some(t) = damage {
            std::fs::write(cut.join("archive.json"), t).unwrap();
        }
        resume(&cut, Some(7), false, Some(2)).unwrap_or_else(|e| panic!("{case}: {e}"));
        for f in ["archive.csv", "history.csv", "pareto.csv"] {
            assert_eq!(read(&full.join(f)), read(&cut.join(f)), "{case}: {f}");
        }
    }
}

/// Item 4: `resume --force` with a changed problem keeps the earlier problem beside the new
/// one and says which generations each evaluated; every generation's designs replay with
/// their own problem and verify; a hand-edited problem.toml is named by replay (not
/// verified) and refused by verify.
#[test]
fn item4_a_forced_resume_keeps_each_generations_problem() {
    let dir = tmp("i4-forced");
    let d = dir.display().to_string();
    let prob = tmp("i4-problem").with_extension("toml");
    let a = read(Path::new(PROBLEM));
    std::fs::write(&prob, &a).unwrap();
    let mut s = spec(&dir, 3);
    s.problem_path = prob.clone();
    optimise(&s).unwrap();
    let tau = a.lines().find(|l| l.trim_start().starts_with("tau")).unwrap();
    let b = a.replacen(tau, "tau = 0.55", 1);
    std::fs::write(&prob, &b).unwrap();
    assert!(resume(&dir, Some(5), false, Some(2)).is_err(), "a changed problem needs --force");
    resume(&dir, Some(5), true, Some(2)).unwrap();
    assert_eq!(read(&dir.join("problem.toml")), b, "problem.toml: the problem in force");
    assert_eq!(read(&dir.join("problem-1.toml")), a, "the earlier problem kept");
    let run = run_json(&dir);
    let problems = run["problems"].as_array().unwrap_or_else(|| panic!("run.json names the problems: {run}"));
    assert_eq!(problems.len(), 2, "{run}");
    assert_eq!(problems[0]["file"], "problem-1.toml");
    assert_eq!(problems[1]["file"], "problem.toml");
    assert_eq!(problems[1]["first_generation"], 4);
    let idx = read_index(&dir.join("recording")).unwrap();
    assert_eq!(idx.len(), 5);
    for e in &idx {
        let r = gripopt::replay(&dir, e.first_id).unwrap();
        assert!(r.verified, "generation {}: design {} replays with its own problem", e.generation, e.first_id);
    }
    // problem.toml edited by hand: replay and verify refuse it (naming the file)
    std::fs::write(dir.join("problem.toml"), b.replacen("tau = 0.55", "tau = 0.6", 1)).unwrap();
    let last = idx.last().unwrap().first_id.to_string();
    let o = cli(&["replay", &d, "--design", &last]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("problem.toml") && stderr(&o).contains("edited"), "{}", stderr(&o));
    let o = cli(&["verify", &d, "--record", "none"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("problem.toml"), "{}", stderr(&o));
    assert!(!dir.join("verify.csv").exists());
}

/// Item 5: a folder left before the first checkpoint (a full disk at the first run.json, a
/// kill -9 in the first generation): `resume` says there is nothing to resume, and
/// `optimise` reuses the folder.
#[test]
fn item5_a_folder_left_before_the_first_checkpoint_is_reused() {
    // killed before it created its folder (the kill trial's 0.2 ms)
    let none = tmp("i5-never-created");
    let o = cli(&["resume", none.to_str().unwrap()]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("nothing to resume") && !none.exists(), "{}", stderr(&o));
    let dir = tmp("i5-first-run-json");
    let d = dir.display().to_string();
    // the first run.json cannot be written (its temporary file's name is taken by a folder)
    std::fs::create_dir_all(dir.join(".run.json.tmp/x")).unwrap();
    let e = optimise(&spec(&dir, 2)).unwrap_err().to_string();
    assert!(e.contains("run.json"), "{e}");
    std::fs::remove_dir_all(dir.join(".run.json.tmp")).unwrap();
    let o = cli(&["resume", &d]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("nothing to resume"), "{}", stderr(&o));
    optimise(&spec(&dir, 2)).unwrap();
    // a kill -9 while the first generation is evaluated
    let dir = tmp("i5-killed-in-generation-1");
    let d = dir.display().to_string();
    let mut child = spawn(&["optimise", PROBLEM, "--out", &d, "--pop", "300", "--generations", "2", "--threads", "1"]);
    wait_for("run.json", || dir.join("run.json").exists());
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!dir.join("checkpoint.json").exists(), "killed before the first checkpoint");
    let o = cli(&["resume", &d]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("nothing to resume"), "{}", stderr(&o));
    let o = cli(&["optimise", PROBLEM, "--out", &d, "--pop", "8", "--generations", "2", "--threads", "1"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
}

/// Item 6: run.json follows the checkpoints; `show` says `running` while a process holds
/// the folder and `stopped` (resumable) after a kill -9.
#[test]
fn item6_show_tells_a_killed_run_from_a_running_one() {
    let dir = tmp("i6-show");
    let d = dir.display().to_string();
    let mut child = spawn_endless(&d);
    wait_for("the second checkpoint", || checkpoint_generation(&dir) >= 2);
    let run = run_json(&dir);
    assert!(run["completed_generations"].as_u64().unwrap() >= 1, "run.json follows the checkpoints: {run}");
    let o = cli(&["show", &d, "--json"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["status"], "running", "{v}");
    child.kill().unwrap();
    child.wait().unwrap();
    let g = checkpoint_generation(&dir);
    let o = cli(&["show", &d, "--json"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["status"], "stopped", "{v}");
    assert_eq!(v["resumable"], true, "{v}");
    let shown = v["completed_generations"].as_u64().unwrap();
    assert!(shown == g || shown + 1 == g, "show {shown}, checkpoint {g}");
    let t = stdout(&cli(&["show", &d]));
    assert!(t.contains("stopped") && t.contains("gripopt resume"), "{t}");
}

/// A folder path with a space and a quote (item 12: printed paths are shell-quoted).
pub(crate) fn odd_folder(name: &str) -> PathBuf {
    tmp(&format!("{name} it's here"))
}
