//! Robustness of the commands around a run (issue 12, continued from `robustness`): bench
//! summaries and flags, the designs-per-thread note, `show` on missing or damaged files, and
//! damaged MCAP shards.
use crate::robustness::{cli, code, read, spec, stderr, tmp, PROBLEM};
use gripopt::record::{read_index, recover};
use gripopt::run::{optimise, resume};
use std::path::{Path, PathBuf};
use std::process::Output;

/// `gripopt bench … --json`: the figures as one JSON object on stdout (the text report on
/// stderr), with the discard counts adding up to the designs drawn.
#[test]
fn bench_json_summaries() {
    let out = cli(&["bench", "static", PROBLEM, "--n", "200", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON object");
    let discarded: u64 = v["discarded_by_stage"].as_array().unwrap().iter().map(|c| c.as_u64().unwrap()).sum();
    assert_eq!(discarded + v["passed_stage_2"].as_u64().unwrap(), 200, "{v}");
    assert!(v["designs_per_s_min_time"].as_f64().unwrap() > 0.0);
    assert!(String::from_utf8_lossy(&out.stderr).contains("static pipeline"));
}

/// `gripopt bench replay` runs to its end: the synthetic run's designs replay (they are
/// found, read and re-evaluated with the problem file the synthetic run recorded), and no
/// count of 0 is taken (exit 2 naming the flag, not a panic).
#[test]
fn bench_replay_runs_to_its_end_and_refuses_zero_designs() {
    let dir = tmp("bench-replay-end");
    let o = dir.to_str().unwrap();
    let out = cli(&["bench", "replay", PROBLEM, "--designs", "6", "--per-shard", "2", "--out", o, "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("stdout is one JSON object");
    assert!(v.to_string().contains("replay"), "{v}");
    assert!(!dir.exists(), "the synthetic run is removed without --keep");
    for flag in ["--designs", "--per-shard"] {
        let out = cli(&["bench", "replay", PROBLEM, flag, "0", "--out", o]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flag}: {err}");
        assert!(err.contains(&format!("{flag} 0")), "{err}");
    }
}

/// `gripopt bench replay --out DIR` never deletes a folder it did not write itself.
#[test]
fn bench_replay_refuses_to_clear_a_folder_it_did_not_write() {
    let dir = tmp("bench-replay-guard");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("precious.csv"), "keep me").unwrap();
    let out = cli(&["bench", "replay", PROBLEM, "--designs", "10", "--out", dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a synthetic run"));
    assert_eq!(std::fs::read_to_string(dir.join("precious.csv")).unwrap(), "keep me");
}

/// `gripopt optimise` of the default problem into `out` with `flags`.
fn optimise_cli(out: &Path, flags: &[&str]) -> Output {
    let o = out.to_str().unwrap();
    cli(&[&["optimise", PROBLEM, "--out", o], flags].concat())
}

/// Too few designs per thread draw a note on stderr (the run still succeeds, and its
/// results do not depend on the thread count); enough designs per thread draw none.
#[test]
fn few_designs_per_thread_draw_a_note() {
    let (a, b) = (tmp("note-few"), tmp("note-enough"));
    let few = optimise_cli(&a, &["--pop", "8", "--generations", "1", "--threads", "4", "--record", "none"]);
    assert_eq!(code(&few), 0, "{}", stderr(&few));
    assert!(stderr(&few).contains("a population of 8 on 4 threads is 2.0 designs per thread"), "{}", stderr(&few));
    // a bad value is refused first, without the note
    let bad = optimise_cli(&tmp("note-bad"), &["--pop", "2", "--generations", "1", "--threads", "4"]);
    assert_eq!(code(&bad), 2, "{}", stderr(&bad));
    assert!(!stderr(&bad).contains("designs per thread"), "{}", stderr(&bad));
    let enough = optimise_cli(&b, &["--pop", "8", "--generations", "1", "--threads", "2", "--record", "none"]);
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
    for (flag, value, range) in [
        ("--threads", "0", "1 to 1024"),
        ("--threads", "1025", "1 to 1024"),
        ("--max-threads", "0", "1 to 1024"),
        ("--max-threads", "1025", "1 to 1024"),
        ("--reps", "0", "at least 1"),
        ("--pop", "0", "at least 4"),
        ("--generations", "0", "at least 1"),
    ] {
        let r = cli(&["bench", "scaling", PROBLEM, flag, value, "--no-record", "--out", o]);
        let e = stderr(&r);
        assert_eq!(code(&r), 2, "{flag} {value}: {e}");
        assert!(e.contains(&format!("{flag} {value}:")) && e.contains(range), "{flag} {value}: {e}");
        // only the offending flag is named
        let others = ["--threads", "--max-threads", "--reps", "--pop", "--generations"]
            .into_iter()
            .filter(|f| *f != flag && !flag.ends_with(&f[2..]) && !f.ends_with(&flag[2..]));
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
    let r = cli(&[
        "bench",
        "--json",
        "scaling",
        PROBLEM,
        "--pop",
        "8",
        "--generations",
        "1",
        "--reps",
        "1",
        "--threads",
        "2",
        "--no-record",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code(&r), 0, "{}", stderr(&r));
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    assert_eq!(rows[0]["threads"], 1);
    assert!(rows[0]["ceiling_efficiency"].is_null() && rows[0]["of_ceiling"].is_null(), "{}", rows[0]);
    assert_eq!(
        rows[0]["independent_wall_s"].as_array().map(Vec::len),
        Some(0),
        "the 1-thread ceiling was run: {}",
        rows[0]
    );
    assert_eq!(rows[1]["threads"], 2);
    assert!(rows[1]["ceiling_efficiency"].as_f64().is_some_and(|c| c > 0.0), "{}", rows[1]);
    assert_eq!(rows[1]["independent_wall_s"].as_array().map(Vec::len), Some(1));
    // the text row at 1 thread: eff 100.0 %, then "-" for ceiling and of ceil.
    let text = stderr(&r);
    let one = text.lines().find(|l| l.trim_start().starts_with("1 ")).unwrap_or_else(|| panic!("{text}"));
    let cells: Vec<&str> = one.split_whitespace().collect();
    assert_eq!(&cells[4..8], &["100.0", "%", "-", "-"], "{one}");
}

/// A small finished run (seed 8, 4 generations: twelve designs in pareto.csv, eleven of them
/// form closed; since issue 42's optimiser), without recording.
fn small_front_run(name: &str) -> PathBuf {
    let dir = tmp(name);
    let o = optimise_cli(&dir, &["--pop", "12", "--generations", "4", "--seed", "8", "--record", "none"]);
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
    let header =
        text.lines().find(|l| l.starts_with("id,")).unwrap().split(',').map(str::to_string).collect::<Vec<_>>();
    let (mo, ts) =
        (header.iter().position(|c| c == "max_offset").unwrap(), header.iter().position(|c| c == "t_stab").unwrap());
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
    // without its checkpoint (whose designs `show` lists when there is one), the run is shown
    // from pareto.csv, as before its first checkpoint
    std::fs::remove_file(dir.join("checkpoint.json")).unwrap();
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
        // `reason` is JSON text (null for a feasible design), not the CSV's quoted cell; the
        // columns come in the file's order
        assert!(designs.iter().all(|x| x["reason"].is_null()), "{v}");
        let keys: Vec<&String> = designs[0].as_object().unwrap().keys().collect();
        assert_eq!(keys.len(), gripopt::run::DESIGN_COLUMNS.len() + 1, "{keys:?}");
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
    assert!(
        !e.contains("Backtrace") && !e.contains('\u{1b}') && !e.contains(".cargo") && !e.contains("records.rs"),
        "{e}"
    );
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
    let epoch_ns =
        summary.chunk_indexes.iter().map(|c| c.message_start_time).min().unwrap() - g2.first_id * 1_000_000_000;
    let ci =
        summary.chunk_indexes.iter().find(|c| c.message_start_time >= epoch_ns + g2.first_id * 1_000_000_000).unwrap();
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
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|f| f.path().is_file())
        .map(|f| (f.file_name().to_string_lossy().to_string(), std::fs::read(f.path()).unwrap()))
        .collect();
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
    assert!(
        r.warnings(&rdir).iter().any(|w| w.contains("generation 2") && w.contains(&g2.file)),
        "{:?}",
        r.warnings(&rdir)
    );
    resume(&dir, Some(4), false, Some(2)).unwrap();
    let gens: Vec<u64> = read_index(&rdir).unwrap().iter().map(|e| e.generation).collect();
    assert_eq!(gens, vec![1, 3, 4]);
    let e = gripopt::record::read_design(&dir, (g2.first_id + g2.last_id) / 2).unwrap_err().to_string();
    assert!(
        e.contains("generation 2") && e.contains(&g2.file) && e.contains(&format!("{}..={}", g2.first_id, g2.last_id)),
        "{e}"
    );
    let o = cli(&["replay", &dir.display().to_string(), "--design", &g2.first_id.to_string()]);
    assert_eq!(code(&o), 2, "{}", stderr(&o));
    assert!(
        !stderr(&o).contains(&format!("0..={}", read_index(&rdir).unwrap().last().unwrap().last_id)),
        "{}",
        stderr(&o)
    );
}
