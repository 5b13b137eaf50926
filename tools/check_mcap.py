#!/usr/bin/env python3
"""Independent check of gripopt's MCAP files with the reference `mcap` reader (PyPI).

For every *.mcap under the given folders: the file opens, has a summary with statistics,
chunk indexes and message indexes, every channel has a jsonschema schema, and every JSON
message validates against its channel's schema. Prints one line per file and a closing
'N passed, N failed' line; exits non-zero on any failure or when no file was found.
"""
import json
import pathlib
import sys

import jsonschema
from mcap.reader import make_reader


def check(path):
    with open(path, "rb") as f:
        reader = make_reader(f)
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
        for cid, ch in summary.channels.items():
            schema = summary.schemas[ch.schema_id]
            if schema.encoding != "jsonschema" or ch.message_encoding != "json":
                raise ValueError(f"channel {ch.topic}: encodings {schema.encoding}/{ch.message_encoding}")
            s = json.loads(schema.data)
            jsonschema.Draft7Validator.check_schema(s)
            validators[cid] = (ch.topic, jsonschema.Draft7Validator(s))
        n = 0
        for schema, channel, message in reader.iter_messages():
            topic, v = validators[channel.id]
            doc = json.loads(message.data)
            errors = sorted(v.iter_errors(doc), key=lambda e: e.path)
            if errors:
                raise ValueError(f"{topic} message at {message.log_time}: {errors[0].message}")
            n += 1
        if n != summary.statistics.message_count:
            raise ValueError(f"read {n} messages, statistics say {summary.statistics.message_count}")
        meta = list(reader.iter_metadata())
        if not any(m.name == "gripopt.run" for m in meta):
            raise ValueError("no gripopt.run metadata record")
        return n, len(summary.chunk_indexes)


def main(folders):
    files = sorted(p for d in folders for p in pathlib.Path(d).rglob("*.mcap"))
    ok = bad = 0
    for p in files:
        try:
            n, chunks = check(p)
            print(f"ok   {p}: {n} messages in {chunks} chunks, all valid")
            ok += 1
        except Exception as e:  # noqa: BLE001 - report every failure
            print(f"FAIL {p}: {e}")
            bad += 1
    print(f"mcap: {ok} passed, {bad} failed")
    if not files:
        print("no MCAP files found in", folders)
        return 1
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:] or ["target/mcap-check"]))
