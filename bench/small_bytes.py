"""Where the bytes of a small version 6 .pln file go (issue 52: small meshes and per-object cost).

For each mesh (loaded as ``bench/compare.py``'s ``load`` does) it writes the file ``bench/at_draco.py``
writes (``encode_scene`` at Draco-14's error from ``--cache``) and splits its bytes into: fixed framing
(signature, chunk types, lengths and CRCs, ``PEND``), header fields (version and header size, flags and
units, widths, h range, bbox, tolerance and error bound, counts), the segment head, and per record
type (record heads; object parent/flags/name length, names, transforms; planes; group heads
(object, kind), references (count, differences, roles) and kind data; colours; metadata). Records are
counted in raw bytes; ``packing`` is what compression of the segment saved (negative: it cost).
Given a ``.pln`` file instead of a mesh it splits that file.

Usage::

    python bench/small_bytes.py --corpus ../shared/bench-corpus --max-triangles 99
    python bench/small_bytes.py file.pln
"""

from __future__ import annotations

import argparse
import collections
import io
import json
import os
import sys
import warnings

sys.path.insert(0, os.path.dirname(__file__))
from at_draco import _meshes  # noqa: E402
from compare import MEASURE_RESOLUTION, load  # noqa: E402

from planefmt.container import schema  # noqa: E402
from planefmt.container.compression import unpack  # noqa: E402
from planefmt.container.chunks import Limits  # noqa: E402

PARTS = ("framing", "version", "flags", "widths", "h_range", "bbox", "tol_err", "counts", "segment",
         "packing", "rec_heads", "obj_fields", "names", "transforms", "planes", "grp_heads", "refs",
         "kind_data", "colours", "meta")


def _varint(data: bytes, pos: int) -> tuple[int, int]:
    value = shift = 0
    while True:
        b = data[pos]
        value |= (b & 0x7F) << shift
        pos += 1
        shift += 7
        if not b & 0x80:
            return value, pos


def _chunks(data: bytes):
    pos, first = 8, True
    while pos < len(data):
        kind = data[pos:pos + 4]
        if first:
            length, body = int.from_bytes(data[pos + 4:pos + 8], "little"), pos + 8
        else:
            length, body = _varint(data, pos + 4)
        yield kind, data[body:body + length], body - pos + 4
        pos = body + length + 4
        first = False


def _header(payload: bytes, out: collections.Counter) -> int:
    size, pos = _varint(payload, 2)
    out["version"] += pos
    flags, coding = payload[pos], payload[pos] >> 3 & 3
    out["flags"] += 2
    pos += 2
    if coding in (2, 3):
        out["widths"] += 2
        pos += 2
        for _ in range(2):
            _, end = _varint(payload, pos)
            out["h_range"] += end - pos
            pos = end
    for name, n, present in (("bbox", 6, flags & 4), ("tol_err", 2, True)):
        for _ in range(n if present else 0):
            _, end = _varint(payload, pos)
            out[name] += end - pos
            pos = end
    if flags & 2:
        start = pos
        for _ in range(3):
            _, pos = _varint(payload, pos)
        out["counts"] += pos - start
    return pos


def _record(tag: int, p: bytes, out: collections.Counter) -> None:
    if tag == schema.TAG_OBJECT:
        _, pos = _varint(p, 0)
        flags = p[pos]
        n, pos = _varint(p, pos + 1)
        out["obj_fields"] += pos
        out["names"] += n
        out["transforms"] += len(p) - pos - n
        out["transform_count"] += bool(flags & 1)
        out["objects"] += 1
    elif tag == schema.TAG_PLANES:
        out["planes"] += len(p)
    elif tag == schema.TAG_GROUP:
        _, pos = _varint(p, 0)
        out["grp_heads"] += pos + 1
        out["kinds"] += 0
        out[f"kind {p[pos]}"] += 1
        start = pos + 1
        m, pos = _varint(p, start)
        for _ in range(m):
            _, pos = _varint(p, pos)
        pos += (m + 7) // 8
        out["refs"] += pos - start
        out["kind_data"] += len(p) - pos
        out["groups"] += 1
    elif tag == schema.TAG_COLOURS:
        out["colours"] += len(p)
    else:
        out["meta"] += len(p)


def split(data: bytes) -> collections.Counter:
    """The bytes of a version 6 file by part (``PARTS``), with object, group and kind counts."""
    out: collections.Counter = collections.Counter()
    out["framing"] += 8
    for kind, payload, head in _chunks(data):
        out["framing"] += head
        if kind not in (schema.PHDR, schema.BODY):
            out["framing"] += len(payload)
            continue
        pos = _header(payload, out) if kind == schema.PHDR else 0
        if pos == len(payload):
            continue
        method = payload[pos]
        raw_size, start = _varint(payload, pos + 1)
        out["segment"] += start - pos
        raw = bytes(unpack(method, memoryview(payload)[start:], raw_size, Limits(), 6))
        out["packing"] -= raw_size - (len(payload) - start)
        rp = 0
        while rp < len(raw):
            tag = raw[rp]
            length, body = _varint(raw, rp + 1)
            out["rec_heads"] += body - rp
            _record(tag, raw[body:body + length], out)
            rp = body + length
    out["total"] = len(data)
    return out


def _encode(path: str, tolerance: float) -> bytes:
    from planefmt import codec

    scene, _, _ = load(path)
    buf = io.BytesIO()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        codec.encode_scene(scene, buf, tolerance=tolerance)
    return buf.getvalue()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="*", help=".pln files to split (instead of meshes of the corpus)")
    ap.add_argument("--corpus", default=None)
    ap.add_argument("--categories", help="comma-separated folders of the corpus (default: all)")
    ap.add_argument("--max-triangles", type=int, default=99)
    ap.add_argument("--cache", default=os.path.join(os.path.dirname(__file__), "draco-errors.json"))
    ap.add_argument("--json", help="write the rows here")
    args = ap.parse_args(argv)
    rows = []
    if args.files:
        rows = [{"mesh": f, **split(open(f, "rb").read())} for f in args.files]
    else:
        cache = json.load(open(args.cache))
        for path in _meshes(args.corpus, args.categories.split(",") if args.categories else None):
            rel = os.path.relpath(path, args.corpus)
            d = cache.get(f"{rel}@14", {})
            if "draco" not in d or d["triangles"] > args.max_triangles:
                continue
            data = _encode(path, max(d["error"], MEASURE_RESOLUTION))
            rows.append({"mesh": rel, "draco": d["draco"], **split(data)})
    cols = [p for p in PARTS if any(r.get(p) for r in rows)]
    print("mesh".ljust(44) + " draco  total " + " ".join(c[:9].rjust(9) for c in cols) + "  objs grps")
    for r in rows:
        print(f"{r['mesh'][-44:]:44s} {r.get('draco', 0):5d} {r['total']:6d} "
              + " ".join(f"{r.get(c, 0):9d}" for c in cols) + f"  {r.get('objects', 0):4d} {r.get('groups', 0):4d}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
