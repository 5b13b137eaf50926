#!/usr/bin/env python3
"""Bytes per design by channel in gripopt recordings (docs/benchmarks.md).

Each design is one zstd chunk. For the designs *with a grasp* (a non-empty trajectory:
/grasp/series with samples, or, in recordings before issue 11, any /grasp/joints message),
and apart the designs of a robust run's shards drawn in their deciding scenario
(/scenario/series with samples: its free scene, or its centred grasp), prints the mean file
bytes per design and splits them by channel: a channel's share of a
chunk's compressed bytes is its share of the chunk's uncompressed message bytes (record
headers included); message-index bytes (stored uncompressed, 16 bytes per message plus a
header per channel) are added to the channel they index. Usage: mcap_sizes.py DIR...
"""
import collections
import pathlib
import sys
import warnings

warnings.filterwarnings("ignore", category=DeprecationWarning)

from mcap.reader import make_reader
from mcap.records import Chunk, MessageIndex
from mcap.stream_reader import StreamReader

HEADER = 1 + 8 + 2 + 4 + 8 + 8  # opcode, length, channel, sequence, log and publish time


def varint(data, i):
    """The protobuf varint at data[i]: (value, index after it)."""
    n = shift = 0
    while True:
        b = data[i]
        i += 1
        n |= (b & 0x7F) << shift
        shift += 7
        if b < 0x80:
            return n, i


def series_len(data, simulated_field, t_field):
    """Number of t values (field `t_field`, packed doubles) of a gripopt series message whose
    sample count is field `simulated_field`; 0 for a placeholder (a count of 0 is not
    encoded; fields come in tag order)."""
    i = 0
    simulated = False
    while i < len(data):
        key, i = varint(data, i)
        field, wire = key >> 3, key & 7
        if wire == 0:
            v, i = varint(data, i)
            simulated = simulated or (field == simulated_field and v != 0)
        elif wire == 2:
            n, i = varint(data, i)
            if field == t_field:
                return n // 8 if simulated else 0
            i += n
        elif wire == 1:
            i += 8
        elif wire == 5:
            i += 4
    return 0


def varint_field(data, wanted):
    """The value of varint field `wanted` of a protobuf message (0 when absent)."""
    i = 0
    while i < len(data):
        key, i = varint(data, i)
        field, wire = key >> 3, key & 7
        if wire == 0:
            v, i = varint(data, i)
            if field == wanted:
                return v
        elif wire == 2:
            n, i = varint(data, i)
            i += n
        elif wire == 1:
            i += 8
        elif wire == 5:
            i += 4
    return 0


def grasp_series_len(data):
    """Number of t values in a gripopt.GraspSeries (field 4, packed doubles); 0 for the
    placeholder sample of a design without a grasp (simulated_samples, field 3, is 0 and so
    not encoded; fields come in tag order)."""
    i = 0
    simulated = False
    while i < len(data):
        key, i = varint(data, i)
        field, wire = key >> 3, key & 7
        if wire == 0:
            v, i = varint(data, i)
            simulated = simulated or (field == 3 and v != 0)
        elif wire == 2:
            n, i = varint(data, i)
            if field == 4:
                return n // 8 if simulated else 0
            i += n
        elif wire == 1:
            i += 8
        elif wire == 5:
            i += 4
    return 0


def main(dirs):
    kinds = ("with a grasp", "drawn in their deciding scenario's free scene", "drawn in their deciding scenario's centred grasp")
    per_channel = {k: collections.Counter() for k in kinds}
    total = collections.Counter()
    designs = collections.Counter()
    all_designs = 0
    all_bytes = 0
    # the optimisation shards only (not their front files or verify recordings)
    for p in sorted(q for d in dirs for q in pathlib.Path(d).rglob("gen-*.mcap")):
        all_bytes += p.stat().st_size
        with open(p, "rb") as f:
            reader = make_reader(f)
            summary = reader.get_summary()
            for ci in summary.chunk_indexes:
                all_designs += 1
                raw = collections.Counter()
                kind = None
                for _, channel, message in reader.iter_messages(start_time=ci.message_start_time, end_time=ci.message_end_time + 1):
                    if message.log_time < ci.message_start_time or message.log_time > ci.message_end_time:
                        continue
                    raw[channel.topic] += HEADER + len(message.data)
                    if channel.topic == "/grasp/joints" or (channel.topic == "/grasp/series" and grasp_series_len(message.data) > 0):
                        kind = kinds[0]
                    if channel.topic == "/scenario/series" and series_len(message.data, 5, 6) > 0:
                        kind = kinds[1] if varint_field(message.data, 4) else kinds[2]
                if kind is None:
                    continue
                designs[kind] += 1
                compressed = ci.compressed_size + 8 + 8 + 8 + 8 + 4 + 4 + len(ci.compression) + 8 + 1 + 8
                index_bytes = ci.message_index_length
                n_raw = sum(raw.values())
                for t, b in raw.items():
                    per_channel[kind][t] += compressed * b / n_raw + index_bytes * b / n_raw
                total[kind] += compressed + index_bytes
    if not designs:
        print("no design with a grasp found")
        return 1
    print(f"files: {all_bytes} bytes in all, {all_bytes / all_designs:.0f} per design ({all_designs} designs)")
    for kind in kinds:
        if not designs[kind]:
            continue
        print(f"{designs[kind]} designs {kind} (of {all_designs})")
        print(f"| channel | bytes per design {kind} |")
        print("|---|---:|")
        for t, b in sorted(per_channel[kind].items()):
            print(f"| `{t}` | {b / designs[kind]:,.0f} |")
        print(f"| **chunk + message index, total** | **{total[kind] / designs[kind]:,.0f}** |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
