"""What shell walks with reflections (kind 12, spec §9.16) save on the corpus at Draco-14's error.

For each corpus mesh, at the draco-14 error ``docs/benchmarks.md`` records for it (two digits), the
default encoder writes the file twice: as it does (kinds 9, 10 and 12 to choose from) and with kind 12
left out of the encoder's shell layouts (``choosing.SHELL_LAYOUTS``: the file a 5.0 writer made).
Printed per mesh: the walk groups' tables and coordinates in each of kinds 9, 10 and 12, each in its
smallest mode (Brotli at quality 11 of the fields, as ``shell_walk_fields`` builds them, summed over the
groups of the file written), the share of explicit corners whose chain turns, both files, and both
over draco-14's bytes; then the category medians of both ratios, and over the whole corpus, as
``docs/benchmarks.md`` takes them.

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
from compare import CATEGORIES, corpus_files, load  # noqa: E402

import planefmt  # noqa: E402
from planefmt import codec  # noqa: E402
from planefmt.codec import choosing  # noqa: E402
from planefmt.container import shellwalk  # noqa: E402
from planefmt.container.shellfields import MAX_TURN, _chains_of, _tree_predictors, code_stream  # noqa: E402
from planefmt.model import GroupKind  # noqa: E402

KINDS = (GroupKind.SHELL_WALK, GroupKind.SHELL_WALK_MULTI, GroupKind.SHELL_WALK_REFLECT)


def draco14(path: str) -> dict[str, tuple[int, float]]:
    """Each mesh's draco-14 bytes and measured error from ``docs/benchmarks.md``'s per-mesh table."""
    out = {}
    for line in open(path, encoding="utf-8"):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 11 and "/" in cells[0] and cells[0] not in out and cells[3][:1].isdigit():
            size, _, error = cells[3].split()
            out[cells[0]] = (int(size.replace(",", "")), float(error))
    return out


def _encoded(scene, tolerance: float, reflections: bool) -> bytes:
    saved = choosing.SHELL_LAYOUTS
    if not reflections:
        choosing.SHELL_LAYOUTS = tuple(k for k in saved if k != GroupKind.SHELL_WALK_REFLECT)
    try:
        buf = io.BytesIO()
        codec.encode_scene(scene, buf, tolerance=tolerance)
        return buf.getvalue()
    finally:
        choosing.SHELL_LAYOUTS = saved


def _turning(shell) -> tuple[int, int]:
    """How many of ``shell``'s explicit corners have a chain that turns (spec §9.16), of how many."""
    explicit = np.asarray(shell.explicit, dtype=bool)
    tri = np.asarray(shell.facets, dtype=np.int64)[:, 1:]
    links = np.asarray(shell.links, dtype=np.int64)
    _, new, _ = code_stream(tri, links == 0)
    step = _tree_predictors(links, tri, explicit, np.where(links == 0, 3, 1), new)[:, 0]
    a, b, c = _chains_of(step)
    g = np.zeros((len(explicit), 3), dtype=np.int64)
    g[explicit] = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)
    d1, d2 = g[b] - g[c], g[a] - g[b]
    turns = explicit & (c >= 0) & (np.abs(np.c_[d1, d2]).max(axis=1) <= MAX_TURN) & (np.abs(d2).sum(axis=1) > 0)
    return int(turns.sum()), int(explicit.sum())


def measure(path: str, tolerance: float) -> dict:
    scene, _, _ = load(path)
    written = _encoded(scene, tolerance, True)
    without = _encoded(scene, tolerance, False)
    sizes = dict.fromkeys(KINDS, 0)
    turned = corners = 0
    with planefmt.open(io.BytesIO(written)) as r:
        for group in r.part_groups():
            if group.kind not in shellwalk.WALK_KINDS or group.source is not None or not group.shell.explicit.any():
                continue
            for kind in KINDS:
                sizes[kind] += min(len(brotli.compress(f["tables"] + f["coordinates"], quality=11))
                                   for f in (shellwalk.shell_walk_fields(group.shell, m, kind)
                                             for m in shellwalk.MODES))
            t, e = _turning(group.shell)
            turned += t
            corners += e
    return dict(file=len(written), without=len(without), sizes=sizes, turning=turned / corners if corners else 0.0)


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--benchmarks", default=os.path.join(os.path.dirname(__file__), "..", "docs", "benchmarks.md"))
    args = ap.parse_args(argv)
    peers = draco14(args.benchmarks)
    before: dict[str, list[float]] = {}
    after: dict[str, list[float]] = {}
    print("| mesh | kind 9 B | kind 10 B | kind 12 B | turning | without kind 12 B | written B | draco-14 B | "
          "ratio without | ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for folder, path in corpus_files(list(CATEGORIES)):
        name = f"{CATEGORIES[folder]}/{os.path.basename(path)}"
        if name not in peers:
            continue
        draco, error = peers[name]
        row = measure(path, error)
        r0, r1 = row["without"] / draco, row["file"] / draco
        for table, r in ((before, r0), (after, r1)):
            table.setdefault(CATEGORIES[folder], []).append(r)
            table.setdefault("all", []).append(r)
        s = row["sizes"]
        print(f"| {name} | {s[KINDS[0]]:,} | {s[KINDS[1]]:,} | {s[KINDS[2]]:,} | {row['turning']:.2f} | "
              f"{row['without']:,} | {row['file']:,} | {draco:,} | {r0:.3f} | {r1:.3f} |", flush=True)
    print()
    print("| category | meshes | median ratio without kind 12 | median ratio |")
    print("|---|---|---|---|")
    for category in list(dict.fromkeys(CATEGORIES.values())) + ["all"]:
        if category in before:
            print(f"| {category} | {len(before[category])} | {statistics.median(before[category]):.3f} | "
                  f"{statistics.median(after[category]):.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
