//! `gripopt verify`'s MCAP recording (docs/recording.md): one window per verified design
//! holding its verify row, the object's pose as the frame hand → object and the fingers.
//! Read back with the `mcap` reader and the Foxglove SDK's decoders and compared with the
//! CSV and with MODEL.md §14.1's initial pose; byte-identical for any thread count;
//! `--record none` writes none. The run lives under target/mcap-check/ so that `make test`
//! checks the file with the independent reader (tools/check_mcap.py).

use foxglove::messages::{FrameTransforms, SceneUpdate};
use foxglove::Decode;
use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_gripopt");

fn tiny_run(name: &str) -> PathBuf {
    crate::common::tiny_run(&format!("verify-record-{name}"), Path::new(crate::common::BOTTLE_FILE), 8, 2)
}

/// Messages of a file as (topic, log time, bytes), in file order.
fn messages(path: &Path) -> Vec<(String, u64, Vec<u8>)> {
    let buf = std::fs::read(path).unwrap();
    mcap::MessageStream::new(&buf)
        .unwrap()
        .map(|m| m.unwrap())
        .map(|m| (m.channel.topic.clone(), m.log_time, m.data.to_vec()))
        .collect()
}

fn csv_rows(p: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    (head, lines.map(|l| l.split(',').map(String::from).collect()).collect())
}

#[test]
fn verify_recording_holds_rows_and_object_pose() {
    let dir = tiny_run("front");
    let d = dir.display().to_string();
    let out = Command::new(BIN).args(["verify", &d, "--threads", "1"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let file = dir.join("verify.mcap");
    let bytes1 = std::fs::read(&file).unwrap();
    assert!(dir.join("foxglove-verify-layout.json").is_file());
    let out = Command::new(BIN).args(["verify", &d, "--threads", "2"]).output().unwrap();
    assert!(out.status.success());
    assert_eq!(bytes1, std::fs::read(&file).unwrap(), "verify.mcap depends on the thread count");

    let run: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("run.json")).unwrap()).unwrap();
    let epoch_ns = run["recording"]["epoch_s"].as_u64().unwrap() * 1_000_000_000;
    let p = gripopt::params::Problem::load(dir.join("problem.toml")).unwrap();
    let s = &p.scene;
    let (r, lc, hc) = (s.object.radius, s.object.length, s.object.grasp_height);
    // §14.1: G starts at (x_off, R, L_c/2 − h_c − δ_g0), δ_g0 = (m_c g / (n_g K_g))^(2/3)
    let dg0 = (s.object.mass() * s.env.g / (s.setup.ground_points as f64 * s.setup.ground_k)).powf(2.0 / 3.0);
    let g0 = [s.setup.x_off, r, lc / 2.0 - hc - dg0];

    let (h, rows) = csv_rows(&dir.join("verify.csv"));
    let c = |name: &str| h.iter().position(|x| x == name).unwrap();
    assert!(!rows.is_empty());
    let msgs = messages(&file);
    // the verify windows start after the run's designs, at the first whole thousand seconds
    // (the run's 16 designs live in [epoch, epoch + 16 s)): no second holds two designs
    assert_eq!(run["evaluations"].as_u64(), Some(16));
    let base = epoch_ns + 1000 * 1_000_000_000;
    assert!(msgs.iter().all(|m| m.1 >= base), "a verify message inside the run's time range");
    for (k, row) in rows.iter().enumerate() {
        let (lo, hi) = (base + k as u64 * 1_000_000_000, base + (k as u64 + 1) * 1_000_000_000);
        let win: Vec<_> = msgs.iter().filter(|m| m.1 >= lo && m.1 < hi).collect();
        let recs: Vec<_> = win.iter().filter(|m| m.0 == "/verify").collect();
        assert_eq!(recs.len(), 1, "window {k}");
        assert_eq!(recs[0].1, lo);
        let v: serde_json::Value = serde_json::from_slice(&recs[0].2).unwrap();
        assert_eq!(v["id"].as_u64().unwrap(), row[c("id")].parse::<u64>().unwrap(), "row {k} in window {k}");
        assert_eq!(v["window"].as_u64(), Some(k as u64));
        for key in ["object_max_displacement", "object_max_tilt_deg", "force_margin", "l21", "psi_deg"] {
            let rec = if key == "l21" || key == "psi_deg" { &v["parameters"][key] } else { &v[key] };
            assert_eq!(rec.as_f64().unwrap(), row[c(key)].parse::<f64>().unwrap(), "window {k}: {key}");
        }
        assert_eq!(v["moved"].as_bool().unwrap(), row[c("moved")] == "true");
        // the object's frame: one hand → object per pose, from G(0) to the end, never further
        // from G(0) horizontally than the measured maximum
        let mut tfs: Vec<(u64, FrameTransforms)> =
            win.iter().filter(|m| m.0 == "/tf").map(|m| (m.1, FrameTransforms::decode(&m.2[..]).unwrap())).collect();
        // one /tf per pose, and the final pose again at the window's last nanosecond (so a
        // seek anywhere in the last window lands inside the recording)
        let end = tfs.pop().unwrap();
        assert_eq!(end.0, hi - 1);
        assert_eq!(tfs.len() as u64, v["poses"].as_u64().unwrap());
        // world → hand in every message: a viewer seeking into the window finds the ground
        for (_, t) in tfs.iter().chain([&end]) {
            assert_eq!(
                (t.transforms[0].parent_frame_id.as_str(), t.transforms[0].child_frame_id.as_str()),
                ("world", "hand")
            );
        }
        // drawn at least 2 ms of simulated time apart (the last pose excepted), so at most
        // 0.1 s / 2 ms + 2 poses; the integrator's steps grow beyond 2 ms once settled
        assert!(tfs.len() >= 10 && tfs.len() <= 52, "{} poses", tfs.len());
        assert!(
            tfs[..tfs.len() - 1].windows(2).all(|w| w[1].0 - w[0].0 >= 2_000_000),
            "window {k}: poses closer than 2 ms"
        );
        assert_eq!(
            (tfs[0].1.transforms[0].parent_frame_id.as_str(), tfs[0].1.transforms[0].child_frame_id.as_str()),
            ("world", "hand")
        );
        assert_eq!(tfs[0].1.transforms[0].translation.unwrap().z, hc, "the hand plane at h_c above the ground");
        let obj = |t: &FrameTransforms| {
            let x = t.transforms.last().unwrap();
            assert_eq!((x.parent_frame_id.as_str(), x.child_frame_id.as_str()), ("hand", "object"));
            x.translation.unwrap()
        };
        let first = obj(&tfs[0].1);
        assert!(
            (first.x - g0[0]).abs() < 1e-15 && (first.y - g0[1]).abs() < 1e-15 && (first.z - g0[2]).abs() < 1e-12,
            "G(0) {first:?} vs {g0:?}"
        );
        let dmax = row[c("object_max_displacement")].parse::<f64>().unwrap();
        for (_, t) in &tfs {
            let g = obj(t);
            assert!(
                (g.x - g0[0]).hypot(g.y - g0[1]) <= dmax * (1.0 + 1e-12),
                "window {k}: a drawn pose beyond the measured maximum"
            );
        }
        let t_end = v["t_end"].as_f64().unwrap();
        assert!((t_end - s.setup.t_obs).abs() < 1e-12, "observed to t_obs");
        assert_eq!(tfs.last().unwrap().0, lo + (t_end * 1e9).round() as u64, "the last pose is the final state");
        // the scene: the bottle in the object frame, both fingers at the pose times
        let st: Vec<SceneUpdate> =
            win.iter().filter(|m| m.0 == "/scene/static").map(|m| SceneUpdate::decode(&m.2[..]).unwrap()).collect();
        let bottle = st[0].entities.iter().find(|e| e.id == "object").unwrap();
        assert_eq!(bottle.frame_id, "object");
        let size = bottle.cylinders[0].size.unwrap();
        assert_eq!((size.x, size.z), (2.0 * r, lc));
        let fingers: Vec<(u64, SceneUpdate)> =
            win.iter().filter(|m| m.0 == "/scene").map(|m| (m.1, SceneUpdate::decode(&m.2[..]).unwrap())).collect();
        assert_eq!(fingers.len(), tfs.len());
        assert!(fingers.iter().zip(&tfs).all(|(f, t)| f.0 == t.0 && f.1.entities[0].lines.len() == 2));
    }
    assert_eq!(msgs.iter().filter(|m| m.0 == "/verify").count(), rows.len());
}

#[test]
fn verify_record_none_writes_no_recording() {
    let dir = tiny_run("none");
    let out = Command::new(BIN).args(["verify", &dir.display().to_string(), "--record", "none"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(dir.join("verify.csv").is_file());
    assert!(!dir.join("verify.mcap").exists() && !dir.join("foxglove-verify-layout.json").exists());
    let out = Command::new(BIN).args(["verify", &dir.display().to_string(), "--record", "some"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}
