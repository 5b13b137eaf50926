//! The rough edges a new user hits (issue 24, items 7–12): sweep folders, integer sweep
//! fields, a full stdout, the max_offset placeholder, a run without feasible designs, and
//! the smaller points of item 12 (values before a discard, ctrl-c, record flags, relative
//! problem paths, shell-quoted paths, control characters, a long simulation, the ground
//! stiffness, `#` unit lines and docs/outputs.md on every CSV). Item 12's verify.csv
//! generation is in verify.rs.

use crate::robustness::{checkpoint_generation, cli, code, read, spec, stderr, tmp, wait_for, BIN, PROBLEM};
use crate::robustness_folders::{odd_folder, spawn_collecting, stdout, wait_at_most};
use gripopt::run::{optimise, resume};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Feasible, not form closed at the centred object (max_offset is not computed).
const NOT_FORM_CLOSED: &str = "l21=0.0336837889909874,b=0.056596184542978364,t22=0.027363072133127088,r=0.6484300584690239,p=0.8670632978236559,psi_deg=90.61847226390265";
/// Discarded at its first impact (impact criterion).
const IMPACT: &str = "l21=0.05752773129759914,b=0.07698714957084737,t22=0.047203289055118364,r=0.4855302585907012,p=1.4977956047528578,psi_deg=100.92685375285232";
/// Discarded at stage 1 by the singularity margin (29.884° < 30°).
const MARGIN: &str = "l21=0.03354290888227425,b=0.07370020863024791,t22=0.059239095851631784,r=0.8429949159398948,p=0.9081155362437263,psi_deg=124.27467636068853";

/// The default problem with one line replaced (`key = ...`).
fn problem_with(name: &str, key: &str, line: &str) -> PathBuf {
    let text = read(Path::new(PROBLEM));
    let old = text.lines().find(|l| l.trim_start().starts_with(&format!("{key} "))).unwrap().to_string();
    let p = tmp(name).with_extension("toml");
    std::fs::write(&p, text.replacen(&old, line, 1)).unwrap();
    p
}

/// A run with designs on its front after 2 generations (seed 16, population 12).
fn front_spec(dir: &Path) -> gripopt::run::RunSpec {
    crate::common::bottle_spec(dir, 2, 16, 2)
}

fn json(o: &std::process::Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}\n{}", stdout(o), stderr(o)))
}

/// Item 7: `sweep --out` writes only into a folder of its own: never over a file it did
/// not write (a user's sweep.csv), never into a run folder; an earlier sweep's files are
/// replaced, none left beside the new ones.
#[test]
fn item7_sweep_writes_only_into_a_folder_of_its_own() {
    let dir = tmp("i7-user");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("sweep.csv"), "my own data\n").unwrap();
    let d = dir.display().to_string();
    let o = cli(&["sweep", PROBLEM, "--vary", "tau=0.3:0.4:2", "--stage", "kinematics", "--out", &d]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("sweep.csv"), "{}", stderr(&o));
    assert_eq!(read(&dir.join("sweep.csv")), "my own data\n");
    let run = tmp("i7-run");
    optimise(&spec(&run, 1)).unwrap();
    let r = run.display().to_string();
    let o = cli(&["sweep", PROBLEM, "--vary", "tau=0.3:0.4:2", "--stage", "kinematics", "--out", &r]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("run folder"), "{}", stderr(&o));
    assert!(!run.join("sweep.csv").exists());
    let own = tmp("i7-own");
    let s = own.display().to_string();
    let two = ["sweep", PROBLEM, "--vary", "tau=0.3:0.4:2", "--vary", "r=0.4:0.5:2", "--stage", "static"];
    let o = cli(&[&two[..], &["--bisect", "tau", "--bisect-steps", "2", "--out", s.as_str()]].concat());
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(own.join("map_verdict.svg").exists() && own.join("boundaries.csv").exists());
    let o = cli(&["sweep", PROBLEM, "--vary", "tau=0.3:0.4:3", "--stage", "static", "--out", &s]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(!own.join("map_verdict.svg").exists() && !own.join("boundaries.csv").exists(), "earlier files left");
    assert!(own.join("line_alpha.svg").exists() && own.join("sweep.csv").exists());
}

/// Item 8: an integer field is swept over whole values only (3:4:5 would record 3.25
/// while 3 ran); whole grids record whole values.
#[test]
fn item8_integer_fields_are_swept_over_whole_values() {
    let out = tmp("i8-int");
    let o = out.display().to_string();
    for v in ["scene.ground_points=3:4:5", "solver.max_steps=1000:2001:3"] {
        let r = cli(&["sweep", PROBLEM, "--vary", v, "--stage", "kinematics", "--out", &o]);
        assert_eq!(code(&r), 2, "{v}: {}", stderr(&r));
        assert!(stderr(&r).contains("whole"), "{v}: {}", stderr(&r));
    }
    // the ground is the free scene's (a centred problem refuses to vary it)
    let free = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/can.toml");
    let r = cli(&["sweep", free, "--vary", "scene.ground_points=3:5:3", "--stage", "kinematics", "--out", &o]);
    assert_eq!(code(&r), 0, "{}", stderr(&r));
    let values: Vec<String> = read(&out.join("sweep.csv"))
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').next().unwrap().to_string())
        .collect();
    assert_eq!(values, ["3", "4", "5"]);
}

/// Item 9: a full stdout (`> /dev/full`) is an error on one line (exit 1), never a panic,
/// in every command that prints.
#[test]
fn item9_a_full_stdout_is_a_clean_error_in_every_command() {
    let run = tmp("i9-run");
    optimise(&front_spec(&run)).unwrap();
    let r = run.display().to_string();
    let id = crate::robustness::rows(&run.join("pareto.csv"))[1][0].clone();
    let (sw, opt) = (tmp("i9-sweep").display().to_string(), tmp("i9-optimise").display().to_string());
    let cases: Vec<Vec<&str>> = vec![
        vec!["evaluate", PROBLEM],
        vec!["evaluate", PROBLEM, "--json"],
        vec!["simulate", PROBLEM],
        vec!["simulate", PROBLEM, "--json"],
        vec!["show", &r],
        vec!["show", &r, "--json"],
        vec!["show", &r, "--design", &id],
        vec!["replay", &r, "--design", &id],
        vec!["replay", &r, "--design", &id, "--json"],
        vec!["moo-test", "zdt1", "--json", "--pop", "8", "--generations", "2"],
        vec!["sweep", PROBLEM, "--vary", "tau=0.3:0.4:2", "--stage", "kinematics", "--out", &sw],
        vec!["optimise", PROBLEM, "--out", &opt, "--pop", "4", "--generations", "1", "--json"],
        vec!["resume", &r, "--generations", "3", "--json"],
        vec!["verify", &r, "--record", "none"],
        vec!["export", PROBLEM, "--format", "json", "--out", "-"],
    ];
    for args in cases {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
        let o = Command::new(BIN).args(&args).stdout(full).stderr(Stdio::piped()).output().unwrap();
        let e = stderr(&o);
        assert_eq!(code(&o), 1, "{args:?}: {e}");
        assert!(!e.contains("panicked") && e.contains("standard output"), "{args:?}: {e}");
        assert_eq!(e.lines().filter(|l| l.starts_with("error:")).count(), 1, "{args:?}: {e}");
    }
}

/// Item 10: max_offset of a design not form closed is null (not the −Δ_off placeholder)
/// in evaluate's JSON and text, and empty in sweep.csv, as in pareto.csv.
#[test]
fn item10_max_offset_is_null_where_it_was_not_computed() {
    let o = cli(&["evaluate", PROBLEM, "--json", "--design", NOT_FORM_CLOSED]);
    let v = json(&o);
    assert!(v["max_offset"].is_null() && v["form_closed"] == false && v["feasible"] == true, "{v}");
    let t = stdout(&cli(&["evaluate", PROBLEM, "--design", NOT_FORM_CLOSED]));
    let verdict = t.lines().find(|l| l.starts_with("verdict")).unwrap();
    assert!(verdict.contains("max_offset —") && !verdict.contains("-0.250"), "{verdict}");
    let out = tmp("i10-sweep");
    let o = cli(&[
        "sweep",
        PROBLEM,
        "--design",
        NOT_FORM_CLOSED,
        "--vary",
        "tau=0.5:0.5:1",
        "--stage",
        "static",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let text = read(&out.join("sweep.csv"));
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let row: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at = |k: &str| row[head.iter().position(|h| *h == k).unwrap_or_else(|| panic!("no {k}"))];
    assert_eq!((at("max_offset"), at("form_closed")), ("", "false"));
}

/// Item 11: a run in which no design is feasible says why (the discard causes), at its end,
/// in `show` and in `verify`.
#[test]
fn item11_a_run_without_feasible_designs_says_why() {
    let p = problem_with("i11-problem", "tau", "tau = 5.0");
    let dir = tmp("i11-none-feasible");
    let d = dir.display().to_string();
    let o = cli(&["optimise", p.to_str().unwrap(), "--out", &d, "--pop", "12", "--generations", "2", "--threads", "2"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let said = stdout(&o);
    assert!(said.contains("all 24 designs evaluated were discarded") && said.contains("% at stage 3"), "{said}");
    let s = stdout(&cli(&["show", &d]));
    assert!(s.contains("discarded") && s.contains("% at stage 3"), "{s}");
    let v = cli(&["verify", &d, "--record", "none"]);
    assert_eq!(code(&v), 2, "{}", stderr(&v));
    assert!(stderr(&v).contains("discarded") && stderr(&v).contains("% at stage 3"), "{}", stderr(&v));
}

/// Item 12: every value computed before a discard is reported (the stage-1 margin), none
/// that was not (the force margin of a design discarded at its first impact).
#[test]
fn item12_values_before_a_discard_and_none_after() {
    let v = json(&cli(&["evaluate", PROBLEM, "--json", "--design", MARGIN]));
    assert_eq!(v["failed_stage"], 1, "{v}");
    let reason = v["reason"].as_str().unwrap();
    let m = v["min_margin_deg"].as_f64().unwrap_or_else(|| panic!("min_margin_deg null: {v}"));
    assert!(reason.contains(&format!("{m:.3} deg")), "{reason} vs {m}");
    let v = json(&cli(&["evaluate", PROBLEM, "--json", "--design", IMPACT]));
    assert_eq!(v["outcome"], "impact criterion: first impact energy above the limit", "{v}");
    assert!(v["min_force_margin"].is_null(), "{v}");
    let t = stdout(&cli(&["evaluate", PROBLEM, "--design", IMPACT]));
    assert!(t.contains("force margin min — N"), "{t}");
}

/// Item 12: ctrl-c is acknowledged on stderr; a second ctrl-c ends the run at once (the
/// generation under way is not finished), resumable.
#[test]
fn item12_ctrl_c_is_acknowledged_and_a_second_one_ends_at_once() {
    let dir = tmp("i12-ctrl-c");
    let d = dir.display().to_string();
    let args = ["--pop", "3000", "--generations", "50", "--record", "none", "--threads", "1"];
    let (mut child, lines) = spawn_collecting(&[&["optimise", PROBLEM, "--out", &d][..], &args[..]].concat());
    wait_for("the first checkpoint", || checkpoint_generation(&dir) >= 1);
    let int = || assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    int();
    let t0 = Instant::now();
    while !lines.lock().unwrap().iter().any(|l| l.contains("ctrl-c")) {
        assert!(t0.elapsed() < Duration::from_secs(20), "no acknowledgement: {:?}", lines.lock().unwrap());
        std::thread::sleep(Duration::from_millis(10));
    }
    int();
    let rc = wait_at_most(&mut child, 20.0);
    assert_eq!(rc, Some(130), "{:?}", lines.lock().unwrap());
    assert_eq!(checkpoint_generation(&dir), 1, "the second ctrl-c did not wait for generation 2");
    resume(&dir, Some(2), false, Some(2)).unwrap();
}

/// Issue 44 class 8: SIGTERM (a batch scheduler's walltime) and SIGHUP (a closed
/// terminal) ended a run at once, where ctrl-c lets it finish the generation under way:
/// each is now acknowledged as ctrl-c is, the run stops after the checkpoint of the
/// generation it was in (exit 130, run.json `interrupted`) and resumes.
#[test]
fn sigterm_and_sighup_finish_the_generation_as_ctrl_c_does() {
    for signal in ["TERM", "HUP"] {
        let dir = tmp(&format!("i44-sig{signal}"));
        let d = dir.display().to_string();
        let args = ["--pop", "300", "--generations", "50", "--record", "none", "--threads", "1"];
        let (mut child, lines) = spawn_collecting(&[&["optimise", PROBLEM, "--out", &d][..], &args[..]].concat());
        wait_for("the first checkpoint", || checkpoint_generation(&dir) >= 1);
        let at = checkpoint_generation(&dir);
        let sig = format!("-{signal}");
        assert!(Command::new("kill").args([sig.as_str(), &child.id().to_string()]).status().unwrap().success());
        let rc = wait_at_most(&mut child, 300.0);
        let text = lines.lock().unwrap().join("\n");
        assert_eq!(rc, Some(130), "{signal}: {text}");
        assert!(text.contains("stopping after this generation's checkpoint"), "{signal}: {text}");
        let g = checkpoint_generation(&dir);
        assert!(g > at && g < 50, "{signal}: stopped at generation {g} (signal during {})", at + 1);
        assert!(read(&dir.join("run.json")).contains("\"interrupted\""), "{signal}");
        resume(&dir, Some(g + 1), false, Some(2)).unwrap();
    }
}

/// Item 12: `--record-every` needs `--record-full`; `--record none|designs` takes no
/// trajectory flag.
#[test]
fn item12_record_flags_that_would_be_ignored_are_refused() {
    let out = tmp("i12-record-flags");
    let o = out.display().to_string();
    let base = ["optimise", PROBLEM, "--out", &o, "--pop", "4", "--generations", "1"];
    for (extra, flag) in [
        (vec!["--record-every", "5"], "--record-every"),
        (vec!["--record", "none", "--record-full"], "--record-full"),
        (vec!["--record", "designs", "--record-every", "2", "--record-full"], "--record-every"),
    ] {
        let r = cli(&[&base[..], &extra[..]].concat());
        assert_eq!(code(&r), 2, "{extra:?}: {}", stderr(&r));
        assert!(stderr(&r).contains(flag), "{extra:?}: {}", stderr(&r));
        assert!(!out.join("run.json").exists());
    }
}

/// Item 12: a relative problem path is resolved where the run started, not where it is
/// resumed (another file of that name there is not the run's problem).
#[test]
fn item12_resume_finds_the_problem_the_run_started_with() {
    let base = tmp("i12-relative");
    let (a, b) = (base.join("a"), base.join("b"));
    std::fs::create_dir_all(&a).unwrap();
    std::fs::create_dir_all(&b).unwrap();
    let text = read(Path::new(PROBLEM));
    std::fs::write(a.join("p.toml"), &text).unwrap();
    let tau = text.lines().find(|l| l.trim_start().starts_with("tau")).unwrap();
    std::fs::write(b.join("p.toml"), text.replacen(tau, "tau = 0.45", 1)).unwrap();
    let run = |dir: &Path, args: &[&str]| Command::new(BIN).current_dir(dir).args(args).output().unwrap();
    let o = run(&a, &["optimise", "p.toml", "--out", "../run", "--pop", "8", "--generations", "2", "--record", "none"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let o = run(&b, &["resume", "../run", "--generations", "3"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
}

/// Item 12: paths printed in commands to copy are shell-quoted; control characters of a
/// problem name (or a path) never reach the terminal raw.
#[test]
fn item12_printed_paths_are_quoted_and_control_characters_escaped() {
    let dir = odd_folder("i12-quoted");
    let d = dir.display().to_string();
    let o = cli(&["optimise", PROBLEM, "--out", &d, "--pop", "12", "--generations", "2", "--seed", "16"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let quoted = format!("'{}'", d.replace('\'', r"'\''"));
    assert!(stdout(&o).contains(&format!("gripopt show {quoted}")), "{}", stdout(&o));
    let s = stdout(&cli(&["show", &d]));
    assert!(s.contains(&format!("gripopt replay {quoted} --design")), "{s}");
    let p = problem_with("i12-control", "name", "name = \"evil\\u001b[31mred\\u0007\"");
    let t = stdout(&cli(&["evaluate", p.to_str().unwrap()]));
    assert!(!t.contains('\u{1b}') && !t.contains('\u{7}') && t.contains("evil"), "{t:?}");
    let bad = tmp("i12-ctl\u{1b}[2J").with_extension("toml");
    let e = stderr(&cli(&["evaluate", bad.to_str().unwrap()]));
    assert!(!e.contains('\u{1b}') && e.contains("i12-ctl"), "{e:?}");
}

/// Item 12: a long single simulation says on stderr that it is still running (and where).
#[test]
fn item12_a_long_simulation_reports_progress() {
    // a tiny v_s with a step budget large enough to run for minutes (the default budget
    // ends it within a second)
    let p = problem_with("i12-slow", "v_s", "v_s = 1e-10");
    let text = read(&p);
    let budget = text.lines().find(|l| l.starts_with("max_steps ")).unwrap();
    std::fs::write(&p, text.replacen(budget, "max_steps = 50000000", 1)).unwrap();
    let (mut child, lines) = spawn_collecting(&["simulate", p.to_str().unwrap()]);
    let t0 = Instant::now();
    let seen = loop {
        if lines.lock().unwrap().iter().any(|l| l.contains("simulating") && l.contains("steps")) {
            break true;
        }
        if t0.elapsed() > Duration::from_secs(15) || child.try_wait().unwrap().is_some() {
            break false;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let _ = child.kill();
    let _ = child.wait();
    assert!(seen, "{:?}", lines.lock().unwrap());
}

/// Item 12: a ground so soft that the object would sink into it is refused, naming the field.
#[test]
fn item12_a_ground_that_swallows_the_object_is_refused() {
    let p = problem_with("i12-soft-ground", "ground_k", "ground_k = 1.0");
    let o = cli(&["simulate", p.to_str().unwrap(), "--scene", "free", "--json"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("scene.ground_k"), "{}", stderr(&o));
}

/// The column names of a CSV with `#` lines; asserts the `#` title and units lines.
fn columns_with_units(p: &Path) -> Vec<String> {
    let text = read(p);
    assert!(text.starts_with("# gripopt"), "{}: no `# gripopt` title line", p.display());
    assert!(text.lines().any(|l| l.starts_with("# units:")), "{}: no `# units:` line", p.display());
    let head = text.lines().find(|l| !l.starts_with('#')).unwrap();
    head.split(',').map(String::from).collect()
}

/// Item 5 (conventions) and 12: every CSV gripopt writes has its `#` title and units lines,
/// and docs/outputs.md names every column; simulate's free JSON has one key per quantity.
#[test]
fn item12_every_csv_has_unit_lines_and_documented_columns() {
    let dir = tmp("i12-csv");
    let d = dir.display().to_string();
    optimise(&front_spec(&dir)).unwrap();
    let id = crate::robustness::rows(&dir.join("pareto.csv"))[1][0].clone();
    let mut files: Vec<PathBuf> = ["pareto.csv", "population.csv", "archive.csv", "history.csv", "pareto_timings.csv"]
        .map(|f| dir.join(f))
        .into();
    let ok = |o: std::process::Output| assert_eq!(code(&o), 0, "{}", stderr(&o));
    ok(cli(&["verify", &d, "--record", "none"]));
    files.push(dir.join("verify.csv"));
    for (scene, name) in [("centred", "sim-centred.csv"), ("offset:0.002", "sim-offset.csv"), ("free", "sim-free.csv")]
    {
        ok(cli(&["simulate", PROBLEM, "--scene", scene, "--csv", dir.join(name).to_str().unwrap()]));
        files.push(dir.join(name));
    }
    ok(cli(&["replay", &d, "--design", &id, "--csv", dir.join("replay.csv").to_str().unwrap()]));
    files.push(dir.join("replay.csv"));
    let sw = tmp("i12-csv-sweep");
    let s = sw.display().to_string();
    ok(cli(&["sweep", PROBLEM, "--vary", "tau=0.3:0.6:4", "--bisect", "tau", "--bisect-steps", "2", "--out", &s]));
    let sf = tmp("i12-csv-sweep-free");
    let free = problem_with("i12-free", "kind", "kind = \"free\"");
    ok(cli(&["sweep", free.to_str().unwrap(), "--vary", "scene.x_off=0:0.002:2", "--out", sf.to_str().unwrap()]));
    files.extend([sw.join("sweep.csv"), sw.join("boundaries.csv"), sf.join("sweep.csv")]);
    let docs = read(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/outputs.md")));
    let mut undocumented = vec![];
    for f in &files {
        for c in columns_with_units(f) {
            if !docs.contains(&format!("`{c}`")) {
                undocumented.push(format!("{}: {c}", f.file_name().unwrap().to_string_lossy()));
            }
        }
    }
    assert!(undocumented.is_empty(), "columns missing in docs/outputs.md (as `name`):\n{}", undocumented.join("\n"));
    // simulate --scene free --json: one key per quantity, the scene in its name
    let v = json(&cli(&["simulate", PROBLEM, "--scene", "free", "--json"]));
    for k in ["first_contact_t", "stats", "energy", "free_end", "first_impact"] {
        assert!(v.get(k).is_none(), "top-level key {k}: {v}");
    }
    assert!(v["free_scene"]["energy"].is_array() && v["free_scene"]["t_first_contact"].is_number(), "{v}");
}

/// An existing file given to `--csv` / `--plot` is refused (exit 2) and left as it was, a
/// run's own files included; `--force` replaces it. `export RUN --design` takes the problem
/// the design's generation was evaluated with and refuses an edited problem.toml.
#[test]
fn existing_output_files_and_edited_problems_are_never_taken_silently() {
    let dir = crate::common::tiny_run("edges-outputs", Path::new(PROBLEM), 8, 1);
    let d = dir.display().to_string();
    let run_json = dir.join("run.json");
    let before = std::fs::read(&run_json).unwrap();
    for flag in ["--csv", "--plot"] {
        let o = cli(&["replay", &d, "--design", "0", flag, run_json.to_str().unwrap()]);
        assert_eq!(code(&o), 2, "{}", stderr(&o));
        assert!(stderr(&o).contains("is a file of the folder"), "{}", stderr(&o));
        assert_eq!(std::fs::read(&run_json).unwrap(), before, "{flag}: run.json untouched");
    }
    // a file of the run folder is never replaced, --force included (hostile pass 34), even
    // one the user put there; beside the folder, --force replaces the user's file
    let inside = dir.join("mine.csv");
    std::fs::write(&inside, "my data\n").unwrap();
    let o = cli(&["simulate", PROBLEM, "--csv", inside.to_str().unwrap(), "--force"]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&inside).unwrap(), "my data\n");
    let mine = dir.with_file_name("edges-outputs-mine.csv");
    std::fs::write(&mine, "my data\n").unwrap();
    let o = cli(&["simulate", PROBLEM, "--csv", mine.to_str().unwrap()]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "my data\n");
    let o = cli(&["simulate", PROBLEM, "--csv", mine.to_str().unwrap(), "--force"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    assert!(std::fs::read_to_string(&mine).unwrap().starts_with("# gripopt"), "replaced by the trajectory");
    // export: the run's problem, refused once edited (written beside the run folder: never into it)
    let out = dir.with_file_name("edges-outputs-design-0.json");
    let _ = std::fs::remove_file(&out);
    let o = cli(&["export", &d, "--design", "0", "--out", out.to_str().unwrap()]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let toml = dir.join("problem.toml");
    let text = std::fs::read_to_string(&toml).unwrap();
    std::fs::write(&toml, text.replace("w = 5e-3", "w = 8e-3")).unwrap();
    let out = dir.with_file_name("edges-outputs-design-0-edited.json");
    let _ = std::fs::remove_file(&out);
    let o = cli(&["export", &d, "--design", "0", "--out", out.to_str().unwrap()]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(stderr(&o).contains("problem.toml") && stderr(&o).contains("edited"), "{}", stderr(&o));
    assert!(!out.exists());
    std::fs::write(&toml, text).unwrap();
}
