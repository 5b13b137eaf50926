//! `gripopt verify`: verify.csv holds one row per Pareto design whose measured motion equals
//! an independent `gripopt simulate --scene free --json` of the design read from pareto.csv
//! (verify itself takes the designs from the checkpoint: an edited pareto.csv changes nothing),
//! the printed confusion table adds up to the rows and matches the CSV, the CSV does not
//! depend on the thread count, and bad folders are refused with exit 2, nothing deleted;
//! verify.csv's and the `/verify` message's columns, what is not observed left out, and the
//! limits and refusals around a verify. A robust run's verify: verify_robust.rs; verify's
//! recording: verify_record.rs.

use crate::common::{
    cli_tiny_run, fifo, folder_bytes, is_fifo, output_text, run_gripopt, run_limited, scratch, BOTTLE_FILE,
};
use crate::robustness::{cli, code, read, stderr, tmp};
use crate::robustness_folders::stdout;
use gripopt::run::{optimise, resume, RunLock};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_gripopt");

/// A tiny run (pop 8, 2 generations; seed 16 has 4 designs on its front) under
/// target/mcap-check/ so that `make test` checks its recording.
fn tiny_run(name: &str) -> PathBuf {
    crate::common::tiny_run(&format!("verify-{name}"), std::path::Path::new(crate::common::BOTTLE_FILE), 8, 2)
}

fn run(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().unwrap()
}

/// (header, rows) of a CSV with `#` lines, split on commas (pareto.csv's quoted `reason`
/// holds no comma for feasible designs: it is empty).
fn table(p: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    (head, lines.map(|l| l.split(',').map(String::from).collect()).collect())
}

fn col(head: &[String], name: &str) -> usize {
    head.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"))
}

#[test]
fn verify_matches_simulate_and_threads() {
    let dir = tiny_run("front");
    let d = dir.display().to_string();
    let out = run(&["verify", &d, "--threads", "1"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let csv1 = std::fs::read_to_string(dir.join("verify.csv")).unwrap();
    let out2 = run(&["verify", &d, "--threads", "2"]);
    assert!(out2.status.success());
    assert_eq!(
        csv1,
        std::fs::read_to_string(dir.join("verify.csv")).unwrap(),
        "verify.csv depends on the thread count"
    );

    let (ph, prow) = table(&dir.join("pareto.csv"));
    let (vh, vrow) = table(&dir.join("verify.csv"));
    let prow: Vec<_> = prow.into_iter().filter(|r| r[col(&ph, "feasible")] == "true").collect();
    assert!(!prow.is_empty(), "the tiny run has no front");
    assert_eq!(vrow.len(), prow.len(), "one verify row per Pareto design");
    let mut ids: Vec<u64> = prow.iter().map(|r| r[col(&ph, "id")].parse().unwrap()).collect();
    ids.sort();
    let vids: Vec<u64> = vrow.iter().map(|r| r[col(&vh, "id")].parse().unwrap()).collect();
    assert_eq!(ids, vids, "rows in id order");

    let problem = dir.join("problem.toml").display().to_string();
    let mut counts = [0usize; 4];
    for r in &prow {
        let id = &r[col(&ph, "id")];
        let design = gripopt::params::DESIGN_NAMES
            .iter()
            .map(|n| format!("{n}={}", r[col(&ph, n)]))
            .collect::<Vec<_>>()
            .join(",");
        let o = run(&["simulate", &problem, "--scene", "free", "--json", "--design", &design]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let v = vrow.iter().find(|v| &v[0] == id).unwrap();
        let f = |name: &str| -> f64 { v[col(&vh, name)].parse().unwrap() };
        let b = |name: &str| -> bool { v[col(&vh, name)].parse().unwrap() };
        for k in ["object_max_displacement", "object_max_tilt_deg", "object_peak_e_trans", "object_peak_e_rot"] {
            assert_eq!(f(k), j["free_scene"][k].as_f64().unwrap(), "design {id}: {k}");
        }
        for k in ["moved", "toppled", "escaped", "rim_contact"] {
            assert_eq!(b(k), j["free_scene"][k].as_bool().unwrap(), "design {id}: {k}");
        }
        // the prediction from simulate's centred keys
        let ratio = j["e_cyl"].as_f64().unwrap() / j["e_lim"].as_f64().unwrap();
        assert_eq!(f("impact_ratio"), ratio, "design {id}: impact ratio");
        let margin = j["min_force_margin"].as_f64().unwrap().min(j["static_force_margin"].as_f64().unwrap());
        assert_eq!(f("force_margin"), margin, "design {id}: force margin");
        let pred = ratio > 1.0 || margin < 0.0;
        assert_eq!(b("predicted_moves"), pred);
        assert_eq!(b("agrees"), pred == b("moved"));
        counts[match (pred, b("moved")) {
            (true, true) => 0,
            (true, false) => 1,
            (false, true) => 2,
            (false, false) => 3,
        }] += 1;
    }
    // the printed table: two rows of two counts, adding up to the rows
    let text = String::from_utf8_lossy(&out.stdout);
    let nums = |prefix: &str| -> Vec<usize> {
        let l = text
            .lines()
            .find(|l| l.trim_start().starts_with(prefix))
            .unwrap_or_else(|| panic!("no `{prefix}` line in {text}"));
        l.split_whitespace().filter_map(|w| w.parse().ok()).collect()
    };
    let (a, b) = (nums("predicted moves"), nums("predicted stays"));
    assert_eq!([a[0], a[1], b[0], b[1]], counts, "{text}");
    assert_eq!(a[0] + a[1] + b[0] + b[1], vrow.len());
}

/// `--all`: one row per distinct feasible id of population.csv and archive.csv; `--sample`:
/// N designs, each passing stage 2 (checked independently with `evaluate --static-only`),
/// identical for 1 and 2 threads.
#[test]
fn verify_all_and_sample() {
    let dir = tiny_run("all");
    let d = dir.display().to_string();
    let o = run(&["verify", &d, "--all"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let mut ids = std::collections::BTreeSet::new();
    for f in ["population.csv", "archive.csv"] {
        let (h, rows) = table(&dir.join(f));
        for r in rows.iter().filter(|r| r[col(&h, "feasible")] == "true") {
            ids.insert(r[col(&h, "id")].parse::<u64>().unwrap());
        }
    }
    let (vh, vrow) = table(&dir.join("verify.csv"));
    let vids: Vec<u64> = vrow.iter().map(|r| r[col(&vh, "id")].parse().unwrap()).collect();
    assert_eq!(vids, ids.into_iter().collect::<Vec<_>>());

    assert!(run(&["verify", &d, "--sample", "6", "--seed", "3", "--threads", "1"]).status.success());
    let s1 = std::fs::read_to_string(dir.join("verify_sample.csv")).unwrap();
    assert!(run(&["verify", &d, "--sample", "6", "--seed", "3", "--threads", "2"]).status.success());
    assert_eq!(s1, std::fs::read_to_string(dir.join("verify_sample.csv")).unwrap());
    let (sh, srow) = table(&dir.join("verify_sample.csv"));
    assert_eq!(srow.len(), 6);
    let problem = dir.join("problem.toml").display().to_string();
    for r in &srow {
        let design = gripopt::params::DESIGN_NAMES
            .iter()
            .map(|n| format!("{n}={}", r[col(&sh, n)]))
            .collect::<Vec<_>>()
            .join(",");
        let o = run(&["evaluate", &problem, "--static-only", "--json", "--design", &design]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert!(j["failed_stage"].is_null(), "sample design {} fails stage {}", r[0], j["failed_stage"]);
    }
}

#[test]
fn verify_refuses_bad_folders() {
    let dir = tiny_run("bad");
    let d = dir.display().to_string();
    // not a folder, not a run
    assert_eq!(run(&["verify", &format!("{d}/nothing-here")]).status.code(), Some(2));
    let not_run = dir.join("not-a-run");
    std::fs::create_dir_all(&not_run).unwrap();
    std::fs::write(not_run.join("keep.txt"), "x").unwrap();
    let o = run(&["verify", &not_run.display().to_string()]);
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("run.json"));
    assert!(not_run.join("keep.txt").exists());
    // a locked run folder
    {
        let _lock = RunLock::acquire(&dir).unwrap();
        let o = run(&["verify", &d]);
        assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(String::from_utf8_lossy(&o.stderr).contains("in use"));
    }
    // a bad scene
    assert_eq!(run(&["verify", &d, "--scene", "centred"]).status.code(), Some(2));
    // the designs come from the checkpoint, not from the CSV views: a pareto.csv edited by
    // hand (a design's l21 changed) or deleted changes nothing verify.csv says
    let out = run(&["verify", &d]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let reference = std::fs::read_to_string(dir.join("verify.csv")).unwrap();
    let pareto = std::fs::read_to_string(dir.join("pareto.csv")).unwrap();
    let (ph, prow) = table(&dir.join("pareto.csv"));
    let l21 = &prow[0][col(&ph, "l21")];
    let edited = pareto.replacen(&format!(",{l21},"), ",0.0432,", 1);
    assert_ne!(edited, pareto, "the edit took");
    std::fs::write(dir.join("pareto.csv"), edited).unwrap();
    let out = run(&["verify", &d]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(std::fs::read_to_string(dir.join("verify.csv")).unwrap(), reference, "verify took an edited pareto.csv");
    std::fs::remove_file(dir.join("pareto.csv")).unwrap();
    let out = run(&["verify", &d]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(std::fs::read_to_string(dir.join("verify.csv")).unwrap(), reference);
    // a missing checkpoint.json: refused naming it, the rest of the run kept
    std::fs::remove_file(dir.join("verify.csv")).unwrap();
    std::fs::rename(dir.join("checkpoint.json"), dir.join("checkpoint.json.away")).unwrap();
    let before: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    let o = run(&["verify", &d]);
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("checkpoint.json"), "{}", String::from_utf8_lossy(&o.stderr));
    for f in before {
        assert!(dir.join(&f).exists(), "{f:?} deleted");
    }
    assert!(!dir.join("verify.csv").exists());
}

/// `verify` of a run whose problem.toml was deleted says that file is missing (run.json is
/// there), not "not a run folder".
/// Origin: hostile pass of session 35 on the CLI.
#[test]
fn verify_names_a_missing_problem_toml() {
    let d = scratch("verify-no-problem");
    let run = cli_tiny_run(&d);
    std::fs::remove_file(run.join("problem.toml")).unwrap();
    let o = run_gripopt(&["verify", run.to_str().unwrap(), "--record", "none"]);
    let text = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{text}");
    assert!(text.contains("problem.toml is missing from the run folder (run.json is there)"), "{text}");
}

/// Origin: the hostile-user review of the scene commands.
#[test]
fn verify_without_observation_and_with_nothing_to_verify() {
    let dir = crate::common::tiny_run("scene-cli-verify", Path::new(BOTTLE_FILE), 8, 2);
    let d = dir.display().to_string();
    // --seed without --sample: refused
    let o = run_gripopt(&["verify", &d, "--seed", "3"]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    assert!(!dir.join("verify.csv").exists());

    // x_off = 20 mm: every design's open finger overlaps the object, nothing is observed
    let o = run_gripopt(&["verify", &d, "--scene", "free:0.02", "--threads", "1"]);
    assert!(o.status.success(), "{}", output_text(&o));
    let csv = std::fs::read_to_string(dir.join("verify.csv")).unwrap();
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let c = |n: &str| head.iter().position(|h| *h == n).unwrap_or_else(|| panic!("no column {n}"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(!rows.is_empty());
    for r in &rows {
        assert_ne!(r[c("free_end")], "t_obs", "{r:?}");
        for k in ["moved", "toppled", "escaped", "agrees", "peak_e_trans_ratio", "peak_e_rot_ratio"] {
            assert_eq!(r[c(k)], "", "{k} must be empty: {r:?}");
        }
    }
    let t = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        t.contains(&format!("not observed (the free scene ended before t_obs; left out of the table): {}", rows.len())),
        "{t}"
    );
    assert!(!t.contains("agreement"), "nothing observed, no agreement: {t}");
    assert!(t.contains(&format!("verified {} design{}", rows.len(), if rows.len() == 1 { "" } else { "s" })), "{t}");
    // the recording: no verdict on /verify, but free_end
    let buf = std::fs::read(dir.join("verify.mcap")).unwrap();
    let recs: Vec<serde_json::Value> = mcap::MessageStream::new(&buf)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == "/verify")
        .map(|m| serde_json::from_slice(&m.data).unwrap())
        .collect();
    assert_eq!(recs.len(), rows.len());
    for v in &recs {
        assert!(
            v.get("moved").is_none()
                && v.get("agrees").is_none()
                && v["free_end"].as_str().is_some_and(|e| e != "t_obs"),
            "{v}"
        );
    }

    // an empty front (a problem no design can meet: stability within 1 ms): refused, naming
    // the checkpoint the designs come from and why none is feasible, nothing written
    let problem = dir.parent().unwrap().join("scene-cli-no-front.toml");
    let text0 = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    assert!(text0.contains("t_max = 0.3 "));
    std::fs::write(&problem, text0.replacen("t_max = 0.3 ", "t_max = 0.001 ", 1)).unwrap();
    let none = crate::common::tiny_run("scene-cli-verify-no-front", &problem, 8, 1);
    let o = run_gripopt(&["verify", &none.display().to_string()]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    assert!(
        output_text(&o).contains("checkpoint.json") && output_text(&o).contains("nothing to verify"),
        "{}",
        output_text(&o)
    );
    assert!(!none.join("verify.csv").exists() && !none.join("verify.mcap").exists());
}

/// Origin: the third hostile pass over the CLI.
#[test]
fn verify_sample_beyond_memory_is_refused_before_the_lock() {
    let d = crate::common::tiny_run("cli-outputs-verify-sample", Path::new(BOTTLE_FILE), 8, 2);
    let ds = d.display().to_string();
    for record in ["all", "none"] {
        // the old code aborted allocating it (exit 134), leaving RUN/.lock behind
        let o = run_gripopt(&["verify", &ds, "--sample", "100000000000", "--record", record]);
        let t = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{t}");
        assert!(t.contains("--sample") && t.contains("of memory") && t.contains("at most"), "{t}");
        assert!(!d.join(".lock").exists(), "{t}");
        assert!(!d.join("verify_sample.csv").exists());
    }
    let o = run_gripopt(&["verify", &ds, "--sample", "0"]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    // hidden: --help says nothing of it
    let help = output_text(&run_gripopt(&["verify", "--help"]));
    assert!(!help.contains("sample"), "{help}");
}

/// `verify --sample N` from the library: an N whose designs cannot fit in memory is refused
/// before anything is drawn or written (the CLI checks it too, before the lock).
/// Origin: hostile pass of session 31, run folders put together by hand.
#[test]
fn a_library_verify_sample_beyond_memory_is_refused() {
    let dir = tmp("trust-sample");
    let run = dir.join("run");
    let mut spec = crate::common::bottle_spec(&run, 1, 5, 1);
    spec.record = gripopt::record::RecordOptions::none();
    optimise(&spec).unwrap();
    let before = folder_bytes(&run);
    let source = gripopt::run::VerifySource::Sample { n: usize::MAX / 2, seed: 1 };
    let e = gripopt::run::verify(&run, source, None, false, &|_| {}, &|| {}).unwrap_err().to_string();
    assert!(e.contains("--sample") && e.contains("needs about"), "{e}");
    assert_eq!(folder_bytes(&run), before);
}

/// Item 12: verify.csv says which generation's front (and which checkpoint and problem) it
/// checked; `show` says when it no longer matches the run.
#[test]
fn item12_verify_csv_names_the_generation_it_checked() {
    let dir = tmp("i12-verify-generation");
    let d = dir.display().to_string();
    optimise(&crate::common::bottle_spec(&dir, 2, 16, 2)).unwrap();
    let o = cli(&["verify", &d, "--record", "none"]);
    assert_eq!(code(&o), 0, "{}", stderr(&o));
    let v = read(&dir.join("verify.csv"));
    let run_line = v.lines().find(|l| l.starts_with("# run:")).unwrap_or_else(|| panic!("{v}"));
    assert!(run_line.contains("generation 2") && run_line.contains("checkpoint sha256"), "{run_line}");
    assert!(stdout(&cli(&["show", &d])).contains("verify.csv: generation 2"));
    resume(&dir, Some(3), false, Some(2)).unwrap();
    let s = stdout(&cli(&["show", &d]));
    assert!(s.contains("verify.csv") && s.contains("generation 2") && s.contains("gripopt verify"), "{s}");
}

/// `show` said nothing (`"verify": null`, no warning) of a named pipe or folder where
/// verify.csv stands: it now shows the run with a warning naming the file.
/// Origin: hostile pass of session 34, files.
#[test]
fn show_warns_of_a_verify_csv_it_cannot_read() {
    let d = scratch("show-verify");
    let run = crate::common::tiny_run("hostile34-show-verify", Path::new(BOTTLE_FILE), 8, 1);
    let csv = run.join("verify.csv");
    let _ = std::fs::remove_file(&csv);
    if !fifo(&csv) {
        return;
    }
    let r = run.to_str().unwrap();
    let o = run_limited(&d, &["show", r]);
    let text = output_text(&o);
    assert_eq!(o.status.code(), Some(0), "{text}");
    assert!(
        text.contains("warning: not read:") && text.contains("verify.csv") && text.contains("named pipe"),
        "{text}"
    );
    let o = run_limited(&d, &["show", r, "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let warned = v["warnings"].as_array().unwrap().iter().any(|w| w.as_str().unwrap().contains("verify.csv"));
    assert!(warned && v["verify"].is_null(), "{v}");
    assert!(is_fifo(&csv), "left as it was");
}

fn verify_row(observed: bool) -> gripopt::run::VerifyRow {
    use gripopt::sim::FreeEnd;
    gripopt::run::VerifyRow {
        id: 7,
        design: crate::common::nominal(),
        impact_ratio: Some(0.5),
        e_trans_rot: Some((2e-3, 0.0)),
        force_margin: f64::INFINITY,
        stable: true,
        predicted_moves: false,
        max_displacement: 1e-4,
        max_tilt_deg: 0.25,
        peak_e: (1e-3, 2e-4),
        moved: observed.then_some(false),
        toppled: observed.then_some(false),
        escaped: observed.then_some(false),
        rim_contact: false,
        end: if observed { FreeEnd::Observed } else { FreeEnd::StepBudget },
        t_end: 0.1,
    }
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn verify_csv_columns_are_the_column_table() {
    use gripopt::run::{verify_csv, VERIFY_COLUMNS};
    let csv = verify_csv(&[verify_row(true), verify_row(false)], 0.0);
    let mut lines = csv.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let names: Vec<&str> = VERIFY_COLUMNS.iter().map(|c| c.0).collect();
    assert_eq!(header, names, "the units table lists verify.csv's columns in order");
    let cell = |line: &str, col: &str| {
        let k = names.iter().position(|n| *n == col).unwrap();
        line.split(',').nth(k).unwrap().to_string()
    };
    let (seen, unseen) = (lines.next().unwrap(), lines.next().unwrap());
    assert_eq!(cell(seen, "free_end"), "t_obs");
    assert_eq!(cell(unseen, "free_end"), "aborted: step budget exhausted", "the enum's words");
    assert_eq!(cell(seen, "force_margin"), "inf", "the CSV writes every number");
    // E_rot = 0: the rotational ratio is infinite, the translational 0.5
    assert_eq!((cell(seen, "peak_e_trans_ratio").as_str(), cell(seen, "peak_e_rot_ratio").as_str()), ("0.5", "inf"));
    for col in ["moved", "agrees", "peak_e_trans_ratio"] {
        assert_eq!(cell(unseen, col), "", "{col}: not observed, an empty cell");
    }
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn a_verify_message_leaves_out_what_was_not_computed_and_its_schema_names_every_field() {
    use gripopt::record::{verify_parameters, verify_schema, VerifyRecord, VerifyScenario, WindowStart};
    let rec = |row: &gripopt::run::VerifyRow, scenario: Option<VerifyScenario>| VerifyRecord {
        window: 1,
        window_start: WindowStart { sec: 5, nsec: 0 },
        window_start_s: 1.0,
        epoch_s: 4,
        id: row.id,
        parameters: verify_parameters(&row.design),
        x_off: 0.0,
        measure: row.measure(),
        t_end: row.t_end,
        poses: 3,
        scenario,
    };
    let json = |r: &VerifyRecord| -> serde_json::Map<String, serde_json::Value> {
        let bytes = r.to_json();
        let text = String::from_utf8(bytes).unwrap();
        let keys: Vec<String> = serde_json::from_str::<serde_json::Map<_, _>>(&text).unwrap().keys().cloned().collect();
        let mut sorted = keys.clone();
        sorted.sort();
        assert_eq!(keys, sorted, "keys written sorted");
        serde_json::from_str(&text).unwrap()
    };
    let seen = json(&rec(&verify_row(true), None));
    assert!(!seen.contains_key("force_margin"), "not finite: left out");
    assert!(!seen.contains_key("peak_e_rot_ratio"), "not finite: left out");
    assert_eq!(seen["peak_e_trans_ratio"], 0.5);
    assert_eq!(seen["free_end"], "t_obs");
    assert!(!seen.contains_key("scenario_object"));
    let s = VerifyScenario { scenario_object: "can".into(), scenario_index: 2, height_offset: -0.004 };
    let unseen = json(&rec(&verify_row(false), Some(s)));
    for k in ["moved", "toppled", "escaped", "agrees", "peak_e_trans_ratio"] {
        assert!(!unseen.contains_key(k), "{k}: not observed, left out");
    }
    assert_eq!((unseen["scenario_object"].as_str(), unseen["scenario_index"].as_u64()), (Some("can"), Some(2)));
    // the schema names every field a message can have, and requires those every one has
    let schema = verify_schema();
    let props = schema["properties"].as_object().unwrap();
    for k in seen.keys().chain(unseen.keys()) {
        assert!(props.contains_key(k), "{k} is in the schema");
    }
    for k in schema["required"].as_array().unwrap() {
        let k = k.as_str().unwrap();
        assert!(seen.contains_key(k) && unseen.contains_key(k), "required {k} is in every message");
    }
}
