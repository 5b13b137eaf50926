//! The 3-D scene of every recording (optimisation shards, `gripopt verify`'s file, and any
//! later scenario recording), drawn with the official `foxglove` SDK types in one physical
//! frame set (docs/recording.md, "The picture"):
//!
//! * `world`: z up, the ground's top face is the plane z = 0;
//! * `hand` (MODEL.md §2 and §14.1): x along the palm towards finger 1, y from the palm towards
//!   the object, z up; its origin, the palm centre, lies h_c (`grasp_height`) above the ground,
//!   axes parallel to `world` (the hand is horizontal, g_eq = 0). `world → hand` is in every
//!   `/tf` message, so a seek to any instant finds it;
//! * `object` (verify only): the free object's body frame, origin at its centre of mass G.
//!
//! The fingers lie in the hand plane z = 0 (rods of radius w); the object stands on the ground
//! with its axis along z, touching the palm. Every entity is `frame_locked`: it is drawn where
//! its frame is at the playback time, so the bottle moves with the frame `object`.

use super::entry::DesignEntry;
use crate::math::V2;
use crate::model::{closed_pose, singularity_sweep, Finger, SweepFailure};
use crate::params::{Design, Problem, SceneParams};
use crate::sim::Sample;
use foxglove::messages::{
    line_primitive, scene_entity_deletion, Color, CubePrimitive, CylinderPrimitive, Duration, FrameTransform,
    FrameTransforms, KeyValuePair, LinePrimitive, Point3, Pose, Quaternion, SceneEntity, SceneEntityDeletion,
    SceneUpdate, TextPrimitive, Timestamp, Vector3,
};
use std::borrow::Cow;

/// The fixed frame: z up, the ground's top face at z = 0.
pub const WORLD: &str = "world";
/// The hand's frame (MODEL.md §2; the free scene's world of §14.1).
pub const HAND: &str = "hand";
/// The free object's body frame (verify recordings).
pub const OBJECT: &str = "object";

/// The last nanosecond of the window starting at `t0_ns`: every design's window ends with a
/// `/tf` message there, so the recording's time range covers its last design's whole window.
pub fn window_end_ns(t0_ns: u64) -> u64 {
    t0_ns + 999_999_999
}

pub(crate) fn stamp(ns: u64) -> Timestamp {
    Timestamp::new((ns / 1_000_000_000).min(u32::MAX as u64) as u32, (ns % 1_000_000_000) as u32)
}

fn rgba(r: f64, g: f64, b: f64, a: f64) -> Option<Color> {
    Some(Color { r, g, b, a })
}

fn at(x: f64, y: f64, z: f64) -> Option<Pose> {
    Some(Pose { position: Some(Vector3 { x, y, z }), orientation: Some(Quaternion { x: 0.0, y: 0.0, z: 0.0, w: 1.0 }) })
}

fn entity(t_ns: u64, frame: &str, id: &str, design_id: u64) -> SceneEntity {
    SceneEntity {
        timestamp: Some(stamp(t_ns)),
        frame_id: frame.into(),
        id: id.into(),
        lifetime: Some(Duration::new(0, 0)),
        // drawn where its frame is at the playback time (not at the message time)
        frame_locked: true,
        metadata: vec![KeyValuePair { key: "design_id".into(), value: design_id.to_string() }],
        ..Default::default()
    }
}

fn delete_all(t_ns: u64) -> Vec<SceneEntityDeletion> {
    vec![SceneEntityDeletion {
        timestamp: Some(stamp(t_ns)),
        r#type: scene_entity_deletion::Type::All as i32,
        id: String::new(),
    }]
}

/// `world → hand`: the hand plane h_c (`sc.object.grasp_height`) above the ground, axes
/// parallel (the hand horizontal).
pub fn hand_transform(t_ns: u64, sc: &SceneParams) -> FrameTransform {
    FrameTransform {
        timestamp: Some(stamp(t_ns)),
        parent_frame_id: WORLD.into(),
        child_frame_id: HAND.into(),
        translation: Some(Vector3 { x: 0.0, y: 0.0, z: sc.object.grasp_height }),
        rotation: Some(Quaternion { x: 0.0, y: 0.0, z: 0.0, w: 1.0 }),
    }
}

/// A `/tf` message holding `world → hand` only.
pub fn frames(t_ns: u64, sc: &SceneParams) -> FrameTransforms {
    FrameTransforms { transforms: vec![hand_transform(t_ns, sc)] }
}

/// Centre of the fixed object in the frame `hand` (MODEL.md §8.5, §14): on the hand's y axis
/// at y = R touching the palm (at x = x_off in the offset scene), standing on the ground
/// (its base at z = −h_c).
pub fn object_centre(sc: &SceneParams) -> [f64; 3] {
    let x = if sc.setup.kind.has_finger2() { sc.setup.x_off } else { 0.0 };
    [x, sc.object.radius, sc.object.length / 2.0 - sc.object.grasp_height]
}

/// The scene a design's picture is drawn in: the problem's, except for a robust design that
/// stage 2 discarded on another of its objects ([`crate::eval::Record::failed_object`]): then that
/// object's cylinder (radius and length), standing on the ground under the reference's hand
/// plane, so that the red closed pose that failed is drawn on the object it failed on; and
/// for a design of the offset scene discarded at stages 0–2, whose statics are the centred
/// grasp's (MODEL.md §14: the offset scene is stage 3's), the object at x = 0, where its red
/// closed pose was computed.
pub fn drawn_scene<'a>(problem: &'a Problem, d: &DesignEntry<'_>) -> Cow<'a, SceneParams> {
    let sc = &problem.scene;
    if sc.setup.kind.has_finger2() && matches!(d.record.verdict.failed_stage, Some(0..=2)) {
        let mut centred = sc.clone();
        centred.setup = centred.setup.to_centred();
        return Cow::Owned(centred);
    }
    let failed_on = (d.record.verdict.failed_stage == Some(2))
        .then(|| d.record.failed_object())
        .flatten()
        .and_then(|o| problem.robust.as_ref()?.objects.get(o));
    match failed_on {
        Some(o) if (o.object.radius, o.object.length) != (sc.object.radius, sc.object.length) => {
            let mut drawn = sc.clone();
            drawn.object.radius = o.object.radius;
            drawn.object.length = o.object.length;
            Cow::Owned(drawn)
        }
        _ => Cow::Borrowed(sc),
    }
}

/// `/scene/static` of a design's window (optimisation recordings): deletes everything of the
/// previous design on this topic, then draws the ground (`world`), the palm and the fixed
/// object (`hand`) and the design's verdict as a text label above the scene (`world`).
pub fn static_scene(t_ns: u64, d: &DesignEntry<'_>, sc: &SceneParams) -> SceneUpdate {
    static_scene_with(t_ns, d.id, &Design::from_array(&d.parameters), sc, &scene_verdict(d, sc))
}

/// [`static_scene`] of design `id` (`design`) with the text `label`.
pub fn static_scene_with(t_ns: u64, id: u64, design: &Design, sc: &SceneParams, label: &str) -> SceneUpdate {
    let [x, y, z] = object_centre(sc);
    let object = object_entity(t_ns, HAND, id, sc, at(x, y, z));
    SceneUpdate {
        deletions: delete_all(t_ns),
        entities: vec![
            ground_entity(t_ns, id),
            palm_entity(t_ns, id, design, sc.hand.w),
            object,
            label_entity(t_ns, id, label),
        ],
    }
}

/// The most characters of a label: 120 characters of the label's 13 px font (about 7.5 px
/// each, 900 px) fit a 3-D panel of half a 1920 px screen, the layouts' 3-D views.
pub const LABEL_MAX_CHARS: usize = 120;

/// The label's font size (px, scale invariant): 13 px (11 px until session 38, where a 0 read
/// as a 9).
pub const LABEL_FONT_PX: f64 = 13.0;

/// Height of the label's centre above the ground (m): the text faces the camera, so half of
/// it hung below the ground and its grid at 2 mm (until session 38); at 12 mm a 13 px line
/// (about 7 mm tall in the oblique view at 0.38 m) clears them.
pub const LABEL_HEIGHT: f64 = 0.012;

/// The label of design `d` in the problem's scene `sc`: one short line saying what became of
/// it, feasible with its objectives, or where and why it was discarded; at most
/// [`LABEL_MAX_CHARS`] characters, so that it fits a 3-D panel of half a screen's width
/// ([`fit_label`]; the whole reason is in `/designs`). A design of a free-kind problem whose stage 3 ran in the free scene says that the grasp drawn is the
/// centred one and the verdict the free scene's (the free scene itself is drawn by `gripopt
/// verify`): "k (gen g) centred grasp; free scene's verdict: …".
pub fn scene_verdict(d: &DesignEntry<'_>, sc: &SceneParams) -> String {
    let head = format!("{} (gen {})", d.id, d.generation);
    if sc.setup.kind.is_free() && d.record.free_scene.is_some() {
        verdict_after(d, format!("{head} centred grasp; free scene's verdict:"))
    } else {
        verdict_after(d, head)
    }
}

/// The verdict of `d` after the words `head`.
pub(super) fn verdict_after(d: &DesignEntry<'_>, head: String) -> String {
    match d.record.verdict.failed_stage {
        Some(s) => fit_label(
            &format!("{head} stage {s}: "),
            d.record.verdict.reason.as_deref().unwrap_or("no reason recorded"),
        ),
        None => {
            let o = d.record.objectives();
            let f =
                |v: Option<f64>, scale: f64, unit: &str| v.map_or("-".into(), |v| format!("{:.1} {unit}", v * scale));
            format!(
                "{head} feasible: F {}, alpha {}, t_stab {}, offset {}",
                f(o[2], 1.0, "N"),
                o[1].map_or("-".into(), |v| format!("{v:.3}")),
                f(o[3], 1e3, "ms"),
                f(o[0].filter(|m| *m >= 0.0), 1e3, "mm"),
            )
        }
    }
}

/// `head` + `reason` if that has at most [`LABEL_MAX_CHARS`] characters; else the reason
/// without its parenthesised details ("… in 0 of 2 scenarios (P(stay) 0.000 < p_min 0.5;
/// …)" loses the bracket), and if still too long cut to the limit, ending with "…".
pub fn fit_label(head: &str, reason: &str) -> String {
    let whole = format!("{head}{reason}");
    if whole.chars().count() <= LABEL_MAX_CHARS {
        return whole;
    }
    let (mut out, mut depth) = (String::new(), 0usize);
    for c in reason.chars() {
        match c {
            '(' => depth += 1,
            ')' if depth > 0 => depth -= 1,
            _ if depth == 0 => out.push(c),
            _ => {}
        }
    }
    // the spaces left around a removed bracket
    let reason = out.split_whitespace().collect::<Vec<_>>().join(" ").replace(" ;", ";").replace(" :", ":");
    let mut out = format!("{head}{reason}");
    if out.chars().count() > LABEL_MAX_CHARS {
        out = out.chars().take(LABEL_MAX_CHARS - 1).collect::<String>() + "…";
    }
    out
}

/// The ground plane (frame `world`, top face at z = 0).
fn ground_entity(t_ns: u64, id: u64) -> SceneEntity {
    let mut ground = entity(t_ns, WORLD, "ground", id);
    ground.cubes.push(CubePrimitive {
        pose: at(0.0, 0.0, -0.0005),
        size: Some(Vector3 { x: 0.6, y: 0.6, z: 0.001 }),
        color: rgba(0.55, 0.55, 0.5, 1.0),
    });
    ground
}

/// The palm (frame `hand`): the model's palm, a rod of radius w along x whose surface is the
/// line y = 0 (MODEL.md §6, the free scene's capsule of §14.2), drawn as a bar b + 2w long and
/// 2w thick centred at (0, −w, 0).
fn palm_entity(t_ns: u64, id: u64, design: &Design, w: f64) -> SceneEntity {
    let mut palm = entity(t_ns, HAND, "palm", id);
    palm.cubes.push(CubePrimitive {
        pose: at(0.0, -w, 0.0),
        size: Some(Vector3 { x: design.b + 2.0 * w, y: 2.0 * w, z: 2.0 * w }),
        color: rgba(0.45, 0.45, 0.45, 1.0),
    });
    palm
}

/// The bottle: a cylinder of radius R and length L_c along the z axis of `frame`, centred at `pose`.
fn object_entity(t_ns: u64, frame: &str, id: u64, sc: &SceneParams, pose: Option<Pose>) -> SceneEntity {
    let r = sc.object.radius;
    let mut object = entity(t_ns, frame, "object", id);
    object.cylinders.push(CylinderPrimitive {
        pose,
        size: Some(Vector3 { x: 2.0 * r, y: 2.0 * r, z: sc.object.length }),
        bottom_scale: 1.0,
        top_scale: 1.0,
        color: rgba(0.2, 0.5, 0.9, 0.4),
    });
    object
}

/// A text label (frame `world`) just above the ground ([`LABEL_HEIGHT`]) 8 cm behind the
/// palm, facing the camera: below the hand in both views of the layouts, never over a finger.
fn label_entity(t_ns: u64, id: u64, text: &str) -> SceneEntity {
    let mut label = entity(t_ns, WORLD, "label", id);
    label.texts.push(TextPrimitive {
        pose: at(0.0, -0.08, LABEL_HEIGHT),
        billboard: true,
        font_size: LABEL_FONT_PX,
        scale_invariant: true,
        color: rgba(1.0, 1.0, 1.0, 1.0),
        text: text.into(),
    });
    label
}

/// Round a coordinate to 2⁻²⁰ m (≈ 1 µm): invisible, and the zeroed low mantissa bits
/// compress well.
fn q(x: f64) -> f64 {
    (x * 1_048_576.0).round() / 1_048_576.0
}

const ORANGE: [f64; 4] = [0.9, 0.4, 0.1, 1.0];
const RED: [f64; 4] = [0.9, 0.1, 0.1, 0.9];

/// One finger at pose `p` as a line strip through tip, O22, base, O12, O13, O22 in the
/// hand's plane (`mirror` −1: finger 2, mirrored in x).
fn finger_line(finger: &Finger, p: &crate::model::Pose, mirror: f64, color: [f64; 4]) -> LinePrimitive {
    let chain: [V2; 6] = [finger.tip(p), p.o22, finger.o21, p.o12, p.o13, p.o22];
    LinePrimitive {
        r#type: line_primitive::Type::LineStrip as i32,
        pose: at(0.0, 0.0, 0.0),
        thickness: 2.0 * finger.w,
        scale_invariant: false,
        points: chain.iter().map(|v| Point3 { x: q(mirror * v.x), y: q(v.y), z: 0.0 }).collect(),
        color: rgba(color[0], color[1], color[2], color[3]),
        ..Default::default()
    }
}

/// Both fingers (finger 2 the mirror of finger 1) at pose `p` as the entity `id`.
fn fingers_entity(t_ns: u64, design_id: u64, id: &str, f: &Finger, p: &crate::model::Pose, c: [f64; 4]) -> SceneEntity {
    let mut e = entity(t_ns, HAND, id, design_id);
    for mirror in [1.0, -1.0] {
        e.lines.push(finger_line(f, p, mirror, c));
    }
    e
}

/// `/scene` message: both fingers at sample `s` (finger 2 the mirror of finger 1 in the
/// centred scene; at its own angles `s.finger2`, mirrored, in the offset scene); with `first`, it
/// first deletes the previous design's fingers. `None` when there is no finger or a pose
/// cannot be assembled (then, with `first`, a message that only deletes).
pub fn scene(id: u64, t_ns: u64, finger: Option<&Finger>, s: Option<&Sample>, first: bool) -> Option<SceneUpdate> {
    let deletions = if first { delete_all(t_ns) } else { vec![] };
    let pose = finger.zip(s).and_then(|(f, s)| f.dgm(s.q[0], s.q[1]).ok().map(|p| (f, p, s.finger2.map(|f2| f2.q))));
    let drawn = match pose {
        Some((finger, p, None)) => Some(fingers_entity(t_ns, id, "fingers", finger, &p, ORANGE)),
        Some((finger, p1, Some(q2))) => finger.dgm(q2[0], q2[1]).ok().map(|p2| two_fingers(t_ns, id, finger, &p1, &p2)),
        None => None,
    };
    let Some(e) = drawn else {
        return first.then(|| SceneUpdate { deletions, entities: vec![] });
    };
    Some(SceneUpdate { deletions, entities: vec![e] })
}

/// `/scene` message of a design recorded without a trajectory (discarded at stages 0–2, or
/// its trajectory not kept): deletes the previous design's fingers, then draws the fingers
/// at the open pose (orange, `fingers`) when the finger can be built and, for a design
/// discarded at stage 1 or 2, the pose that explains the discard (red, `failing_pose`): the
/// pose of the singularity sweep closest to a singularity ("singularity margin"), the last
/// pose the linkage can still be assembled in ("not mountable" at a larger θ2), or the
/// closed pose on the object whose forces fail the statics (stage 2).
/// The closed pose is drawn on the drawn object ([`drawn_scene`]: a robust design's failing
/// object); the finger and its sweep are the problem's (`sc`).
pub fn discarded_scene(
    t_ns: u64,
    id: u64,
    x: &Design,
    failed_stage: Option<u8>,
    sc: &SceneParams,
    drawn: &SceneParams,
) -> SceneUpdate {
    let mut m = SceneUpdate { deletions: delete_all(t_ns), entities: vec![] };
    let Ok(f) = Finger::new(x, sc) else { return m };
    m.entities.push(fingers_entity(t_ns, id, "fingers", &f, &f.open, ORANGE));
    let failing = failed_stage.filter(|s| (1..=2).contains(s)).and_then(|_| failing_pose(&f, sc, drawn.object.radius));
    if let Some((p, _)) = failing {
        m.entities.push(fingers_entity(t_ns, id, "failing_pose", &f, &p, RED));
    }
    m
}

/// The linkage pose that explains a stage-1 or stage-2 discard (see [`discarded_scene`]) and
/// its θ2; a stage-2 discard's closed pose on the object of radius `radius`.
fn failing_pose(f: &Finger, sc: &SceneParams, radius: f64) -> Option<(crate::model::Pose, f64)> {
    match singularity_sweep(f, sc) {
        Err(SweepFailure::Margin(s)) => f.ik(f.open.q21, s.at_theta2).ok().map(|p| (p, s.at_theta2)),
        Err(SweepFailure::Pose(th2, _)) => {
            // a θ2 in [0, th2) at which the linkage stops being assembled (bisection)
            let (mut lo, mut hi) = (0.0, th2);
            f.ik(f.open.q21, lo).ok()?;
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if f.ik(f.open.q21, mid).is_ok() {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            f.ik(f.open.q21, lo).ok().map(|p| (p, lo))
        }
        Err(SweepFailure::ClosedPose(..)) => None,
        Ok(_) => closed_pose(f, radius, 0.0).ok().map(|c| (c.pose, c.theta2)),
    }
}

// ---- the free scene (`gripopt verify`'s recording): the object a rigid body whose pose is
// ---- the frame `object`

/// `/tf` of the free scene at `t_ns`: `world → hand` and `hand → object` (origin at G, axes
/// the body's: its axis along z) for the free object's position `g` and orientation `q`
/// (w, x, y, z; normalised here).
pub fn free_frames(t_ns: u64, sc: &SceneParams, g: [f64; 3], q: [f64; 4]) -> FrameTransforms {
    let [w, x, y, z] = q;
    let n = (w * w + x * x + y * y + z * z).sqrt();
    let object = FrameTransform {
        timestamp: Some(stamp(t_ns)),
        parent_frame_id: HAND.into(),
        child_frame_id: OBJECT.into(),
        translation: Some(Vector3 { x: g[0], y: g[1], z: g[2] }),
        rotation: Some(Quaternion { x: x / n, y: y / n, z: z / n, w: w / n }),
    };
    FrameTransforms { transforms: vec![hand_transform(t_ns, sc), object] }
}

/// `/scene/static` of the free scene at a design's window start: deletes everything, then
/// the ground (`world`), the palm (`hand`), the bottle (`object`, centred at G, its axis
/// along z) and the text `label` above the scene.
pub fn free_static_scene(t_ns: u64, id: u64, design: &Design, sc: &SceneParams, label: &str) -> SceneUpdate {
    let object = object_entity(t_ns, OBJECT, id, sc, at(0.0, 0.0, 0.0));
    SceneUpdate {
        deletions: delete_all(t_ns),
        entities: vec![
            ground_entity(t_ns, id),
            palm_entity(t_ns, id, design, sc.hand.w),
            object,
            label_entity(t_ns, id, label),
        ],
    }
}

/// `/scene` of the free scene: both fingers, each at its own angles (`q`: q11, q21 of
/// finger 1, then of finger 2 in its mirrored frame); with `first`, it first deletes the
/// previous design's fingers. `None` when a pose cannot be assembled (then, with `first`,
/// a message that only deletes).
pub fn free_fingers(id: u64, t_ns: u64, finger: Option<&Finger>, q: [f64; 4], first: bool) -> Option<SceneUpdate> {
    let deletions = if first { delete_all(t_ns) } else { vec![] };
    let poses = finger.and_then(|f| Some((f, f.dgm(q[0], q[1]).ok()?, f.dgm(q[2], q[3]).ok()?)));
    let Some((finger, p1, p2)) = poses else {
        return first.then(|| SceneUpdate { deletions, entities: vec![] });
    };
    Some(SceneUpdate { deletions, entities: vec![two_fingers(t_ns, id, finger, &p1, &p2)] })
}

/// The entity `fingers`: finger 1 at pose `p1`, finger 2 at its own pose `p2` (in its
/// mirrored frame).
fn two_fingers(t_ns: u64, id: u64, finger: &Finger, p1: &crate::model::Pose, p2: &crate::model::Pose) -> SceneEntity {
    let mut e = entity(t_ns, HAND, "fingers", id);
    e.lines.push(finger_line(finger, p1, 1.0, ORANGE));
    e.lines.push(finger_line(finger, p2, -1.0, ORANGE));
    e
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::dist_to_singular;
    use rand::SeedableRng;

    fn bottle() -> crate::params::Problem {
        crate::params::Problem::load(concat!(env!("CARGO_MANIFEST_DIR"), "/problems/bottle-1l.toml")).unwrap()
    }

    #[test]
    fn a_long_label_is_shortened_to_fit() {
        let short = "force positiveness violated (min force -7.2609 N)";
        assert_eq!(fit_label("12 (gen 1) stage 2: ", short), format!("12 (gen 1) stage 2: {short}"));
        let robust = "object bottle-full: stays (finger criteria met, object barely moves) in 0 of 2 scenarios (P(stay) 0.000 < p_min 0.5; Clopper–Pearson 95%: [0.000, 0.842]); stopped early after 5 of 8 scenarios";
        assert_eq!(
            fit_label("88 (gen 3) stage 3: ", robust),
            "88 (gen 3) stage 3: object bottle-full: stays in 0 of 2 scenarios; stopped early after 5 of 8 scenarios"
        );
        let long = "x".repeat(300);
        assert_eq!(fit_label("1 (gen 1) stage 3: ", &long).chars().count(), LABEL_MAX_CHARS);
        assert!(fit_label("1 (gen 1) stage 3: ", &long).ends_with('…'));
    }

    #[test]
    fn the_object_stands_on_the_ground_touching_the_palm() {
        let sc = bottle().scene;
        let [x, y, z] = object_centre(&sc);
        let h = hand_transform(0, &sc).translation.unwrap();
        // base on the ground plane z = 0 of `world`, side on the palm face y = 0 of `hand`
        assert_eq!((x, y - sc.object.radius), (0.0, 0.0));
        assert!((h.z + z - sc.object.length / 2.0).abs() < 1e-15);
    }

    /// Designs drawn from the default box and discarded at stages 1–2 show the pose that
    /// explains the discard: its margin is the sweep's minimum (independently recomputed from
    /// the pose's angles), or it is the last assemblable pose, or the closed pose on the object.
    #[test]
    fn a_discarded_design_shows_the_pose_that_explains_it() {
        let p = bottle();
        let sc = &p.scene;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut margin, mut pose, mut statics) = (0, 0, 0);
        for _ in 0..3000 {
            let x = p.bounds.sample(&mut rng);
            let ev = crate::eval::evaluate_statics(&x, sc);
            let Some(stage) = ev.discard.map(|d| d.stage).filter(|s| (1..=2).contains(s)) else { continue };
            let Ok(f) = Finger::new(&x, sc) else { continue };
            let m = discarded_scene(7, 1, &x, Some(stage), sc, sc);
            assert_eq!((m.deletions.len(), m.entities[0].id.as_str()), (1, "fingers"));
            let drawn = m.entities.iter().any(|e| e.id == "failing_pose");
            match singularity_sweep(&f, sc) {
                Err(SweepFailure::Margin(s)) => {
                    let (q, _) = failing_pose(&f, sc, sc.object.radius).unwrap();
                    let d = [q.q12, q.q22, q.q13].map(dist_to_singular).into_iter().fold(f64::INFINITY, f64::min);
                    assert!((d - s.min_margin).abs() < 1e-12 && drawn);
                    margin += 1;
                }
                Err(SweepFailure::Pose(th2, _)) => {
                    // the edge of the assemblable poses below the sweep's failing θ2: a pose
                    // through which the linkage passes a singularity (q12, q22 or q13 at 0 or π)
                    let (q, th) = failing_pose(&f, sc, sc.object.radius).unwrap();
                    assert!(crate::math::wrap(q.q22 + f.psi - th).abs() < 1e-9);
                    let d = [q.q12, q.q22, q.q13].map(dist_to_singular).into_iter().fold(f64::INFINITY, f64::min);
                    assert!(th < th2 && d < 1e-4 && drawn, "{th} {th2} {d}");
                    pose += 1;
                }
                Err(SweepFailure::ClosedPose(..)) => assert!(!drawn),
                Ok(_) => {
                    assert_eq!(stage, 2);
                    statics += drawn as usize;
                }
            }
        }
        assert!(margin > 0 && statics > 0, "{margin} {pose} {statics}");
    }
}
