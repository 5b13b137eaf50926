"""The front files of a finished run (`recording/front-NNNNN.mcap`, one for each
shard gen-NNNNN.mcap), checked as a viewer would open them with their shards. Knows nothing of gripopt's
code: it reads what tools/check_mcap.py decoded of each file (its `gripopt.front` metadata,
its /front messages, the shards' ids, time ranges and /designs records) and pareto.csv.
"""
import math


def check_fronts(run, r):
    """The front information of a finished run: one front file per shard
    (`front-NNNNN.mcap`, its metadata naming the shard's generation), its /front messages
    exactly the shard's designs and inside the shard's time range (opened together, the
    timeline is the shard's: it starts at the shard's first design and is not stretched); the
    members those of pareto.csv, feasible and mutually non-dominated. A whole-run front file
    (no generation: written before session 38) covers exactly all the shards' designs."""
    shards = {int(i.meta["generation"]): i for i in r["shards"]}
    members = set()
    for f in r["fronts"]:
        if "generation" not in f.meta:
            every = set().union(*(i.ids for i in r["shards"])) if r["shards"] else set()
            if set(f.front) != every:
                raise ValueError(f"{f.path.name} does not cover exactly the shards' designs")
        else:
            g = int(f.meta["generation"])
            shard = shards.get(g)
            if shard is None:
                raise ValueError(f"{f.path.name} annotates generation {g}, which has no shard")
            if f.path.name != shard.path.name.replace("gen-", "front-", 1):
                raise ValueError(f"{f.path.name} annotates {shard.path.name}: its name must be the shard's with front- for gen-")
            if set(f.front) != shard.ids:
                raise ValueError(f"{f.path.name} does not cover exactly the designs of {shard.path.name}")
            if f.start < shard.start or f.end > shard.end:
                raise ValueError(f"{f.path.name} has messages outside {shard.path.name}'s time range ([{f.start}, {f.end}] vs [{shard.start}, {shard.end}]): opened together it stretches the timeline")
        members |= {i for i, on in f.front.items() if on}
    missing = sorted(set(shards) - {int(f.meta["generation"]) for f in r["fronts"] if "generation" in f.meta})
    if missing and all("generation" in f.meta for f in r["fronts"]):
        raise ValueError(f"generations {missing} have a shard but no front file")
    designs = {k: v for i in r["shards"] for k, v in i.designs.items()}
    check_front_members(members, designs)
    pareto_csv = run / "pareto.csv"
    newest = max(f.path.stat().st_mtime_ns for f in r["fronts"])
    if pareto_csv.is_file() and pareto_csv.stat().st_mtime_ns <= newest:
        rows = [l for l in pareto_csv.read_text().splitlines() if l and not l.startswith("#")]
        pareto = {int(l.split(",")[0]) for l in rows[1:]}
        if members != pareto:
            raise ValueError(f"the front files mark {sorted(members)} on the final front, pareto.csv holds {sorted(pareto)}")
        return f"{len(r['fronts'])} front files, each inside its shard; front of {len(members)} designs = pareto.csv"
    return f"{len(r['fronts'])} front files; front of {len(members)} designs (pareto.csv edited after them: not compared)"


def check_front_members(members, designs):
    """The designs the front files mark must be feasible and mutually non-dominated in the four
    objectives of their /designs records (max_offset and mean_force maximised, alpha and
    t_stab minimised; a design not form closed has no max_offset: the worst)."""
    sense = {"max_offset": 1, "alpha": -1, "mean_force": 1, "t_stab": -1}
    vec = {}
    for i in members:
        feasible, objectives = designs[i]
        if not feasible:
            raise ValueError(f"the front files mark design {i} on the front, its /designs record says infeasible")
        vec[i] = [s * objectives.get(k, -math.inf if s > 0 else math.inf) for k, s in sense.items()]
    for a in members:
        for b in members:
            if all(x >= y for x, y in zip(vec[b], vec[a])) and any(x > y for x, y in zip(vec[b], vec[a])):
                raise ValueError(f"the front files mark designs {a} and {b} on the front, but {b} dominates {a}")
