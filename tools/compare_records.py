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
# simulate --scene free: the free scene's own keys, now under free_scene (old -> new name)
FREE_OWN = ("first_contact_t t_first_contact, end, t_end, events, rhs_evals, jac_block_evals, "
            "stats.steps steps, stats.rejected rejected_steps, stats.jac jac_evals, stats.lu lu_count, "
            "stats.newton newton_iters, stats.newton_fail newton_failures, cpu_s, free_end end")
FREE_RESULT = {}
for pair in FREE_OWN.split(", "):
    old, _, new = pair.partition(" ")
    FREE_RESULT[old] = (f"free_scene.{new or old}", None)
FREE_RESULT["first_contact_phalanx"] = ("free_scene.first_contact_phalanx", PHALANX.get)
FREE_RESULT.update({f"first_impact.{k}": (f"free_scene.{k}", None)
                    for k in ["e_cyl", "e_lim", "e_rot", "e_trans", "m_finger", "v_impact"]})
FREE_RESULT.update({k: (f"free_scene.{k}", None) for k in [
    "energy.0", "energy.1", "max_energy_rise", "object_max_displacement", "object_max_dx",
    "object_max_dy", "object_max_tilt_deg", "object_max_tilt_y", "object_max_spin",
    "object_final_displacement", "object_final_tilt_deg", "object_peak_e_trans",
    "object_peak_e_rot", "moved", "toppled", "escaped", "rim_contact"]})
FREE_RECORD = {k: (f"free_scene.{k}", None) for k in [
    "object_max_displacement", "object_max_dx", "object_max_dy", "object_max_tilt_deg",
    "object_final_displacement", "object_final_tilt_deg", "object_peak_e_trans",
    "object_peak_e_rot", "moved", "toppled", "escaped", "rim_contact"]}
FREE_RECORD.update({"object_x_off": ("x_off", None), "free_end": ("free_scene.end", None),
                    "free_steps": ("free_scene.steps", None),
                    "free_rhs_evals": ("free_scene.rhs_evals", None)})
RENAMED = {
    "sim-free": FREE_RESULT,
    "sim-offset": {
        "first_phalanx": ("first_contact_phalanx", PHALANX.get),
        **{k: (f"offset_scene.{k}", None) for k in ["hand_x_end", "hand_y_end", "hand0_x", "hand0_y", "recentres"]},
    },
    "eval-free": FREE_RECORD,
}
# old keys dropped on purpose: the stepper's own RHS count duplicated the total
REMOVED = {"sim-free": {"stats.rhs"}}
TIMINGS = {"cpu_s", "free_scene.cpu_s", "replay_s"}


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
            if k in TIMINGS or nk in TIMINGS:
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
