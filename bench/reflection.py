"""What a shell walk predicting its corners by circle-continuing reflection would save on the corpus at
Draco-14's error: a measurement for a coding not in the format (issue 31's closing note, stop 45).

For each corpus mesh, at the draco-14 error ``docs/benchmarks.md`` records for it (two digits), the
default encoder writes the file; each of its walk groups (kinds 9 and 10) whose corners are all
explicit has its coordinates predicted again, in grid values, as the candidate coding would: corner
k from a, b, c, the step sources of k, a and b (spec §9.11's p, the corner k's coordinates are a
step from),

    d1 = b - c, d2 = a - b, D = d2·d2,
    prediction = a + floor((2N + D) / (2D)),  N = 2 (d1·d2) d2 - D d1   (per axis; half rounds up),

a step d2 rotated on from the step d1 by the angle between them: exact on a regular polygon (a
tessellated circle walked round), in integers, used where the chain exists, D > 0 and every component
of d1 and d2 is within 2^18 (so that every product fits a signed 64-bit integer), else the step
a + 0. Printed per mesh: the written walk's tables and coordinates (``shell_bits.shell_fields``, Brotli
at quality 11, as the writer compresses), the same corners' residuals under the reflection (zigzag
varints, every x, then y, then z, Brotli 11), the share of corners with a chain, the file, the file a
writer choosing the smaller of the two per group would make (an estimate: fields compressed alone, as
here, sum to a little more than a body compressed whole), and both over draco-14's bytes; then the
category medians of both ratios, and over the whole corpus, as ``docs/benchmarks.md`` takes them.

Usage: ``python bench/reflection.py [--benchmarks docs/benchmarks.md]``
"""

from __future__ import annotations

import argparse
import io
import os
import statistics
import sys

import brotli

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from compare import CATEGORIES, CORPUS, corpus_files, load  # noqa: E402
from shell_bits import shell_fields  # noqa: E402

import planefmt  # noqa: E402
from planefmt import codec  # noqa: E402
from planefmt.container import shellwalk, varint  # noqa: E402
from planefmt.container.shellfields import _tree_predictors, code_stream  # noqa: E402

#: The largest component of a step the reflection takes (beyond it, the step predicts).
REFLECTION_LIMIT = 2 ** 18


def reflection(values: np.ndarray, source: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each corner's prediction (V, 3) from the grid ``values`` (V, 3) and each corner's step
    ``source`` (-1: none), and whether it had a chain."""
    g2 = np.where(source >= 0, source[np.maximum(source, 0)], -1)
    g3 = np.where(g2 >= 0, source[np.maximum(g2, 0)], -1)
    a, b, c = (values[np.maximum(x, 0)] for x in (source, g2, g3))
    d1, d2 = b - c, a - b
    d = (d2 * d2).sum(axis=1)
    chain = (g3 >= 0) & (d > 0) & (np.abs(d1).max(axis=1) <= REFLECTION_LIMIT) \
        & (np.abs(d2).max(axis=1) <= REFLECTION_LIMIT)
    den = np.where(chain, d, 1)[:, None]
    num = 2 * (d1 * d2).sum(axis=1)[:, None] * d2 - den * d1
    return np.where(chain[:, None], a + np.floor_divide(2 * num + den, 2 * den), a), chain


def _brotli(data: bytes) -> int:
    return len(brotli.compress(bytes(data), quality=11))


def draco14(path: str) -> dict[str, tuple[int, float]]:
    """Each mesh's draco-14 bytes and measured error from ``docs/benchmarks.md``'s per-mesh table."""
    out = {}
    for line in open(path, encoding="utf-8"):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 11 and "/" in cells[0] and cells[0] not in out and cells[3][:1].isdigit():
            size, _, error = cells[3].split()
            out[cells[0]] = (int(size.replace(",", "")), float(error))
    return out


def measure(path: str, tolerance: float) -> dict:
    scene, _, _ = load(path)
    buf = io.BytesIO()
    codec.encode_scene(scene, buf, tolerance=tolerance)
    written = candidate = corners = chained = 0
    with planefmt.open(io.BytesIO(buf.getvalue())) as r:
        for group in r.part_groups():
            if group.kind not in shellwalk.WALK_KINDS or group.source is not None:
                continue
            shell = group.shell
            explicit = np.asarray(shell.explicit, dtype=bool)
            if not explicit.all():
                continue
            fields = shell_fields(group)
            tri = np.asarray(shell.facets, dtype=np.int64)[:, 1:]
            links = np.asarray(shell.links, dtype=np.int64)
            values = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)
            _, new, _ = code_stream(tri, links == 0)
            step = _tree_predictors(links, tri, explicit, np.where(links == 0, 3, 1), new, False)
            prediction, chain = reflection(values, step[:, 0])
            before = _brotli(fields["tables"] + fields["coordinates"])
            after = _brotli(varint.encode(varint.zigzag((values - prediction).T)))
            written += before
            candidate += min(before, after)
            corners += len(values)
            chained += int(chain.sum())
    size = len(buf.getvalue())
    return dict(file=size, written=written, candidate=candidate, estimate=size - written + candidate,
                chained=chained / corners if corners else 0.0)


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--benchmarks", default=os.path.join(os.path.dirname(__file__), "..", "docs", "benchmarks.md"))
    args = ap.parse_args(argv)
    peers = draco14(args.benchmarks)
    labels = {folder: label for folder, label in CATEGORIES.items()}
    before: dict[str, list[float]] = {}
    after: dict[str, list[float]] = {}
    print("| mesh | walk corners written B | smaller with reflection B | chains | file B | estimate B | draco-14 B | ratio | estimate ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    for folder, path in corpus_files(list(CATEGORIES)):
        name = f"{labels[folder]}/{os.path.basename(path)}"
        if name not in peers:
            continue
        draco, error = peers[name]
        row = measure(path, error)
        r0, r1 = row["file"] / draco, row["estimate"] / draco
        for table, r in ((before, r0), (after, r1)):
            table.setdefault(labels[folder], []).append(r)
            table.setdefault("all", []).append(r)
        print(f"| {name} | {row['written']:,} | {row['candidate']:,} | {row['chained']:.2f} | {row['file']:,} | "
              f"{row['estimate']:,} | {draco:,} | {r0:.3f} | {r1:.3f} |", flush=True)
    print()
    print("| category | meshes | median ratio | median estimate ratio |")
    print("|---|---|---|---|")
    for category in list(dict.fromkeys(labels.values())) + ["all"]:
        if category in before:
            print(f"| {category} | {len(before[category])} | {statistics.median(before[category]):.3f} | "
                  f"{statistics.median(after[category]):.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
