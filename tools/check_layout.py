"""Does every topic, message path and frame a shipped Foxglove layout names exist in the
recordings it is shipped with? Knows nothing of gripopt's code: it reads the layout JSON the
way Foxglove and Lichtblick do (panel type = the part of the panel id before '!') and resolves
each message path (Foxglove message-path syntax: `/topic.field[:]{field=="value"}.field`) on
the messages decoded with the reference readers.

Panel types and the keys holding paths or frames (the only ones the shipped layouts use; an
unknown panel type fails, so that a new panel cannot go unchecked):
  3D          followTf, transforms "frame:NAME", topics (keys), layers[].frameId
  Plot        paths[].value (a number is a reference line), xAxisPath.value; each y path and
              the x path must give numbers, and equally many in every message; no two series
              in one colour (over 7, the viewers' palette, each its own `color`), legend labels
              that fit `sidebarDimension`, reference lines inside fixed y limits, off the top
              edge and not on one another
  RawMessages topicPath
  Indicator   path (a boolean, number or string)
Every panel must carry its title under both viewers' keys (foxglovePanelTitle,
lichtblickPanelTitle), the mosaic must name exactly the panels of configById, and
playbackConfig.speed must be a number (Lichtblick refuses a layout without it).
"""
import json
import re

TITLE_KEYS = ("foxglovePanelTitle", "lichtblickPanelTitle")
TOKEN = re.compile(r"""\.([A-Za-z_][A-Za-z0-9_]*)|\[(:|-?\d+)\]|\{([A-Za-z_][A-Za-z0-9_.]*)==("[^"]*"|'[^']*'|[-\w.]+)\}""")


class Recording:
    """What a set of files holds: topics -> decoded messages (capped), and frame ids."""

    def __init__(self, cap=400):
        self.cap = cap
        self.messages = {}
        self.frames = set()

    def add(self, topic, msg):
        kept = self.messages.setdefault(topic, [])
        if len(kept) < self.cap:
            kept.append(msg)
        if topic == "/tf":
            for x in msg.transforms:
                self.frames.update((x.parent_frame_id, x.child_frame_id))


def split_topic(path, topics):
    best = None
    for t in topics:
        if path == t or (path.startswith(t) and path[len(t)] in ".[{"):
            if best is None or len(t) > len(best):
                best = t
    if best is None:
        raise ValueError(f"topic of {path!r} is not in the recording (topics: {sorted(topics)})")
    rest, tokens, pos = path[len(best):], [], 0
    while pos < len(rest):
        m = TOKEN.match(rest, pos)
        if not m:
            raise ValueError(f"cannot parse {path!r} at {rest[pos:]!r}")
        tokens.append(m.groups())
        pos = m.end()
    return best, tokens


def field(value, name):
    if isinstance(value, dict):
        if name not in value:
            raise KeyError(name)
        return value[name]
    descriptor = getattr(value, "DESCRIPTOR", None)
    if descriptor is None or name not in descriptor.fields_by_name:
        raise KeyError(name)
    return getattr(value, name)


def literal(text):
    if text[:1] in "\"'":
        return text[1:-1]
    if text in ("true", "false"):
        return text == "true"
    try:
        return float(text)
    except ValueError:
        return text


def resolve(msg, tokens):
    """The values a message path gives on one message (KeyError: a field it lacks)."""
    values = [msg]
    for name, index, key, lit in tokens:
        out = []
        for v in values:
            if name is not None:
                out.append(field(v, name))
            elif index is not None:
                seq = list(v)
                out.extend(seq if index == ":" else seq[int(index):int(index) + 1 or None])
            else:
                want = literal(lit)
                out.extend([v] if field(v, key) == want else [])
        values = out
    return values


def is_number(v):
    """What a Plot panel plots: numbers (booleans count as 0/1)."""
    return isinstance(v, (int, float))


def check_path(rec, path, kind, where):
    """Resolve `path` on the recording's messages; the values per message."""
    topic, tokens = split_topic(path, rec.messages.keys())
    per_message, missing = [], 0
    for msg in rec.messages[topic]:
        try:
            per_message.append(resolve(msg, tokens))
        except KeyError:
            missing += 1
    if not any(per_message):
        raise ValueError(f"{where}: {path!r} gives no value in any {topic} message ({missing} lack the field)")
    if kind == "number" and not all(is_number(v) for vs in per_message for v in vs):
        raise ValueError(f"{where}: {path!r} gives values that are not numbers")
    if kind == "scalar" and not all(isinstance(v, (bool, int, float, str)) for vs in per_message for v in vs):
        raise ValueError(f"{where}: {path!r} gives values that are not a boolean, number or string")
    return topic, per_message


def leaves(node):
    if isinstance(node, str):
        return [node]
    if isinstance(node, dict):
        return leaves(node.get("first")) + leaves(node.get("second"))
    return []


PALETTE_SIZE = 7  # the viewers' default series colours (Lichtblick/Foxglove Plot); an 8th series repeats the 1st
CHAR_PX = 6.6  # legend text, px per character
SWATCH_PX = 40  # the legend's colour swatch and padding


def check_plot_look(cfg, where):
    """What a reader sees of a Plot: no two series in one colour (more than the palette's 7
    need explicit, distinct `color`s), legend labels that fit the legend's width, and every
    reference line inside fixed y limits, away from the top edge, no two at one value (the
    second hidden)."""
    paths = cfg["paths"]
    colors = [p.get("color") for p in paths]
    given = [c for c in colors if c]
    if len(given) != len(set(given)) or (len(paths) > PALETTE_SIZE and len(given) != len(paths)):
        raise ValueError(f"{where}: {len(paths)} series on a {PALETTE_SIZE}-colour palette with colours {colors}: two series would share a colour")
    fits = int((cfg.get("sidebarDimension", 0) - SWATCH_PX) / CHAR_PX)
    if cfg.get("legendDisplay") in ("left", "top") or cfg.get("legendDisplay") is None:
        for p in paths:
            label = p.get("label") or p["value"]
            if cfg.get("legendDisplay") == "left" and len(label) > fits:
                raise ValueError(f"{where}: legend label {label!r} ({len(label)} characters) is cut at {cfg.get('sidebarDimension')} px ({fits} fit)")
    lines = []
    for p in paths:
        try:
            lines.append(float(p["value"]))
        except ValueError:
            pass
    if lines:
        lo, hi = cfg.get("minYValue"), cfg.get("maxYValue")
        if lo is None or hi is None:
            raise ValueError(f"{where}: reference lines {lines} without fixed y limits: the automatic range puts a line the curves stay under on the plot's top edge")
        if any(not (float(lo) < v < float(hi) - 0.1 * (float(hi) - float(lo))) for v in lines) or len(set(lines)) != len(lines):
            raise ValueError(f"{where}: reference lines {lines} on or near the edge of y {lo}..{hi}, or two at one value")


def check_layout(layout_path, rec):
    """Check one layout file against a recording; the number of paths and frames checked."""
    layout = json.loads(open(layout_path).read())
    speed = layout.get("playbackConfig", {}).get("speed")
    if not isinstance(speed, (int, float)):
        raise ValueError("playbackConfig.speed missing (Lichtblick refuses the layout)")
    configs = layout.get("configById", {})
    if sorted(leaves(layout.get("layout"))) != sorted(configs):
        raise ValueError(f"the mosaic names {sorted(leaves(layout.get('layout')))}, configById {sorted(configs)}")
    checked = 0
    for pid, cfg in configs.items():
        kind = pid.split("!")[0]
        where = f"{layout_path.name} {pid}"
        for k in TITLE_KEYS:
            if not isinstance(cfg.get(k), str) or not cfg[k]:
                raise ValueError(f"{where}: no title under {k}")
        if kind == "3D":
            frames = [cfg["followTf"]] + [k.split(":", 1)[1] for k in cfg.get("transforms", {})]
            frames += [layer["frameId"] for layer in cfg.get("layers", {}).values() if "frameId" in layer]
            for f in frames:
                if f not in rec.frames:
                    raise ValueError(f"{where}: frame {f!r} is not in /tf (frames: {sorted(rec.frames)})")
            for t in cfg.get("topics", {}):
                if t not in rec.messages:
                    raise ValueError(f"{where}: topic {t!r} is not in the recording")
            checked += len(frames) + len(cfg.get("topics", {}))
        elif kind == "Plot":
            check_plot_look(cfg, where)
            x = cfg["xAxisPath"]["value"] if cfg.get("xAxisVal") in ("custom", "currentCustom") else None
            xs = check_path(rec, x, "number", where)[1] if x else None
            for p in cfg["paths"]:
                try:
                    float(p["value"])
                    continue  # a reference line
                except ValueError:
                    pass
                topic, ys = check_path(rec, p["value"], "number", where)
                if xs is not None and cfg.get("xAxisVal") == "currentCustom":
                    if [len(v) for v in ys] != [len(v) for v in xs]:
                        raise ValueError(f"{where}: {p['value']!r} and the x path {x!r} differ in length (the viewer warns 'mismatched data lengths')")
                checked += 1
            checked += x is not None
        elif kind == "RawMessages":
            topic = cfg["topicPath"]
            if topic not in rec.messages:
                check_path(rec, topic, "any", where)
            checked += 1
        elif kind == "Indicator":
            check_path(rec, cfg["path"], "scalar", where)
            checked += 1
        else:
            raise ValueError(f"{where}: panel type {kind!r} unknown to this checker (add how its paths are read)")
    return checked
