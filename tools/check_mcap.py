#!/usr/bin/env python3
"""Independent check of gripopt's MCAP files, as a Foxglove viewer would read them.

Knows nothing of gripopt's code: it uses the reference `mcap` reader, `mcap-protobuf-support`
(decodes protobuf messages with the descriptor embedded in the file) and the official
Foxglove schemas from `foxglove-schemas-protobuf`. For every *.mcap under the given folders:

1. the file opens, has a summary with statistics, chunk and message indexes, and a
   `gripopt.run` metadata record with generation, first_id, last_id, designs, epoch_s;
2. every channel is protobuf (schema encoding `protobuf`) or JSON (`jsonschema`);
   a `foxglove.*` schema must be protobuf and its descriptor (every message it reaches:
   field names, numbers, labels, types, type names; enum values) must equal the official
   one; every JSON schema must parse the way Foxglove's JSON-schema parser does (one type
   per field, no union types; every array with typed `items`; every object with properties);
3. every message decodes (protobuf with the embedded descriptor; JSON, validated against
   its schema), and the count equals the statistics;
4. the time convention and scene: each design's `/designs` message sits at the start of its
   time window, epoch_s + id s; in that window `/grasp/series` has equal-length columns with
   time running forward inside the window; where there is a scene, `/tf` (world → hand),
   `/scene/static` (deleting all, then ground, palm, object) and `/scene` (deleting all first)
   are at the window start, and the last `/scene` message is at the last recorded sample.
5. a `gripopt verify` recording (metadata `gripopt.verify` instead of `gripopt.run`): window k
   holds one `/verify` record (window k, at the window start); `/scene/static` at the window
   start deletes all, then draws ground (frame world), palm (hand) and object (object); `/tf`
   carries world → hand and hand → object at the window start, then hand → object only, one
   per drawn pose (as many as the record says), time running forward, stamps equal to the log
   times, unit quaternions, the last at the record's t_end; `/scene` deletes all first and
   draws the two fingers only at pose times, the last at the last pose.

Prints one line per file and 'N passed, N failed'; exits non-zero on any failure or when
no file was found.
"""
import importlib
import json
import pathlib
import sys

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
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        if "gripopt.run" in meta:
            name, first, last, per_design = "gripopt.run", "first_id", "last_id", check_design
            keys = ("generation", "first_id", "last_id", "designs", "epoch_s")
        elif "gripopt.verify" in meta:
            name, first, last, per_design = "gripopt.verify", "first_window", "last_window", check_verify_design
            keys = ("first_window", "last_window", "designs", "epoch_s", "scene_dt")
        else:
            raise ValueError("no gripopt.run (or gripopt.verify) metadata record")
        run = meta[name]
        for k in keys:
            if k not in run:
                raise ValueError(f"{name} metadata lacks {k!r}")
        epoch = int(run["epoch_s"]) * NS
        n = 0
        by_design = {}
        for schema, channel, message, decoded in reader.iter_decoded_messages():
            n += 1
            if channel.message_encoding == "json":
                errors = sorted(validators[channel.id].iter_errors(decoded), key=lambda e: e.path)
                if errors:
                    raise ValueError(f"{channel.topic} message at {message.log_time}: {errors[0].message}")
            d = (message.log_time - epoch) // NS
            by_design.setdefault(d, []).append((channel.topic, message.log_time, decoded))
        if n != summary.statistics.message_count:
            raise ValueError(f"read {n} messages, statistics say {summary.statistics.message_count}")
        ids = sorted(by_design)
        if [ids[0], ids[-1], len(ids)] != [int(run[first]), int(run[last]), int(run["designs"])]:
            raise ValueError(f"designs {ids[0]}..{ids[-1]} ({len(ids)}) disagree with the metadata {run[first]}..{run[last]} ({run['designs']})")
        scene = any(ch.topic == "/scene" for ch in summary.channels.values())
        for d, msgs in by_design.items():
            per_design(d, epoch + d * NS, msgs, scene)
        return n, len(summary.chunk_indexes)


def check_design(d, t0, msgs, scene):
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
    cols = [s.t, s.q11, s.q21, s.theta2, s.proximal_normal_force, s.distal_normal_force, s.hand_force, s.energy]
    if len({len(c) for c in cols}) != 1:
        raise ValueError(f"design {d}: /grasp/series columns differ in length")
    t = list(s.t)
    if t and (t[0] != 0.0 or any(b < a for a, b in zip(t, t[1:])) or t[-1] >= 1.0):
        raise ValueError(f"design {d}: /grasp/series.t must start at 0 and run forward inside the window")
    if not scene:
        return
    tf, static, fingers = at("/tf"), at("/scene/static"), at("/scene")
    if not tf or tf[0][0] != t0 or [(x.parent_frame_id, x.child_frame_id) for x in tf[0][1].transforms] != [("world", "hand")]:
        raise ValueError(f"design {d}: no world → hand transform at the window start")
    if not static or static[0][0] != t0:
        raise ValueError(f"design {d}: no /scene/static message at the window start")
    st = static[0][1]
    if not st.deletions or st.deletions[0].type != 1 or {e.id for e in st.entities} != {"ground", "palm", "object"}:
        raise ValueError(f"design {d}: /scene/static must delete all, then draw ground, palm and object")
    if not fingers or fingers[0][0] != t0 or not fingers[0][1].deletions or fingers[0][1].deletions[0].type != 1:
        raise ValueError(f"design {d}: the first /scene message must be at the window start and delete the previous fingers")
    drawn = [(tm, m) for tm, m in fingers if m.entities]
    if t and drawn:
        last = t0 + min(round(t[-1] * NS), NS - 1)
        if drawn[-1][0] != last:
            raise ValueError(f"design {d}: the last finger pose is at {drawn[-1][0] - t0} ns, the last sample at {last - t0} ns")


def check_verify_design(d, t0, msgs, scene):
    at = lambda topic: [(t, m) for tp, t, m in msgs if tp == topic]  # noqa: E731
    rec = at("/verify")
    if len(rec) != 1 or rec[0][0] != t0 or rec[0][1]["window"] != d:
        raise ValueError(f"window {d}: /verify must hold one message, for window {d}, at the window start {t0}")
    r = rec[0][1]
    ws = r["window_start"]
    if ws["sec"] * NS + ws["nsec"] != t0:
        raise ValueError(f"window {d}: /verify.window_start {ws} is not the window start {t0}")
    tf, static, fingers = at("/tf"), at("/scene/static"), at("/scene")
    if len(static) != 1 or static[0][0] != t0:
        raise ValueError(f"window {d}: /scene/static must hold one message at the window start")
    st = static[0][1]
    frames = {e.id: e.frame_id for e in st.entities}
    if not st.deletions or st.deletions[0].type != 1 or frames != {"ground": "world", "palm": "hand", "object": "object"}:
        raise ValueError(f"window {d}: /scene/static must delete all, then draw ground (world), palm (hand) and object (object); got {frames}")
    if not fingers or fingers[0][0] != t0 or not fingers[0][1].deletions or fingers[0][1].deletions[0].type != 1:
        raise ValueError(f"window {d}: the first /scene message must be at the window start and delete the previous fingers")
    if len(tf) != r["poses"]:
        raise ValueError(f"window {d}: {len(tf)} /tf messages, the record says {r['poses']} poses")
    if not tf:
        return
    pairs = [[(x.parent_frame_id, x.child_frame_id) for x in m.transforms] for _, m in tf]
    if tf[0][0] != t0 or pairs[0] != [("world", "hand"), ("hand", "object")] or any(p != [("hand", "object")] for p in pairs[1:]):
        raise ValueError(f"window {d}: /tf must carry world → hand and hand → object at the window start, then hand → object only")
    times = [t for t, _ in tf]
    if any(b <= a for a, b in zip(times, times[1:])) or times[-1] >= t0 + NS:
        raise ValueError(f"window {d}: /tf times must run forward inside the window")
    for t, m in tf:
        for x in m.transforms:
            if x.timestamp.seconds * NS + x.timestamp.nanos != t:
                raise ValueError(f"window {d}: a /tf stamp differs from its log time {t}")
        q = m.transforms[-1].rotation
        if abs(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w - 1.0) > 1e-9:
            raise ValueError(f"window {d}: hand → object rotation at {t} is not a unit quaternion")
    last = t0 + min(round(r["t_end"] * NS), NS - 1)
    if times[-1] != last:
        raise ValueError(f"window {d}: the last object pose is at {times[-1] - t0} ns, the record's t_end at {last - t0} ns")
    drawn = [(t, m) for t, m in fingers if m.entities]
    if any(t not in set(times) for t, _ in drawn) or any(len(m.entities[0].lines) != 2 for _, m in drawn):
        raise ValueError(f"window {d}: /scene must draw two fingers, only at object pose times")
    if drawn and drawn[-1][0] != times[-1]:
        raise ValueError(f"window {d}: the last finger pose is at {drawn[-1][0] - t0} ns, the last object pose at {times[-1] - t0} ns")


def main(folders):
    # folders are searched recursively; a file argument is checked as given
    files = sorted(p for d in folders for p in ([pathlib.Path(d)] if pathlib.Path(d).is_file() else pathlib.Path(d).rglob("*.mcap")))
    ok = bad = 0
    for p in files:
        try:
            n, chunks = check(p)
            print(f"ok   {p}: {n} messages in {chunks} chunks decoded; schemas official / viewer-parsable; scene and time windows consistent")
            ok += 1
        except Exception as e:  # noqa: BLE001 - report every failure
            print(f"FAIL {p}: {e}")
            bad += 1
    print(f"mcap: {ok} passed, {bad} failed")
    if not files:
        print("no MCAP files found in", folders, "(give MCAP files or folders holding them)")
        return 1
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:] or ["target/mcap-check"]))
