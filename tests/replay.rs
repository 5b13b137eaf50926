//! `gripopt replay RUN --design ID` (and `--scenario`, `--scene`): the recorded design
//! re-evaluated with the problem of its own run and compared with its recording. The run's
//! own scene verifies; another scene reports what `simulate --scene S` reports and cannot be
//! verified; an edited problem file, a run without recording, a robust design the solver
//! aborted and an offset run's finger 2 each get the answer the recording allows. Replays of
//! older recordings: replay_recorded.rs; of a free-kind run's free scene: replay_free.rs.

use crate::common::{
    check_dir, copy_dir, gripopt_exits, json_exits, kitchen_with_max_steps, offset_problem, output_text,
    recorded_fixture, run_gripopt, run_limited, scratch, tiny_run_in, BOTTLE_FILE,
};
use crate::robustness::tmp;
use gripopt::record::{read_design, read_index, Finger2Columns, GraspSeries};
use gripopt::replay;
use gripopt::run::optimise;
use prost::Message;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "exit {:?}: {}", o.status.code(), String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&o.stdout)))
}

/// Drop the keys that are wall-clock timings.
fn untimed(mut v: serde_json::Value) -> serde_json::Value {
    for k in ["cpu_s", "replay_s"] {
        v.as_object_mut().unwrap().remove(k);
    }
    if let Some(f) = v.get_mut("free_scene").and_then(|f| f.as_object_mut()) {
        f.remove("cpu_s");
    }
    v
}

/// `replay RUN --design ID --scene S`: the run's own scene verifies as without `--scene`;
/// another scene re-simulates the recorded design there, reports exactly what `simulate
/// --scene S` reports for the design read from pareto.csv, says it cannot be verified
/// (`verified: null`) and exits 0; a bad scene is refused with exit 2.
#[test]
fn replay_in_another_scene() {
    let dir = crate::common::tiny_run("replay-scene", std::path::Path::new(crate::common::BOTTLE_FILE), 8, 2);
    let front = gripopt::run::read_design_csv(&dir.join("pareto.csv")).unwrap();
    let (id, x) = front[0];
    let (d, ids) = (dir.display().to_string(), id.to_string());
    let problem = dir.join("problem.toml").display().to_string();
    let design = gripopt::params::DESIGN_NAMES
        .iter()
        .zip(x.to_array())
        .map(|(n, v)| format!("{n}={v}"))
        .collect::<Vec<_>>()
        .join(",");

    // the run's own scene (centred): verification, unchanged by --scene
    let plain = untimed(json(&run_gripopt(&["replay", &d, "--design", &ids, "--json"])));
    let same = untimed(json(&run_gripopt(&["replay", &d, "--design", &ids, "--json", "--scene", "centred"])));
    assert_eq!(plain["verified"], serde_json::json!(true));
    assert_eq!(plain, same);

    // another scene: simulate's report of the recorded design, marked as not verifiable
    for scene in ["free", "free:0.001", "offset:0.001"] {
        let r = untimed(json(&run_gripopt(&["replay", &d, "--design", &ids, "--json", "--scene", scene])));
        let s = untimed(json(&run_gripopt(&["simulate", &problem, "--design", &design, "--json", "--scene", scene])));
        assert!(r["verified"].is_null(), "{scene}: {r}");
        assert_eq!(r["replay"]["recorded_scene"], "centred");
        assert!(r["note"].as_str().unwrap().contains("cannot be verified"), "{scene}");
        for (k, v) in s.as_object().unwrap() {
            assert_eq!(&r[k], v, "{scene}: key {k}");
        }
    }
    let r = json(&run_gripopt(&["replay", &d, "--design", &ids, "--json", "--scene", "free"]));
    let f = &r["free_scene"];
    assert!(f["object_max_displacement"].as_f64().is_some() && f["moved"].is_boolean());

    // text output and --csv with the object pose
    let csv = dir.join("replay-free.csv");
    let o =
        run_gripopt(&["replay", &d, "--design", &ids, "--scene", "free:0.002", "--csv", &csv.display().to_string()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("cannot be verified against the recording") && text.contains("free:0.002"), "{text}");
    let text = std::fs::read_to_string(&csv).unwrap();
    // after the `#` title and units lines (docs/outputs.md)
    let head = text.lines().find(|l| !l.starts_with('#')).unwrap_or_default();
    assert!(head.starts_with("t,gx,gy,gz,qw,qx,qy,qz"), "{head}");

    // bad scenes: exit 2
    for bad in ["sideways", "offset:abc", "free:9"] {
        let o = run_gripopt(&["replay", &d, "--design", &ids, "--scene", bad]);
        assert_eq!(o.status.code(), Some(2), "--scene {bad}: {}", String::from_utf8_lossy(&o.stderr));
    }
}

/// An offset-kind run at x_off = 0: `--scene offset:-0` is the run's own scene.
/// Origin: the hostile-user review of the scene commands.
#[test]
fn replay_minus_zero_is_the_recorded_scene() {
    let base = std::env::temp_dir().join(format!("gripopt-scene-cli-offset-{}", std::process::id()));
    std::fs::create_dir_all(&base).unwrap();
    let problem = base.join("offset.toml");
    let src = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    assert!(src.contains("kind = \"centred\""));
    std::fs::write(&problem, src.replacen("kind = \"centred\"", "kind = \"offset\"", 1)).unwrap();
    let dir = crate::common::tiny_run("scene-cli-offset", &problem, 4, 1);
    // any recorded design (feasible or not): the first row of population.csv
    let pop = std::fs::read_to_string(dir.join("population.csv")).unwrap();
    let mut rows = pop.lines().filter(|l| !l.starts_with('#'));
    let id_col = rows.next().unwrap().split(',').position(|h| h == "id").unwrap();
    let id = rows.next().unwrap().split(',').nth(id_col).unwrap().to_string();
    let d = dir.display().to_string();
    for scene in ["offset:0", "offset:-0", "offset:0e0"] {
        let o = run_gripopt(&["replay", &d, "--design", &id, "--json", "--scene", scene]);
        let j: serde_json::Value =
            serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{scene}: {e}: {}", output_text(&o)));
        // the replay of the recording (not a re-simulation in "another" scene with its note)
        assert!(
            j.get("note").is_none() && j.get("replay").is_none() && j.get("compared_samples").is_some(),
            "{scene}: {j}"
        );
    }
    // the offset scene records no trajectory: every design verifies by its record's values
    // (stage, reason, violation, objectives, simulation work), exit 0 ...
    let ids: Vec<String> = pop
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').nth(id_col).unwrap().to_string())
        .collect();
    for id in &ids {
        let o = run_gripopt(&["replay", &d, "--design", id, "--json"]);
        let j: serde_json::Value =
            serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{id}: {e}: {}", output_text(&o)));
        assert_eq!((o.status.code(), j["verified"].as_bool()), (Some(0), Some(true)), "design {id}: {j}");
        assert!(j["compared_values"].as_u64().unwrap() >= 3, "design {id}: {j}");
    }
    // ... and a run whose problem was changed afterwards is refused, naming the file (exit 2;
    // exit 3 "not verified" before hostile pass 34)
    let p = dir.join("problem.toml");
    let text0 = std::fs::read_to_string(&p).unwrap();
    let tau_line = text0.lines().find(|l| l.trim_start().starts_with("tau")).unwrap().to_string();
    std::fs::write(&p, text0.replacen(&tau_line, "tau = 0.45", 1)).unwrap();
    for id in &ids {
        let o = run_gripopt(&["replay", &d, "--design", id, "--json"]);
        let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!((o.status.code(), &j["exit_code"]), (Some(2), &serde_json::json!(2)), "design {id}: {j}");
        assert!(j["error"].as_str().is_some_and(|e| e.contains("problem.toml: edited after the run")), "{j}");
    }
    let _ = std::fs::remove_dir_all(&base);
}

/// `replay` after the run's problem.toml was edited re-evaluated the design with the edited
/// problem, exited 3 and printed two verdicts, the second contradicting the first. Now it
/// is refused as `resume` refuses it: exit 2, one message naming the file, nothing
/// evaluated (nothing on stdout).
/// Origin: hostile pass of session 34, files.
#[test]
fn replay_refuses_an_edited_problem_file() {
    let run = crate::common::tiny_run_in(scratch("edited").join("run"), Path::new(BOTTLE_FILE), 8, 2);
    let problem = run.join("problem.toml");
    let mut text = std::fs::read_to_string(&problem).unwrap();
    text.push_str("# edited by hand\n");
    std::fs::write(&problem, text).unwrap();
    let r = run.to_str().unwrap();
    let dir = run.parent().unwrap();
    for args in [&["replay", r, "--design", "3"][..], &["replay", r, "--design", "3", "--json"], &["resume", r]] {
        let o = run_limited(dir, args);
        let err = output_text(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", output_text(&o));
        assert!(err.contains(&format!("{}: edited after the run", problem.display())), "{args:?}: {err}");
        assert!(!output_text(&o).contains("verified"), "{args:?}: a verdict: {}", output_text(&o));
    }
}

/// Origin: issue 21 (session 37), gripopt's own files read into types; older versions still load.
#[test]
fn replay_of_a_run_without_recording_says_why_from_run_json() {
    let d = scratch("unrecorded");
    copy_dir(&recorded_fixture("centred"), &d);
    std::fs::remove_dir_all(d.join("recording")).unwrap();
    let e = gripopt::record::read_design(&d, 0).unwrap_err().to_string();
    assert!(e.contains("says the run recorded"), "recording on in run.json: {e}");
    let text = std::fs::read_to_string(d.join("run.json")).unwrap();
    std::fs::write(d.join("run.json"), text.replace("\"enabled\": true", "\"enabled\": false")).unwrap();
    let e = gripopt::record::read_design(&d, 0).unwrap_err().to_string();
    assert!(e.contains("the run was not recorded"), "recording off in run.json: {e}");
    std::fs::write(d.join("run.json"), "{}").unwrap();
    let e = gripopt::record::read_design(&d, 0).unwrap_err().to_string();
    assert!(e.contains("does not say whether"), "{e}");
}

/// Finding 7: `replay --scenario` writes into the run folder under its lock: refused while
/// another process holds it.
/// Origin: hostile pass of session 31, run folders put together by hand.
#[test]
fn replay_of_a_scenario_takes_the_run_folders_lock() {
    let dir = tmp("trust-scenario-lock");
    let mut spec = crate::common::bottle_spec(&dir, 1, 5, 1);
    spec.record = gripopt::record::RecordOptions::none();
    optimise(&spec).unwrap();
    let held = gripopt::run::RunLock::acquire(&dir).unwrap();
    let e = gripopt::app::replay_scenario(&dir, 0, "bottle", 0, true).unwrap_err();
    assert!(matches!(e, gripopt::Error::Locked { .. }), "{e}");
    drop(held);
    // without the lock held: the folder's own answer (not a robust run)
    let e = gripopt::app::replay_scenario(&dir, 0, "bottle", 0, true).unwrap_err().to_string();
    assert!(e.contains("not a robust problem"), "{e}");
}

/// The id of the first design of `run`'s population.csv whose reason contains `word`.
fn design_whose_reason_has(run: &Path, word: &str) -> String {
    let text = std::fs::read_to_string(run.join("population.csv")).unwrap();
    let line = text.lines().find(|l| !l.starts_with('#') && l.contains(word)).expect("such a design");
    line.split(',').next().unwrap().to_string()
}

/// `file` with every occurrence of `from` replaced by `to` (bytes), at least one.
fn replace_in(file: &Path, from: &str, to: &str) {
    let b = std::fs::read(file).unwrap();
    let (f, t) = (from.as_bytes(), to.as_bytes());
    assert_eq!(f.len(), t.len());
    let mut out = b.clone();
    let mut n = 0;
    for i in 0..b.len().saturating_sub(f.len() - 1) {
        if &b[i..i + f.len()] == f {
            out[i..i + f.len()].copy_from_slice(t);
            n += 1;
        }
    }
    assert!(n > 0, "{} holds {from}", file.display());
    std::fs::write(file, out).unwrap();
}

fn sha256_of(file: &Path) -> String {
    use sha2::Digest;
    sha2::Sha256::digest(std::fs::read(file).unwrap()).iter().map(|b| format!("{b:02x}")).collect()
}

/// With `[solver] max_steps = 1` the kitchen's designs that reach stage 3 are solver-failure
/// discards (`object bottle-full: scenario 0: aborted: …`). Their replay, and the replay of
/// the aborted scenario, reproduce the record field for field: verified (exit 0). A replay
/// that really differs — the same run, its problem given `max_steps = 2` (its hashes in
/// run.json and in the shard updated, so that the replay uses it and names no other
/// problem) — is not (exit 3): the scenario's steps differ.
/// Origin: hostile pass of session 34, replay and verify of robust designs the solver aborted.
#[test]
fn a_robust_design_the_solver_aborted_replays_as_verified() {
    let d = scratch("replay");
    let problem = d.join("k1.toml");
    std::fs::write(&problem, kitchen_with_max_steps(1, false)).unwrap();
    let run = d.join("run");
    let (p, r) = (problem.to_str().unwrap(), run.to_str().unwrap());
    gripopt_exits(&["optimise", p, "--out", r, "--pop", "8", "--generations", "1", "--seed", "1"], 0);
    let id = design_whose_reason_has(&run, "scenario 0: aborted");

    let text = gripopt_exits(&["replay", r, "--design", &id], 0);
    assert!(text.contains("verified (no trajectory recorded for this design)"), "{text}");
    let j = json_exits(&["replay", r, "--design", &id, "--json"], 0);
    assert_eq!((&j["verified"], &j["verdict_agrees"]), (&Value::Bool(true), &Value::Bool(true)), "{j}");
    assert_eq!(j["robust"]["scenarios"][0]["cause"], "aborted", "{j}");

    let scenario = ["replay", r, "--design", &id, "--scenario", "bottle-full:0"];
    let text = gripopt_exits(&scenario, 0);
    assert!(text.contains("verified: the re-simulation equals the recorded scenario"), "{text}");
    let j = json_exits(&[&scenario[..], &["--json"]].concat(), 0);
    assert_eq!(j["verified"], true, "{j}");
    assert_eq!(j["scenario"], j["recorded"], "{j}");
    assert_eq!(j["scenario"]["cause"], "aborted", "{j}");
    assert!(j["scenario"].get("abort").is_none(), "{j}");

    // a real difference: the problem changed (max_steps 2), its hashes made the run's
    let other = d.join("other");
    crate::common::copy_dir(&run, &other);
    let was = sha256_of(&other.join("problem.toml"));
    std::fs::write(other.join("problem.toml"), kitchen_with_max_steps(2, false)).unwrap();
    let now = sha256_of(&other.join("problem.toml"));
    replace_in(&other.join("run.json"), &was, &now);
    replace_in(&other.join("recording/gen-00001.mcap"), &was, &now);
    let o = other.to_str().unwrap();
    let text = gripopt_exits(&["replay", o, "--design", &id], 3);
    assert!(text.contains("NOT verified"), "{text}");
    let j = json_exits(&["replay", o, "--design", &id, "--json"], 3);
    assert_eq!((&j["verified"], &j["problem_note"]), (&Value::Bool(false), &Value::Null), "{j}");
    let scenario = ["replay", o, "--design", &id, "--scenario", "bottle-full:0", "--json"];
    let j = json_exits(&scenario, 3);
    assert_eq!(j["verified"], false, "{j}");
    assert_eq!((&j["scenario"]["steps"][0], &j["recorded"]["steps"][0]), (&Value::from(2), &Value::from(1)), "{j}");
}

/// The shard holding design `id` and `id`'s window's series.
fn shard_of(run: &Path, id: u64) -> PathBuf {
    let e = read_index(&run.join("recording")).unwrap().into_iter().find(|e| (e.first_id..=e.last_id).contains(&id));
    run.join("recording").join(e.unwrap().file)
}

/// Rewrite the shard `path` with `edit` applied to every `/grasp/series` message (the other
/// records copied as they are): a recording of another gripopt, made here.
fn rewrite_series(path: &Path, edit: impl Fn(&mut GraspSeries)) {
    let buf = std::fs::read(path).unwrap();
    let summary = mcap::Summary::read(&buf).unwrap().unwrap();
    let mut w = mcap::Writer::new(std::io::Cursor::new(Vec::new())).unwrap();
    for mi in &summary.metadata_indexes {
        w.write_metadata(&mcap::read::metadata(&buf, mi).unwrap()).unwrap();
    }
    let mut channels = std::collections::BTreeMap::new();
    for m in mcap::MessageStream::new(&buf).unwrap().map(|m| m.unwrap()) {
        let c = &m.channel;
        let id = *channels.entry(c.id).or_insert_with(|| {
            let schema = c.schema.as_ref().map_or(0, |s| w.add_schema(&s.name, &s.encoding, &s.data).unwrap());
            w.add_channel(schema, &c.topic, &c.message_encoding, &c.metadata).unwrap()
        });
        let mut data = m.data.to_vec();
        if c.topic == "/grasp/series" {
            let mut s = GraspSeries::decode(&data[..]).unwrap();
            edit(&mut s);
            data = s.encode_to_vec();
        }
        let h = mcap::records::MessageHeader {
            channel_id: id,
            sequence: m.sequence,
            log_time: m.log_time,
            publish_time: m.publish_time,
        };
        w.write_to_known_channel(&h, &data).unwrap();
    }
    w.finish().unwrap();
    std::fs::write(path, w.into_inner().into_inner()).unwrap();
}

/// (c) An offset run records finger 2's columns and replay verifies them (a changed finger-2
/// force is found); `replay --csv` writes them as recorded; shards without them (session
/// 36's, its angles only, and older ones, none) still replay and verify.
/// Origin: session 37, finger 2 of the offset scene in the samples, the recording and replay.
#[test]
fn an_offset_run_records_and_replays_finger_2() {
    let base = check_dir("s37-offset");
    let problem = offset_problem(&base.with_extension("problem"));
    let run = tiny_run_in(base, &problem, 16, 1);
    let ids: Vec<u64> =
        read_index(&run.join("recording")).unwrap().iter().flat_map(|e| e.first_id..=e.last_id).collect();
    let id = *ids
        .iter()
        .find(|&&id| {
            read_design(&run, id).unwrap().samples.iter().any(|s| s.finger2.is_some_and(|f| f.normal[0] > 0.0))
        })
        .expect("a design whose finger 2 touches the object: change the run");
    let rec = read_design(&run, id).unwrap();
    assert_eq!(rec.finger2_columns, Finger2Columns::All);
    let r = replay(&run, id).unwrap();
    assert!(r.verified && r.max_difference == 0.0 && r.compared > 10, "design {id}: replay");
    // replay --csv: finger 1's columns, then finger 2's, as recorded
    let csv = scratch("csv").join("replay.csv");
    let o =
        run_gripopt(&["replay", run.to_str().unwrap(), "--design", &id.to_string(), "--csv", csv.to_str().unwrap()]);
    assert!(o.status.success(), "{}", crate::common::output_text(&o));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let names: Vec<&str> = gripopt::SAMPLE_COLUMNS.iter().chain(&gripopt::FINGER2_COLUMNS).map(|c| c.0).collect();
    assert_eq!(head, names);
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), rec.samples.len());
    for (row, s) in rows.iter().zip(&rec.samples) {
        assert_eq!(row[..16], gripopt::sample_values(s));
        assert_eq!(row[16..], s.finger2.unwrap().values());
    }
    // a finger-2 force changed in the recording does not verify
    let scratch = scratch("shapes");
    let copy = |name: &str| {
        let to = scratch.join(name);
        copy_dir(&run, &to);
        to
    };
    let tampered = copy("tampered");
    rewrite_series(&shard_of(&tampered, id), |s| {
        if let Some(k) = s.finger2_proximal_normal_force.iter().position(|&f| f > 0.0) {
            s.finger2_proximal_normal_force[k] *= 1.001;
        }
    });
    let r = replay(&tampered, id).unwrap();
    assert!(!r.verified && r.max_difference > 1e-4, "a changed finger-2 force: {}", r.max_difference);
    // a shard missing one of finger 2's columns is refused, naming the file
    let partial = copy("partial");
    rewrite_series(&shard_of(&partial, id), |s| s.finger2_theta2.clear());
    let e = read_design(&partial, id).unwrap_err().to_string();
    assert!(e.contains("differ in length") && e.contains(".mcap"), "{e}");
    // session 36's shards (finger 2's angles only) and older ones (none) still verify
    for (name, keep, shape) in [("s36", 2, Finger2Columns::Angles), ("s35", 0, Finger2Columns::None)] {
        let old = copy(name);
        rewrite_series(&shard_of(&old, id), |s| {
            let cols = [
                &mut s.finger2_q11,
                &mut s.finger2_q21,
                &mut s.finger2_q11_dot,
                &mut s.finger2_q21_dot,
                &mut s.finger2_theta2,
                &mut s.finger2_proximal_penetration,
                &mut s.finger2_distal_penetration,
                &mut s.finger2_proximal_normal_force,
                &mut s.finger2_distal_normal_force,
                &mut s.finger2_proximal_friction_force,
                &mut s.finger2_distal_friction_force,
            ];
            for c in cols.into_iter().skip(keep) {
                c.clear();
            }
        });
        let rec = read_design(&old, id).unwrap();
        assert_eq!(rec.finger2_columns, shape, "{name}");
        let r = replay(&old, id).unwrap();
        assert!(r.verified && r.max_difference == 0.0, "{name}: replay of a shard without finger 2's contacts");
        if keep == 2 {
            // its angles are read back, the columns it lacks are NaN
            let f2 = rec.samples[rec.samples.len() / 2].finger2.unwrap();
            assert!(f2.q.iter().all(|q| q.is_finite()) && f2.normal.iter().all(|f| f.is_nan()));
        }
    }
}
