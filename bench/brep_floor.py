"""What a boundary-representation part group could cost: the faces, corners and dual mesh of CAD meshes.

A BSP group lists a convex decomposition's planes, each plane as often as
pieces it bounds (2 to 4 times on the corpus's CAD meshes). A boundary
representation on the same planes would store only which faces meet at
each corner: a corner on exactly three faces is their planes' meeting point,
so it needs no coordinates and no plane triple of its own. This script
measures what that information is on each mesh, for a future part-group kind
to be weighed against:

* *faces*: connected regions of triangles on one plane (the planes of
  ``planefmt.geometry.polygonize`` at half the tolerance, as the encoder takes them;
  a plane can hold several faces);
* *corners*: vertices on three or more faces, by the number of faces; a
  vertex on one or two faces (inside a face, on a straight edge) is not a
  corner, since a boundary representation leaves it out;
* the *dual mesh*: one vertex per face, one polygon per corner (its faces in
  order around it, fanned into triangles): a trivalent solid's dual is a
  triangulation with one triangle per corner; its bytes through Draco at
  1-bit quantization (DracoPy, compression level 10) are about what a
  Draco-class connectivity coder spends on it, beside the same figure for
  the mesh's own triangles (``bench/compare.py``'s ``draco_connectivity``).

Draco's figures include its header and 1-bit positions (a few dozen
bytes). They estimate a coding that does not exist yet; they are not a
measurement of a pln file.

Usage::

    python bench/brep_floor.py                          # the corpus's cad/ meshes, tolerance 3e-5
    python bench/brep_floor.py --tolerance 1e-4 FILE ...
"""

from __future__ import annotations

import argparse
import glob
import os
import sys

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from compare import CORPUS, load  # noqa: E402

from planefmt.geometry.polygonize import COPLANAR_TOLERANCE, edge_adjacency, polygonize  # noqa: E402
from planefmt.geometry.repair import merge_close_vertices  # noqa: E402


def faces_of(v: np.ndarray, f: np.ndarray, tolerance: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Welded vertices, triangles, each triangle's face label and the number of planes."""
    diag = float(np.linalg.norm(np.ptp(v[np.unique(f)], axis=0)))
    v, f, _, _ = merge_close_vertices(v, f, 1e-3 * tolerance * diag)
    poly = polygonize(v, f, tolerance=min(COPLANAR_TOLERANCE, tolerance / 2))
    e = edge_adjacency(poly.faces, len(poly.vertices))
    ta, tb = e.a // 3, e.b // 3
    same = poly.face_plane[ta] == poly.face_plane[tb]
    m = len(poly.faces)
    _, label = connected_components(coo_matrix((np.ones(int(same.sum())), (ta[same], tb[same])), shape=(m, m)),
                                    directed=False)
    return poly.vertices, poly.faces, label, len(np.unique(poly.face_plane))


def corner_cycles(f: np.ndarray, label: np.ndarray, vertex_count: int) -> list[list[int]]:
    """For each fan of triangles around a vertex on three or more faces: its faces in order around it."""
    e = edge_adjacency(f, vertex_count)
    twin = np.full(3 * len(f), -1, dtype=np.int64)
    twin[e.a], twin[e.b] = e.b, e.a
    labels_at = np.unique(np.column_stack([f.reshape(-1), np.repeat(label, 3)]), axis=0)
    faces_per_vertex = np.bincount(labels_at[:, 0], minlength=vertex_count)
    corner = faces_per_vertex[f.reshape(-1)] >= 3
    seen = np.zeros(3 * len(f), dtype=bool)
    cycles = []
    for start in np.flatnonzero(corner):
        if seen[start]:
            continue
        ring, k = [], int(start)
        # Half-edge 3t + j leaves corner f[t, j]; the edge entering it in t is 3t + (j + 2) % 3, whose
        # twin leaves the corner in the next triangle of the fan.
        while not seen[k]:
            seen[k] = True
            ring.append(int(label[k // 3]))
            back = twin[3 * (k // 3) + (k % 3 + 2) % 3]
            if back < 0:
                break
            k = int(back)
        cycle = [x for i, x in enumerate(ring) if x != ring[i - 1]] or ring[:1]
        if len(cycle) >= 3:
            cycles.append(cycle)
    return cycles


def measure(path: str, tolerance: float) -> dict:
    import DracoPy

    _, v0, f0 = load(path)
    v, f, label, planes = faces_of(v0, f0, tolerance)
    cycles = corner_cycles(f, label, len(v))
    degree = np.array([len(c) for c in cycles])
    dual = np.array([[c[0], c[i], c[i + 1]] for c in cycles for i in range(1, len(c) - 1)], dtype=np.uint32)
    count = int(label.max()) + 1
    centre = np.zeros((count, 3))
    np.add.at(centre, label, v[f].mean(axis=1))
    centre /= np.bincount(label, minlength=count)[:, None]

    def draco(points: np.ndarray, triangles: np.ndarray) -> int:
        return len(DracoPy.encode(points.astype(np.float32), triangles.astype(np.uint32), quantization_bits=1,
                                  compression_level=10))

    return {"mesh": os.path.relpath(path, CORPUS), "triangles": len(f0), "planes": planes, "faces": count,
            "corners": len(cycles), "on 3": int((degree == 3).sum()), "on 4": int((degree == 4).sum()),
            "on 5+": int((degree >= 5).sum()), "dual triangles": len(dual), "dual": draco(centre, dual),
            "draco mesh": draco(v0, f0)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", help="meshes (default: the corpus's cad/ folder)")
    ap.add_argument("--tolerance", type=float, default=3e-5,
                    help="fraction of the diagonal (default 3e-5, about draco-14's error on the CAD meshes)")
    args = ap.parse_args(argv)
    files = args.files or sorted(glob.glob(os.path.join(CORPUS, "cad", "*")))
    print(f"`python bench/brep_floor.py --tolerance {args.tolerance:g}`\n")
    print("| mesh | triangles | planes | faces | corners | on 3 faces | on 4 | on 5+ | dual triangles "
          "| Draco 1-bit, dual B | Draco 1-bit, mesh B |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for path in files:
        r = measure(path, args.tolerance)
        print(f"| {r['mesh']} | {r['triangles']} | {r['planes']} | {r['faces']} | {r['corners']} | {r['on 3']} "
              f"| {r['on 4']} | {r['on 5+']} | {r['dual triangles']} | {r['dual']} | {r['draco mesh']} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
