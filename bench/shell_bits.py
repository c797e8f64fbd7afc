"""Where a shell's bytes go on the corpus: version 3.2's layout (§9.10) against the shell trees of
versions 3.3 and 3.4 (§9.11, §9.12), 4.1's shell walk (§9.13) and 4.2's choice of it or the walk with
multi-parallelograms (§9.14, the default since), at draco-14's error, with draco-14 measured in the
same run (issues 30, 31).

For each mesh, at draco-14's measured error on it (``D14_ERROR``: the
certified measure of ``bench/compare.py``, as docs/benchmarks.md records it,
to two digits), the default encoder (``codec.encode_scene``, shell scheme,
deflate) writes the file four times: with version 3.2's shell layout only
(``planefmt.codec.choosing.SHELL_LAYOUTS = (GroupKind.SHELL,)``, what the encoder wrote before
3.3), with kinds 6 to 8 (a shell tree of kind 7 or 8 where smaller, labelled 3.4), with kinds 6 to 9
(a shell walk of kind 9 where smaller, labelled 4.1) and with its default choice (kind 9 or 10,
labelled 4.2). Printed per
mesh: triangles; draco-14's bytes (DracoPy, quantization 14, compression
level 10); each file's bytes, its ratio to draco-14 and its plane table's
bytes; bits per triangle of each field of the shell body, each field
compressed alone by Brotli at quality 11 (so the fields add up to a little
more than the body, which is compressed whole):

* 3.2: ``flags`` (explicit bits), ``planes`` (three references per named
  corner), ``grid`` (explicit corners as steps from the previous one),
  ``faces`` (face references), ``codes`` (3 corner codes per triangle);
* 3.4 (kinds 7 and 8 alike): ``links`` (each triangle's parent and edge), ``codes`` (a root's
  three corners, an attached triangle's third), ``faces`` (0 on the
  parent's plane), ``flags``, ``picks``, ``coordinates`` (residuals);
* 4.1 and 4.2 (kinds 9 and 10): ``symbols`` (each triangle's children and third corner's code), ``escapes`` (a
  root's codes, corner steps), ``faces``, ``flags``, ``picks``, ``mode``, ``grid``, ``tables``,
  ``coordinates``; its connectivity (``symbols`` + ``escapes``) against 3.4's (``links`` +
  ``codes``) is printed in bits per triangle;

named corners of all corners; the tree's depth (its longest chain of
parents) and the pointer-jumping rounds that take a reader through it; and
encode (the whole ``encode_scene``) and decode (``decode_scene``) seconds.
The last line gives the CAD medians of the ratios to draco-14.

Usage: ``python bench/shell_bits.py [paths relative to the corpus]``
"""

from __future__ import annotations

import io
import math
import os
import statistics
import sys
import time

import brotli

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from compare import CORPUS, load, pln_parts  # noqa: E402

import planefmt  # noqa: E402
from planefmt import codec  # noqa: E402
from planefmt.codec import choosing  # noqa: E402
from planefmt.container import shellfields, shellwalk, varint  # noqa: E402
from planefmt.model import FREE, GroupKind  # noqa: E402
from planefmt.container.shellfields import corner_codes  # noqa: E402

#: Draco-14's measured error (fraction of the bbox diagonal), from docs/benchmarks.md (2 digits).
D14_ERROR = {
    "cad/1002_tray_bottom.STL": 2.9e-05, "cad/20mm-xyz-cube.stl": 2.4e-05, "cad/ADIS16480.STL": 3.3e-05,
    "cad/angle_block.STL": 2.8e-05, "cad/box.STL": 3.9e-05, "cad/featuretype.STL": 4.1e-05,
    "cad/octagonal_pocket.stl": 3.7e-05, "cad/plate_holes.STL": 3.7e-05,
    "nonconvex_watertight/torus.STL": 3.2e-05, "nonconvex_watertight/fuze.obj": 3.8e-05,
    "open/suzanne.ply": 3.2e-05, "smooth_dense/npm_bunny.ply": 3.0e-05,
}


def shell_fields(group) -> dict[str, bytes]:
    """The fields of a shell group's kind data by name: spec §9.10's, §9.11's, §9.12's or §9.13's."""
    shell = group.shell
    if group.kind in shellwalk.WALK_KINDS:
        return shellwalk.shell_walk_fields(shell, None, group.kind)
    if group.kind in (GroupKind.SHELL_TREE, GroupKind.SHELL_TREE_PARALLELOGRAM):
        return shellfields.shell_tree_fields(shell, group.kind == GroupKind.SHELL_TREE_PARALLELOGRAM)
    fc = np.asarray(shell.facets, dtype=np.int64)
    grid = np.asarray(shell.grid, dtype=np.int64).reshape(-1, 3)
    return {"flags": np.packbits(np.asarray(shell.explicit, dtype=bool), bitorder="little").tobytes(),
            "planes": varint.encode(np.asarray(shell.vertex_planes, dtype=np.uint64).reshape(-1)),
            "grid": varint.encode(varint.zigzag(np.diff(grid, axis=0, prepend=np.zeros((1, 3), dtype=np.int64)))),
            "faces": varint.encode(np.diff(fc[fc[:, 0] != FREE, 0], prepend=0)),
            "codes": varint.encode(corner_codes(fc[:, 1:]))}


def tree_depth(links: np.ndarray) -> int:
    """The longest chain of parents of a shell tree (a root's depth is 0)."""
    root = links == 0
    parent = np.where(root, -1, np.arange(len(links)) - ((links - 1) // 3 + 1))
    return int(shellfields.resolve_chains(np.zeros(len(links), dtype=np.int64), parent,
                                      (~root).astype(np.int64)).max())


def encoded(scene, tolerance: float, layouts: tuple[GroupKind, ...]) -> tuple[bytes, float, float]:
    """The file of ``scene`` with the encoder held to shell ``layouts``; encode and decode seconds."""
    before = choosing.SHELL_LAYOUTS
    choosing.SHELL_LAYOUTS = layouts
    try:
        t0 = time.perf_counter()
        buf = io.BytesIO()
        codec.encode_scene(scene, buf, tolerance=tolerance, compress=True, compact=True)
        t1 = time.perf_counter()
    finally:
        choosing.SHELL_LAYOUTS = before
    data = buf.getvalue()
    codec.decode_scene(io.BytesIO(data))
    return data, t1 - t0, time.perf_counter() - t1


def describe(data: bytes, triangles: int) -> dict:
    with planefmt.open(io.BytesIO(data)) as r:
        groups = [g for g in r.part_groups() if g.kind in codec.SHELL_KINDS]
    bits: dict[str, float] = {}
    for g in groups:
        for name, field in shell_fields(g).items():
            bits[name] = bits.get(name, 0.0) + 8.0 * (len(brotli.compress(field, quality=11)) if field else 0) / triangles
    trees = [g.shell.links for g in groups if g.kind in (GroupKind.SHELL_TREE, GroupKind.SHELL_TREE_PARALLELOGRAM,
                                                         *shellwalk.WALK_KINDS)]
    depth = max(map(tree_depth, trees), default=0)
    return dict(bytes=len(data), planes=pln_parts(data)["planes"], bits=bits,
                named=sum(int((~np.asarray(g.shell.explicit)).sum()) for g in groups),
                corners=sum(len(g.shell.explicit) for g in groups), depth=depth,
                rounds=math.ceil(math.log2(depth + 1)) + 1 if trees else 0)


#: The shell kinds of versions 3.2 to 3.4 (spec §9.10 to §9.12).
LAYOUTS_3_4 = (GroupKind.SHELL, GroupKind.SHELL_TREE, GroupKind.SHELL_TREE_PARALLELOGRAM)


def measure(rel: str) -> dict:
    import DracoPy

    scene, v, f = load(os.path.join(CORPUS, rel))
    draco = len(DracoPy.encode(v, f, quantization_bits=14, compression_level=10))
    row = dict(mesh=rel, triangles=len(f), draco=draco)
    for name, layouts in (("3.2", (GroupKind.SHELL,)), ("3.4", LAYOUTS_3_4), ("4.1", LAYOUTS_3_4 + (GroupKind.SHELL_WALK,)),
                          ("4.2", codec.SHELL_KINDS)):
        data, enc, dec = encoded(scene, D14_ERROR[rel], layouts)
        row[name] = dict(describe(data, len(f)), encode=enc, decode=dec)
    return row


def main(argv: list[str]) -> int:
    rows = []
    for rel in argv or list(D14_ERROR):
        r = measure(rel)
        rows.append(r)
        print(f"{r['mesh']}: {r['triangles']} triangles, draco-14 {r['draco']} B", flush=True)
        for name in ("3.2", "3.4", "4.1", "4.2"):
            x = r[name]
            fields = " ".join(f"{k} {b:.1f}" for k, b in x["bits"].items())
            b = x["bits"]
            fields += f"; connectivity {b.get('symbols', 0) + b.get('escapes', 0) + b.get('links', 0) + b.get('codes', 0):.1f}"
            print(f"  {name}: {x['bytes']} B ({x['bytes'] / r['draco']:.2f}x draco-14; planes {x['planes']} B); "
                  f"bits/triangle {fields}; named {x['named']}/{x['corners']}; depth {x['depth']} "
                  f"({x['rounds']} rounds); encode {x['encode']:.1f} s, decode {x['decode']:.3f} s", flush=True)
    cad = [r for r in rows if r["mesh"].startswith("cad/")]
    if cad:
        print("CAD median pln@d14 / draco-14: " + ", ".join(
            f"{name} {statistics.median(r[name]['bytes'] / r['draco'] for r in cad):.2f}" for name in ("3.2", "3.4", "4.1", "4.2")))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
