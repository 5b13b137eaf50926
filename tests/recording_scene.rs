//! What a designer sees in Foxglove is the grasp that was simulated (issue 27): the shards
//! draw the model's physical scene in world coordinates (the hand horizontal at the grasp
//! height, the object standing on the ground touching the palm, the fingers in the hand
//! plane, every base joint at (±b/2, 0) of the design), a design without a grasp clears the
//! plots and shows its open (and failing) linkage, every window ends with a /tf message, and
//! `recording/front.mcap` marks the final front, also after a resume; the offset scene draws
//! finger 2 at its own angles touching the object, a robust run's stage-2 discard draws its
//! failing pose on the object that failed, scenario recordings have their own windows, and
//! the labels fit the 3-D panel. Decoded with the Foxglove SDK's own decoders and compared
//! with the problem file, the design parameters and geometry computed here (never with the
//! code's own drawing); the runs live under target/mcap-check/ so that `make test` also runs
//! the independent checker (tools/check_mcap.py) over them.

use crate::common::{check_dir, offset_problem, tiny_run_in, BOTTLE_FILE};
use foxglove::messages::{FrameTransforms, LinePrimitive, SceneUpdate};
use foxglove::Decode;
use gripopt::record::{read_index, GraspSeries};
use gripopt::run::{optimise, resume, RunSpec};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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

/// The final front is known only when the run ends: front.mcap is written then, for every
/// recorded design (also those of the generations written before a crash), and says exactly
/// what pareto.csv says; a resumed run rewrites it.
#[test]
fn front_recording_marks_the_final_front_after_a_resume() {
    let run = check_dir("scene-front-resume");
    let s = spec(&run, 4);
    assert!(crate::common::optimise_crashing_after(&s, 2).is_err());
    assert!(!run.join("recording/front.mcap").exists(), "no front before the run ends");
    resume(&run, None, false, Some(1)).unwrap();
    let buf = std::fs::read(run.join("recording/front.mcap")).unwrap();
    let mut on = vec![];
    let mut ids = vec![];
    let info: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
    let epoch = info["recording"]["epoch_s"].as_u64().unwrap() * 1_000_000_000;
    for m in mcap::MessageStream::new(&buf).unwrap().map(|m| m.unwrap()) {
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        let id = v["id"].as_u64().unwrap();
        assert_eq!(m.log_time, epoch + id * 1_000_000_000, "at the design's window start");
        ids.push(id);
        if v["on_final_front"].as_bool().unwrap() {
            on.push(id);
        }
    }
    assert_eq!(ids, (0..64).collect::<Vec<_>>(), "every recorded design");
    assert_eq!(on, csv_ids(&run.join("pareto.csv")));
    assert!(!on.is_empty());
}

/// The messages of every shard of a run as (topic, log time − epoch, bytes), by design.
fn messages(run: &Path) -> Vec<Vec<(String, u64, Vec<u8>)>> {
    let info: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("run.json")).unwrap()).unwrap();
    let epoch = info["recording"]["epoch_s"].as_u64().unwrap() * 1_000_000_000;
    let mut out: std::collections::BTreeMap<u64, Vec<_>> = Default::default();
    for e in read_index(&run.join("recording")).unwrap() {
        let buf = std::fs::read(run.join("recording").join(&e.file)).unwrap();
        for m in mcap::MessageStream::new(&buf).unwrap().map(|m| m.unwrap()) {
            let t = m.log_time - epoch;
            out.entry(t / 1_000_000_000).or_default().push((m.channel.topic.clone(), t, m.data.to_vec()));
        }
    }
    out.into_values().collect()
}

/// Distance from `p` to the segment a–b (plane).
fn seg_dist(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let s = (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
    (a.0 + s * dx - p.0).hypot(a.1 + s * dy - p.1)
}

/// The drawn finger's gap to the object's circle (centre `c`, radius `r`): the nearer of its
/// two phalanges (tip–O22, O22–base) as a rod of the line's thickness; < 0: drawn inside.
fn gap(line: &LinePrimitive, c: (f64, f64), r: f64) -> f64 {
    let p: Vec<(f64, f64)> = line.points.iter().map(|q| (q.x, q.y)).collect();
    seg_dist(c, p[0], p[1]).min(seg_dist(c, p[1], p[2])) - r - line.thickness / 2.0
}

/// In the offset scene finger 2 is not finger 1's mirror image: at the last pose of every
/// stable grasp both drawn fingers touch the drawn object (their gaps within the contact's
/// micrometres of penetration), and the series carries finger 2's angles; replay verifies them.
/// Origin: session 36's recording fixes.
#[test]
fn offset_scene_draws_finger_2_touching_the_object() {
    let base = check_dir("s36-offset");
    let problem = offset_problem(&base.with_extension("problem"));
    let run = tiny_run_in(base, &problem, 24, 2);
    let (mut stable, mut apart, mut red_poses) = (0, 0.0f64, 0);
    for msgs in messages(&run) {
        let of = |topic: &'static str| msgs.iter().filter(move |m| m.0 == topic);
        let rec: serde_json::Value = serde_json::from_slice(&of("/designs").next().unwrap().2).unwrap();
        let s = <GraspSeries as prost::Message>::decode(&of("/grasp/series").next().unwrap().2[..]).unwrap();
        // finger 2's angles, as many as the other columns (a NaN placeholder without a grasp)
        assert_eq!((s.finger2_q11.len(), s.finger2_q21.len()), (s.t.len(), s.t.len()), "finger 2's angles");
        if s.simulated_samples == 0 && rec["failed_stage"] == 2 {
            // stage 2 is the centred grasp's (the offset scene is stage 3's): its red closed
            // pose touches the object drawn at x = 0 with both phalanges
            let st = SceneUpdate::decode(&of("/scene/static").next().unwrap().2[..]).unwrap();
            let cyl = &st.entities.iter().find(|e| e.id == "object").unwrap().cylinders[0];
            let pos = cyl.pose.unwrap().position.unwrap();
            let scene = SceneUpdate::decode(&of("/scene").next().unwrap().2[..]).unwrap();
            if let Some(red) = scene.entities.iter().find(|e| e.id == "failing_pose") {
                assert_eq!(pos.x, 0.0, "design {}: a stage-2 discard's object", rec["id"]);
                for line in &red.lines {
                    assert!(gap(line, (pos.x, pos.y), cyl.size.unwrap().x / 2.0).abs() < 3e-6, "design {}", rec["id"]);
                }
                red_poses += 1;
            }
        }
        if s.simulated_samples == 0 || rec["feasible"] != true {
            continue;
        }
        let st = SceneUpdate::decode(&of("/scene/static").next().unwrap().2[..]).unwrap();
        let cyl = &st.entities.iter().find(|e| e.id == "object").unwrap().cylinders[0];
        let pos = cyl.pose.unwrap().position.unwrap();
        let (c, r) = ((pos.x, pos.y), cyl.size.unwrap().x / 2.0);
        assert!((c.0 - 0.002).abs() < 1e-12, "the object at x_off");
        let last = of("/scene").next_back().map(|m| SceneUpdate::decode(&m.2[..]).unwrap()).unwrap();
        let lines = &last.entities[0].lines;
        let (g1, g2) = (gap(&lines[0], c, r), gap(&lines[1], c, r));
        // a stable grasp holds the object with both fingers: each touches it, pressed in by
        // micrometres (the drawing is rounded to 2^-20 m)
        for (k, g) in [g1, g2].into_iter().enumerate() {
            assert!((-60e-6..=3e-6).contains(&g), "design {}: finger {} gap {g:e} m", rec["id"], k + 1);
        }
        apart = apart.max(g2.abs());
        stable += 1;
        let r = gripopt::replay(&run, rec["id"].as_u64().unwrap()).unwrap();
        assert!(r.verified && r.max_difference == 0.0, "design {}: replay", rec["id"]);
    }
    assert!(
        stable > 0 && red_poses > 0,
        "no stable grasp or red pose to check ({stable}, {red_poses}): change the run"
    );
    assert!(apart < 60e-6);
}

/// kitchen.toml with the can first among the robust objects (stage 2 then discards many
/// designs on the can) and 2 scenarios per object, in `dir`.
fn can_first_problem(dir: &Path) -> PathBuf {
    let src = std::fs::read_to_string(Path::new(BOTTLE_FILE).with_file_name("kitchen.toml")).unwrap();
    let start = src.find("[[robust.objects]]\nname = \"can\"").expect("kitchen.toml's can: fix the test");
    let len = src[start..].find("\n\n").unwrap() + 2;
    let can = src[start..start + len].to_string();
    let mut src = format!("{}{}", &src[..start], &src[start + len..]);
    let first = src.find("[[robust.objects]]").unwrap();
    src.insert_str(first, &can);
    let src = src.replacen("scenarios = 8 ", "scenarios = 2 ", 1).replacen("p_min = 0.85 ", "p_min = 0.5 ", 1);
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join("kitchen-can-first.toml");
    std::fs::write(&p, src).unwrap();
    p
}

/// A robust design that stage 2 discards on an object other than the reference shows that
/// object (its radius and length, standing on the ground) and the red closed pose on it: both
/// phalanges touch it (the closed pose's contacts, at zero penetration). Every label fits the
/// 3-D panel, the robust reasons of 200 characters included.
/// Origin: session 36's recording fixes.
#[test]
fn a_robust_stage_2_discard_is_drawn_on_the_object_it_failed_on() {
    let base = check_dir("s36-robust-red");
    let problem = can_first_problem(&base.with_extension("problem"));
    let p = gripopt::params::Problem::load(&problem).unwrap();
    let run = tiny_run_in(base, &problem, 60, 1);
    let robust = p.robust.as_ref().unwrap();
    let hc = p.scene.object.grasp_height;
    let (mut on, mut longest) = (std::collections::BTreeMap::new(), 0);
    for msgs in messages(&run) {
        let of = |topic: &'static str| msgs.iter().filter(move |m| m.0 == topic);
        let rec: serde_json::Value = serde_json::from_slice(&of("/designs").next().unwrap().2).unwrap();
        let reason = rec["reason"].as_str().unwrap_or("");
        // every label fits the 3-D panel (docs/recording.md: at most 120 characters)
        let st = SceneUpdate::decode(&of("/scene/static").next().unwrap().2[..]).unwrap();
        let label = &st.entities.iter().find(|e| e.id == "label").unwrap().texts[0].text;
        assert!(label.chars().count() <= 120, "{} characters: {label}", label.chars().count());
        longest = longest.max(reason.chars().count());
        let Some(o) = robust.objects.iter().find(|o| reason.starts_with(&format!("object {}: ", o.name))) else {
            continue;
        };
        if rec["failed_stage"] != 2 {
            continue;
        }
        let scene = SceneUpdate::decode(&of("/scene").next().unwrap().2[..]).unwrap();
        let Some(red) = scene.entities.iter().find(|e| e.id == "failing_pose") else { continue };
        let st = SceneUpdate::decode(&of("/scene/static").next().unwrap().2[..]).unwrap();
        let cyl = &st.entities.iter().find(|e| e.id == "object").unwrap().cylinders[0];
        let (pos, size) = (cyl.pose.unwrap().position.unwrap(), cyl.size.unwrap());
        assert_eq!((size.x / 2.0, size.z), (o.object.radius, o.object.length), "design {}: {reason}", rec["id"]);
        assert_eq!(pos.y, o.object.radius, "touching the palm");
        assert!((pos.z - (o.object.length / 2.0 - hc)).abs() < 1e-15, "standing on the ground");
        for line in &red.lines {
            let pts: Vec<(f64, f64)> = line.points.iter().map(|q| (q.x, q.y)).collect();
            let c = (pos.x, pos.y);
            for (a, b) in [(2, 1), (1, 0)] {
                let g = seg_dist(c, pts[a], pts[b]) - o.object.radius - line.thickness / 2.0;
                assert!(g.abs() < 3e-6, "design {}: red phalanx {g:e} m off the drawn {}", rec["id"], o.name);
            }
        }
        *on.entry(o.name.clone()).or_insert(0) += 1;
    }
    assert!(on.get("can").copied().unwrap_or(0) > 0, "no stage-2 discard on the can: {on:?}");
    assert!(longest > 120, "no reason longer than a label: the label check checked nothing");
}

/// `replay --scenario` recordings of one run each sit in their own window (opened together
/// they never mix), say which scenario they are (metadata, `/verify`, label), and draw the
/// hand at the scenario's physical height: the object's grasp height + its height offset.
/// Origin: session 36's recording fixes.
#[test]
fn scenario_recordings_have_their_own_windows_and_say_which_scenario() {
    let base = check_dir("s36-scenarios");
    let problem = can_first_problem(&base.with_extension("problem"));
    let p = gripopt::params::Problem::load(&problem).unwrap();
    let run = tiny_run_in(base, &problem, 60, 1);
    let robust = p.robust.as_ref().unwrap();
    let mut files = vec![];
    'designs: for id in 0..60 {
        for o in &robust.objects {
            for k in 0..2 {
                if let Ok(r) = gripopt::app::replay_scenario(&run, id, &o.name, k, true) {
                    files.extend(r.recording);
                }
                if files.len() >= 3 {
                    break 'designs;
                }
            }
        }
    }
    assert!(files.len() >= 2, "scenario recordings: {files:?}");
    let mut windows = std::collections::BTreeSet::new();
    for f in &files {
        let buf = std::fs::read(f).unwrap();
        let summary = mcap::Summary::read(&buf).unwrap().unwrap();
        let meta: std::collections::BTreeMap<String, String> = summary
            .metadata_indexes
            .iter()
            .map(|i| mcap::read::metadata(&buf, i).unwrap())
            .find(|m| m.name == "gripopt.verify")
            .unwrap()
            .metadata;
        let (object, k) = (&meta["scenario_object"], meta["scenario_index"].parse::<u64>().unwrap());
        let name = f.file_name().unwrap().to_str().unwrap();
        assert!(name.ends_with(&format!("-{object}-{k}.mcap")), "{name}");
        let case = robust.objects.iter().find(|o| &o.name == object).unwrap();
        let h: f64 = meta["height_offset"].parse().unwrap();
        assert_eq!(meta["object_grasp_height"].parse::<f64>().unwrap(), case.object.grasp_height);
        for m in mcap::MessageStream::new(&buf).unwrap().map(|m| m.unwrap()) {
            windows.insert((m.log_time / 1_000_000_000, name.to_string()));
            match m.channel.topic.as_str() {
                "/verify" => {
                    let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
                    assert_eq!(
                        (v["scenario_object"].as_str(), v["scenario_index"].as_u64()),
                        (Some(object.as_str()), Some(k))
                    );
                }
                "/tf" => {
                    let tf = foxglove::messages::FrameTransforms::decode(&m.data[..]).unwrap();
                    assert_eq!(
                        tf.transforms[0].translation.unwrap().z,
                        case.object.grasp_height + h,
                        "{name}: hand height"
                    );
                }
                "/scene/static" => {
                    let st = SceneUpdate::decode(&m.data[..]).unwrap();
                    let label = &st.entities.iter().find(|e| e.id == "label").unwrap().texts[0].text;
                    assert!(label.contains(&format!("scenario {object}:{k}")), "{label}");
                }
                _ => {}
            }
        }
    }
    // each file one second of its own: no second holds two files' messages
    let seconds: std::collections::BTreeSet<u64> = windows.iter().map(|w| w.0).collect();
    assert_eq!(seconds.len(), files.len(), "{windows:?}");
    // the same scenario replayed again replaces its file; a file of another origin at that
    // name (another scenario's recording) is refused, named, and kept byte for byte
    let source = |f: &std::path::Path| {
        let buf = std::fs::read(f).unwrap();
        let summary = mcap::Summary::read(&buf).unwrap().unwrap();
        let m = summary.metadata_indexes.iter().map(|i| mcap::read::metadata(&buf, i).unwrap());
        m.into_iter().find(|m| m.name == "gripopt.verify").unwrap().metadata["source"].clone()
    };
    let src = source(&files[0]);
    let (id, case) = src.strip_prefix("design ").unwrap().split_once(" scenario ").unwrap();
    let (object, k) = case.rsplit_once(':').unwrap();
    let (id, k): (u64, usize) = (id.parse().unwrap(), k.parse().unwrap());
    let again = gripopt::app::replay_scenario(&run, id, object, k, true).unwrap();
    assert_eq!(again.recording.as_ref(), Some(&files[0]));
    std::fs::copy(&files[1], &files[0]).unwrap();
    let foreign = std::fs::read(&files[0]).unwrap();
    let e = gripopt::app::replay_scenario(&run, id, object, k, true).unwrap_err().to_string();
    assert!(e.contains(files[0].file_name().unwrap().to_str().unwrap()) && e.contains("nothing was done"), "{e}");
    assert_eq!(std::fs::read(&files[0]).unwrap(), foreign, "the foreign file was changed");
    std::fs::remove_file(&files[0]).unwrap();
    gripopt::app::replay_scenario(&run, id, object, k, true).unwrap();
}

/// A free-kind run's shards draw the centred diagnostic grasp (object at x = 0) and say so:
/// the label of every design the free scene judged reads "centred grasp; free scene's
/// verdict: …", and the shard's `gripopt.run` metadata names the scene kind and x_off (a
/// centred run's metadata has neither, as before).
/// Origin: session 36's recording fixes.
#[test]
fn a_free_kind_shard_says_it_draws_the_centred_grasp() {
    let base = check_dir("s36-free-kind");
    let dir = base.with_extension("problem");
    std::fs::create_dir_all(&dir).unwrap();
    let src = std::fs::read_to_string(BOTTLE_FILE).unwrap();
    let src = src.replacen("kind = \"centred\"", "kind = \"free\"", 1).replacen("x_off = 0.0 ", "x_off = 0.002 ", 1);
    assert!(src.contains("x_off = 0.002"), "the problem's [scene] changed: fix the test");
    std::fs::write(dir.join("free.toml"), src).unwrap();
    let run = tiny_run_in(base, &dir.join("free.toml"), 24, 2);
    let shard_meta = |run: &Path| {
        let e = &read_index(&run.join("recording")).unwrap()[0];
        let buf = std::fs::read(run.join("recording").join(&e.file)).unwrap();
        let summary = mcap::Summary::read(&buf).unwrap().unwrap();
        let m = summary.metadata_indexes.iter().map(|i| mcap::read::metadata(&buf, i).unwrap());
        m.into_iter().find(|m| m.name == "gripopt.run").unwrap().metadata
    };
    let meta = shard_meta(&run);
    assert_eq!((meta["scene_kind"].as_str(), meta["x_off"].as_str()), ("free", "0.002"));
    let mut judged = 0;
    for msgs in messages(&run) {
        let of = |topic: &'static str| msgs.iter().filter(move |m| m.0 == topic);
        let rec: serde_json::Value = serde_json::from_slice(&of("/designs").next().unwrap().2).unwrap();
        let st = SceneUpdate::decode(&of("/scene/static").next().unwrap().2[..]).unwrap();
        let label = &st.entities.iter().find(|e| e.id == "label").unwrap().texts[0].text;
        let x = st.entities.iter().find(|e| e.id == "object").unwrap().cylinders[0].pose.unwrap().position.unwrap().x;
        assert_eq!(x, 0.0, "the centred grasp's object");
        assert!(label.chars().count() <= 120, "{label}");
        if rec.get("free_scene").is_some() {
            assert!(label.contains("centred grasp; free scene's verdict: "), "{label}");
            judged += 1;
        } else {
            assert!(!label.contains("free scene's verdict"), "{label}");
        }
    }
    assert!(judged > 0, "no design reached the free scene");
    let centred = tiny_run_in(check_dir("s36-centred-meta"), Path::new(BOTTLE_FILE), 8, 1);
    let meta = shard_meta(&centred);
    assert!(!meta.contains_key("scene_kind") && !meta.contains_key("x_off"), "{meta:?}");
}
