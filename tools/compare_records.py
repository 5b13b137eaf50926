#!/usr/bin/env python3
"""Compare `evaluate --json` / `simulate --json` outputs of two gripopt builds by value.

    tools/compare_records.py OLD_DIR NEW_DIR

For every *.json in OLD_DIR (as /work/baseline/run.sh writes them: eval-*.json, sim-*.json)
the file of the same name in NEW_DIR must carry every old value, exactly, under its key or
under its new name (RENAMED, listed in docs/outputs.md). Wall-clock timings are not
compared. Prints the renamed, removed and added keys; exit 1 on any difference.
"""
import json
import sys
from pathlib import Path

# old key (dotted path) -> (new key, value conversion), for the files whose name starts so
PHALANX = {1: "proximal", 2: "distal"}
RENAMED = {
    "sim-free": {
        "first_contact_t": ("free_t_first_contact", None),
        "first_contact_phalanx": ("free_first_contact_phalanx", PHALANX.get),
        "first_impact.e_cyl": ("free_e_cyl", None),
        "first_impact.e_lim": ("free_e_lim", None),
        "first_impact.e_rot": ("free_e_rot", None),
        "first_impact.e_trans": ("free_e_trans", None),
        "first_impact.m_finger": ("free_m_finger", None),
        "first_impact.v_impact": ("free_v_impact", None),
        "end": ("free_end", None),
        "t_end": ("free_t_end", None),
        "events": ("free_events", None),
        "rhs_evals": ("free_rhs_evals", None),
        "jac_block_evals": ("free_jac_block_evals", None),
        "stats.steps": ("free_steps", None),
        "stats.rejected": ("free_rejected_steps", None),
        "stats.jac": ("free_jac_evals", None),
        "stats.lu": ("free_lu_count", None),
        "stats.newton": ("free_newton_iters", None),
        "stats.newton_fail": ("free_newton_failures", None),
        "energy.0": ("free_energy_start", None),
        "energy.1": ("free_energy_end", None),
        "max_energy_rise": ("free_max_energy_rise", None),
        "cpu_s": ("free_cpu_s", None),
    },
    "sim-offset": {"first_phalanx": ("first_contact_phalanx", PHALANX.get)},
    "eval-free": {"object_x_off": ("x_off", None)},
}
# old keys dropped on purpose: the stepper's own RHS count duplicated the total
REMOVED = {"sim-free": {"stats.rhs"}}
TIMINGS = {"cpu_s", "free_cpu_s", "replay_s"}


def flat(v, prefix=""):
    if isinstance(v, dict):
        out = {}
        for k, x in v.items():
            out.update(flat(x, f"{prefix}{k}."))
        return out
    if isinstance(v, list):
        out = {}
        for i, x in enumerate(v):
            out.update(flat(x, f"{prefix}{i}."))
        return out
    return {prefix[:-1]: v}


def main(old_dir, new_dir):
    bad, renamed, added = 0, set(), set()
    for old in sorted(Path(old_dir).glob("*.json")):
        kind = next((k for k in RENAMED | REMOVED if old.name.startswith(k)), None)
        ren, rem = RENAMED.get(kind, {}), REMOVED.get(kind, set())
        a = flat(json.loads(old.read_text()))
        b = flat(json.loads((Path(new_dir) / old.name).read_text()))
        # arrays kept as arrays (masses): compare their elements by path
        used = set()
        for k, v in a.items():
            if k in rem:
                renamed.add(f"{kind}: {k} -> (removed)")
                continue
            nk, conv = ren.get(k, (k, None))
            if nk != k:
                renamed.add(f"{kind}: {k} -> {nk}")
            used.add(nk)
            if nk not in b:
                print(f"{old.name}: {k} missing (as {nk})")
                bad += 1
                continue
            want = conv(v) if conv else v
            if k.split(".")[-1] in TIMINGS or nk in TIMINGS:
                continue
            if b[nk] != want:
                print(f"{old.name}: {k} = {v!r}, now {nk} = {b[nk]!r}")
                bad += 1
        added |= {f"{kind or old.name.split('-')[0]}: {k}" for k in b if k not in used and k.split(".")[0] not in a}
    print("renamed:", *sorted(renamed), sep="\n  ")
    print("added:", *sorted(added), sep="\n  ")
    print("differences:", bad)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
