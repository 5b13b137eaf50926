//! What a script sees: exit codes and `--json` failures. `moo-test` exits 3 when a
//! hypervolume median lies outside the reference band (0 inside), with and without `--json`;
//! a command that fails with `--json` prints one JSON object `{"error", "exit_code"}` on stdout
//! (its stderr line and exit code unchanged), usage errors included; run.json keeps the
//! problem file's path absolute and normalised, and a run folder with the older
//! un-normalised form still resumes and still notices a changed problem file; the folder
//! lock's refusals, messages and numbers in them. The tests written in session 33 carry no
//! origin line; the later regression tests do.

use crate::common::{json_stdout, output_text, run_gripopt, scratch, BOTTLE_FILE, GRIPOPT_BIN};
use std::path::Path;
use std::process::{Command, Output};

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Reference NSGA-II hypervolume bands [min, max] over seeds 1..11 (the numbers,
/// docs/benchmarks.md "Optimiser validation"), written here independently of the library.
const BNH_BAND: (f64, f64) = (6458.39, 6462.71);
const ZDT1_BAND: (f64, f64) = (0.86919, 0.86992);

#[test]
fn moo_test_exits_3_when_the_median_lies_outside_the_reference_band() {
    // inside: BNH at the reference settings, seeds 1-3 (the median of three runs)
    for json in [false, true] {
        let mut args = vec!["moo-test", "bnh", "--seeds", "1-3"];
        if json {
            args.push("--json");
        }
        let o = run_gripopt(&args);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {}", output_text(&o));
        if json {
            let mut hv: Vec<f64> = stdout(&o)
                .lines()
                .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()["hv"].as_f64().unwrap())
                .collect();
            assert_eq!(hv.len(), 3, "{}", output_text(&o));
            hv.sort_by(f64::total_cmp);
            assert!(hv[1] >= BNH_BAND.0 && hv[1] <= BNH_BAND.1, "median {} outside {BNH_BAND:?}", hv[1]);
            assert!(stderr(&o).is_empty(), "{}", stderr(&o));
        } else {
            assert!(stdout(&o).contains(": inside;"), "{}", output_text(&o));
        }
    }
    // outside: a population of 8 for 2 generations is nowhere near ZDT1's front
    for json in [false, true] {
        let mut args = vec!["moo-test", "zdt1", "--pop", "8", "--generations", "2", "--seed", "1"];
        if json {
            args.push("--json");
        }
        let o = run_gripopt(&args);
        assert_eq!(o.status.code(), Some(3), "{args:?}: {}", output_text(&o));
        if json {
            // stdout stays one object per run (the per-run stream scripts read); the verdict
            // is on stderr
            let lines: Vec<serde_json::Value> = stdout(&o).lines().map(|l| serde_json::from_str(l).unwrap()).collect();
            assert_eq!(lines.len(), 1, "{}", output_text(&o));
            assert!(lines[0]["hv"].as_f64().unwrap() < ZDT1_BAND.0, "{}", output_text(&o));
            assert!(stderr(&o).contains("ZDT1") && stderr(&o).contains("OUTSIDE"), "{}", stderr(&o));
        } else {
            assert!(stdout(&o).contains(": OUTSIDE;"), "{}", output_text(&o));
        }
    }
}

/// `o` failed with `code`, its stderr one line `error: MESSAGE` and its stdout exactly one
/// JSON object `{"error": MESSAGE, "exit_code": code}`; MESSAGE contains `needle`.
fn assert_json_failure(o: &Output, code: i32, needle: &str) {
    assert_eq!(o.status.code(), Some(code), "{}", output_text(o));
    let out = stdout(o);
    assert_eq!(out.lines().count(), 1, "stdout: {out}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"));
    assert_eq!(v.as_object().unwrap().len(), 2, "{v}");
    assert_eq!(v["exit_code"], code, "{v}");
    let message = v["error"].as_str().unwrap();
    assert!(message.contains(needle), "{v}");
    let e = stderr(o);
    assert!(e.lines().any(|l| l == format!("error: {message}")), "stderr: {e}");
}

#[test]
fn a_failed_command_with_json_prints_one_json_object_on_stdout() {
    let d = scratch("json-failures");
    // evaluate: a problem file that does not exist (bad input, exit 2)
    let missing = d.join("missing.toml").display().to_string();
    assert_json_failure(&run_gripopt(&["evaluate", &missing, "--json"]), 2, "missing.toml");
    // without --json stdout stays empty (the error is on stderr only)
    let o = run_gripopt(&["evaluate", &missing]);
    assert_eq!(o.status.code(), Some(2));
    assert!(o.stdout.is_empty() && stderr(&o).starts_with("error: "), "{}", output_text(&o));
    // show: a folder that is not a run (exit 2)
    let ds = d.display().to_string();
    assert_json_failure(&run_gripopt(&["show", &ds, "--json"]), 2, "run.json");
    // simulate --csv: a write that fails (a file-size limit as a full disk; exit 1)
    let o = Command::new("sh")
        .current_dir(&d)
        .arg("-c")
        .arg("trap '' XFSZ; ulimit -f 8; exec \"$0\" \"$@\"")
        .arg(GRIPOPT_BIN)
        .args(["simulate", BOTTLE_FILE, "--json", "--csv", "t.csv"])
        .output()
        .unwrap();
    assert_json_failure(&o, 1, "t.csv");
    // a usage error clap reports (exit 2), --json among the arguments: clap's stderr as it
    // prints it, the JSON object its whole message on one line (first line, then the tip)
    let o = run_gripopt(&["evaluate", BOTTLE_FILE, "--json", "--desing", "x"]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    let v: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap_or_else(|e| panic!("{e}: {}", output_text(&o)));
    let (message, first) = (v["error"].as_str().unwrap(), stderr(&o).lines().next().unwrap().to_string());
    assert_eq!((v["exit_code"].as_i64(), v.as_object().unwrap().len()), (Some(2), 2), "{v}");
    assert!(message.starts_with(first.trim_start_matches("error: ")), "{message} / {first}");
    assert!(message.contains("'--desing'") && message.contains("tip: a similar argument exists: '--design'"), "{v}");
    // a check that did not pass is not an error: moo-test's per-run lines, no error object
    let o = run_gripopt(&["moo-test", "zdt1", "--pop", "8", "--generations", "2", "--json"]);
    assert_eq!(o.status.code(), Some(3), "{}", output_text(&o));
    assert!(!stdout(&o).contains("\"error\""), "{}", output_text(&o));
}

/// run.json's `problem_path`.
fn recorded_path(run_dir: &Path) -> String {
    let info: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run_dir.join("run.json")).unwrap()).unwrap();
    info["problem_path"].as_str().unwrap().to_string()
}

/// Set run.json's `problem_path` to `p` (what an older gripopt wrote).
fn set_recorded_path(run_dir: &Path, p: &str) {
    let file = run_dir.join("run.json");
    let mut info: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    info["problem_path"] = p.into();
    std::fs::write(&file, serde_json::to_string_pretty(&info).unwrap()).unwrap();
}

/// `gripopt optimise PROBLEM` (a relative path, from `cwd`) into `out`: 4 designs, 1 generation.
fn tiny_optimise(cwd: &Path, problem: &str, out: &Path) -> Output {
    let o = Command::new(GRIPOPT_BIN)
        .current_dir(cwd)
        .args(["optimise", problem, "--out"])
        .arg(out)
        .args(["--pop", "4", "--generations", "1", "--record", "none", "--threads", "1"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    o
}

#[test]
fn run_json_keeps_the_problem_path_absolute_and_normalised() {
    let d = scratch("problem-path");
    let root = std::fs::canonicalize(env!("CARGO_MANIFEST_DIR")).unwrap();
    // `./problems/../problems/bottle-1l.toml` from the repository: the `..` removed
    let out = d.join("plain");
    tiny_optimise(&root, "./problems/../problems/bottle-1l.toml", &out);
    assert_eq!(recorded_path(&out), root.join("problems/bottle-1l.toml").display().to_string());

    // `link/../p.toml` where link -> real/sub: the file opened is real/p.toml, not the
    // `p.toml` beside link that removing `..` as written would name
    let d = std::fs::canonicalize(&d).unwrap();
    std::fs::create_dir_all(d.join("real/sub")).unwrap();
    std::fs::copy(BOTTLE_FILE, d.join("real/p.toml")).unwrap();
    std::fs::write(d.join("p.toml"), "not the problem the run used\n").unwrap();
    std::os::unix::fs::symlink(d.join("real/sub"), d.join("link")).unwrap();
    let out = d.join("linked");
    tiny_optimise(&d, "link/../p.toml", &out);
    assert_eq!(recorded_path(&out), d.join("real/p.toml").display().to_string());

    // a run folder of an earlier gripopt: absolute, `..` kept; it resumes from that file
    let old = d.join("real/sub/../p.toml").display().to_string();
    set_recorded_path(&out, &old);
    let o = run_gripopt(&["resume", &out.display().to_string(), "--generations", "2"]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    assert!(!output_text(&o).contains("not found"), "the run's copy was used: {}", output_text(&o));
    assert_eq!(recorded_path(&out), old, "resume keeps run.json's path as it was");
    // and a changed problem file is still noticed there
    let edited = std::fs::read_to_string(d.join("real/p.toml")).unwrap().replace("bottle", "bottle, edited");
    std::fs::write(d.join("real/p.toml"), edited).unwrap();
    let o = run_gripopt(&["resume", &out.display().to_string(), "--generations", "3"]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    assert!(output_text(&o).contains("changed since the run started"), "{}", output_text(&o));
}

/// Issue 44 class 3: every command that writes into a folder holds that folder's lock and
/// refuses a held one (exit 2, naming the holder's pid): a sweep, `bench replay` and
/// `optimise` into a folder another process holds (here: this test's process) wrote into it
/// (a sweep, a bench) or first judged the files the holder was writing.
#[test]
fn a_folder_another_process_holds_is_refused_naming_it() {
    let d = scratch("i44-held");
    let held = d.join("held");
    std::fs::create_dir_all(&held).unwrap();
    let lock = gripopt::run::RunLock::acquire(&held).unwrap();
    let h = held.to_str().unwrap();
    let pid = format!("pid {}", std::process::id());
    for args in [
        vec!["sweep", BOTTLE_FILE, "--vary", "r=0.3:0.7:2", "--stage", "kinematics", "--out", h],
        vec!["bench", "replay", BOTTLE_FILE, "--designs", "1", "--out", h],
        vec!["optimise", BOTTLE_FILE, "--out", h, "--pop", "4", "--generations", "1", "--record", "none"],
    ] {
        let o = run_gripopt(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", output_text(&o));
        assert!(
            stderr(&o).contains("in use by another gripopt process") && stderr(&o).contains(&pid),
            "{args:?}: {}",
            output_text(&o)
        );
    }
    let names: Vec<_> = std::fs::read_dir(&held).unwrap().flatten().map(|e| e.file_name()).collect();
    assert_eq!(names, vec![std::ffi::OsString::from(".lock")], "written into the held folder");
    drop(lock);
}

/// Issue 44 class 3: a lock held by this very process (an earlier run or run folder of the
/// same program still open) named the caller's own pid as "another gripopt process"; it now
/// says it is this process. And an I/O race (a file the command made that went missing
/// before its rename) is a failure (exit 1), never bad input (exit 2).
#[test]
fn the_lock_error_says_when_the_holder_is_this_process_and_a_race_is_not_bad_input() {
    let d = scratch("i44-own-lock");
    let _held = gripopt::run::RunLock::acquire(&d).unwrap();
    let e = gripopt::run::RunLock::acquire(&d).unwrap_err().to_string();
    assert!(e.contains("this same process") && !e.contains("another gripopt process"), "{e}");
    let gone = || std::io::Error::from(std::io::ErrorKind::NotFound);
    let race = gripopt::Error::io(d.join("x"), "cannot rename the temporary file into place", gone());
    assert_eq!(race.exit_code(), 1, "{race}");
    // a folder that does not exist, given by the user, stays bad input
    let missing = gripopt::Error::io(d.join("none/x"), "cannot create", gone());
    assert_eq!(missing.exit_code(), 2, "{missing}");
}

/// Issue 44 class 8: Unicode format characters (U+202E RIGHT-TO-LEFT OVERRIDE turns the
/// rest of a line around on a terminal) reached the terminal raw in messages; they are
/// escaped as control characters are. A path starting with `-` (`--out=-weird`) was printed
/// in commands to copy as `-weird`, which the command takes for an option: now `./-weird`.
#[test]
fn messages_escape_format_characters_and_paths_that_look_like_options() {
    let d = scratch("i44-escape");
    let evil = d.join("a\u{202e}fdp.toml");
    let o = run_gripopt(&["evaluate", evil.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    assert!(!output_text(&o).contains('\u{202e}') && stderr(&o).contains("\\u{202e}"), "{}", output_text(&o));
    assert_eq!(gripopt::run::shell_quote("-weird"), "./-weird");
    assert_eq!(gripopt::run::shell_quote("a\u{202e}b"), "$'a\\u202eb'");
    let o = Command::new(GRIPOPT_BIN)
        .current_dir(&d)
        .args(["optimise", BOTTLE_FILE, "--out=-weird", "--pop", "4", "--generations", "1", "--record", "none"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    let all = output_text(&o);
    for (at, _) in all.match_indices("-weird") {
        assert!(all[..at].ends_with("./"), "a command names `-weird` bare: {all}");
    }
    let show = Command::new(GRIPOPT_BIN).current_dir(&d).args(["show", "./-weird"]).output().unwrap();
    assert_eq!(show.status.code(), Some(0), "{}", output_text(&show));
}

/// Issue 44 class 8: numbers in messages are compact: with `criteria.dx_max = 1e-300` every
/// design fails the impact criterion by a violation of ~1e298, which the run's closing
/// account of discards printed with 299 digits.
#[test]
fn numbers_in_messages_never_run_to_hundreds_of_digits() {
    let d = scratch("i44-digits");
    let p = d.join("p.toml");
    let text_ = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    let edited: String = text_
        .lines()
        .map(|l| if l.starts_with("dx_max") { "dx_max = 1e-300".to_string() } else { l.to_string() })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(&p, edited).unwrap();
    let out = d.join("run");
    let o = run_gripopt(&[
        "optimise",
        p.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--pop",
        "4",
        "--generations",
        "1",
        "--record",
        "none",
    ]);
    let all = output_text(&o);
    assert!(all.contains("violation"), "{all}");
    let longest = all.split(|c: char| !c.is_ascii_digit()).map(str::len).max().unwrap_or(0);
    assert!(longest < 25, "a number of {longest} digits: {all}");
    assert_eq!(gripopt::run::short_num(1.477_742_540_137_088e298, 4), "1.478e298");
    assert_eq!(gripopt::run::short_num(0.12345, 4), "0.1235");
    assert_eq!(gripopt::run::exact_num(1e-300), "1e-300");
}

/// Issue 44 class 3: writers of one file at the same moment (two exports to one `--out`)
/// raced on its temporary file: one failed with "File exists" or "No such file", reported as
/// bad input (exit 2). Now the temporary file is locked before it takes its name: each write
/// either lands whole or fails as busy (exit 1), and the file always holds one whole write.
#[test]
fn writers_of_one_file_at_once_never_fail_as_bad_input() {
    let d = scratch("i44-writers-race");
    let f = d.join("out.txt");
    let texts: Vec<String> = (0..4).map(|k| format!("{k}").repeat(200_000)).collect();
    std::thread::scope(|s| {
        for t in &texts {
            let f = &f;
            s.spawn(move || {
                for _ in 0..50 {
                    if let Err(e) = gripopt::write_atomic(f, t.as_bytes()) {
                        assert_eq!(e.exit_code(), 1, "{e}");
                    }
                }
            });
        }
    });
    let got = std::fs::read_to_string(&f).unwrap();
    assert!(texts.contains(&got), "a mixed or partial file");
    let names: Vec<String> =
        std::fs::read_dir(&d).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
    assert_eq!(names, vec!["out.txt".to_string()], "temporary files left");
}

/// A seed range too long to hold was an allocation failure (SIGABRT, exit 134, no JSON):
/// now exit 2 with the JSON error naming the flag and the limit.
/// Origin: hostile pass of session 34, the CLI.
#[test]
fn a_huge_seed_range_is_bad_input_not_an_abort() {
    let o =
        run_gripopt(&["moo-test", "zdt1", "--seeds", "1-10000000000", "--pop", "4", "--generations", "1", "--json"]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    let e = json_stdout(&o)["error"].as_str().unwrap().to_string();
    assert!(e.contains("--seeds") && e.contains("at most 100000"), "{e}");
}

/// The text report counts the seeds it ran ("1 seed", "2 seeds"), not "seeds  1".
/// Origin: hostile pass of session 34, the CLI.
#[test]
fn moo_test_says_how_many_seeds_it_ran() {
    let text = |seeds: &str| {
        let o = run_gripopt(&["moo-test", "zdt1", "--seeds", seeds, "--pop", "8", "--generations", "2"]);
        output_text(&o)
    };
    assert!(text("3-3").contains(" 1 seed: HV median"), "{}", text("3-3"));
    assert!(text("3-4").contains(" 2 seeds: HV median"), "{}", text("3-4"));
}

/// A usage error under `--json` kept only clap's first line ("the following required
/// arguments were not provided:"), not which argument.
/// Origin: hostile pass of session 34, the CLI.
#[test]
fn a_json_usage_error_names_what_is_missing_or_wrong() {
    let error = |args: &[&str]| {
        let o = run_gripopt(args);
        assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
        json_stdout(&o)["error"].as_str().unwrap().to_string()
    };
    assert_eq!(error(&["moo-test", "--json"]), "the following required arguments were not provided: <NAME>");
    assert_eq!(
        error(&["optimise", "--json"]),
        "the following required arguments were not provided: --out <OUT>, <PROBLEM>"
    );
    let bad = error(&["simulate", BOTTLE_FILE, "--json", "--method", "foo"]);
    assert!(bad.contains("'foo'") && bad.contains("--method") && bad.contains("auto"), "{bad}");
}

/// `--json=yes` (a flag given a value) printed clap's refusal on stderr only: it asked for
/// JSON, so the refusal is the JSON object too.
/// Origin: hostile pass of session 34, the CLI.
#[test]
fn a_json_flag_given_a_value_still_gets_a_json_refusal() {
    let o = run_gripopt(&["evaluate", BOTTLE_FILE, "--json=yes"]);
    assert_eq!(o.status.code(), Some(2), "{}", output_text(&o));
    let e = json_stdout(&o)["error"].as_str().unwrap().to_string();
    assert!(e.contains("--json"), "{e}");
}
