"""Deflate against Brotli on the payloads of .pln files (spec §6: method 1 against method 2, version 4.0).

For each corpus mesh (``bench/compare.py``'s ``load``: the file read by the converters), the default
encoder writes the file at ``--tolerance`` (default 3e-5, about draco-14's measured error on the corpus,
docs/benchmarks.md) with ``planefmt.codec.encode_scene``: version 4.0, each PLNS block and GRUP body
stored by whichever of deflate and Brotli is smaller (``planefmt.container.records.pack``). Each of those
payloads is then measured again under deflate alone, at the level the writer uses for it, which is what a
version 3.4 writer stored. Printed per mesh: the file's bytes; the PLNS and GRUP payload bytes under
deflate alone and as written; the saving. Then the median saving per corpus category and overall.

Usage: ``python bench/compression.py [--tolerance T] [paths relative to the corpus]``
"""

from __future__ import annotations

import argparse
import io
import os
import statistics
import sys
import warnings
import zlib

sys.path.insert(0, os.path.dirname(__file__))
from compare import CORPUS, load  # noqa: E402

from planefmt import codec  # noqa: E402
from planefmt.container import records, schema  # noqa: E402
from planefmt.container.chunks import Limits, chunks_of  # noqa: E402
from planefmt.model import TREE_KINDS  # noqa: E402

MESH_SUFFIXES = (".stl", ".obj", ".ply", ".off", ".glb", ".gltf", ".usd", ".usda", ".usdz", ".usdc")


def payload_bytes(data: bytes) -> tuple[int, int]:
    """(PLNS and GRUP payload bytes as stored, the same payloads deflated alone) of a version 4 or 5 file."""
    stored = deflated = 0
    for chunk in chunks_of(data):
        if chunk.type == schema.GRUP:
            head = schema.GroupHead3.parse(chunk.payload)
            body, level = bytes(head.body), records.SHELL_TREE_LEVEL if head.kind in TREE_KINDS else 9
            raw = records.unpack(head.compression, body, head.raw_size, Limits(), 4)
        elif chunk.type == schema.PLNS:
            head = schema.PlaneBlock3.parse(chunk.payload)
            body, level = bytes(head.data), 9
            raw = records.unpack(head.compression, body, head.raw_size, Limits(), 4)
        else:
            continue
        stored += len(body)
        deflated += min(len(raw), len(zlib.compress(raw, level)))
    return stored, deflated


def main(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--tolerance", type=float, default=3e-5)
    parser.add_argument("paths", nargs="*")
    args = parser.parse_args(argv)
    paths = args.paths or sorted(os.path.relpath(os.path.join(d, f), CORPUS)
                                 for d, _, files in os.walk(CORPUS) for f in files
                                 if f.lower().endswith(MESH_SUFFIXES))
    savings: dict[str, list[float]] = {}
    print(f"tolerance {args.tolerance:g} of the bbox diagonal; bytes: file | PLNS+GRUP payloads deflate-only -> "
          f"as written (deflate or Brotli) | saving of the file")
    for rel in paths:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            scene, _, _ = load(os.path.join(CORPUS, rel))
            buf = io.BytesIO()
            codec.encode_scene(scene, buf, tolerance=args.tolerance)
        data = buf.getvalue()
        stored, deflated = payload_bytes(data)
        saving = (deflated - stored) / (len(data) + deflated - stored)
        savings.setdefault(rel.split("/")[0], []).append(saving)
        print(f"{rel:40s} {len(data):9,d} | {deflated:9,d} -> {stored:9,d} | {100 * saving:5.1f} %", flush=True)
    every = [s for v in savings.values() for s in v]
    for name, values in [*savings.items(), ("all", every)]:
        print(f"median saving {name:22s} {100 * statistics.median(values):5.1f} %  ({len(values)} meshes)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
