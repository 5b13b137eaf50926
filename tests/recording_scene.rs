//! What a designer sees in Foxglove is the grasp that was simulated (issue 27): the shards
//! draw the model's physical scene in world coordinates (the hand horizontal at the grasp
//! height, the object standing on the ground touching the palm, the fingers in the hand
//! plane, every base joint at (±b/2, 0) of the design), a design without a grasp clears the
//! plots and shows its open (and failing) linkage, every window ends with a /tf message,
//! `recording/front-NNNNN.mcap` for each shard marks the final front, also after a
//! resume, and a robust design is drawn in the scenario that decided its verdict. Decoded with the
//! Foxglove SDK's own decoders and compared with the problem file and the design parameters;
//! the runs live under target/mcap-check/ so that `make test` also runs the independent
//! checker (tools/check_mcap.py) over them.

use foxglove::messages::{FrameTransforms, SceneUpdate};
use foxglove::Decode;
use gripopt::record::{front_file, read_index, GraspSeries, ScenarioSeries};
use gripopt::run::{optimise, resume, RunSpec};

use crate::common::check_dir;
use std::collections::BTreeMap;
use std::path::Path;

fn spec(out: &Path, generations: u64) -> RunSpec {
    RunSpec { pop: 16, ..crate::common::bottle_spec(out, generations, 16, 2) }
}

/// Messages of every shard of a run, by design id (window), as (topic, log time, bytes).
fn windows(run: &Path) -> BTreeMap<u64, Vec<(String, u64, Vec<u8>)>> {
    let info: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
    let epoch = info["recording"]["epoch_s"].as_u64().unwrap() * 1_000_000_000;
    let mut out = BTreeMap::new();
    for e in read_index(&run.join("recording")).unwrap() {
        let buf = std::fs::read(run.join("recording").join(&e.file)).unwrap();
        for m in mcap::MessageStream::new(&buf).unwrap().map(|m| m.unwrap()) {
            let id = (m.log_time - epoch) / 1_000_000_000;
            out.entry(id).or_insert_with(Vec::new).push((m.channel.topic.clone(), m.log_time - epoch, m.data.to_vec()));
        }
    }
    out
}

fn csv_ids(p: &Path) -> Vec<u64> {
    let text = std::fs::read_to_string(p).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(|l| l.split(',').next().unwrap().parse().unwrap())
        .collect()
}

#[test]
fn shards_draw_the_simulated_scene_in_world_coordinates() {
    let run = check_dir("scene-world");
    optimise(&spec(&run, 3)).unwrap();
    let p = gripopt::params::Problem::load(run.join("problem.toml")).unwrap();
    let (r, lc, hc, w) = (p.scene.object.radius, p.scene.object.length, p.scene.object.grasp_height, p.scene.hand.w);
    let (mut grasps, mut open_only, mut failing) = (0, 0, 0);
    for (id, msgs) in windows(&run) {
        let of = |topic: &'static str| msgs.iter().filter(move |m| m.0 == topic);
        let rec: serde_json::Value = serde_json::from_slice(&of("/designs").next().unwrap().2).unwrap();
        let b = rec["parameters"]["b"].as_f64().unwrap();
        // world → hand: at h_c, not rotated, in every /tf message, the last at the window's end
        let tfs: Vec<(u64, FrameTransforms)> =
            of("/tf").map(|m| (m.1, FrameTransforms::decode(&m.2[..]).unwrap())).collect();
        assert_eq!((tfs[0].0 % 1_000_000_000, tfs.last().unwrap().0 % 1_000_000_000), (0, 999_999_999), "design {id}");
        for (_, t) in &tfs {
            let x = &t.transforms[0];
            assert_eq!((x.parent_frame_id.as_str(), x.child_frame_id.as_str()), ("world", "hand"));
            let (tr, q) = (x.translation.unwrap(), x.rotation.unwrap());
            assert_eq!((tr.x, tr.y, tr.z), (0.0, 0.0, hc), "the hand plane at the grasp height");
            assert_eq!((q.x, q.y, q.z, q.w), (0.0, 0.0, 0.0, 1.0), "the hand horizontal");
        }
        // the object: a cylinder R × L_c in `hand`, axis along z, touching the palm face y = 0,
        // its base on the ground (world z = 0 = hand z − h_c); the ground's top face at z = 0
        let st = SceneUpdate::decode(&of("/scene/static").next().unwrap().2[..]).unwrap();
        let ent = |id: &str| st.entities.iter().find(|e| e.id == id).unwrap();
        let (obj, ground) = (ent("object"), ent("ground"));
        assert!(st.entities.iter().all(|e| e.frame_locked), "entities follow their frames");
        assert_eq!(obj.frame_id, "hand");
        let c = &obj.cylinders[0];
        let (pos, size) = (c.pose.unwrap().position.unwrap(), c.size.unwrap());
        assert_eq!((size.x, size.y, size.z), (2.0 * r, 2.0 * r, lc));
        assert_eq!((pos.x, pos.y - r), (0.0, 0.0), "design {id}: the object touches the palm, centred");
        assert!((hc + pos.z - lc / 2.0).abs() < 1e-15, "design {id}: the object's base on the ground");
        let g = &ground.cubes[0];
        assert_eq!(ground.frame_id, "world");
        assert!((g.pose.unwrap().position.unwrap().z + g.size.unwrap().z / 2.0).abs() < 1e-15);
        let label = &ent("label").texts[0].text;
        assert!(label.starts_with(&format!("{id} (gen ")), "{label}");
        // the series: never empty (an empty one would leave the previous curves on screen)
        let s = <GraspSeries as prost::Message>::decode(&of("/grasp/series").next().unwrap().2[..]).unwrap();
        assert!(!s.t.is_empty());
        let scenes: Vec<SceneUpdate> = of("/scene").map(|m| SceneUpdate::decode(&m.2[..]).unwrap()).collect();
        if s.simulated_samples == 0 {
            // no grasp: one NaN sample at t = 0, and the open linkage (and the failing pose)
            assert!(s.t == [0.0] && s.q11[0].is_nan() && s.proximal_normal_force[0].is_nan(), "design {id}");
            assert_eq!(scenes.len(), 1);
            assert!(label.contains(" stage "), "{label}");
            open_only += scenes[0].entities.iter().any(|e| e.id == "fingers") as usize;
            failing += scenes[0].entities.iter().any(|e| e.id == "failing_pose") as usize;
        } else {
            grasps += 1;
            assert_eq!(s.mean_force_objective.len(), s.t.len());
            let f = rec["objectives"]["mean_force"].as_f64().unwrap();
            assert!(s.mean_force_objective.iter().all(|&v| v == f as f32 as f64), "design {id}: F~ line");
        }
        // every finger point in the hand plane, its rod wholly above the ground; the base
        // joints at (±b/2, 0), the design's palm
        for e in scenes.iter().flat_map(|m| &m.entities) {
            assert_eq!(e.frame_id, "hand");
            for (k, l) in e.lines.iter().enumerate() {
                assert!(l.points.iter().all(|q| q.z == 0.0 && hc + q.z - l.thickness / 2.0 > 0.0));
                assert!((l.thickness - 2.0 * w).abs() < 1e-15);
                let base = &l.points[2];
                let sign = if k == 0 { 1.0 } else { -1.0 };
                assert!((base.x - sign * b / 2.0).abs() < 1e-6 && base.y.abs() < 1e-6, "design {id}: base joint");
            }
        }
    }
    assert!(grasps > 0 && open_only > 0 && failing > 0, "{grasps} {open_only} {failing}");
}

/// The final front is known only when the run ends: a front file for each shard is
/// written then (also for the generations written before a crash), each covering exactly
/// its shard's designs inside the shard's own time range (opened with it, the timeline is the
/// shard's: issue 43's E1), together saying exactly what pareto.csv says; a file at the old
/// whole-run name that gripopt did not write is left alone.
#[test]
fn front_recording_marks_the_final_front_after_a_resume() {
    let run = check_dir("scene-front-resume");
    let s = spec(&run, 4);
    assert!(crate::common::optimise_crashing_after(&s, 2).is_err());
    let index = read_index(&run.join("recording")).unwrap();
    assert!(
        index.iter().all(|e| !run.join("recording").join(front_file(e.generation)).exists()),
        "no front before the run ends"
    );
    std::fs::write(run.join("recording/front.mcap"), b"the user's own file").unwrap();
    resume(&run, None, false, Some(1)).unwrap();
    let info: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
    let epoch = info["recording"]["epoch_s"].as_u64().unwrap() * 1_000_000_000;
    let (mut on, mut ids) = (vec![], vec![]);
    for e in read_index(&run.join("recording")).unwrap() {
        let shard = std::fs::read(run.join("recording").join(&e.file)).unwrap();
        let stats = mcap::Summary::read(&shard).unwrap().unwrap().stats.unwrap();
        let buf = std::fs::read(run.join("recording").join(front_file(e.generation))).unwrap();
        let mut mine = vec![];
        for m in mcap::MessageStream::new(&buf).unwrap().map(|m| m.unwrap()) {
            let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
            let id = v["id"].as_u64().unwrap();
            assert_eq!(m.log_time, epoch + id * 1_000_000_000, "at the design's window start");
            assert!((stats.message_start_time..=stats.message_end_time).contains(&m.log_time), "inside {}", e.file);
            mine.push(id);
            if v["on_final_front"].as_bool().unwrap() {
                on.push(id);
            }
        }
        assert_eq!(mine, (e.first_id..=e.last_id).collect::<Vec<_>>(), "{}: its shard's designs", e.file);
        ids.extend(mine);
    }
    assert_eq!(ids, (0..64).collect::<Vec<_>>(), "every recorded design");
    assert_eq!(on, csv_ids(&run.join("pareto.csv")));
    assert!(!on.is_empty());
    assert_eq!(std::fs::read(run.join("recording/front.mcap")).unwrap(), b"the user's own file");
    std::fs::remove_file(run.join("recording/front.mcap")).unwrap();
}

/// The scenario a window draws, decided independently from its `/designs` record
/// (docs/recording.md): a feasible design's worst by displacement (the first of equals;
/// none measured: its first), a P(stay) failure's first failure of the first object that
/// fails p_min, a solver failure's aborted scenario.
fn deciding(rec: &serde_json::Value) -> Option<(String, u64)> {
    let rb = &rec["robust"];
    let runs = rb["scenarios"].as_array().filter(|r| !r.is_empty())?;
    let name = |r: &serde_json::Value| {
        rb["objects"][r["object"].as_u64().unwrap() as usize]["name"].as_str().unwrap().to_string()
    };
    let pick = |r: &serde_json::Value| Some((name(r), r["k"].as_u64().unwrap()));
    if rec["feasible"] == true {
        let mut best: Option<&serde_json::Value> = None;
        for r in runs.iter().filter(|r| r["max_displacement"].is_number()) {
            if best.is_none_or(|b| r["max_displacement"].as_f64() > b["max_displacement"].as_f64()) {
                best = Some(r);
            }
        }
        return pick(best.unwrap_or(&runs[0]));
    }
    let reason = rec["reason"].as_str().unwrap_or("");
    let aborted = |r: &&serde_json::Value| matches!(r["cause"].as_str(), Some("aborted" | "free_scene_aborted"));
    if reason.split(": ").nth(1).is_some_and(|w| w.starts_with("scenario ")) {
        return pick(runs.iter().find(aborted)?);
    }
    let failing = rb["objects"].as_array()?.iter().position(|o| o["meets_p_min"] == false)? as u64;
    pick(runs.iter().find(|r| r["object"] == failing && r["stays"] == false)?)
}

/// A robust run's shards draw every design that reached its scenarios in the scenario that
/// decided its verdict (issue 43's E2): `/designs` names it (and the command that records
/// any other), `/scenario/series` is that scenario's free scene — sample for sample the
/// poses of its re-simulation by `replay --scenario` — or, where the free scene did not run,
/// its centred grasp; the hand at the object's grasp height plus the scenario's drawn offset,
/// the object at its own size. The results are those of the same run recording nothing.
#[test]
fn a_robust_design_is_drawn_in_the_scenario_that_decided_it() {
    let kitchen = concat!(env!("CARGO_MANIFEST_DIR"), "/problems/kitchen.toml");
    let run = check_dir("scene-robust");
    let s = RunSpec { problem_path: kitchen.into(), pop: 16, ..crate::common::bottle_spec(&run, 3, 2, 2) };
    optimise(&s).unwrap();
    let bare = crate::common::scratch_dir("scene-robust", "unrecorded");
    let _ = std::fs::remove_dir(&bare);
    optimise(&RunSpec { out: bare.clone(), record: gripopt::record::RecordOptions::none(), ..s.clone() }).unwrap();
    for f in ["pareto.csv", "archive.csv", "population.csv"] {
        let rows = |d: &Path| -> Vec<String> {
            let t = std::fs::read_to_string(d.join(f)).unwrap();
            t.lines().filter(|l| !l.starts_with('#')).map(String::from).collect()
        };
        assert_eq!(rows(&run), rows(&bare), "{f}: recording the deciding scenarios changes no result");
    }
    let p = gripopt::params::Problem::load(run.join("problem.toml")).unwrap();
    let objects = p.robust.as_ref().unwrap().objects.clone();
    let (mut free, mut centred, mut other) = (0, 0, 0);
    for (id, msgs) in windows(&run) {
        let of = |topic: &'static str| msgs.iter().filter(move |m| m.0 == topic);
        let rec: serde_json::Value = serde_json::from_slice(&of("/designs").next().unwrap().2).unwrap();
        let series = <ScenarioSeries as prost::Message>::decode(&of("/scenario/series").next().unwrap().2[..]).unwrap();
        let Some((object, k)) = deciding(&rec) else {
            assert!(rec.get("shown_scenario").is_none() && series.simulated_samples == 0 && series.t == [0.0]);
            other += 1;
            continue;
        };
        let shown = &rec["shown_scenario"];
        assert_eq!(
            (shown["object"].as_str().unwrap(), shown["k"].as_u64().unwrap()),
            (object.as_str(), k),
            "design {id}"
        );
        assert_eq!((series.object.as_str(), series.scenario_index as u64), (object.as_str(), k));
        assert!(shown["replay"].as_str().unwrap().contains(&format!("--design {id} --scenario {object}:{k}")));
        let ob = objects.iter().find(|o| o.name == object).unwrap();
        let ran = rec["robust"]["scenarios"].as_array().unwrap().iter();
        let ran = ran
            .clone()
            .find(|r| {
                r["k"] == k && rec["robust"]["objects"][r["object"].as_u64().unwrap() as usize]["name"] == *object
            })
            .unwrap();
        // the hand at the scenario's height, the object at its size
        let hand =
            FrameTransforms::decode(&of("/tf").next().unwrap().2[..]).unwrap().transforms[0].translation.unwrap();
        let offset = ran["inputs"]["height_offset"].as_f64().unwrap();
        assert!((hand.z - (ob.object.grasp_height + offset)).abs() < 1e-15, "design {id}: hand at {}", hand.z);
        let st = SceneUpdate::decode(&of("/scene/static").next().unwrap().2[..]).unwrap();
        let size = st.entities.iter().find(|e| e.id == "object").unwrap().cylinders[0].size.unwrap();
        assert_eq!((size.x, size.z), (2.0 * ob.object.radius, ob.object.length), "design {id}");
        let replayed = gripopt::app::replay_scenario(&run, id, &object, k as usize, false).unwrap();
        assert_eq!(replayed.verified, Some(true), "design {id}");
        if !series.free_scene {
            assert!(ran["max_displacement"].is_null() && series.displacement_mm.iter().all(|d| d.is_nan()));
            centred += 1;
            continue;
        }
        let g0 = replayed.poses[0].g;
        for (j, t) in series.t.iter().enumerate() {
            let p = replayed.poses.iter().find(|p| p.t == *t).unwrap_or_else(|| panic!("design {id}: no pose at {t}"));
            let disp = ((p.g[0] - g0[0]).hypot(p.g[1] - g0[1]) * 1e3) as f32 as f64;
            assert_eq!(series.displacement_mm[j], disp, "design {id} at {t}");
            assert_eq!(series.finger2_distal_normal_force[j], p.normal[3] as f32 as f64);
            assert_eq!(series.finger1_q21[j], p.fingers[1] as f32 as f64);
        }
        let last = replayed.poses.last().unwrap().t;
        assert_eq!(*series.t.last().unwrap(), last, "design {id}: the series ends where the free scene ended");
        free += 1;
    }
    assert!(
        free > 0 && centred > 0 && other > 0,
        "{free} drawn in their free scene, {centred} in their centred grasp, {other} not drawn"
    );
}
