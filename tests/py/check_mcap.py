#!/usr/bin/env python3
"""Checks a co-simulation MCAP recording with the Python `mcap` package (pip install 'mcap==1.*').

usage: check_mcap.py FILE.mcap [--truncated | --unfinished] [--allow-gaps]

Opens the file, reads every message, and checks that
  - every channel is a known topic with the expected message encoding and schema
    (bus and checkpoint channels: "bincode", schema "protocol::wire::Message"/"bincode-serde";
    "/diagnostics": "json", schema "cosim.Diagnostics"/"jsonschema" holding a JSON object);
    topics are '/'-rooted (record layout 2),
  - every bincode message starts with the frame magic b"FSI\\0" and protocol version 7,
  - the Foxglove channels ("/foxglove/solid": schema "foxglove.SceneUpdate", "/foxglove/fluid":
    "foxglove.Grid"; "json"/"jsonschema") hold JSON objects whose timestamp, log time and
    publish time are the same simulated time (they are views of the output files: counted
    apart, on stderr),
  - every diagnostics message parses as a JSON object with an integer "step", and its log time
    is its "t" (the step's end) in nanoseconds (log time = simulated time),
  - log times never decrease within a channel (frames: the start time of their step),
  - sequence numbers count up from 0 per channel (with --allow-gaps, as in a record recovered
    from a damaged one, they only increase), and the metadata "scene" and "run" exist,
  - the file has a summary whose message count matches (unless --truncated: then the file is
    read with the streaming reader up to where it ends; or --unfinished, the record of a killed
    run: then the standard `make_reader` must read it as it is, a file without summary).
Prints "ok N messages, last step S" (N without the Foxglove views) and exits 0, or prints the first problem and exits 1.
"""

import json
import struct
import sys

from mcap.reader import make_reader
from mcap.records import Channel, Message, Metadata, Schema
from mcap.stream_reader import StreamReader

FRAME_TOPICS = {
    "/fluid-to-coupler",
    "/coupler-to-fluid",
    "/solid-to-coupler",
    "/coupler-to-solid",
    "/checkpoint/fluid",
    "/checkpoint/solid",
    "/checkpoint/coupler",
}
DIAGNOSTICS = "/diagnostics"
FOXGLOVE = {"/foxglove/solid": "foxglove.SceneUpdate", "/foxglove/fluid": "foxglove.Grid"}
PROTOCOL_VERSION = 7


class CheckError(Exception):
    pass


def check_channel(channel, schema):
    if channel.topic in FRAME_TOPICS:
        if channel.message_encoding != "bincode":
            raise CheckError(f"{channel.topic}: message encoding {channel.message_encoding!r}, want 'bincode'")
        if schema is None or schema.name != "protocol::wire::Message" or schema.encoding != "bincode-serde":
            raise CheckError(f"{channel.topic}: schema {schema and (schema.name, schema.encoding)!r}")
        if b"protocol version" not in schema.data:
            raise CheckError(f"{channel.topic}: schema data does not name the protocol version")
    elif channel.topic == DIAGNOSTICS:
        if channel.message_encoding != "json":
            raise CheckError(f"diagnostics: message encoding {channel.message_encoding!r}, want 'json'")
        if schema is None or schema.encoding != "jsonschema":
            raise CheckError(f"diagnostics: schema {schema and (schema.name, schema.encoding)!r}")
        doc = json.loads(schema.data)
        if doc.get("type") != "object" or "step" not in doc.get("properties", {}):
            raise CheckError("diagnostics: json schema is not an object schema with 'step'")
    elif channel.topic in FOXGLOVE:
        want = FOXGLOVE[channel.topic]
        if channel.message_encoding != "json":
            raise CheckError(f"{channel.topic}: message encoding {channel.message_encoding!r}, want 'json'")
        if schema is None or (schema.name, schema.encoding) != (want, "jsonschema"):
            raise CheckError(f"{channel.topic}: schema {schema and (schema.name, schema.encoding)!r}, want {want!r}")
        if json.loads(schema.data).get("type") != "object":
            raise CheckError(f"{channel.topic}: json schema is not an object schema")
    else:
        raise CheckError(f"unknown topic {channel.topic!r}")


ALLOW_GAPS = False
# Messages on the Foxglove channels (not in N: the readers of the project leave them out).
VIEWS = [0]
LAST_LOG_TIME = {}


def check_message(channel, message, next_seq):
    """Checks one message; returns its coupling step (from the payload)."""
    if message.log_time < LAST_LOG_TIME.get(channel.id, 0):
        raise CheckError(f"{channel.topic} seq {message.sequence}: log time {message.log_time} goes back")
    LAST_LOG_TIME[channel.id] = message.log_time
    want = next_seq.get(channel.id, 0)
    if ALLOW_GAPS and message.sequence > want:
        want = message.sequence
    if message.sequence != want:
        raise CheckError(f"{channel.topic}: sequence {message.sequence}, want {want}")
    next_seq[channel.id] = want + 1
    data = message.data
    if channel.topic in FOXGLOVE:
        value = json.loads(data)
        stamp = value["timestamp"] if channel.topic == "/foxglove/fluid" else value["entities"][0]["timestamp"]
        ns = stamp["sec"] * 1_000_000_000 + stamp["nsec"]
        if not (ns == message.log_time == message.publish_time):
            raise CheckError(f"{channel.topic} seq {message.sequence}: timestamp {ns}, log time {message.log_time}, publish time {message.publish_time} differ")
        return None
    if channel.topic == DIAGNOSTICS:
        value = json.loads(data)
        if not isinstance(value, dict) or not isinstance(value.get("step"), int):
            raise CheckError(f"diagnostics at log_time {message.log_time}: not an object with an integer step")
        t = value.get("t")
        if not isinstance(t, (int, float)) or abs(message.log_time - round(t * 1e9)) > 1:
            raise CheckError(f"diagnostics step {value['step']}: log_time {message.log_time} is not t = {t} s in ns")
        return value["step"]
    else:
        if len(data) < 24 or data[:4] != b"FSI\x00":
            raise CheckError(f"{channel.topic} seq {message.sequence}: not a frame (magic {data[:4]!r})")
        (version,) = struct.unpack_from("<I", data, 4)
        if version != PROTOCOL_VERSION:
            raise CheckError(f"{channel.topic} seq {message.sequence}: protocol version {version}")
        (step,) = struct.unpack_from("<Q", data, 12)
        return step


def check_complete(path, unfinished=False):
    with open(path, "rb") as f:
        reader = make_reader(f)
        try:
            summary = reader.get_summary()
        except Exception as e:  # a file without footer makes the summary lookup fail
            raise CheckError(f"no readable summary ({type(e).__name__}); truncated file? use --truncated")
        if unfinished:
            if summary is not None:
                raise CheckError("a summary section: the run finished, not --unfinished")
        elif summary is None:
            raise CheckError("no summary section (truncated file? use --truncated)")
        metadata = {m.name for m in reader.iter_metadata()}
        for name in ("scene", "run"):
            if name not in metadata:
                raise CheckError(f"metadata {name!r} missing")
        next_seq = {}
        n = 0
        last = None
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            check_channel(channel, schema)
            step = check_message(channel, message, next_seq)
            if channel.topic in FOXGLOVE:
                VIEWS[0] += 1
            else:
                n += 1
            if channel.topic == DIAGNOSTICS:
                last = step
        total = n + VIEWS[0]
        if summary is not None and summary.statistics is not None and summary.statistics.message_count != total:
            raise CheckError(f"summary counts {summary.statistics.message_count} messages, read {total}")
        return n, last


def check_truncated(path):
    schemas, channels, next_seq = {}, {}, {}
    metadata = set()
    n = 0
    last = None
    with open(path, "rb") as f:
        try:
            for record in StreamReader(f, skip_magic=False, emit_chunks=False).records:
                if isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Channel):
                    channels[record.id] = record
                elif isinstance(record, Metadata):
                    metadata.add(record.name)
                elif isinstance(record, Message):
                    channel = channels[record.channel_id]
                    check_channel(channel, schemas.get(channel.schema_id))
                    step = check_message(channel, record, next_seq)
                    if channel.topic in FOXGLOVE:
                        VIEWS[0] += 1
                    else:
                        n += 1
                    if channel.topic == DIAGNOSTICS:
                        last = step
        except CheckError:
            raise
        except Exception as e:  # the streaming reader ends with an error where the file was cut
            print(f"stream ends: {type(e).__name__}: {e}", file=sys.stderr)
    for name in ("scene", "run"):
        if name not in metadata:
            raise CheckError(f"metadata {name!r} missing")
    return n, last


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__)
        return 2
    path = argv[1]
    global ALLOW_GAPS
    ALLOW_GAPS = "--allow-gaps" in argv[2:]
    try:
        if "--truncated" in argv[2:]:
            n, last = check_truncated(path)
        else:
            n, last = check_complete(path, unfinished="--unfinished" in argv[2:])
    except (CheckError, json.JSONDecodeError, KeyError) as e:
        print(f"{path}: {e}")
        return 1
    print(f"ok {n} messages, last step {last}")
    print(f"foxglove views: {VIEWS[0]}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
