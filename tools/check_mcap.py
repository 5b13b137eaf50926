#!/usr/bin/env python3
"""Independent check of gripopt's MCAP files and shipped layouts, as a Foxglove viewer would read them.

Knows nothing of gripopt's code: it uses the reference `mcap` reader, `mcap-protobuf-support`
(decodes protobuf messages with the descriptor embedded in the file) and the official
Foxglove schemas from `foxglove-schemas-protobuf`, and composes the /tf transforms itself
(tools/mcap_scene.py). For every *.mcap under the given folders:

1. the file opens, has a summary with statistics, chunk and message indexes, and a
   `gripopt.run` (shard), `gripopt.verify` or `gripopt.front` metadata record with its keys;
2. every channel is protobuf (schema encoding `protobuf`) or JSON (`jsonschema`);
   a `foxglove.*` schema must be protobuf and its descriptor (every message it reaches:
   field names, numbers, labels, types, type names; enum values) must equal the official
   one; every JSON schema must parse the way Foxglove's JSON-schema parser does (one type
   per field, no union types; every array with typed `items`; every object with properties);
3. every message decodes (protobuf with the embedded descriptor; JSON, validated against
   its schema), and the count equals the statistics;
4. a shard: each design's `/designs` message sits at the start of its time window,
   epoch_s + id s; in that window `/grasp/series` has equal-length columns with time running
   forward inside the window (a design without a grasp: one placeholder sample at t = 0 with
   `simulated_samples` = 0, so a Plot panel redraws); where there is a scene, `/tf` at the window
   start and at its last nanosecond, `/scene/static` (deleting all, then ground, palm, object,
   label, at most 120 characters on one line) and `/scene` (deleting all first) at the window start, and the last finger pose at
   the last recorded sample; the drawn fingers touch the drawn object where the series has a
   contact force (check_fingers_touch), never deeper inside it than 1.5 x the deepest kept
   penetration + 20 um,
   and hold it at the last pose of a feasible design; a stage-2 discard's red closed pose
   touches the drawn object with both phalanges;
5. a verify recording: window k (at epoch_s + window_base_s + k s) holds one `/verify` record
   and one `/verify/series` at the window start; `/scene/static` deletes all, then draws ground
   (frame world), palm (hand), object (object) and a label; `/tf` carries world -> hand and
   hand -> object at every pose (as many as the record says, time running forward, the last
   at the record's t_end) and once more at the window's last nanosecond; `/scene` deletes all
   first and draws the two fingers only at pose times, the last at the last pose;
6. a front recording: one `/front` message per design at its window start;
7. the geometry in world coordinates (tools/mcap_scene.py): world -> hand in every /tf
   message and constant; every entity frame_locked; no finger point below the ground plane
   at any instant; the object upright with its base on the ground at each window start; a
   moving object never below the ground by more than a contact penetration.

Then per run folder: the same world frame (world -> hand, ground plane) in its shards and
verify files, except a `replay --scenario` file, whose hand is level at exactly its scenario's
height (metadata object_grasp_height + height_offset, the grasp height that of problem.toml's
object) over the same ground; verify and scenario files in time ranges disjoint from the shards' and from each other (with
or without shards); the
front recording present when the run finished, covering the shards' designs, its members
those of pareto.csv; and every topic, message path and frame of each shipped layout
(foxglove-layout.json: the shards and front.mcap; foxglove-verify-layout.json: each verify
file) present in the recordings it is shipped with (tools/check_layout.py).

Prints one line per file and folder and 'N passed, N failed'; exits non-zero on any failure
or when no file was found.
"""
import importlib
import json
import math
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from check_layout import Recording, check_layout  # noqa: E402
from check_front import check_fronts  # noqa: E402
from check_scenario import check_robust_window, check_scenario_hands  # noqa: E402
from mcap_scene import Scene  # noqa: E402

import jsonschema
from google.protobuf import descriptor_pb2
from mcap.decoder import DecoderFactory as McapDecoderFactory
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

NS = 1_000_000_000


# ---------------------------------------------------------------- JSON schema, viewer-style
def parse_like_viewer(schema, path="$"):
    """Walk a JSON schema the way Foxglove's parser does; raise on what it rejects."""
    t = schema.get("type")
    if isinstance(t, list):
        raise ValueError(f"{path}: Unsupported type {json.dumps(t)} (union types are not parsed)")
    if t is None:
        if "oneOf" in schema and all("const" in s for s in schema["oneOf"]):
            return
        raise ValueError(f"{path}: no `type`")
    if t == "object":
        props = schema.get("properties")
        if not isinstance(props, dict):
            raise ValueError(f"{path}: object without properties")
        for k, v in props.items():
            parse_like_viewer(v, f"{path}.{k}")
    elif t == "array":
        items = schema.get("items")
        if not isinstance(items, dict) or "type" not in items and "oneOf" not in items:
            raise ValueError(f"{path}: array without typed `items` (reading 'type' of undefined)")
        parse_like_viewer(items, f"{path}[]")
    elif t not in ("string", "number", "integer", "boolean", "null"):
        raise ValueError(f"{path}: unsupported type {t!r}")


# ---------------------------------------------------------------- protobuf descriptors
def messages_of(fds):
    """full name -> normalised description of every message and enum in a FileDescriptorSet."""
    out = {}

    def walk_enum(prefix, e):
        out[f"{prefix}{e.name}"] = ("enum", sorted((v.name, v.number) for v in e.value))

    def walk_msg(prefix, m):
        name = f"{prefix}{m.name}"
        fields = sorted((f.name, f.number, f.label, f.type, f.type_name.lstrip(".")) for f in m.field)
        out[name] = ("message", fields)
        for n in m.nested_type:
            walk_msg(f"{name}.", n)
        for e in m.enum_type:
            walk_enum(f"{name}.", e)

    for f in fds.file:
        prefix = f"{f.package}." if f.package else ""
        for m in f.message_type:
            walk_msg(prefix, m)
        for e in f.enum_type:
            walk_enum(prefix, e)
    return out


def official_descriptor(full_name):
    """The FileDescriptorSet of an official Foxglove message (foxglove-schemas-protobuf)."""
    short = full_name.split(".", 1)[1]
    module = importlib.import_module(f"foxglove_schemas_protobuf.{short}_pb2")
    desc = getattr(module, short).DESCRIPTOR
    fds = descriptor_pb2.FileDescriptorSet()
    seen = set()

    def add(fd):
        if fd.name in seen:
            return
        seen.add(fd.name)
        for dep in fd.dependencies:
            add(dep)
        fd.CopyToProto(fds.file.add())

    add(desc.file)
    return fds


def reachable(name, table, acc=None):
    acc = set() if acc is None else acc
    if name in acc or name not in table:
        return acc
    acc.add(name)
    kind, body = table[name]
    if kind == "message":
        for field in body:
            if field[4]:
                reachable(field[4], table, acc)
    return acc


def check_foxglove_schema(schema):
    if schema.encoding != "protobuf":
        why = ""
        if schema.encoding == "jsonschema":
            try:
                parse_like_viewer(json.loads(schema.data), schema.name)
            except ValueError as e:
                why = f" (and the viewer rejects it: {e})"
        raise ValueError(f"schema {schema.name}: encoding {schema.encoding!r}, not the official protobuf schema{why}")
    recorded = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    mine, theirs = messages_of(recorded), messages_of(official_descriptor(schema.name))
    for name in sorted(reachable(schema.name, theirs)):
        if name not in mine:
            raise ValueError(f"schema {schema.name}: {name} missing from the embedded descriptor")
        if mine[name] != theirs[name]:
            raise ValueError(f"schema {schema.name}: {name} differs from the official descriptor:\n  file:     {mine[name]}\n  official: {theirs[name]}")


# ---------------------------------------------------------------- the file
class JsonDecoderFactory(McapDecoderFactory):
    """JSON messages: json.loads (validated against the channel's schema below)."""

    def decoder_for(self, message_encoding, schema):
        return json.loads if message_encoding == "json" else None


class FileInfo:
    """What the folder checks need from one file."""

    def __init__(self, path, kind):
        self.path, self.kind = path, kind
        self.recording = Recording()
        self.scene = None
        self.start = self.end = None
        self.front = {}  # /front: id -> on_final_front
        self.designs = {}  # /designs: id -> (feasible, objectives)
        self.ids = set()
        self.contacts = 0  # drawn contacts checked against the series' forces
        self.meta = {}  # the gripopt.* metadata record
        self.robust = False  # a robust run's shard (/scenario/series)
        self.scenario_hands = {}  # object -> {hand height - height offset} of its drawn scenarios
        self.scenario_windows = set()  # designs whose window draws their deciding scenario
        self.ref_hands = set()  # world -> hand of the other windows


def check(path):
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory(), JsonDecoderFactory()])
        summary = reader.get_summary()
        if summary is None:
            raise ValueError("no summary section")
        if summary.statistics is None:
            raise ValueError("no statistics record")
        if not summary.chunk_indexes:
            raise ValueError("no chunk indexes")
        for ci in summary.chunk_indexes:
            if not ci.message_index_offsets:
                raise ValueError(f"chunk at {ci.chunk_start_offset} has no message index")
        validators = check_channels(summary)
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        if "gripopt.run" in meta:
            name, first, last, per_design, kind = "gripopt.run", "first_id", "last_id", check_design, "shard"
            keys = ("generation", "first_id", "last_id", "designs", "epoch_s")
        elif "gripopt.verify" in meta:
            name, first, last, per_design, kind = "gripopt.verify", "first_window", "last_window", check_verify_design, "verify"
            keys = ("first_window", "last_window", "designs", "epoch_s", "window_base_s", "scene_dt")
        elif "gripopt.front" in meta:
            name, first, last, per_design, kind = "gripopt.front", "first_id", "last_id", check_front_design, "front"
            keys = ("first_id", "last_id", "designs", "epoch_s", "front_size", "generations")
        else:
            raise ValueError("no gripopt.run, gripopt.verify or gripopt.front metadata record")
        run = meta[name]
        for k in keys:
            if k not in run:
                raise ValueError(f"{name} metadata lacks {k!r}")
        info = FileInfo(path, kind)
        info.meta = dict(run)
        base = int(run.get("window_base_s", 0))
        epoch = (int(run["epoch_s"]) + base) * NS
        window_start = lambda t: (t - epoch) % NS == 0  # noqa: E731
        info.scene = Scene(window_start)
        scene_topics = any(ch.topic == "/scene" for ch in summary.channels.values())
        info.robust = any(ch.topic == "/scenario/series" for ch in summary.channels.values())
        n = 0
        by_design = {}
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            n += 1
            if channel.message_encoding == "json":
                errors = sorted(validators[channel.id].iter_errors(decoded), key=lambda e: e.path)
                if errors:
                    raise ValueError(f"{channel.topic} message at {message.log_time}: {errors[0].message}")
            t = message.log_time
            info.start = t if info.start is None else min(info.start, t)
            info.end = t if info.end is None else max(info.end, t)
            d = (t - epoch) // NS
            by_design.setdefault(d, []).append((channel.topic, t, decoded))
            info.recording.add(channel.topic, decoded)
            if scene_topics:
                info.scene.add(channel.topic, t, decoded)
            if channel.topic == "/front":
                info.front[decoded["id"]] = decoded["on_final_front"]
            if channel.topic == "/designs":
                info.designs[decoded["id"]] = (decoded["feasible"], decoded["objectives"])
        if n != summary.statistics.message_count:
            raise ValueError(f"read {n} messages, statistics say {summary.statistics.message_count}")
        ids = sorted(by_design)
        if [ids[0], ids[-1], len(ids)] != [int(run[first]), int(run[last]), int(run["designs"])]:
            raise ValueError(f"designs {ids[0]}..{ids[-1]} ({len(ids)}) disagree with the metadata {run[first]}..{run[last]} ({run['designs']})")
        for d, msgs in by_design.items():
            info.contacts += per_design(d, epoch + d * NS, msgs, scene_topics, info) or 0
        info.ids = set(ids)
        if scene_topics:
            info.geometry = info.scene.finish()
        return n, len(summary.chunk_indexes), info


def check_channels(summary):
    validators = {}
    problems = []  # every channel's problem, not only the first
    for cid, ch in sorted(summary.channels.items()):
        schema = summary.schemas[ch.schema_id]
        try:
            if schema.name.startswith("foxglove."):
                check_foxglove_schema(schema)
            if schema.encoding == "protobuf" and ch.message_encoding == "protobuf":
                descriptor_pb2.FileDescriptorSet.FromString(schema.data)
            elif schema.encoding == "jsonschema" and ch.message_encoding == "json":
                s = json.loads(schema.data)
                parse_like_viewer(s, f"{ch.topic} ({schema.name})")
                jsonschema.Draft7Validator.check_schema(s)
                validators[cid] = jsonschema.Draft7Validator(s)
            else:
                raise ValueError(f"channel {ch.topic}: encodings {schema.encoding}/{ch.message_encoding}")
        except Exception as e:  # noqa: BLE001 - collect them all
            problems.append(f"channel {ch.topic}: {e}")
    if problems:
        raise ValueError("\n    " + "\n    ".join(problems))
    return validators


def repeated(f):
    """A repeated field (protobuf >= 5 has `is_repeated`; older ones `label`)."""
    rep = getattr(f, "is_repeated", None)
    return rep if rep is not None else f.label == f.LABEL_REPEATED


LABEL_MAX_CHARS = 120  # 13 px text, ~7.5 px a character: 900 px, a 3-D panel of half a 1920 px screen
LABEL_MIN_PX = 12  # at 11 px a 0 read as a 9
LABEL_MIN_Z = 0.01  # m above the ground: a text facing the camera is centred on its pose; lower, the ground and grid cross it


def check_label(what, st):
    """The label (one line) fits the 3-D panel, is readable and clears the ground."""
    for e in st.entities:
        for t in e.texts:
            if len(t.text) > LABEL_MAX_CHARS or "\n" in t.text:
                raise ValueError(f"{what}: label of {len(t.text)} characters (at most {LABEL_MAX_CHARS} on one line fit a 3-D panel of half a screen): {t.text[:60]}...")
            if t.font_size < LABEL_MIN_PX or (e.frame_id == "world" and t.pose.position.z < LABEL_MIN_Z):
                raise ValueError(f"{what}: label of {t.font_size} px at {t.pose.position.z * 1e3:.1f} mm above the ground (at least {LABEL_MIN_PX} px and {LABEL_MIN_Z * 1e3:.0f} mm: the ground and its grid cross a lower one)")


def window_end(t0):
    return t0 + NS - 1


def check_design(d, t0, msgs, scene, info):
    at = lambda topic: [(t, m) for tp, t, m in msgs if tp == topic]  # noqa: E731
    designs, series = at("/designs"), at("/grasp/series")
    if len(designs) != 1 or designs[0][0] != t0 or designs[0][1]["id"] != d:
        raise ValueError(f"design {d}: /designs must hold one message, for id {d}, at the window start {t0}")
    ws = designs[0][1]["window_start"]
    if ws["sec"] * NS + ws["nsec"] != t0:
        raise ValueError(f"design {d}: /designs.window_start {ws} is not the window start {t0}")
    if len(series) != 1 or series[0][0] != t0 or series[0][1].design_id != d:
        raise ValueError(f"design {d}: /grasp/series must hold one message for this design at the window start")
    s = series[0][1]
    cols = [s.t] + [getattr(s, f.name) for f in s.DESCRIPTOR.fields if repeated(f) and f.name != "t"]
    if len({len(c) for c in cols}) != 1:
        raise ValueError(f"design {d}: /grasp/series columns differ in length")
    t = list(s.t)
    if not t:
        raise ValueError(f"design {d}: /grasp/series is empty (a Plot panel would keep the previous design's curves)")
    if t[0] != 0.0 or any(b < a for a, b in zip(t, t[1:])) or t[-1] >= 1.0:
        raise ValueError(f"design {d}: /grasp/series.t must start at 0 and run forward inside the window")
    placeholder = s.simulated_samples == 0
    if placeholder and (len(t) != 1 or not all(math.isnan(c[0]) for c in cols[1:])):
        raise ValueError(f"design {d}: a design without a grasp must have one placeholder sample (t = 0, NaN values)")
    if info.robust:
        drawn = check_robust_window(d, t0, designs[0][1], msgs, scene, info, check_label)
        if drawn is not None:
            return drawn
        info.ref_hands.update(hand_keys(at("/tf")))
    if not scene:
        return
    tf, static, fingers = at("/tf"), at("/scene/static"), at("/scene")
    if len(tf) != 2 or tf[0][0] != t0 or tf[1][0] != window_end(t0):
        raise ValueError(f"design {d}: /tf must be at the window start and at its last nanosecond (so a seek anywhere in the last design's window works)")
    if not static or static[0][0] != t0:
        raise ValueError(f"design {d}: no /scene/static message at the window start")
    st = static[0][1]
    if not st.deletions or st.deletions[0].type != 1 or {e.id for e in st.entities} != {"ground", "palm", "object", "label"}:
        raise ValueError(f"design {d}: /scene/static must delete all, then draw ground, palm, object and label")
    check_label(f"design {d}", st)
    if not fingers or fingers[0][0] != t0 or not fingers[0][1].deletions or fingers[0][1].deletions[0].type != 1:
        raise ValueError(f"design {d}: the first /scene message must be at the window start and delete the previous fingers")
    drawn = [(tm, m) for tm, m in fingers if m.entities]
    if placeholder:
        if len(fingers) != 1:
            raise ValueError(f"design {d}: without a grasp, /scene holds one message (the open and failing poses)")
        return check_closed_pose_touches(d, designs[0][1], st, fingers[0][1])
    if drawn:
        last = t0 + min(round(t[-1] * NS), NS - 1)
        if drawn[-1][0] != last:
            raise ValueError(f"design {d}: the last finger pose is at {drawn[-1][0] - t0} ns, the last sample at {last - t0} ns")
    return check_fingers_touch(d, t0, s, st, drawn, designs[0][1]["feasible"])


# ---------------------------------------------------------------- drawn contact
def check_closed_pose_touches(d, rec, st, scene):
    """A design discarded at stage 2 whose red pose is drawn: that pose is the closed pose on
    the object whose statics failed, so both phalanges of each finger touch the drawn object
    (zero penetration, within the drawing's rounding). 1 when checked."""
    red = [e for e in scene.entities if e.id == "failing_pose"]
    if rec.get("failed_stage") != 2 or not red:
        return 0
    c, r = drawn_object(st)
    for n, line in enumerate(red[0].lines):
        for g, name in zip(phalanx_gaps(line, c, r), ("proximal", "distal")):
            if abs(g) > CONTACT_TOL:
                raise ValueError(f"design {d}: the red closed pose of a stage-2 discard draws finger {n + 1}'s {name} phalanx {g * 1e6:+.1f} um from the drawn object ({rec.get('reason', '')[:60]})")
    return 1


CONTACT_TOL = 5e-6  # m: the drawing is rounded to 2^-20 m (1 um), compact values to f32


def seg_dist(p, a, b):
    dx, dy = b[0] - a[0], b[1] - a[1]
    s = max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy or 1.0)))
    return math.hypot(a[0] + s * dx - p[0], a[1] + s * dy - p[1])


def phalanx_gaps(line, c, r):
    """A drawn finger (line strip tip, O22, base, ...) against the object's circle (centre c,
    radius r) in the hand plane: the gaps (m; < 0 drawn inside) of its proximal phalanx
    (base - O22) and distal phalanx (O22 - tip), rods of the line's thickness."""
    p = [(q.x, q.y) for q in line.points]
    half = line.thickness / 2
    return seg_dist(c, p[2], p[1]) - r - half, seg_dist(c, p[1], p[0]) - r - half


def drawn_object(st):
    cyl = next(e for e in st.entities if e.id == "object").cylinders[0]
    return (cyl.pose.position.x, cyl.pose.position.y), cyl.size.x / 2


def finger_contacts(s, mirrored):
    """Each drawn finger's (penetrations, normal forces) by phalanx, as the series records
    them: finger 1's columns; finger 2's own (`finger2_...`, the offset scene since session
    37), finger 1's where finger 2 is its mirror (object at x = 0, no finger-2 columns), or
    None (an offset shard written before session 37 records no finger-2 force)."""
    one = ((s.proximal_penetration, s.distal_penetration), (s.proximal_normal_force, s.distal_normal_force))
    f2 = [getattr(s, "finger2_" + n, []) for n in ("proximal_penetration", "distal_penetration", "proximal_normal_force", "distal_normal_force")]
    if all(len(c) for c in f2):
        return [one, ((f2[0], f2[1]), (f2[2], f2[3]))]
    return [one, one if mirrored else None]


def check_fingers_touch(d, t0, s, st, drawn, feasible):
    """The drawn fingers touch the drawn object where the series says they do: at every
    drawn pose whose time is a series sample, a phalanx with a non-zero normal force lies
    within [-(delta + tol), tol] of the object's surface (delta its recorded penetration);
    finger 1's contacts from its columns, finger 2's from its own (`finger2_...`, the offset
    scene) or finger 1's where it is finger 1's mirror (object at x = 0, no finger-2 columns).
    No drawn finger is ever deeper in the object than
    1.5 times the deepest penetration the series kept + 20 um (a drawn pose between its
    samples may be deeper than the kept ones), and at the last pose of a feasible (stable) grasp both
    fingers touch it. The number of contacts checked."""
    c, r = drawn_object(st)
    mirrored = not len(getattr(s, "finger2_q11", [])) and abs(c[0]) < 1e-12
    contacts = finger_contacts(s, mirrored)
    at_sample = {round(t * NS): k for k, t in enumerate(s.t)}
    deltas = [col for f in contacts if f for col in f[0]]
    deepest = max([0.0] + [x for col in deltas for x in col if x == x])
    # a drawn pose between the series' samples may lie deeper than the deepest kept sample
    # (a damped impact's deepest point follows its force peak, which the series keeps)
    inside_limit = 1.5 * deepest + 20e-6
    checked = 0
    for tm, m in drawn:
        lines = next(e for e in m.entities if e.id == "fingers").lines
        for n, line in enumerate(lines):
            g = min(phalanx_gaps(line, c, r))
            if g < -inside_limit:
                raise ValueError(f"design {d}: at {(tm - t0) / 1e6:.3f} ms finger {n + 1} is drawn {-g * 1e6:.1f} um inside the object (deepest penetration kept {deepest * 1e6:.1f} um)")
        k = at_sample.get(tm - t0)
        if k is None:
            continue
        for n, (line, finger) in enumerate(zip(lines, contacts)):
            if finger is None:
                continue
            for ph, name in enumerate(("proximal", "distal")):
                f, delta = finger[1][ph][k], finger[0][ph][k]
                if not f > 0:
                    continue
                g = phalanx_gaps(line, c, r)[ph]
                if not -(delta + CONTACT_TOL) <= g <= CONTACT_TOL:
                    raise ValueError(f"design {d}: at {(tm - t0) / 1e6:.3f} ms finger {n + 1}'s {name} phalanx is drawn {g * 1e6:+.1f} um from the object's surface while its contact force is {f:.3g} N (penetration {delta * 1e6:.1f} um)")
                checked += 1
    if feasible and drawn:
        for n, line in enumerate(next(e for e in drawn[-1][1].entities if e.id == "fingers").lines):
            g = min(phalanx_gaps(line, c, r))
            if not -(deepest + CONTACT_TOL) <= g <= CONTACT_TOL:
                raise ValueError(f"design {d}: the stable grasp's last pose draws finger {n + 1} {g * 1e6:+.1f} um from the object's surface (it holds the object)")
    return checked


def hand_keys(tf):
    """The world -> hand transforms of `/tf` messages (for the folder's one-world check)."""
    from mcap_scene import transform_key
    return {transform_key(x) for _, m in tf for x in m.transforms if (x.parent_frame_id, x.child_frame_id) == ("world", "hand")}


def check_verify_design(d, t0, msgs, scene, info):
    at = lambda topic: [(t, m) for tp, t, m in msgs if tp == topic]  # noqa: E731
    rec, series = at("/verify"), at("/verify/series")
    if len(rec) != 1 or rec[0][0] != t0 or rec[0][1]["window"] != d:
        raise ValueError(f"window {d}: /verify must hold one message, for window {d}, at the window start {t0}")
    r = rec[0][1]
    ws = r["window_start"]
    if ws["sec"] * NS + ws["nsec"] != t0:
        raise ValueError(f"window {d}: /verify.window_start {ws} is not the window start {t0}")
    if len(series) != 1 or series[0][0] != t0 or series[0][1]["window"] != d:
        raise ValueError(f"window {d}: /verify/series must hold one message for this window at its start")
    sr = series[0][1]
    if not sr["t"] or len({len(sr[k]) for k in ("t", "displacement_mm", "tilt_deg")}) != 1:
        raise ValueError(f"window {d}: /verify/series columns must be non-empty and of equal length")
    tf, static, fingers = at("/tf"), at("/scene/static"), at("/scene")
    if len(static) != 1 or static[0][0] != t0:
        raise ValueError(f"window {d}: /scene/static must hold one message at the window start")
    st = static[0][1]
    check_label(f"window {d}", st)
    frames = {e.id: e.frame_id for e in st.entities}
    if not st.deletions or st.deletions[0].type != 1 or frames != {"ground": "world", "palm": "hand", "object": "object", "label": "world"}:
        raise ValueError(f"window {d}: /scene/static must delete all, then draw ground (world), palm (hand), object (object) and label (world); got {frames}")
    if not fingers or fingers[0][0] != t0 or not fingers[0][1].deletions or fingers[0][1].deletions[0].type != 1:
        raise ValueError(f"window {d}: the first /scene message must be at the window start and delete the previous fingers")
    if r["poses"] == 0:
        if tf:
            raise ValueError(f"window {d}: /tf without poses")
        return
    if len(tf) != r["poses"] + 1 or tf[-1][0] != window_end(t0):
        raise ValueError(f"window {d}: {len(tf)} /tf messages, the record says {r['poses']} poses (and one more at the window's last nanosecond)")
    pairs = [[(x.parent_frame_id, x.child_frame_id) for x in m.transforms] for _, m in tf]
    if tf[0][0] != t0 or any(p != [("world", "hand"), ("hand", "object")] for p in pairs):
        raise ValueError(f"window {d}: every /tf message must carry world -> hand and hand -> object, the first at the window start")
    times = [t for t, _ in tf[:-1]]
    if any(b <= a for a, b in zip(times, times[1:])) or times[-1] >= t0 + NS:
        raise ValueError(f"window {d}: /tf times must run forward inside the window")
    last = t0 + min(round(r["t_end"] * NS), NS - 1)
    if times[-1] != last:
        raise ValueError(f"window {d}: the last object pose is at {times[-1] - t0} ns, the record's t_end at {last - t0} ns")
    drawn = [(t, m) for t, m in fingers if m.entities]
    if any(t not in set(times) for t, _ in drawn) or any(len(m.entities[0].lines) != 2 for _, m in drawn):
        raise ValueError(f"window {d}: /scene must draw two fingers, only at object pose times")
    if drawn and drawn[-1][0] != times[-1]:
        raise ValueError(f"window {d}: the last finger pose is at {drawn[-1][0] - t0} ns, the last object pose at {times[-1] - t0} ns")


def check_front_design(d, t0, msgs, scene, info):
    if len(msgs) != 1 or msgs[0][0] != "/front" or msgs[0][1] != t0 or msgs[0][2]["id"] != d:
        raise ValueError(f"design {d}: /front must hold one message for this design at its window start")


# ---------------------------------------------------------------- run folders
def run_folders(infos):
    """run folder -> {"shards": [...], "fronts": [...], "verify": [...]}."""
    runs = {}
    for info in infos:
        p = info.path
        run = p.parent.parent if p.parent.name == "recording" else p.parent
        r = runs.setdefault(run, {"shards": [], "fronts": [], "verify": []})
        if info.kind == "shard":
            r["shards"].append(info)
        elif info.kind == "front":
            r["fronts"].append(info)
        else:
            r["verify"].append(info)
    return runs


def check_run_folder(run, r):
    """The folder-level checks of one run folder; a description of what was checked."""
    done = []
    scenes = [i for i in r["shards"] + r["verify"] if i.scene is not None and i.scene.world_hand is not None]
    scenarios = [i for i in scenes if scenario_height(i) is not None]
    # a robust shard's windows that draw a scenario have the hand at the scenario's height
    common = [i for i in scenes if scenario_height(i) is None and not (i.robust and not i.ref_hands)]
    hands = lambda i: i.ref_hands if i.robust else i.scene.world_hands  # noqa: E731
    frames = {(tuple(sorted(hands(i))), round(i.scene.ground_top, 12)) for i in common}
    if len(frames) > 1:
        raise ValueError(f"the world frame differs between files: {sorted(frames)} ({[str(i.path.name) for i in common]})")
    if common:
        done.append(f"one world frame in {len(common)} files")
    for i in scenarios:
        check_scenario_frame(run, i, frames)
    if scenarios:
        done.append(f"{len(scenarios)} scenario files with the hand at their scenario's height")
    drawn = [i for i in r["shards"] if i.scenario_hands]
    if drawn:
        done.append(check_scenario_hands(run, drawn))
    ranges = [(i.path.name, i.start, i.end) for i in r["verify"]]
    if r["shards"]:
        ranges.insert(0, ("the shards", min(i.start for i in r["shards"]), max(i.end for i in r["shards"])))
    if len(ranges) > 1:
        check_disjoint(ranges)
        done.append(f"time ranges of {len(ranges)} recordings disjoint")
    status = {}
    if (run / "run.json").is_file():
        status = json.loads((run / "run.json").read_text())
    finished = status.get("status") == "finished" and status.get("completed_generations") == status.get("generations")
    if r["shards"] and not r["fronts"] and finished and status.get("recording", {}).get("enabled"):
        raise ValueError("the run finished but recording/ has no front files (front-NNNNN.mcap)")
    if r["fronts"]:
        done.append(check_fronts(run, r))
    layout = run / "foxglove-layout.json"
    if layout.is_file() and r["shards"]:
        rec = merged([*r["shards"], *r["fronts"]])
        if not r["fronts"]:
            rec.messages.setdefault("/front", [{"id": 0, "on_final_front": False}])  # not written yet: the run has not finished
        if any(i.robust for i in r["shards"]) and not any(i.scenario_windows for i in r["shards"]):
            # no design of this run draws a scenario (none reached its scenarios, or the run
            # keeps no trajectory of them): the scenario panel has nothing to show yet
            rec.messages["/designs"].append({"shown_scenario": {}})
        done.append(f"{check_layout(layout, rec)} layout paths of {layout.name}")
    vlayout = run / "foxglove-verify-layout.json"
    for v in r["verify"]:
        if not vlayout.is_file():
            raise ValueError(f"{v.path.name} is shipped without {vlayout.name}")
        done.append(f"{check_layout(vlayout, v.recording)} layout paths of {vlayout.name} in {v.path.name}")
    return done


def check_disjoint(ranges):
    """(name, first, last log time) of recordings of one run: no two overlap (opened
    together, two designs would share a second, and a viewer applies a deletion of all
    entities whatever its timestamp)."""
    for a in range(len(ranges)):
        for b in range(a + 1, len(ranges)):
            (na, la, ha), (nb, lb, hb) = ranges[a], ranges[b]
            if la <= hb and lb <= ha:
                raise ValueError(f"{na} and {nb} overlap in time ([{la}, {ha}] and [{lb}, {hb}]): opened together, two designs would share a second")


def scenario_height(info):
    """The hand height of a `replay --scenario` file: the scenario object's grasp height plus
    the scenario's drawn height offset, as its metadata says (None: not a scenario file)."""
    m = info.meta
    if info.kind != "verify" or "height_offset" not in m or "object_grasp_height" not in m or "scenario_object" not in m:
        return None
    return float(m["object_grasp_height"]) + float(m["height_offset"])


def check_scenario_frame(run, info, frames):
    """A scenario file's world frame: the hand level at exactly its scenario's height (its
    metadata's object grasp height + height offset; the object's grasp height that of the
    run's problem.toml where the object is given there inline), the ground where the other
    files have it."""
    h, m = scenario_height(info), info.meta
    want = ("world", "hand", 0.0, 0.0, round(h, 12), 0.0, 0.0, 0.0, 1.0)
    got = sorted(info.scene.world_hands)
    if got != [want]:
        raise ValueError(f"{info.path.name}: world -> hand {got}, its scenario {m['scenario_object']}:{m.get('scenario_index')} puts the hand at {h * 1e3:.3f} mm (grasp height {m['object_grasp_height']} + height offset {m['height_offset']})")
    grounds = {g for _, g in frames}
    if grounds and round(info.scene.ground_top, 12) not in grounds:
        raise ValueError(f"{info.path.name}: the ground plane differs from the other files'")
    problem = run / "problem.toml"
    if problem.is_file():
        import tomllib
        objects = tomllib.loads(problem.read_text()).get("robust", {}).get("objects", [])
        o = next((o for o in objects if o.get("name") == m["scenario_object"]), None)
        if o is None:
            raise ValueError(f"{info.path.name}: scenario object {m['scenario_object']!r} is not one of problem.toml's [[robust.objects]]")
        if "grasp_height" in o and o["grasp_height"] != float(m["object_grasp_height"]):
            raise ValueError(f"{info.path.name}: object_grasp_height {m['object_grasp_height']}, problem.toml gives {m['scenario_object']} grasp_height {o['grasp_height']}")


def merged(infos):
    rec = Recording()
    for i in infos:
        for topic, msgs in i.recording.messages.items():
            for m in msgs:
                rec.add(topic, m)
    return rec


def main(folders):
    # folders are searched recursively; a file argument is checked as given
    files = sorted(p for d in folders for p in ([pathlib.Path(d)] if pathlib.Path(d).is_file() else pathlib.Path(d).rglob("*.mcap")))
    ok = bad = 0
    infos = []
    for p in files:
        if not p.is_file():  # a folder or a FIFO named *.mcap: never opened (a FIFO would block)
            print(f"FAIL {p}: not a regular file")
            bad += 1
            continue
        try:
            n, chunks, info = check(p)
            infos.append(info)
            geo = getattr(info, "geometry", None)
            extra = ""
            if geo:
                extra = f"; world geometry: {geo['finger_points']} finger points, lowest {geo['lowest_finger_z'] * 1e3:.1f} mm above the ground, {geo['objects']} objects standing"
            if info.contacts:
                extra += f"; {info.contacts} drawn contacts touch the object"
            print(f"ok   {p}: {n} messages in {chunks} chunks decoded; schemas official / viewer-parsable; time windows consistent{extra}")
            ok += 1
        except Exception as e:  # noqa: BLE001 - report every failure
            print(f"FAIL {p}: {e}")
            bad += 1
    for run, r in sorted(run_folders(infos).items()):
        try:
            done = check_run_folder(run, r)
            print(f"ok   {run}/: {'; '.join(done)}")
            ok += 1
        except Exception as e:  # noqa: BLE001
            print(f"FAIL {run}/: {e}")
            bad += 1
    print(f"mcap: {ok} passed, {bad} failed")
    if not files:
        print("no MCAP files found in", folders, "(give MCAP files or folders holding them)")
        return 1
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:] or ["target/mcap-check"]))
