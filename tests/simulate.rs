//! `gripopt simulate`: `--csv` streams its rows to the file while the simulation runs (no
//! trajectory held in memory; the file holds exactly the library's trajectory, appears only
//! when complete, nothing is left behind on failure or ctrl-c), `--object` simulates one
//! object of a robust problem, and `--json` carries the flags that change the record.

use crate::common::{
    json_of, json_stdout, kitchen_with, output_text, run_gripopt, scratch, untimed, without_robust, BOTTLE_FILE,
    KITCHEN_FILE,
};
use gripopt::params::{Problem, SceneKind};
use serde_json::Value;
use std::path::Path;
use std::time::{Duration, Instant};

fn names(d: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// The numbers of a CSV's data rows (after the `#` lines and the header).
fn rows(p: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    lines.next().expect("a header");
    lines.map(|l| l.split(',').map(|c| c.parse().unwrap()).collect()).collect()
}

/// The streamed CSV of the centred and the free scene holds, row for row, the samples the
/// library's own `simulate` keeps in memory (parsed back from `{:e}`, exact for f64).
/// Origin: session 35, simulate --csv streamed to the file.
#[test]
fn the_streamed_csv_is_the_librarys_trajectory() {
    let d = scratch("same");
    let p = Problem::load(Path::new(BOTTLE_FILE)).unwrap();
    for (scene, kind) in [("centred", SceneKind::Centred), ("free", SceneKind::Free)] {
        let csv = d.join(format!("{scene}.csv"));
        let o = run_gripopt(&["simulate", BOTTLE_FILE, "--scene", scene, "--csv", csv.to_str().unwrap()]);
        let text = output_text(&o);
        assert_eq!(o.status.code(), Some(0), "{text}");
        let choice = Some(gripopt::SceneChoice { kind, x_off: None });
        let req = gripopt::SimulateRequest { scene: choice, ..Default::default() };
        let sim = gripopt::simulate(&p, &p.nominal, &req).unwrap();
        let want: Vec<Vec<f64>> = if kind == SceneKind::Free {
            sim.poses.iter().map(|s| gripopt::pose_values(s).to_vec()).collect()
        } else {
            sim.trajectory.samples.iter().map(|s| gripopt::sample_values(s).to_vec()).collect()
        };
        let got = rows(&csv);
        assert!(want.len() > 100, "{scene}: {} samples", want.len());
        assert_eq!(got, want, "{scene}");
        assert!(text.contains(&format!("trajectory: {} samples written to", want.len())), "{text}");
        assert_eq!(names(&d).iter().filter(|n| n.ends_with(".tmp")).count(), 0, "{:?}", names(&d));
    }
}

/// A design that never reaches its scene writes no CSV and leaves no temporary file.
/// Origin: session 35, simulate --csv streamed to the file.
#[test]
fn a_discarded_design_leaves_nothing() {
    let d = scratch("discarded");
    let csv = d.join("t.csv");
    // stage 1: no closed pose on the object
    let design = "l21=0.02,b=0.09,t22=0.035,r=0.5,p=0.4,psi_deg=130";
    let o = run_gripopt(&["simulate", BOTTLE_FILE, "--design", design, "--csv", csv.to_str().unwrap()]);
    assert_ne!(o.status.code(), Some(0), "{}", output_text(&o));
    assert!(output_text(&o).contains("discarded"), "{}", output_text(&o));
    assert!(names(&d).is_empty(), "left behind: {:?}", names(&d));
}

/// ctrl-c during a long `simulate --csv` ends it (exit 130) without a CSV or its temporary
/// file.
/// Origin: session 35, simulate --csv streamed to the file.
#[test]
fn ctrl_c_leaves_no_csv() {
    let d = scratch("ctrl-c");
    let text = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    let line = |key: &str| text.lines().find(|l| l.starts_with(&format!("{key} "))).unwrap().to_string();
    let slow = text.replacen(&line("v_s"), "v_s = 1e-10", 1).replacen(&line("max_steps"), "max_steps = 50000000", 1);
    let p = d.join("slow.toml");
    std::fs::write(&p, slow).unwrap();
    let csv = d.join("t.csv");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_gripopt"))
        .args(["simulate", p.to_str().unwrap(), "--csv", csv.to_str().unwrap()])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let tmp = d.join(".t.csv.tmp");
    let t0 = Instant::now();
    // rows are being written (the temporary file grows), and the run is still going
    while std::fs::metadata(&tmp).map_or(0, |m| m.len()) < 64 << 10 {
        assert!(t0.elapsed() < Duration::from_secs(60), "no rows streamed: {:?}", names(&d));
        assert!(child.try_wait().unwrap().is_none(), "ended early");
        std::thread::sleep(Duration::from_millis(20));
    }
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{status:?}");
    assert_eq!(names(&d), vec!["slow.toml".to_string()]);
}

/// A link left at an output's temporary name (`.NAME.tmp`) is never written through: the
/// plot and the CSV are written, the link's target is untouched.
/// Origin: session 35, simulate --csv streamed to the file.
#[test]
fn a_link_at_the_temporary_name_is_not_followed() {
    let d = scratch("tmp-link");
    let victim = d.join("victim.txt");
    std::fs::write(&victim, "mine").unwrap();
    for (flag, file) in [("--plot", "p.svg"), ("--csv", "t.csv")] {
        std::os::unix::fs::symlink(&victim, d.join(format!(".{file}.tmp"))).unwrap();
        let out = d.join(file);
        let o = run_gripopt(&["simulate", BOTTLE_FILE, flag, out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "mine", "{flag}");
        assert!(std::fs::metadata(&out).unwrap().len() > 1000, "{flag}");
    }
    assert_eq!(names(&d), vec!["p.svg", "t.csv", "victim.txt"]);
}

/// The free scene's first pose is the state as the scene begins, its ground points pre-sunk
/// and in contact: its energy is the record's E(0), ground springs included (the first row
/// used to leave out their 4.4 µJ).
/// Origin: session 35, simulate --csv streamed to the file.
#[test]
fn the_free_scenes_first_pose_has_the_records_initial_energy() {
    let d = scratch("first-pose");
    let csv = d.join("free.csv");
    let o = run_gripopt(&["simulate", BOTTLE_FILE, "--scene", "free", "--json", "--csv", csv.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let e0 = v["free_scene"]["energy"][0].as_f64().unwrap();
    let first = &rows(&csv)[0];
    let energy = first[gripopt::POSE_COLUMNS.iter().position(|c| c.0 == "energy").unwrap()];
    assert_eq!(first[0], 0.0);
    assert!((energy - e0).abs() <= 1e-12 * e0, "first row {energy} J, record {e0} J");
}

/// `simulate` of a robust problem ran the reference `[object]` without a word (export and
/// sweep say so) and could not run any of its objects, while docs/robust.md said `file =`
/// objects work for simulate. Now `--object NAME` simulates the design on that object —
/// the same as simulating a single-object problem made of that object — and without it a
/// note on stderr names the objects and the flag (stdout stays one JSON object).
/// Origin: hostile pass of session 34, robust design.
#[test]
fn simulate_object_grasps_the_named_robust_object() {
    let d = scratch("simulate");
    // kitchen's can as the [object] of a problem without [robust] (its tau = [hand] tau)
    let can = kitchen_with(&d, "can-single.toml", |t| {
        let t = without_robust(t);
        let (a, b) = (t.find("[object]\n").unwrap(), t.find("[contact]").unwrap());
        let obj = "[object]\nradius = 0.030\nlength = 0.115\ndensity = 1050.0\ngrasp_height = 0.040\n\n";
        format!("{}{obj}{}", &t[..a], &t[b..])
    });
    let mut on_can = json_of(&["simulate", KITCHEN_FILE, "--object", "can", "--json"]);
    assert_eq!(on_can["object"], "can");
    on_can.as_object_mut().unwrap().remove("object");
    let single = json_of(&["simulate", &can, "--json"]);
    assert_eq!(untimed(on_can.clone()), untimed(single), "--object can = the can's own problem");

    let o = run_gripopt(&["simulate", KITCHEN_FILE, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    let reference: Value = serde_json::from_slice(&o.stdout).expect("stdout is one JSON object");
    assert!(reference.get("object").is_none());
    let note = String::from_utf8_lossy(&o.stderr);
    for w in ["note:", "reference [object]", "--object", "bottle-full, bottle-half, can, small-bottle"] {
        assert!(note.contains(w), "{w}: {note}");
    }
    // E_lim = min(μ_g m_c g Δx_max, …): 1.34 mJ for the can, 3.94 mJ for the bottle
    // (docs/robust.md, "The can"); the finger's own impact energy hardly changes
    let e_lim = |v: &Value| v["e_lim"].as_f64().unwrap() * 1e3;
    assert!((e_lim(&on_can) - 1.34).abs() < 0.005, "{}", e_lim(&on_can));
    assert!((e_lim(&reference) - 3.94).abs() < 0.005, "{}", e_lim(&reference));
    assert_ne!(on_can["f0_1"], reference["f0_1"]);
    assert_ne!(on_can["t_first_contact"], reference["t_first_contact"]);

    // --object without a note; the text report names the object
    let o = run_gripopt(&["simulate", KITCHEN_FILE, "--object", "can"]);
    assert_eq!(o.status.code(), Some(0), "{}", output_text(&o));
    assert!(!String::from_utf8_lossy(&o.stderr).contains("note:"), "{}", output_text(&o));
    let first = String::from_utf8_lossy(&o.stdout).lines().next().unwrap_or_default().to_string();
    assert!(first.contains("object can"), "{first}");
}

/// An unknown object, or `--object` on a problem without [robust], is an input error
/// (exit 2) naming the flag, as `export --object`'s.
/// Origin: hostile pass of session 34, robust design.
#[test]
fn simulate_object_refuses_unknown_names() {
    let bottle = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml");
    for (file, says) in [(KITCHEN_FILE, "no such robust object"), (bottle, "not robust")] {
        for json in [false, true] {
            let mut args = vec!["simulate", file, "--object", "mug"];
            if json {
                args.push("--json");
            }
            let o = run_gripopt(&args);
            let text = output_text(&o);
            assert_eq!(o.status.code(), Some(2), "{text}");
            assert!(text.contains("--object mug") && text.contains(says), "{text}");
        }
    }
}

/// `simulate --json --rtol R` did not carry R: it does, and a run at the problem's rtol
/// prints the record as before (no `rtol` key).
/// Origin: hostile pass of session 34, the CLI.
#[test]
fn simulate_json_names_an_rtol_set_on_the_command_line() {
    let v = json_stdout(&run_gripopt(&["simulate", BOTTLE_FILE, "--json", "--rtol", "1e-5"]));
    assert_eq!(v["rtol"].as_f64(), Some(1e-5), "{v}");
    let v = json_stdout(&run_gripopt(&["simulate", BOTTLE_FILE, "--json"]));
    assert!(v.get("rtol").is_none(), "{v}");
}
