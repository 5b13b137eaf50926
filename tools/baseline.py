#!/usr/bin/env python3
"""The results of one gripopt binary on the baseline problems, as a SHA-256 table.

Runs a fixed set of commands (centred, offset, free and kitchen problems: a short optimise
with every design recorded, `evaluate --json`, `simulate --json` and `--csv`, `verify`) with
BIN into OUT, then prints one line `sha256  name` per output, after removing what is not a
result: wall times (`stage_seconds`, `wall_s`, timings.csv, `*_s` timing keys), the random
run id (and the checkpoint hash over it), absolute paths and the gripopt version. MCAP files
are compared message by message (topic, log time, payload; JSON payloads normalised as
above) and metadata by metadata, not by their bytes (zstd chunks and indexes may differ
while every message is equal). Two binaries give the same results iff their tables are
equal:

    tools/baseline.py BIN OUT > table.txt
    diff old.txt new.txt

Needs the PyPI `mcap` package (`make venv`: .venv/bin/python tools/baseline.py ...).
"""
import csv
import hashlib
import io
import json
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NOISE_KEYS = {"stage_seconds", "wall_s", "run_id", "sha256", "gripopt_version", "epoch_s", "problem_path",
              "seconds", "elapsed_s", "cpu_s", "settings_hash", "bytes", "window_start", "created", "finished", "started", "pid", "host", "timings", "threads"}
KITCHEN_DESIGN = ("l21=0.04304807948252374,b=0.06871978187729287,t22=0.03375918412304188,"
                  "r=0.2601664030440584,p=0.25261005423197275,psi_deg=135.766034896994")


def strip(o):
    """A JSON value without its non-result keys (recursively)."""
    if isinstance(o, dict):
        return {k: strip(v) for k, v in o.items() if k not in NOISE_KEYS and not k.endswith("_seconds")}
    if isinstance(o, list):
        return [strip(v) for v in o]
    if isinstance(o, str):
        return re.sub(r"/[^\s\"']*/(run-[a-z]+)", r"\1", o)
    return o


def canon(o):
    return json.dumps(strip(o), sort_keys=True, separators=(",", ":")).encode()


def raw_json(b):
    """JSON text `b` with the values of its non-result keys blanked in place: the key order,
    the layout and every number's digits kept (a reordered or reformatted output differs)."""
    for k in NOISE_KEYS | {"[a-z_]*_seconds"}:
        b = re.sub(rb'("' + k.encode() + rb'"\s*:\s*)("[^"]*"|\[[^\]]*\]|[-0-9.eE+]+|\{[^{}]*\})', rb"\1null", b)
    return re.sub(rb"/[^\s\"']*/(run-[a-z]+)", rb"\1", b)


def sha(b):
    return hashlib.sha256(b).hexdigest()


def run(cmd, out=None, ok=(0, 1, 3)):
    p = subprocess.run(cmd, capture_output=True, cwd=ROOT)
    if p.returncode not in ok:
        sys.exit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr.decode()}")
    if out:
        with open(out, "wb") as f:
            f.write(p.stdout)
    return p


def shift_stamps(m, epoch_s):
    """Protobuf message `m` with every google.protobuf.Timestamp moved back by the run's
    epoch (the recording's clock starts at the wall time of the run's start)."""
    if m.DESCRIPTOR.full_name == "google.protobuf.Timestamp":
        m.seconds -= epoch_s
        return
    for fd, v in m.ListFields():
        if fd.message_type is None:
            continue
        for x in (v if isinstance(v, (list, tuple)) or hasattr(v, "extend") else [v]):
            if hasattr(x, "DESCRIPTOR"):
                shift_stamps(x, epoch_s)


def mcap_lines(path, name):
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory
    h = hashlib.sha256()
    with open(path, "rb") as f:
        r = make_reader(f)
        factory, decoders = DecoderFactory(), {}
        epoch = 0
        for m in r.iter_metadata():
            h.update(b"M" + m.name.encode() + canon({k: _maybe_json(v) for k, v in m.metadata.items()}))
            epoch = int(float(m.metadata.get("epoch_s", 0)) * 1e9) or epoch
        n = 0
        for schema, ch, msg in r.iter_messages(log_time_order=True):
            if ch.message_encoding == "json":
                data = raw_json(msg.data)
            else:
                if schema.id not in decoders:
                    decoders[schema.id] = factory.decoder_for(ch.message_encoding, schema)
                dec = decoders[schema.id](msg.data)
                shift_stamps(dec, epoch // 1_000_000_000)
                data = dec.SerializeToString(deterministic=True)
            h.update(ch.topic.encode() + str(msg.log_time - epoch).encode() + data)
            n += 1
    return [(h.hexdigest(), f"{name} ({n} messages)")]


def _maybe_json(v):
    try:
        return json.loads(v)
    except ValueError:
        return v


def file_lines(path, name):
    if path.endswith(".mcap"):
        return mcap_lines(path, name)
    with open(path, "rb") as f:
        b = f.read()
    if path.endswith(".json"):
        return [(sha(raw_json(b)), name)]
    if path.endswith(".jsonl"):
        return [(sha(raw_json(b)), name)]
    if path.endswith(".csv"):
        # a table's comment lines name the run id and the checkpoint hash over it
        b = re.sub(rb"(run:? )[0-9a-f]{16}", rb"\1RUN", b)
        b = re.sub(rb"(checkpoint sha256:? )[0-9a-f]{64}", rb"\1HASH", b)
    return [(sha(b), name)]


def run_folder_lines(d, label):
    lines = []
    for sub in sorted(os.walk(d)):
        root, _, files = sub
        for fn in sorted(files):
            if fn in ("timings.csv", "pareto_timings.csv", ".lock", "run.json") or fn.endswith(".svg"):
                continue
            if fn.endswith(".toml"):
                continue
            rel = os.path.relpath(os.path.join(root, fn), d)
            lines += file_lines(os.path.join(root, fn), f"{label}/{rel}")
    return lines


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    b, out = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    os.makedirs(out, exist_ok=True)
    bottle = os.path.join(ROOT, "problems/bottle-1l.toml")
    src = open(bottle).read()
    offset = os.path.join(out, "offset.toml")
    open(offset, "w").write(src.replace('kind = "centred"', 'kind = "offset"', 1).replace("x_off = 0.0 ", "x_off = 0.002 ", 1))
    problems = {
        "centred": (bottle, 24, 3),
        "offset": (offset, 16, 3),
        "free": (os.path.join(ROOT, "problems/can.toml"), 12, 3),
        "kitchen": (os.path.join(ROOT, "problems/kitchen.toml"), 16, 3),
    }
    lines = []
    for label, (p, pop, gens) in problems.items():
        rd = os.path.join(out, f"run-{label}")
        if os.path.exists(rd):
            subprocess.run(["rm", "-rf", rd])
        run([b, "optimise", p, "--out", rd, "--pop", str(pop), "--generations", str(gens), "--seed", "1",
             "--threads", "2"])
        lines += run_folder_lines(rd, f"run-{label}")
        ev = os.path.join(out, f"{label}-evaluate.json")
        run([b, "evaluate", p, "--json"], ev)
        lines += file_lines(ev, os.path.basename(ev))
        if label != "kitchen":
            sim = os.path.join(out, f"{label}-simulate.json")
            tcsv = os.path.join(out, f"{label}-simulate.csv")
            if os.path.exists(tcsv):
                os.remove(tcsv)
            run([b, "simulate", p, "--json", "--csv", tcsv], sim)
            lines += file_lines(sim, os.path.basename(sim)) + file_lines(tcsv, os.path.basename(tcsv))
        else:
            kd = os.path.join(out, "kitchen-design.json")
            run([b, "evaluate", p, "--design", KITCHEN_DESIGN, "--json"], kd)
            lines += file_lines(kd, os.path.basename(kd))
    for label in ("centred", "free", "kitchen"):
        rd = os.path.join(out, f"run-{label}")
        run([b, "verify", rd, "--threads", "2"], ok=(0, 1, 2, 3))
        for fn in sorted(os.listdir(rd)):
            if fn.startswith("verify") and not fn.endswith(".svg"):
                lines += file_lines(os.path.join(rd, fn), f"run-{label}/{fn} (after verify)")
    for h, name in lines:
        print(f"{h}  {name}")


if __name__ == "__main__":
    main()
