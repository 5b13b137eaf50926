//! Session 37: in the offset scene finger 2 moves on its own, and its state and contacts are
//! now in the samples, the recording's `/grasp/series`, the trajectory CSVs and replay. Each
//! check is against something computed here: the penetration and contact normal of each
//! finger from its recorded angles (the linkage's DGM and a closest point found here), the
//! hand force as the sum of both fingers' forces on the object (MODEL.md §14: both fingers'
//! forces summed in the world frame), finger 1's values where finger 2 is its mirror
//! (x_off = 0), and the recording's own columns.

use crate::common::{bottle, check_dir, copy_dir, offset_problem, run_gripopt, scratch_dir, tiny_run_in};
use gripopt::model::Finger;
use gripopt::params::{Problem, SceneKind};
use gripopt::record::{read_design, read_index, Finger2Columns, GraspSeries};
use gripopt::replay;
use gripopt::sim::{FingerSample, Sample};
use nalgebra::Vector2;
use prost::Message;
use std::path::{Path, PathBuf};

type V = Vector2<f64>;

/// The grasp samples of the nominal design in the offset scene at `x_off`.
fn offset_samples(p: &Problem, x_off: f64) -> Vec<Sample> {
    let scene = Some(gripopt::SceneChoice { kind: SceneKind::Offset, x_off: Some(x_off) });
    gripopt::simulate(p, &p.nominal, &gripopt::SimulateRequest { scene, ..Default::default() })
        .unwrap()
        .trajectory
        .samples
}

/// A phalanx (segment from `a`, direction `dir`, length `len`, a rod of radius `w`) against
/// the circle (centre `c`, radius `r`): its penetration δ = r + w − d and the unit normal
/// from the phalanx to the centre, through the closest point of the segment.
fn touch(a: V, dir: V, len: f64, c: V, r: f64, w: f64) -> (f64, V) {
    let k = (c - a).dot(&dir).clamp(0.0, len);
    let n = c - (a + k * dir);
    (r + w - n.norm(), n / n.norm())
}

/// One finger at its recorded sample `s`, the object's centre at `c` in its local frame:
/// the penetrations its angles give (proximal, distal) and the y component of its force on
/// the object from its recorded contact forces (F = F_n y_c − F_t t_c, t_c = (y_c,y, −y_c,x);
/// the y axis is the same in both fingers' frames).
fn finger_on_object(f: &Finger, s: &FingerSample, c: V, r: f64) -> ([f64; 2], f64) {
    let p = f.dgm(s.q[0], s.q[1]).unwrap();
    let phalanges = [(f.o21, p.x21, f.l21), (p.o22, f.distal_dir(&p), f.t22)];
    let mut delta = [0.0; 2];
    let mut fy = 0.0;
    for (k, (a, dir, len)) in phalanges.into_iter().enumerate() {
        let (d, n) = touch(a, dir, len, c, r, f.w);
        delta[k] = d;
        fy += s.normal[k] * n.y + s.friction[k] * n.x;
    }
    (delta, fy)
}

/// (a) At x_off = 3 mm finger 2's recorded contacts are its own: the penetrations its
/// recorded angles give are the recorded ones, a normal force only with a penetration > 0,
/// and finger 2's force on the object plus finger 1's is the recorded hand force F_hand,y —
/// which twice finger 1's is not (finger 2 is not finger 1's mirror here).
#[test]
fn finger_2s_contacts_are_its_own_and_add_up_to_the_hand_force() {
    let p = bottle();
    let x_off = 0.003;
    let samples = offset_samples(&p, x_off);
    let f = Finger::new(&p.nominal, &p.scene).unwrap();
    let r = p.scene.object.radius;
    let scale = samples.iter().map(|s| s.hand_fy.abs()).fold(0.0, f64::max);
    assert!(scale > 10.0, "the grasp presses the object ({scale} N)");
    let (mut loaded, mut apart, mut not_mirror) = (0, 0.0f64, 0.0f64);
    for s in &samples {
        let f2 = s.finger2.expect("finger 2's values in every offset-scene sample");
        let (d1, y1) = finger_on_object(&f, &s.finger1(), V::new(x_off, r), r);
        let (d2, y2) = finger_on_object(&f, &f2, V::new(-x_off, r), r);
        for k in 0..2 {
            for (what, got, want) in [("finger 1", s.delta[k], d1[k]), ("finger 2", f2.delta[k], d2[k])] {
                assert!(
                    (got - want).abs() < 1e-12,
                    "t {}: {what}'s penetration {k}: {got:e}, its angles give {want:e}",
                    s.t
                );
            }
            if f2.normal[k] != 0.0 {
                assert!(f2.normal[k] > 0.0 && f2.delta[k] > 0.0, "t {}: finger 2 pushes at δ = {:e}", s.t, f2.delta[k]);
                loaded += 1;
            }
            apart = apart.max((f2.normal[k] - s.normal[k]).abs());
        }
        let sum = y1 + y2;
        assert!(
            (sum - s.hand_fy).abs() <= 1e-9 * scale,
            "t {}: F1,y + F2,y = {sum:e} N, hand_fy {:e} N",
            s.t,
            s.hand_fy
        );
        not_mirror = not_mirror.max((2.0 * y1 - s.hand_fy).abs());
    }
    assert!(loaded > 50, "finger 2 carries load at {loaded} contact samples");
    assert!(apart > 0.01 * scale, "finger 2's forces differ from finger 1's at an offset ({apart} N)");
    assert!(not_mirror > 1e-3 * scale, "the hand force is not twice finger 1's ({not_mirror} N)");
}

/// (b) At x_off = 0 finger 2 is finger 1's mirror image: each of its values equals finger
/// 1's within 1e-9 of that quantity's largest magnitude over the grasp; the friction forces
/// within 1e-8 (at a stick–slip reversal F_t swings by hundreds of newtons in microseconds,
/// and the fingers' contact events, located one after the other at the same time, differ
/// in the last bits: measured 3.3e-9 of its largest value on the nominal design).
#[test]
fn at_no_offset_finger_2_is_finger_1s_mirror() {
    let p = bottle();
    let samples = offset_samples(&p, 0.0);
    let one: Vec<[f64; 11]> = samples.iter().map(|s| s.finger1().values()).collect();
    let two: Vec<[f64; 11]> = samples.iter().map(|s| s.finger2.unwrap().values()).collect();
    let names = gripopt::FINGER2_COLUMNS.map(|c| c.0);
    let mut loaded = 0;
    for k in 0..11 {
        let scale = one.iter().map(|v| v[k].abs()).fold(0.0, f64::max);
        let tol = if names[k].starts_with("finger2_ft") { 1e-8 } else { 1e-9 };
        for (a, b) in one.iter().zip(&two) {
            assert!((a[k] - b[k]).abs() <= tol * scale, "{}: {:e} vs finger 1's {:e}", names[k], b[k], a[k]);
        }
        loaded += usize::from(names[k].starts_with("finger2_fn") && scale > 1.0);
    }
    assert_eq!(loaded, 2, "both phalanges carry load");
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
    let csv = scratch_dir("s37", "csv").join("replay.csv");
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
    let scratch = scratch_dir("s37", "shapes");
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
