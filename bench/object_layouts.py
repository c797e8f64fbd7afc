"""What other layouts of the version 6 object record would save (issue 52: per-object cost), measured by
rewriting the object records of real files and compressing the segment again as the writer does.

For each mesh (``encode_scene`` at Draco-14's error from ``--cache``, as ``bench/at_draco.py``) the file's
one segment is rebuilt with its object records (spec §8) coded otherwise, and the file's size taken with
that segment stored by the writer's rule (the smallest of methods 0, 1, 2). Layouts, each on top of the
one before:

* ``head``: flags and name_length in one varint (name_length × 2 + HAS_TRANSFORM);
* ``r32``: transform entries of code 2 (an f32) as r32 (spec §2.2: 1 to 5 bytes; 1.0, -1.0, 0.5, 4.0 two);
* ``decimal``: a transform entry of code 3 (an f64) as a decimal where that is shorter and gives the same
  f64 back (zigzag mantissa varint and exponent byte: -1.1 is 2 bytes, not 8);
* ``one``: the objects of a file in one record (no tag and length per object).

It measures candidates for a version 6.1; no reader reads these layouts. A file of more than one segment
is skipped. Usage::

    python bench/object_layouts.py --corpus ../shared/bench-corpus --categories gltf_scene,usd
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from at_draco import _meshes  # noqa: E402
from compare import MEASURE_RESOLUTION  # noqa: E402
from small_bytes import _chunks, _encode, _header, _varint  # noqa: E402

from planefmt.container import schema  # noqa: E402
from planefmt.container.chunks import Limits  # noqa: E402
from planefmt.container.compression import unpack  # noqa: E402
from planefmt.container.segments import record_bytes, segment_bytes  # noqa: E402

LAYOUTS = ("6.0", "head", "r32", "decimal", "one")


def _uvarint(n: int) -> bytes:
    return schema.Varint.build(n)


def _decimal(v: float) -> bytes | None:
    """``v`` as zigzag mantissa and exponent varints, if that gives ``v`` back exactly."""
    text = repr(v)
    if "inf" in text or "nan" in text:
        return None
    mantissa, _, exp = text.partition("e")
    whole, _, frac = mantissa.partition(".")
    frac = frac.rstrip("0")
    m = int(whole + frac) if (whole + frac) not in ("", "-") else 0
    e = int(exp or 0) - len(frac)
    if float(f"{m}e{e}") != v:
        return None
    zz = lambda x: 2 * x if x >= 0 else -2 * x - 1  # noqa: E731
    return _uvarint(zz(m)) + _uvarint(zz(e))


def _object(p: bytes, layout: int) -> bytes:
    parent, pos = _varint(p, 0)
    flags = p[pos]
    n, pos = _varint(p, pos + 1)
    name, pos = p[pos:pos + n], pos + n
    out = _uvarint(parent) + (_uvarint(n * 2 + (flags & 1)) if layout >= 1 else bytes([flags]) + _uvarint(n)) + name
    if not flags & 1:
        return out + p[pos:]
    codes = schema.transform_codes(p[pos:pos + 3])
    values, vp = [], pos + 3
    for c in codes:
        size = schema.TRANSFORM_VALUE_SIZES[c]
        values.append(p[vp:vp + size])
        vp += size
    coded = []
    for c, raw in zip(codes, values):
        if c == 2 and layout >= 2:
            bits = int.from_bytes(raw, "little")
            coded.append(schema.Varint32.build(schema.reverse32(bits)))
        elif c == 3 and layout >= 3:
            v = float(np.frombuffer(raw, "<f8")[0])
            d = _decimal(v)
            coded.append(d if d is not None and len(d) < 8 else raw)
        else:
            coded.append(raw)
    return out + p[pos:pos + 3] + b"".join(coded) + p[vp:]


def sizes(data: bytes) -> dict[str, int] | None:
    """The file's size with each layout of its object records; None for a file of several segments."""
    chunks = list(_chunks(data))
    if any(kind == schema.BODY for kind, _, _ in chunks):
        return None
    payload = chunks[0][1]
    import collections
    pos = _header(payload, collections.Counter())
    if pos == len(payload):
        return None
    raw_size, start = _varint(payload, pos + 1)
    raw = bytes(unpack(payload[pos], memoryview(payload)[start:], raw_size, Limits(), 6))
    recs, rp = [], 0
    while rp < len(raw):
        length, body = _varint(raw, rp + 1)
        recs.append((raw[rp], raw[body:body + length]))
        rp = body + length
    stored = len(payload) - pos
    out = {}
    for k, name in enumerate(LAYOUTS):
        if name == "one":
            objs = [_object(p, 3) for t, p in recs if t == schema.TAG_OBJECT]
            rest = [record_bytes(t, p) for t, p in recs if t != schema.TAG_OBJECT]
            # One record of every object (each with its length), where the first object record stood.
            first = next(i for i, (t, _) in enumerate(recs) if t == schema.TAG_OBJECT)
            body = _uvarint(len(objs)) + b"".join(_uvarint(len(o)) + o for o in objs)
            new = b"".join(rest[:first]) + record_bytes(schema.TAG_OBJECT, body) + b"".join(rest[first:])
        else:
            new = b"".join(record_bytes(t, _object(p, k) if t == schema.TAG_OBJECT else p) for t, p in recs)
        out[name] = len(data) - stored + len(segment_bytes(new, True))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--corpus", required=True)
    ap.add_argument("--categories", default="gltf_scene,usd")
    ap.add_argument("--max-triangles", type=int, default=30000)
    ap.add_argument("--cache", default=os.path.join(os.path.dirname(__file__), "draco-errors.json"))
    ap.add_argument("--json", help="write the rows here")
    args = ap.parse_args(argv)
    cache = json.load(open(args.cache))
    rows = []
    print("mesh".ljust(46) + " draco " + " ".join(n.rjust(7) for n in LAYOUTS))
    for path in _meshes(args.corpus, args.categories.split(",")):
        rel = os.path.relpath(path, args.corpus)
        d = cache.get(f"{rel}@14", {})
        if "draco" not in d or d["triangles"] > args.max_triangles:
            continue
        s = sizes(_encode(path, max(d["error"], MEASURE_RESOLUTION)))
        if s is None:
            continue
        rows.append({"mesh": rel, "draco": d["draco"], **s})
        print(f"{rel[-46:]:46s} {d['draco']:6d} " + " ".join(f"{s[n]:7d}" for n in LAYOUTS), flush=True)
    for cat in sorted({r["mesh"].split("/")[0] for r in rows}):
        sel = [r for r in rows if r["mesh"].startswith(cat + "/")]
        print(f"{cat:22s} {len(sel):3d} median / draco " + " ".join(
            f"{statistics.median(r[n] / r['draco'] for r in sel):7.3f}" for n in LAYOUTS))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
