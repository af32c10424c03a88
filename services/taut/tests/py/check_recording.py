#!/usr/bin/env python3
"""Checks a taut recording with the PyPI `mcap` reader (the issue's acceptance test).

    check_recording.py RUN_DIR [--allow-drops]
        RUN_DIR holds recording.mcap and logs/*.log (a `taut sim` --out folder). Lists every
        channel with its schema, JSON-decodes every message (its keys must be the schema's
        properties), and checks per topic: messages == published - drops, where `published`
        comes from the services' `[ipc] published N on <root>/taut/<uav>/<topic>` log lines and
        `drops` from the recording's `taut.drops` metadata; zero drops and zero samples missed
        before the recorder started are expected unless --allow-drops.

    check_recording.py --killed FILE
        FILE was cut short (the recorder got SIGKILL): reads it front to back up to the torn end
        and prints the decoded message count per topic.

The last line printed is `RESULT <json>` for the calling test.
"""

import glob
import json
import os
import re
import sys
from collections import Counter

from mcap.exceptions import McapError
from mcap.reader import NonSeekingReader, make_reader

PUBLISHED = re.compile(r"^\[ipc\] published (\d+) on (\S+)")


def published_counts(log_dir):
    """channel topic (/uav/topic) -> samples published, summed over the logs."""
    out = Counter()
    for path in glob.glob(os.path.join(log_dir, "*.log")):
        with open(path, encoding="utf-8", errors="replace") as f:
            for line in f:
                m = PUBLISHED.match(line.strip())
                if m:
                    parts = m.group(2).split("/")
                    # <root>/taut/<uav>/<topic>
                    out["/" + "/".join(parts[-2:])] += int(m.group(1))
    return out


def decode_all(reader, fail, counts, schemas):
    """Decodes every message, counting per topic into `counts` (kept if the file is torn)."""
    props = {}
    for schema, channel, message in reader.iter_messages(log_time_order=False):
        topic = channel.topic
        if topic not in schemas:
            if schema is None:
                fail(f"{topic}: no schema")
                continue
            schemas[topic] = (schema.name, schema.encoding, channel.message_encoding)
            if schema.encoding != "jsonschema" or channel.message_encoding != "json":
                fail(f"{topic}: encodings {schema.encoding}/{channel.message_encoding}")
            props[topic] = set(json.loads(schema.data)["properties"])
        obj = json.loads(message.data)
        if set(obj) != props[topic]:
            fail(f"{topic}: message keys {sorted(obj)} != schema {sorted(props[topic])}")
        if obj["header"]["sequence"] % (1 << 32) != message.sequence:
            fail(f"{topic}: MCAP sequence {message.sequence} != header")
        counts[topic] += 1


def check_run(run_dir, allow_drops):
    problems = []
    fail = problems.append
    path = os.path.join(run_dir, "recording.mcap")
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        if summary is None:
            fail("no summary section: the recorder did not close the file")
        counts, schemas = Counter(), {}
        decode_all(reader, fail, counts, schemas)
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        attachments = [a.name for a in reader.iter_attachments()]
    print(f"{path}: {sum(counts.values())} messages on {len(counts)} channels")
    print(f"{'channel':32} {'schema':24} {'enc':10} {'messages':>9} {'published':>9} {'drops':>6}")
    published = published_counts(os.path.join(run_dir, "logs"))
    drops = {k: int(v) for k, v in meta.get("taut.drops", {}).items()}
    missed = {k: int(v) for k, v in meta.get("taut.missed_before_start", {}).items()}
    received = {k: int(v) for k, v in meta.get("taut.received", {}).items()}
    if "taut.drops" not in meta or "taut.recording" not in meta:
        fail(f"metadata missing: {sorted(meta)}")
    for topic in sorted(set(counts) | {t for t, n in published.items() if n > 0}):
        name, enc, _ = schemas.get(topic, ("-", "-", "-"))
        n, p, d = counts[topic], published.get(topic), drops.get(topic, 0)
        print(f"{topic:32} {name:24} {enc:10} {n:9} {p if p is not None else '-':>9} {d:6}")
        if p is None:
            fail(f"{topic}: recorded but no service logged what it published")
            continue
        if n != p - d - missed.get(topic, 0):
            fail(f"{topic}: {n} messages, published {p} - drops {d} - missed {missed.get(topic, 0)}")
        if received.get(topic, 0) != n:
            fail(f"{topic}: taut.received says {received.get(topic)}, file holds {n}")
        if not allow_drops and (d or missed.get(topic, 0)):
            fail(f"{topic}: {d} drops, {missed.get(topic, 0)} missed before start (0 expected)")
    uavs = meta.get("taut.recording", {}).get("uavs", "").split(",")
    for uav in uavs:
        if f"config/{uav}.toml" not in attachments:
            fail(f"no config attachment for {uav}: {attachments}")
    result = {
        "channels": len(counts),
        "messages": sum(counts.values()),
        "drops": sum(drops.values()),
        "published": sum(published.values()),
        "attachments": attachments,
        "problems": problems,
    }
    return problems, result


def count_killed(path):
    """Counts what a cut-short file yields, front to back, up to its torn end."""
    problems = []
    counts = Counter()
    torn = None
    with open(path, "rb") as f:
        # No footer, so the summary cannot be used: read linearly.
        reader = NonSeekingReader(f)
        try:
            decode_all(reader, problems.append, counts, {})
        except (McapError, EOFError, ValueError) as e:
            torn = repr(e)
    return problems, {"counts": dict(counts), "torn": torn, "problems": problems}


def main():
    args = sys.argv[1:]
    if args and args[0] == "--killed":
        problems, result = count_killed(args[1])
    else:
        problems, result = check_run(args[0], "--allow-drops" in args)
    for p in problems:
        print("PROBLEM:", p)
    print("RESULT", json.dumps(result))
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
