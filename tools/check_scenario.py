"""The window of a robust run's shard that draws a design's deciding scenario, checked as a
viewer would read it. Knows nothing of gripopt's code: it reads the decoded `/designs`,
`/scenario/series`, `/tf`, `/scene/static` and `/scene` messages of one design's window and
checks them against each other and against an independent reading of the design's record:

* which scenario: the one that decided the verdict, recomputed from `/designs` → `robust`
  (docs/recording.md): a feasible design's worst by the free object's largest displacement
  (the first of equals; none measured: its first scenario), a P(stay) failure's first scenario,
  in the order run, in which the first object that fails p_min did not stay, a solver
  failure's (reason "object NAME: scenario K: ...") aborted scenario; `shown_scenario` and the
  series name it; its `replay` names `gripopt replay ... --design ID --scenario OBJECT:K`;
* the drawing: the free scene (the object in the moving frame `object`, `/tf` with world ->
  hand and hand -> object at every drawn pose, the fingers drawn only at those poses) or the
  centred grasp (the object fixed in `hand`, `/tf` at the window start and its end); the
  last finger pose at the series' last sample;
* the free object's motion in `/tf` is the series': at every drawn pose that is a series
  sample, |G_xy - G_xy(0)| and the tilt of the object's axis from `/tf` equal the series'
  displacement and tilt;
* the drawn fingers touch the drawn object where the series has a contact force: the distance
  between the phalanx (a segment of the drawn line strip, a rod of its thickness) and the
  object's axis segment (a capsule of the cylinder's radius), in 3-D with the object where
  `/tf` has it, lies within [-(delta + tol), tol] of contact (delta the series' penetration);
  no finger deeper than 1.5 x the deepest kept penetration + 20 um;
* the hand's height above the ground minus the scenario's height offset (the object's grasp
  height, compared with problem.toml per run folder).
"""
import json
import math
import re

NS = 1_000_000_000
CONTACT_TOL = 5e-6  # m: the drawing is rounded to 2^-20 m (1 um), compact values to f32
ABORT_REASON = re.compile(r"object (\S+): scenario (\d+): ")
FINGER_COLUMNS = [("finger1_proximal", "finger1_distal"), ("finger2_proximal", "finger2_distal")]
# the value columns of /scenario/series (docs/recording.md), each as long as `t`
SERIES_COLUMNS = ["displacement_mm", "tilt_deg"] + [
    f"{f}_{v}" for v in ("normal_force", "penetration") for pair in FINGER_COLUMNS for f in pair
] + [f"finger{n}_{q}" for n in (1, 2) for q in ("q11", "q21")]


# ---------------------------------------------------------------- which scenario
def deciding(rec):
    """(object name, k, why) of the scenario that decided the verdict of a robust design's
    /designs record `rec`, or None (no scenario ran, or stages 0-2 decided)."""
    rb = rec.get("robust") or {}
    runs = rb.get("scenarios") or []
    names = [o["name"] for o in rb.get("objects", [])]
    if not runs:
        return None
    pick = lambda s, why: (names[s["object"]], s["k"], why)  # noqa: E731
    if rec.get("feasible"):
        best = None
        for s in runs:
            if "max_displacement" in s and (best is None or s["max_displacement"] > best["max_displacement"]):
                best = s
        return pick(best, "worst displacement") if best else pick(runs[0], "first scenario")
    if rec.get("failed_stage") != 3:
        return None
    m = ABORT_REASON.match(rec.get("reason", ""))
    if m:
        s = next((s for s in runs if s.get("cause") in ("aborted", "free_scene_aborted")), None)
        return pick(s, "aborted") if s else None
    failing = next((i for i, o in enumerate(rb.get("objects", [])) if o.get("meets_p_min") is False), None)
    if failing is None:
        return None
    s = next((s for s in runs if s["object"] == failing and not s["stays"]), None)
    return pick(s, "first failure") if s else None


# ---------------------------------------------------------------- geometry
def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def seg_seg_distance(p0, p1, q0, q1):
    """The distance between segments p0-p1 and q0-q1 in 3-D (closest points by the clamped
    normal equations, each end case tried)."""
    d1, d2, r = sub(p1, p0), sub(q1, q0), sub(p0, q0)
    a, e, f = dot(d1, d1), dot(d2, d2), dot(d2, r)
    c, b = dot(d1, r), dot(d1, d2)
    candidates = []
    clamp = lambda x: min(1.0, max(0.0, x))  # noqa: E731
    denom = a * e - b * b
    if denom > 1e-30 * a * e and a > 0 and e > 0:
        s = clamp((b * f - c * e) / denom)
        t = (b * s + f) / e
        candidates.append((s, clamp(t)))
    for s in (0.0, 1.0):
        candidates.append((s, clamp((b * s + f) / e) if e > 0 else 0.0))
    for t in (0.0, 1.0):
        candidates.append((clamp((b * t - c) / a) if a > 0 else 0.0, t))
    best = math.inf
    for s, t in candidates:
        p = [x + s * y for x, y in zip(p0, d1)]
        q = [x + t * y for x, y in zip(q0, d2)]
        best = min(best, math.dist(p, q))
    return best


def phalanges(line):
    """The proximal (base - O22) and distal (O22 - tip) segments of a drawn finger (line
    strip tip, O22, base, ...) in its frame, and the rod's half thickness."""
    p = [[q.x, q.y, q.z] for q in line.points]
    return (p[2], p[1]), (p[1], p[0]), line.thickness / 2


def quat_rotate(q, v):
    x, y, z, w = q.x, q.y, q.z, q.w
    # v + 2 w (u x v) + 2 u x (u x v), u = (x, y, z)
    ux = [y * v[2] - z * v[1], z * v[0] - x * v[2], x * v[1] - y * v[0]]
    uux = [y * ux[2] - z * ux[1], z * ux[0] - x * ux[2], x * ux[1] - y * ux[0]]
    return [v[i] + 2 * w * ux[i] + 2 * uux[i] for i in range(3)]


# ---------------------------------------------------------------- the window
def check_scenario_window(d, t0, rec, series, msgs, info, check_label):
    """Check design `d`'s window drawing its deciding scenario; the drawn contacts checked."""
    at = lambda topic: [(t, m) for tp, t, m in msgs if tp == topic]  # noqa: E731
    shown = rec.get("shown_scenario")
    want = deciding(rec)
    if shown is None:
        raise ValueError(f"design {d}: /scenario/series draws a scenario but /designs has no shown_scenario")
    got = (shown["object"], shown["k"], shown["why"])
    if want is None or got != want:
        raise ValueError(f"design {d}: the window draws scenario {got}, the record's deciding scenario is {want}")
    if (series.object, series.scenario_index, series.free_scene) != (shown["object"], shown["k"], shown["free_scene"]):
        raise ValueError(f"design {d}: /scenario/series ({series.object}:{series.scenario_index}, free {series.free_scene}) is not the shown scenario {shown}")
    if f"--design {d} --scenario {shown['object']}:{shown['k']}" not in shown["replay"]:
        raise ValueError(f"design {d}: shown_scenario.replay {shown['replay']!r} does not name this scenario")
    tf, static, fingers = at("/tf"), at("/scene/static"), at("/scene")
    end = t0 + NS - 1
    if len(static) != 1 or static[0][0] != t0:
        raise ValueError(f"design {d}: /scene/static must hold one message at the window start")
    st = static[0][1]
    check_label(f"design {d}", st)
    frames = {e.id: e.frame_id for e in st.entities}
    object_frame = "object" if series.free_scene else "hand"
    if not st.deletions or st.deletions[0].type != 1 or frames != {"ground": "world", "palm": "hand", "object": object_frame, "label": "world"}:
        raise ValueError(f"design {d}: /scene/static must delete all, then draw ground (world), palm (hand), object ({object_frame}) and label (world); got {frames}")
    label = next(e for e in st.entities if e.id == "label").texts[0].text
    if f"{shown['object']}:{shown['k']}" not in label:
        raise ValueError(f"design {d}: the label {label!r} does not name the scenario {shown['object']}:{shown['k']}")
    if not tf or tf[0][0] != t0 or tf[-1][0] != end:
        raise ValueError(f"design {d}: /tf must be at the window start and at its last nanosecond")
    pairs = {tuple((x.parent_frame_id, x.child_frame_id) for x in m.transforms) for _, m in tf}
    want_pairs = {(("world", "hand"), ("hand", "object"))} if series.free_scene else {(("world", "hand"),)}
    if pairs != want_pairs:
        raise ValueError(f"design {d}: /tf carries {sorted(pairs)}, the {'free scene' if series.free_scene else 'centred grasp'} needs {sorted(want_pairs)}")
    if not series.free_scene and len(tf) != 2:
        raise ValueError(f"design {d}: the centred grasp's /tf is at the window start and its end only")
    if not fingers or fingers[0][0] != t0 or not fingers[0][1].deletions or fingers[0][1].deletions[0].type != 1:
        raise ValueError(f"design {d}: the first /scene message must be at the window start and delete the previous fingers")
    drawn = [(t, m) for t, m in fingers if m.entities]
    pose_times = {t for t, _ in tf[:-1]}
    if series.free_scene and any(t not in pose_times for t, _ in drawn):
        raise ValueError(f"design {d}: the free scene's fingers are drawn at times without an object pose")
    t = list(series.t)
    if drawn and series.simulated_samples and drawn[-1][0] != t0 + min(round(t[-1] * NS), NS - 1):
        raise ValueError(f"design {d}: the last finger pose is at {drawn[-1][0] - t0} ns, the series' last sample at {round(t[-1] * NS)} ns")
    hand = tf[0][1].transforms[0].translation.z
    info.scenario_hands.setdefault(shown["object"], set()).add(round(hand - shown["height_offset"], 9))
    poses = {tm: m for tm, m in tf}
    return check_motion(d, t0, series, poses) + check_touch(d, t0, series, st, drawn, poses)


def object_pose(m):
    x = next(x for x in m.transforms if x.child_frame_id == "object")
    return x.translation, x.rotation


def check_motion(d, t0, s, poses):
    """The free object's displacement and tilt in /tf equal the series' at every pose drawn
    at a series sample; the number compared."""
    if not s.free_scene:
        if any(v == v for v in s.displacement_mm):
            raise ValueError(f"design {d}: a centred grasp's series measures no free object (displacement must be NaN)")
        return 0
    g0 = object_pose(poses[t0])[0]
    n = 0
    for k, t in enumerate(s.t):
        m = poses.get(t0 + round(t * NS))
        if m is None:
            continue
        g, q = object_pose(m)
        disp = math.hypot(g.x - g0.x, g.y - g0.y) * 1e3
        axis = quat_rotate(q, [0.0, 0.0, 1.0])
        tilt = math.degrees(math.atan2(math.hypot(axis[0], axis[1]), axis[2]))
        if abs(disp - s.displacement_mm[k]) > 1e-6 + 1e-6 * disp or abs(tilt - s.tilt_deg[k]) > 1e-4 + 1e-6 * tilt:
            raise ValueError(f"design {d}: at {t * 1e3:.3f} ms /tf puts G {disp:.6f} mm from its start, tilted {tilt:.5f} deg; the series says {s.displacement_mm[k]:.6f} mm, {s.tilt_deg[k]:.5f} deg")
        n += 1
    return n


def check_touch(d, t0, s, st, drawn, poses):
    """The drawn fingers touch the drawn object where the series has a contact force (see
    the module's documentation); the number of contacts checked."""
    obj = next(e for e in st.entities if e.id == "object")
    cyl = obj.cylinders[0]
    r, half_len = cyl.size.x / 2, cyl.size.z / 2
    c = cyl.pose.position
    at_sample = {round(t * NS): k for k, t in enumerate(s.t)}
    pens = [getattr(s, f"{f}_penetration") for pair in FINGER_COLUMNS for f in pair]
    deepest = max([0.0] + [x for col in pens for x in col if x == x])
    inside_limit = 1.5 * deepest + 20e-6
    checked = 0
    latest = poses[t0]
    for tm, m in drawn:
        latest = poses.get(tm, latest)
        if s.free_scene:
            g, q = object_pose(latest)
            a = quat_rotate(q, [0.0, 0.0, half_len])
            axis = ([g.x - a[0], g.y - a[1], g.z - a[2]], [g.x + a[0], g.y + a[1], g.z + a[2]])
        else:
            axis = ([c.x, c.y, c.z - half_len], [c.x, c.y, c.z + half_len])
        lines = next(e for e in m.entities if e.id == "fingers").lines
        k = at_sample.get(tm - t0)
        for n, line in enumerate(lines):
            segs = phalanges(line)
            gaps = [seg_seg_distance(*seg, *axis) - r - segs[2] for seg in segs[:2]]
            if min(gaps) < -inside_limit:
                raise ValueError(f"design {d}: at {(tm - t0) / 1e6:.3f} ms finger {n + 1} is drawn {-min(gaps) * 1e6:.1f} um inside the object (deepest penetration kept {deepest * 1e6:.1f} um)")
            if k is None:
                continue
            for ph, name in enumerate(FINGER_COLUMNS[n]):
                f, delta = getattr(s, f"{name}_normal_force")[k], getattr(s, f"{name}_penetration")[k]
                if not f > 0:
                    continue
                if not -(delta + CONTACT_TOL) <= gaps[ph] <= CONTACT_TOL:
                    raise ValueError(f"design {d}: at {(tm - t0) / 1e6:.3f} ms {name.replace('_', ' ')} is drawn {gaps[ph] * 1e6:+.1f} um from the object while its contact force is {f:.3g} N (penetration {delta * 1e6:.1f} um)")
                checked += 1
    return checked


# ---------------------------------------------------------------- a robust shard's windows
def recorded_trajectories(info):
    """Which designs' trajectories the shard's run records (`recording` of its metadata):
    all, feasible or none."""
    try:
        return json.loads(info.meta.get("recording", "{}")).get("trajectories", "all")
    except ValueError:
        return "all"


def check_robust_window(d, t0, rec, msgs, scene, info, check_label):
    """A robust shard's design: one /scenario/series at the window start; a design that
    reached its scenarios (and whose trajectory the run records) draws its deciding scenario
    (tools/check_scenario.py), others the placeholder. (contacts checked, or None: the
    window is a reference-object window, checked as any other.)"""
    series = [(t, m) for tp, t, m in msgs if tp == "/scenario/series"]
    if len(series) != 1 or series[0][0] != t0 or series[0][1].design_id != d:
        raise ValueError(f"design {d}: /scenario/series must hold one message for this design at the window start")
    s = series[0][1]
    cols = [s.t] + [getattr(s, c) for c in SERIES_COLUMNS]
    t = list(s.t)
    if len({len(c) for c in cols}) != 1 or not t or t[0] != 0.0 or any(b < a for a, b in zip(t, t[1:])) or t[-1] >= 1.0:
        raise ValueError(f"design {d}: /scenario/series columns must be non-empty, equally long, t from 0 forward inside the window")
    keeps = recorded_trajectories(info)
    expected = deciding(rec) is not None and (keeps == "all" or (keeps == "feasible" and rec.get("feasible")))
    if "shown_scenario" not in rec:
        if expected:
            what = "a feasible design" if rec.get("feasible") else "a design that reached its scenarios"
            raise ValueError(f"design {d}: {what} whose window draws no grasp (its deciding scenario {deciding(rec)} is not drawn; the run records trajectories: {keeps})")
        if s.simulated_samples != 0 or len(t) != 1:
            raise ValueError(f"design {d}: without a drawn scenario, /scenario/series holds one placeholder sample")
        return None
    if not expected:
        raise ValueError(f"design {d}: draws scenario {rec['shown_scenario']} although the run records no trajectory of it ({keeps})")
    if not scene:
        return 0
    info.scenario_windows.add(d)
    return check_scenario_window(d, t0, rec, s, msgs, info, check_label)


def check_scenario_hands(run, shards):
    """The windows that draw a scenario put the hand at the scenario's height: less the
    drawn height offset, each object's hand height is one value, its grasp height in the run's
    problem.toml ([[robust.objects]] grasp_height, where given inline)."""
    per = {}
    for i in shards:
        for o, hs in i.scenario_hands.items():
            per.setdefault(o, set()).update(hs)
    objects = {}
    problem = run / "problem.toml"
    if problem.is_file():
        import tomllib
        objects = {o.get("name"): o for o in tomllib.loads(problem.read_text()).get("robust", {}).get("objects", [])}
    for o, hs in per.items():
        if len(hs) != 1:
            raise ValueError(f"the scenarios of {o} are drawn with the hand at {sorted(hs)} m above the ground less their height offsets: one grasp height expected")
        if o in objects and "grasp_height" in objects[o] and abs(next(iter(hs)) - objects[o]["grasp_height"]) > 1e-9:
            raise ValueError(f"the scenarios of {o} are drawn with the hand at grasp height {next(iter(hs))} m, problem.toml gives {objects[o]['grasp_height']}")
    n = sum(len(i.scenario_windows) for i in shards)
    return f"{n} deciding scenarios drawn with the hand at their object's grasp height + offset"
