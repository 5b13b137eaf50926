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
* a layout naming a topic or a field the recording lacks, a panel titled for one viewer only,
  an unknown panel type;
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
from check_mcap import check_disjoint, check_fingers_touch, check_scenario_frame  # noqa: E402
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

    # layouts against a recording holding /grasp/series-like JSON and the frames
    rec = Recording()
    rec.add("/tf", tf(0, now[0], now[1]))
    rec.add("/series", {"t": [0.0, 0.1], "f": [1.0, 2.0]})
    rec.add("/scene", fingers(finger))
    plot = {"paths": [{"value": "/series.f[:]"}, {"value": "9.5"}], "xAxisVal": "currentCustom", "xAxisPath": {"value": "/series.t[:]"}}
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
    print("checker self-test: all passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
