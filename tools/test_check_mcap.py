#!/usr/bin/env python3
"""Self-test of the independent checker (run by `make test`): the world-geometry and layout
checks must reject the defects they exist for (the checks must be able to fail), on scenes
built here from the official Foxglove message classes (foxglove-schemas-protobuf):

* the optimisation recording before issue 27 (world -> hand = Rx(-90 deg) at z = 2R: the hand
  not level, the bottle lying, finger rods below the ground, each check on its own), a /tf
  message without world -> hand, an entity
  that is not frame_locked, an object lifted off the ground;
* fingers drawn off the object they hold: finger 2 drawn as finger 1's mirror with the
  object at x_off = 2 mm (the offset scene before session 36: 4 mm off the object), a
  phalanx with a contact force drawn 3 mm away, a finger drawn deep inside the object, and in
  the offset scene a finger-2 force recorded (its own columns, session 37) while finger 2 is
  drawn 3 mm off the object or 12 um inside it (recorded penetration 3 um);
* a scenario file (`replay --scenario`) whose hand is not at its scenario's height, over
  another ground, or naming a grasp height problem.toml does not give; two scenario files in
  one time window;
* a robust shard's window: the scenario shown not the deciding one (recomputed from the
  record), a feasible design whose window draws no grasp, a finger drawn where a vertical
  object would touch it while the free object is tilted 10 deg (the contact is checked in 3-D
  with the object where /tf has it); a front file with a message outside its shard's time
  range; a label of 11 px, or 2 mm above the ground (its grid crossed it);
* a layout naming a topic or a field the recording lacks, a panel titled for one viewer only,
  an unknown panel type, a plot of 9 series on the 7-colour palette, a legend label cut by the
  legend's width, limit lines on the plot's top edge or on one another;
and accept the scene and layout as gripopt now writes them.
"""
import math
import pathlib
import sys
import tempfile
import json
from types import SimpleNamespace

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from check_layout import Recording, check_layout  # noqa: E402
from check_front import check_fronts  # noqa: E402
from check_mcap import check_disjoint, check_fingers_touch, check_label, check_scenario_frame  # noqa: E402
from check_scenario import SERIES_COLUMNS, check_robust_window, check_touch, deciding  # noqa: E402
from mcap_scene import Scene  # noqa: E402
from foxglove_schemas_protobuf.FrameTransforms_pb2 import FrameTransforms  # noqa: E402
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate  # noqa: E402

R, L, H = 0.04, 0.2, 0.05


def tf(t, rotation, z, with_hand=True):
    m = FrameTransforms()
    if with_hand:
        x = m.transforms.add()
        x.timestamp.seconds, x.timestamp.nanos = divmod(t, 1_000_000_000)
        x.parent_frame_id, x.child_frame_id = "world", "hand"
        x.translation.z = z
        x.rotation.x, x.rotation.y, x.rotation.z, x.rotation.w = rotation
    return m


def static(t, object_centre, locked=True):
    m = SceneUpdate()
    g = m.entities.add(id="ground", frame_id="world", frame_locked=locked)
    c = g.cubes.add()
    c.pose.position.z, c.pose.orientation.w = -0.0005, 1.0
    c.size.x, c.size.y, c.size.z = 0.6, 0.6, 0.001
    o = m.entities.add(id="object", frame_id="hand", frame_locked=locked)
    cyl = o.cylinders.add()
    cyl.pose.position.x, cyl.pose.position.y, cyl.pose.position.z = object_centre
    cyl.pose.orientation.w = 1.0
    cyl.size.x, cyl.size.y, cyl.size.z = 2 * R, 2 * R, L
    return m


def fingers(points):
    m = SceneUpdate()
    e = m.entities.add(id="fingers", frame_id="hand", frame_locked=True)
    line = e.lines.add(thickness=0.01)
    line.pose.orientation.w = 1.0
    for x, y in points:
        line.points.add(x=x, y=y, z=0.0)
    return m


def hand_pair(xs, y_top=0.08, thickness=0.01):
    """Both fingers as straight proximal phalanges x = xs[k] from the palm to y_top (tip
    beyond, away from the object), the way the recording's line strips run: tip, O22, base."""
    m = SceneUpdate()
    e = m.entities.add(id="fingers", frame_id="hand", frame_locked=True)
    for x in xs:
        line = e.lines.add(thickness=thickness)
        line.pose.orientation.w = 1.0
        sign = 1 if x > 0 else -1
        for px, py in [(x + sign * 0.03, y_top + 0.03), (x, y_top), (x, 0.0), (x + sign * 0.01, 0.01)]:
            line.points.add(x=px, y=py, z=0.0)
    return m


def contact_cases():
    """check_fingers_touch on a drawn proximal contact (object R = 40 mm, rods 10 mm thick:
    a rod at |x - x_c| = 45 mm touches)."""
    def series(f2, f2_force=None):
        s = SimpleNamespace(t=[0.0, 0.01], proximal_normal_force=[0.0, 5.0], distal_normal_force=[0.0, 0.0],
                            proximal_penetration=[0.0, 2e-6], distal_penetration=[0.0, 0.0], finger2_q11=f2)
        if f2_force is not None:  # finger 2's own contact columns (offset shards since session 37)
            s.finger2_proximal_normal_force, s.finger2_distal_normal_force = [0.0, f2_force], [0.0, 0.0]
            s.finger2_proximal_penetration, s.finger2_distal_penetration = [0.0, 3e-6 if f2_force else 0.0], [0.0, 0.0]
        return s
    ms = 1_000_000

    def run(centre_x, xs_last, f2, feasible=True, f2_force=None):
        st = static(0, (centre_x, R, L / 2 - H))
        drawn = [(0, hand_pair([centre_x + 0.06, centre_x - 0.06])), (10 * ms, hand_pair(xs_last))]
        return check_fingers_touch(7, 0, series(f2, f2_force), st, drawn, feasible)

    assert run(0.0, [0.045 - 2e-6, -0.045 + 2e-6], []) == 2  # centred: both (mirrored) fingers pressed in 2 um
    assert run(0.002, [0.047 - 2e-6, -0.043], [0.1, 0.1]) == 1  # offset before session 37: finger 2 at its own angles, touching
    # offset since session 37: finger 2's own force checked against its drawn phalanx (pressed in 3 um)
    assert run(0.002, [0.047 - 2e-6, -0.043 + 3e-6], [0.1, 0.1], f2_force=4.0) == 2
    # finger 2 drawn off the object where it records no force: nothing to check for it (not a stable grasp)
    assert run(0.002, [0.047 - 2e-6, -0.046], [0.1, 0.1], feasible=False, f2_force=0.0) == 1
    print("ok   accepts fingers drawn touching the object where the series has a contact force")
    expect_failure("finger 2 drawn as finger 1's mirror in the offset scene (x_off = 2 mm)",
                   lambda: run(0.002, [0.047, -0.047], [0.1, 0.1]), "finger 2")
    expect_failure("a finger-2 force recorded while finger 2 is drawn 3 mm off the object (offset scene)",
                   lambda: run(0.002, [0.047 - 2e-6, -0.046], [0.1, 0.1], feasible=False, f2_force=4.0),
                   "finger 2's proximal phalanx")
    expect_failure("a finger-2 force recorded while finger 2 is drawn 12 um inside the object (penetration 3 um)",
                   lambda: run(0.002, [0.047 - 2e-6, -0.043 + 12e-6], [0.1, 0.1], feasible=False, f2_force=4.0),
                   "finger 2's proximal phalanx")
    expect_failure("a proximal phalanx with a contact force drawn 3 mm off the object",
                   lambda: run(0.0, [0.048, -0.048], [], feasible=False), "proximal phalanx")
    expect_failure("a finger drawn 2 mm inside the object", lambda: run(0.0, [0.043, -0.043], []), "inside the object")


def scenario_cases():
    """A `replay --scenario` file: its hand at its scenario's height (the object's grasp
    height + the drawn height offset, as its metadata says, the grasp height problem.toml's);
    scenario files of one run in disjoint windows."""
    def info(z, meta, ground=0.0):
        scene = SimpleNamespace(world_hands={("world", "hand", 0.0, 0.0, round(z, 12), 0.0, 0.0, 0.0, 1.0)}, ground_top=ground)
        return SimpleNamespace(path=pathlib.Path("scenario-68-can-1.mcap"), kind="verify", meta=meta, scene=scene)
    meta = {"scenario_object": "can", "scenario_index": "1", "object_grasp_height": "0.04", "height_offset": "0.0042"}
    frames = {((("world", "hand", 0.0, 0.0, 0.05, 0.0, 0.0, 0.0, 1.0),), 0.0)}
    with tempfile.TemporaryDirectory() as d:
        run = pathlib.Path(d)
        (run / "problem.toml").write_text('[[robust.objects]]\nname = "can"\ngrasp_height = 0.040\n')
        check_scenario_frame(run, info(0.04 + 0.0042, meta), frames)
        print("ok   accepts a scenario file with the hand at its scenario's height")
        expect_failure("a scenario file whose hand is not at its scenario's height",
                       lambda: check_scenario_frame(run, info(0.05, meta), frames), "puts the hand at")
        expect_failure("a scenario file over another ground", lambda: check_scenario_frame(run, info(0.0442, meta, 0.01), frames), "ground plane")
        expect_failure("a scenario file whose object grasp height is not problem.toml's",
                       lambda: check_scenario_frame(run, info(0.0542, {**meta, "object_grasp_height": "0.05"}), frames), "problem.toml gives")
    s = 1_000_000_000
    check_disjoint([("the shards", 0, 99 * s), ("scenario-68-can-0.mcap", 3546 * s, 3547 * s - 1), ("scenario-68-can-1.mcap", 3547 * s, 3548 * s - 1)])
    expect_failure("two scenario files in one window (before session 36)",
                   lambda: check_disjoint([("scenario-68-can-0.mcap", 3000 * s, 3001 * s - 1), ("scenario-68-bottle-full-0.mcap", 3000 * s, 3001 * s - 1)]), "overlap")


def robust_cases():
    """Which scenario a robust design's window draws, and its fingers on the free object."""
    def sc(o, k, stays, disp=None, cause=None):
        r = {"object": o, "k": k, "stays": stays}
        if disp is not None:
            r["max_displacement"] = disp
        if cause:
            r["cause"] = cause
        return r
    objects = [{"name": "bottle", "meets_p_min": True}, {"name": "can", "meets_p_min": False}]
    runs = [sc(0, 0, True, 1e-4), sc(1, 0, True, 3e-4), sc(0, 1, False, 2e-3, "object_moved"), sc(1, 1, False, None, "fold"), sc(1, 2, False, 5e-3, "object_moved")]
    feasible = {"feasible": True, "robust": {"objects": objects, "scenarios": runs}}
    pstay = {"feasible": False, "failed_stage": 3, "reason": "object can: stays in 1 of 3 scenarios", "robust": {"objects": objects, "scenarios": runs}}
    aborted = {**pstay, "reason": "object can: scenario 1: aborted: step budget exhausted", "robust": {"objects": objects, "scenarios": [runs[0], sc(1, 1, False, None, "aborted")]}}
    assert deciding(feasible) == ("can", 2, "worst displacement")
    assert deciding(pstay) == ("can", 1, "first failure")  # the can's first failure, not the bottle's earlier one
    assert deciding(aborted) == ("can", 1, "aborted")
    assert deciding({"feasible": False, "failed_stage": 2, "robust": {"objects": objects, "scenarios": []}}) is None
    print("ok   recomputes the deciding scenario: the worst displacement, the failing object's first failure, the aborted scenario")

    info = SimpleNamespace(meta={"recording": json.dumps({"trajectories": "all"})}, scenario_windows=set(), scenario_hands={})
    series = SimpleNamespace(t=[0.0], design_id=4, simulated_samples=0, **{c: [math.nan] for c in SERIES_COLUMNS})
    msgs = [("/scenario/series", 0, series)]
    assert check_robust_window(4, 0, {"feasible": False, "failed_stage": 2, "robust": {"objects": objects, "scenarios": []}}, msgs, True, info, check_label) is None
    expect_failure("a feasible robust design whose window draws no grasp",
                   lambda: check_robust_window(4, 0, feasible, msgs, True, info, check_label), "draws no grasp")

    # a free object tilted 10 deg about y at G = (0, R, 0) of the hand frame: a phalanx along y
    # in the hand plane at x touches its capsule (radius R, rods of half thickness w) at
    # x cos(10 deg) = R + w - delta; drawn where a vertical object is touched, it is 0.8 mm inside
    w, th, delta = 0.005, math.radians(10.0), 2e-6
    pose = FrameTransforms()
    x = pose.transforms.add(parent_frame_id="hand", child_frame_id="object")
    x.translation.y = R
    x.rotation.y, x.rotation.w = math.sin(th / 2), math.cos(th / 2)
    obj = SceneUpdate()
    cyl = obj.entities.add(id="object", frame_id="object", frame_locked=True).cylinders.add()
    cyl.size.x, cyl.size.y, cyl.size.z = 2 * R, 2 * R, L
    cyl.pose.orientation.w = 1.0

    def touch(xf):
        m = SceneUpdate()
        e = m.entities.add(id="fingers", frame_id="hand", frame_locked=True)
        for sign in (1, -1):
            line = e.lines.add(thickness=2 * w)
            for px, py in [(sign * (xf + 0.03), 2 * R + 0.03), (sign * xf, 2 * R), (sign * xf, 0.0)]:
                line.points.add(x=px, y=py, z=0.0)
        cols = {c: [0.0] for c in SERIES_COLUMNS}
        for f in ("finger1", "finger2"):
            cols[f"{f}_proximal_normal_force"], cols[f"{f}_proximal_penetration"] = [3.0], [delta]
        s = SimpleNamespace(t=[0.0], free_scene=True, **cols)
        return check_touch(9, 0, s, obj, [(0, m)], {0: pose})

    assert touch((R + w - delta) / math.cos(th)) == 2
    print("ok   accepts both fingers touching a tilted free object where the series has a contact force")
    expect_failure("a finger drawn where a vertical object would touch it (the free object tilted 10 deg)",
                   lambda: touch(R + w - delta), "inside the object")


def front_cases():
    """A front file annotates its own shard, inside the shard's time range."""
    s = 1_000_000_000
    shard = SimpleNamespace(meta={"generation": "2"}, ids={40, 41}, start=40 * s, end=42 * s - 1, path=pathlib.Path("gen-00002.mcap"), designs={40: (True, {}), 41: (False, {})})

    def run(start, end):
        front = SimpleNamespace(meta={"generation": "2"}, front={40: True, 41: False}, start=start, end=end, path=pathlib.Path("front-00002.mcap"))
        with tempfile.TemporaryDirectory() as d:
            (pathlib.Path(d) / "front-00002.mcap").write_bytes(b"")
            front.path = pathlib.Path(d) / "front-00002.mcap"
            return check_fronts(pathlib.Path(d), {"shards": [shard], "fronts": [front]})
    run(40 * s, 41 * s)
    print("ok   accepts a front file inside its shard's time range")
    expect_failure("a front file with a message outside its shard (the whole run's front.mcap stretched the timeline)",
                   lambda: run(0, 41 * s), "outside")

    def label(px, z):
        m = SceneUpdate()
        t = m.entities.add(id="label", frame_id="world", frame_locked=True).texts.add(text="12 (gen 1) feasible", font_size=px)
        t.pose.position.z = z
        return check_label("design 12", m)
    label(13.0, 0.012)
    expect_failure("an 11 px label (a 0 read as a 9)", lambda: label(11.0, 0.012), "px")
    expect_failure("a label 2 mm above the ground (the ground and grid crossed it)", lambda: label(13.0, 0.002), "above the ground")


def run_scene(messages, level_hand=False):
    s = Scene(lambda t: t % 1_000_000_000 == 0, level_hand)
    for topic, t, m in messages:
        s.add(topic, t, m)
    return s.finish()


def expect_failure(what, fn, words):
    try:
        fn()
    except ValueError as e:
        if words not in str(e):
            raise AssertionError(f"{what}: failed for another reason: {e}")
        print(f"ok   rejects {what}: {e}")
        return
    raise AssertionError(f"{what}: accepted")


def main():
    s = math.sqrt(0.5)
    finger = [(0.11, 0.10), (0.07, 0.09), (0.03, 0.0), (0.05, 0.01), (0.08, 0.06), (0.07, 0.09)]
    now = (0, 0, 0, 1), H, (0.0, R, L / 2 - H)
    old = (-s, 0, 0, s), 2 * R, (0.0, R, 0.0)  # before issue 27: hand y -> world -z, the bottle lying
    # the scene as gripopt writes it now
    stats = run_scene([("/tf", 0, tf(0, now[0], now[1])), ("/scene/static", 0, static(0, now[2])), ("/scene", 0, fingers(finger))], True)
    assert stats["objects"] == 1 and stats["finger_points"] == 6, stats
    print("ok   accepts the scene as recorded (hand horizontal at h_c, object standing, fingers in the hand plane)")
    # the old frames: fingers below the ground (scene without the object), then the lying bottle
    ground_only = static(0, old[2])
    del ground_only.entities[1]
    expect_failure("finger rods below the ground (Rx(-90) at 2R)",
                   lambda: run_scene([("/tf", 0, tf(0, old[0], old[1])), ("/scene/static", 0, ground_only), ("/scene", 0, fingers(finger))]),
                   "below the ground plane")
    expect_failure("a hand that is not level (Rx(-90) at 2R)",
                   lambda: run_scene([("/tf", 0, tf(0, old[0], old[1]))], level_hand=True), "not level")
    expect_failure("the bottle lying (Rx(-90) at 2R)",
                   lambda: run_scene([("/tf", 0, tf(0, old[0], old[1])), ("/scene/static", 0, static(0, old[2]))]), "not upright")
    expect_failure("an object floating 1 mm above the ground",
                   lambda: run_scene([("/tf", 0, tf(0, now[0], now[1])), ("/scene/static", 0, static(0, (0.0, R, L / 2 - H + 0.001)))]), "above the ground plane")
    expect_failure("a /tf message without world -> hand",
                   lambda: run_scene([("/tf", 0, tf(0, now[0], now[1])), ("/tf", 5, tf(5, now[0], now[1], with_hand=False))]), "no world -> hand")
    expect_failure("an entity that is not frame_locked",
                   lambda: run_scene([("/tf", 0, tf(0, now[0], now[1])), ("/scene/static", 0, static(0, now[2], locked=False))]), "frame_locked")

    contact_cases()
    scenario_cases()
    robust_cases()
    front_cases()

    # layouts against a recording holding /grasp/series-like JSON and the frames
    rec = Recording()
    rec.add("/tf", tf(0, now[0], now[1]))
    rec.add("/series", {"t": [0.0, 0.1], "f": [1.0, 2.0]})
    rec.add("/scene", fingers(finger))
    plot = {"paths": [{"value": "/series.f[:]"}, {"value": "9.5"}], "xAxisVal": "currentCustom", "xAxisPath": {"value": "/series.t[:]"},
            "minYValue": 0, "maxYValue": 20, "legendDisplay": "left", "sidebarDimension": 200}
    three = {"followTf": "world", "transforms": {"frame:hand": {}}, "topics": {"/scene": {}}, "layers": {}}

    def layout(configs):
        titled = {k: {**v, "foxglovePanelTitle": k, "lichtblickPanelTitle": k} for k, v in configs.items()}
        ids = list(titled)
        tree = ids[0] if len(ids) == 1 else {"direction": "row", "first": ids[0], "second": ids[1]}
        return {"configById": titled, "layout": tree, "globalVariables": {}, "playbackConfig": {"speed": 0.02}}

    def check(doc):
        with tempfile.TemporaryDirectory() as d:
            p = pathlib.Path(d) / "layout.json"
            p.write_text(json.dumps(doc))
            return check_layout(p, rec)

    assert check(layout({"Plot!a": plot, "3D!b": three})) == 2 + 3  # x and y paths; two frames and a topic
    print("ok   accepts a layout whose paths and frames exist")
    expect_failure("a path to a missing field", lambda: check(layout({"Plot!a": {**plot, "paths": [{"value": "/series.g[:]"}]}})), "no value")
    expect_failure("a missing topic", lambda: check(layout({"Plot!a": {**plot, "paths": [{"value": "/grasp/series.f[:]"}]}})), "not in the recording")
    expect_failure("a frame not in /tf", lambda: check(layout({"3D!b": {**three, "followTf": "base_link"}})), "not in /tf")
    doc = layout({"Plot!a": plot})
    del doc["configById"]["Plot!a"]["lichtblickPanelTitle"]
    expect_failure("a title only Foxglove reads", lambda: check(doc), "lichtblickPanelTitle")
    expect_failure("an unknown panel type", lambda: check(layout({"Gauge!x": {"path": "/series.f[0]"}})), "unknown")
    nine = [{"value": "/series.f[:]", "label": f"s{k}"} for k in range(9)]
    check(layout({"Plot!a": {**plot, "paths": [{**p, "color": f"#00000{k}"} for k, p in enumerate(nine)]}}))
    expect_failure("9 series on the 7-colour palette (the offset layout's contact forces)",
                   lambda: check(layout({"Plot!a": {**plot, "paths": nine}})), "share a colour")
    expect_failure("a legend label cut at 200 px",
                   lambda: check(layout({"Plot!a": {**plot, "paths": [{"value": "/series.f[:]", "label": "finger 2 proximal friction force"}]}})), "is cut")
    expect_failure("a limit line on the plot's top edge (automatic y range)",
                   lambda: check(layout({"Plot!a": {k: v for k, v in plot.items() if k != "maxYValue"}})), "top edge")
    expect_failure("two limit lines at one value (1 mm and 1 deg)",
                   lambda: check(layout({"Plot!a": {**plot, "paths": plot["paths"] + [{"value": "9.5"}]}})), "one value")
    print("checker self-test: all passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
