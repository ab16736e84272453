#!/usr/bin/env python3
"""Writes the replay harness's seeds (fuzz/corpus/replay/) from a recorded replay.

    overtake drive --minutes 0.05 --record tiny.otr
    fuzz/tools/make_replay_seeds.py tiny.otr fuzz/corpus/replay

A recorded header holds the lane lines of the whole track (80 KB for the default track), so
the seeds keep 3 points of each: the reader takes them as they are, and small seeds let the
fuzzer spend its time on the records. Layout: docs/replay.md.
"""
import json
import struct
import sys
import zlib
from pathlib import Path


def split(data):
    """The replay's header (dict) and its records [(kind, payload)]."""
    version, header_len = struct.unpack("<II", data[8:16])
    assert data[:8] == b"OVTKRPLY" and version == 2, "not a version 2 replay"
    header = json.loads(data[16:16 + header_len])
    body = zlib.decompress(data[16 + header_len:])
    records, at = [], 0
    while at < len(body):
        kind, n = struct.unpack("<BI", body[at:at + 5])
        records.append((kind, body[at + 5:at + 5 + n]))
        at += 5 + n
    return header, records


def replay(header, records, level=6, version=2):
    text = json.dumps(header, separators=(",", ":")).encode()
    body = b"".join(struct.pack("<BI", k, len(p)) + p for k, p in records)
    return b"OVTKRPLY" + struct.pack("<II", version, len(text)) + text + zlib.compress(body, level)


def with_key(header, section, key, value):
    changed = json.loads(json.dumps(header))
    changed[section][key] = value
    return changed


def main():
    source, out = Path(sys.argv[1]), Path(sys.argv[2])
    header, records = split(source.read_bytes())
    header["lane_lines"] = [line[:6] for line in header["lane_lines"]]
    end = [r for r in records if r[0] == 4]
    first = records[:12] + end  # a few frames and paths, then the report
    out.mkdir(parents=True, exist_ok=True)
    whole = replay(header, records)
    seeds = {
        "recorded.otr": whole,
        # Stored (uncompressed) deflate blocks: mutations reach the records directly.
        "stored_first_records.otr": replay(header, first, level=0),
        "truncated.otr": whole[: len(whole) * 2 // 3],
        "header_only.otr": whole[: 16 + struct.unpack("<I", whole[12:16])[0]],
        "version_1.otr": replay(header, first, version=1),
        "bad_checksum.otr": whole[:-1] + bytes([whole[-1] ^ 0xFF]),
        "record_after_end.otr": replay(header, first + records[:1], level=0),
        # Header integers that do not fit (found by the harness; see docs/fuzzing.md).
        "header_lanes_1e300.otr": replay(with_key(header, "road", "lanes", 1e300), first, level=0),
        "header_seed_negative.otr": replay(with_key(header, "provenance", "seed", -1), first, level=0),
    }
    for name, data in seeds.items():
        (out / name).write_bytes(data)
        print(f"{out / name}: {len(data)} bytes")


if __name__ == "__main__":
    main()
