//! What gripopt reads and writes in and beside run folders: `--force` replaces an earlier
//! output and nothing else (never a pipe, a device, a link, the command's own input, another
//! run's file or a robust problem's object file); a run folder's file that is not a regular
//! file is refused, never read or waited on; a folder where a rewritten file goes is refused
//! before any work; no run is created inside another run's folder. Pipes are made only in
//! the tests' scratch folders (skipped where `mkfifo` is unavailable); /dev/zero is only ever
//! read, through a link, by a process limited to 2 GiB of memory.

use crate::common::{
    cli_tiny_run, fifo, is_fifo, output_text, run_gripopt, run_limited, scratch, BOTTLE_FILE, KITCHEN_FILE,
};
use std::path::{Path, PathBuf};
use std::process::Output;

fn is_link(path: &Path) -> bool {
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink())
}

/// Exit 2 naming `flag`, `path` and `why`.
fn refused(o: &Output, flag: &str, path: &Path, why: &str) {
    let text = output_text(o);
    assert_eq!(o.status.code(), Some(2), "{text}");
    assert!(text.contains(&format!("{flag} {}", path.display())), "{text}");
    assert!(text.contains(why), "{text}");
}

/// `--force` replaced whatever stood at the output path: a named pipe, a link to a device,
/// the export's own problem file (named as itself, or through a link). Now each is refused
/// (exit 2, naming the flag and the path) and left as it was; `--force` still replaces an
/// earlier export; a link, dangling or not, is refused even with `--force` (issue 44).
/// Origin: hostile pass of session 34, files.
#[test]
fn force_replaces_an_earlier_output_and_nothing_else() {
    let d = scratch("force");
    let export = |source: &Path, out: &Path, force: bool| {
        let (source, out) = (source.to_str().unwrap(), out.to_str().unwrap());
        let mut args = vec!["export", source, "--format", "json", "--out", out];
        if force {
            args.push("--force");
        }
        run_limited(&d, &args)
    };
    // the export's own problem file, and a link to it
    let own = d.join("own.toml");
    std::fs::copy(KITCHEN_FILE, &own).unwrap();
    let before = std::fs::read(&own).unwrap();
    refused(&export(&own, &own, true), "--out", &own, "is the command's input");
    let link = d.join("link.json");
    std::os::unix::fs::symlink("own.toml", &link).unwrap();
    refused(&export(&own, &link, true), "--out", &link, "is the command's input");
    assert_eq!(std::fs::read(&own).unwrap(), before, "the problem file was overwritten");
    assert!(is_link(&link), "the link was replaced");
    // a link to a device (never written: the link would have been replaced, not followed)
    let zero = d.join("zero.json");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    refused(&export(&own, &zero, true), "--out", &zero, "not a regular file (a device)");
    assert!(is_link(&zero), "the link to the device was replaced");
    // an earlier export is replaced with --force (and refused without)
    let sheet = d.join("sheet.json");
    assert_eq!(export(&own, &sheet, false).status.code(), Some(0));
    refused(&export(&own, &sheet, false), "--out", &sheet, "add --force");
    let o = export(&own, &sheet, true);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    // a dangling link: a link is never replaced nor written through, --force included
    // (issue 44 class 1: it was replaced with --force)
    let dangling = d.join("dangling.json");
    std::os::unix::fs::symlink("nowhere.json", &dangling).unwrap();
    for force in [false, true] {
        refused(&export(&own, &dangling, force), "--out", &dangling, "is a symbolic link to nowhere.json");
    }
    assert!(is_link(&dangling) && !d.join("nowhere.json").exists());
    // a named pipe: export --out and simulate --csv / --plot
    let pipe = d.join("pipe.csv");
    if !fifo(&pipe) {
        return;
    }
    refused(&export(&own, &pipe, true), "--out", &pipe, "not a regular file (a named pipe)");
    let p = pipe.to_str().unwrap();
    let o = run_limited(&d, &["simulate", BOTTLE_FILE, "--csv", p, "--force"]);
    refused(&o, "--csv", &pipe, "not a regular file (a named pipe)");
    assert!(is_fifo(&pipe), "the pipe was replaced");
}

/// A recorded run of bottle-1l (pop 8, 2 generations, seed 16) in `target/hostile34/NAME`.
fn run_folder(name: &str) -> PathBuf {
    crate::common::tiny_run_in(scratch(name).join("run"), Path::new(BOTTLE_FILE), 8, 2)
}

/// `file` of the run folder `run` replaced by `what` (`pipe`, `zero`: a link to /dev/zero,
/// `folder`, or a sparse regular file of `big` bytes); false when a pipe cannot be made.
fn replace(run: &Path, file: &str, what: &str, big: u64) -> bool {
    let p = run.join(file);
    std::fs::remove_file(&p).unwrap();
    match what {
        "pipe" => return fifo(&p),
        "zero" => std::os::unix::fs::symlink("/dev/zero", &p).unwrap(),
        "folder" => std::fs::create_dir(&p).unwrap(),
        _ => std::fs::File::create(&p).unwrap().set_len(big).unwrap(),
    }
    true
}

/// A run folder's file that is not a regular file hung `resume` (checkpoint.json a pipe,
/// holding the folder's lock), filled the memory (a link to /dev/zero) or hung `show`
/// (run.json), and `show` and `verify` called a checkpoint.json that is a folder or pipe
/// missing (`export` a run folder whose problem.toml is a folder not a run folder). Now each
/// command ends with exit 2 naming the file and saying "not a regular file"; a file far
/// larger than gripopt writes is refused before it is read; a recording index that cannot
/// be read is rebuilt from the shards (replay of design 3 verifies).
/// Origin: hostile pass of session 34, files.
#[test]
fn run_folder_files_are_read_only_when_regular_files() {
    let base = run_folder("folder");
    let dir = base.parent().unwrap();
    let case = dir.join("case");
    let r = case.to_str().unwrap();
    let cases: [(&str, &str, &[&str], &str); 9] = [
        ("checkpoint.json", "pipe", &["resume", r], "not a regular file (a named pipe"),
        ("checkpoint.json", "pipe", &["show", r], "not a regular file (a named pipe"),
        ("checkpoint.json", "zero", &["resume", r], "not a regular file (a device"),
        ("checkpoint.json", "folder", &["show", r], "not a regular file (a folder"),
        ("checkpoint.json", "pipe", &["verify", r], "not a regular file (a named pipe"),
        (
            "problem.toml",
            "folder",
            &["export", r, "--design", "3", "--format", "json", "--out", "-"],
            "not a regular file (a folder",
        ),
        ("run.json", "zero", &["show", r], "not a regular file (a device"),
        ("run.json", "pipe", &["show", r], "not a regular file (a named pipe"),
        ("run.json", "big", &["show", r], "larger than 67108864 bytes"),
    ];
    for (file, what, args, why) in cases {
        crate::common::copy_dir(&base, &case);
        if !replace(&case, file, what, (64 << 20) + 1) {
            return;
        }
        let o = run_limited(dir, args);
        let text = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{file} {what}, {args:?}: {text}");
        assert!(text.contains(&format!("{file}: ")) && text.contains(why), "{file} {what}, {args:?}: {text}");
        assert!(!text.contains("missing"), "{file} {what}, {args:?}: {text}");
    }
    // the recording index: read from the shards instead
    for what in ["zero", "pipe"] {
        crate::common::copy_dir(&base, &case);
        if !replace(&case, "recording/index.jsonl", what, 0) {
            return;
        }
        let o = run_limited(dir, &["replay", r, "--design", "3"]);
        assert_eq!(o.status.code(), Some(0), "index.jsonl {what}: {}", output_text(&o));
        assert!(String::from_utf8_lossy(&o.stdout).contains("verified"), "{}", output_text(&o));
    }
}

/// `simulate P --csv P --force` overwrote its own problem file, and `replay RUN --csv
/// RUN/run.json --force` the run's run.json. Now both are refused (exit 2, the file left as
/// it was); a new file inside the run folder is still written.
/// Origin: hostile pass of session 34, files.
#[test]
fn simulate_and_replay_never_write_over_their_inputs() {
    let d = scratch("inputs");
    let own = d.join("own.toml");
    std::fs::copy(BOTTLE_FILE, &own).unwrap();
    let before = std::fs::read(&own).unwrap();
    let o = run_limited(&d, &["simulate", own.to_str().unwrap(), "--csv", own.to_str().unwrap(), "--force"]);
    refused(&o, "--csv", &own, "is the command's input");
    assert_eq!(std::fs::read(&own).unwrap(), before, "the problem file was overwritten");
    let run = run_folder("inputs-run");
    let (r, run_json) = (run.to_str().unwrap(), run.join("run.json"));
    let before = std::fs::read(&run_json).unwrap();
    for flag in ["--csv", "--plot"] {
        let o = run_limited(&d, &["replay", r, "--design", "3", flag, run_json.to_str().unwrap(), "--force"]);
        refused(&o, flag, &run_json, "is a file of the folder");
    }
    assert_eq!(std::fs::read(&run_json).unwrap(), before, "run.json was overwritten");
    let new = run.join("design-3.csv");
    let o = run_limited(&d, &["replay", r, "--design", "3", "--csv", new.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    assert!(new.is_file());
}

/// A second pass found `--force` still replacing the files of a run folder that was not the
/// command's input (`simulate P --csv OTHER_RUN/pareto.csv --force`, through a link to the
/// folder too, and `replay` into another run), and a robust problem's object file
/// (`file = "can2.toml"`, then `--csv can2.toml --force`), which broke the problem. Both
/// are refused now, the files unchanged; a new file beside a run's is still written.
/// Origin: hostile pass of session 34, files.
#[test]
fn force_never_replaces_a_run_folders_file_or_an_object_file() {
    let d = scratch("run-files");
    let run = crate::common::tiny_run("hostile34-other-run", Path::new(BOTTLE_FILE), 8, 1);
    let link = d.join("link-to-run");
    std::os::unix::fs::symlink(&run, &link).unwrap();
    let before: Vec<Vec<u8>> =
        ["pareto.csv", "population.csv", "history.csv"].iter().map(|f| std::fs::read(run.join(f)).unwrap()).collect();
    for target in [run.join("pareto.csv"), link.join("history.csv")] {
        let o = run_limited(&d, &["simulate", BOTTLE_FILE, "--csv", target.to_str().unwrap(), "--force"]);
        refused(&o, "--csv", &target, "is a file of the gripopt run folder");
    }
    let other = crate::common::tiny_run("hostile34-replayed-run", Path::new(BOTTLE_FILE), 8, 1);
    let target = run.join("population.csv");
    let args = ["replay", other.to_str().unwrap(), "--design", "1", "--csv", target.to_str().unwrap(), "--force"];
    refused(&run_limited(&d, &args), "--csv", &target, "is a file of the gripopt run folder");
    let after: Vec<Vec<u8>> =
        ["pareto.csv", "population.csv", "history.csv"].iter().map(|f| std::fs::read(run.join(f)).unwrap()).collect();
    assert!(before == after, "a run's tables changed");
    let fresh = run.join("mine.csv");
    let o = run_limited(&d, &["simulate", BOTTLE_FILE, "--csv", fresh.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));

    // a robust problem whose can comes from a file beside it
    let kitchen = std::fs::read_to_string(KITCHEN_FILE).unwrap();
    let inline = "name = \"can\"             # as can.toml: a 330 ml can, 0.34 kg\nradius = 0.030\nlength = 0.115\ndensity = 1050.0\ngrasp_height = 0.040\n";
    assert!(kitchen.contains(inline), "kitchen.toml's can is inline");
    let problem = d.join("k-file.toml");
    std::fs::write(&problem, kitchen.replacen(inline, "name = \"can\"\nfile = \"can2.toml\"\n", 1)).unwrap();
    let can = d.join("can2.toml");
    std::fs::copy(Path::new(KITCHEN_FILE).with_file_name("can.toml"), &can).unwrap();
    let can_text = std::fs::read(&can).unwrap();
    let p = problem.to_str().unwrap();
    let o = run_limited(&d, &["simulate", p, "--object", "can", "--csv", can.to_str().unwrap(), "--force"]);
    refused(&o, "--csv", &can, "is the command's input");
    let o = run_limited(
        &d,
        &["export", p, "--object", "can", "--format", "json", "--out", can.to_str().unwrap(), "--force"],
    );
    refused(&o, "--out", &can, "is the command's input");
    assert_eq!(std::fs::read(&can).unwrap(), can_text, "the object file is unchanged");
}

/// A folder where a run's view stands (pareto.csv) made `resume` evaluate a whole generation
/// and then fail on the rename, again on every retry (history.csv already a generation
/// ahead of the checkpoint); a folder at verify.csv failed `verify` after all its work. Both
/// are refused before any work now, the folder as it was.
/// Origin: hostile pass of session 34, files.
#[test]
fn a_folder_where_a_rewritten_file_goes_is_refused_before_any_work() {
    let d = scratch("rewritten");
    let run = crate::common::tiny_run("hostile34-rewritten", Path::new(BOTTLE_FILE), 8, 1);
    let r = run.to_str().unwrap();
    let checkpoint = std::fs::read(run.join("checkpoint.json")).unwrap();
    let history = std::fs::read(run.join("history.csv")).unwrap();
    std::fs::remove_file(run.join("pareto.csv")).unwrap();
    std::fs::create_dir(run.join("pareto.csv")).unwrap();
    let o = run_limited(&d, &["resume", r, "--generations", "2"]);
    let e = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains("pareto.csv") && e.contains("not a regular file (a folder)") && e.contains("nothing was done"),
        "{e}"
    );
    assert_eq!(std::fs::read(run.join("checkpoint.json")).unwrap(), checkpoint, "checkpoint unchanged");
    assert_eq!(std::fs::read(run.join("history.csv")).unwrap(), history, "history not extended");
    std::fs::create_dir(run.join("verify.csv")).unwrap();
    let o = run_limited(&d, &["verify", r]);
    let e = output_text(&o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("verify.csv") && e.contains("not a regular file (a folder)"), "{e}");
}

/// `optimise --out RUN/recording/sub` (or `RUN/sub`) created a run inside another run's
/// folder; refused (exit 2) like export and sweep refuse to write into a run folder, with
/// nothing created.
/// Origin: hostile pass of session 35 on the CLI.
#[test]
fn optimise_refuses_a_run_inside_another_runs_folder() {
    let d = scratch("nested");
    let run = cli_tiny_run(&d);
    for sub in ["recording/sub", "sub", "sub/deeper"] {
        let out = run.join(sub);
        let o =
            run_gripopt(&["optimise", BOTTLE_FILE, "--out", out.to_str().unwrap(), "--pop", "4", "--generations", "1"]);
        let text = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{sub}: {text}");
        assert!(text.contains("inside the run folder") && text.contains("holds run.json"), "{sub}: {text}");
        assert!(!out.exists() && !run.join("sub").exists(), "{sub}: nothing created");
    }
    // beside the run: a new run as before
    let o = run_gripopt(&[
        "optimise",
        BOTTLE_FILE,
        "--out",
        d.join("other").to_str().unwrap(),
        "--pop",
        "4",
        "--generations",
        "1",
    ]);
    assert!(o.status.success(), "{}", output_text(&o));
}

/// The library refuses it too (Python's `optimise` and any Rust caller go through
/// `run::optimise`, not the CLI's check): nothing is created inside the run.
/// Origin: hostile pass of session 35 on the CLI.
#[test]
fn the_library_refuses_a_run_inside_another_runs_folder() {
    let d = scratch("nested-lib");
    let run = cli_tiny_run(&d);
    let out = run.join("recording").join("sub");
    let spec = gripopt::run::RunSpec {
        problem_path: PathBuf::from(BOTTLE_FILE),
        out: out.clone(),
        pop: 4,
        generations: 1,
        seed: 1,
        threads: Some(1),
        record: gripopt::record::RecordOptions::default(),
    };
    let e = gripopt::run::optimise(&spec).unwrap_err().to_string();
    assert!(e.contains("inside the run folder") && e.contains("holds run.json"), "{e}");
    assert!(!out.exists());
}
