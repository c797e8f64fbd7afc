"""Convex decoding throughput of planefmt against DracoPy, measured in the same run.

``python bench/bench_convex_decode.py [--quick]``

Method. Each mesh (the corpus's convex meshes, and random hulls of 10,000
and 50,000 points on a sphere, where every point is a vertex and nearly
every triangle a plane: about 20,000 and 100,000 planes) is encoded once
into an in-memory .pln file, the corpus meshes with
``planefmt.codec.encode_scene`` at the default lossless tolerance (1e-6 of
the diagonal), the hulls as their polygon planes in float32 (see
``write_pln``), and once with DracoPy at 14-bit quantization. Timed, best
of several repeats on one thread, after a warm-up:

* ``pln geometry``: ``codec.decode_mesh`` from the plane triplets a reader
  returns (half-space intersection to triangles);
* ``pln file``: ``codec.decode_scene`` from the file bytes (reading, CRC
  checks, dequantization and decoding);
* ``draco``: ``DracoPy.decode`` of the Draco bytes.

Throughput is output triangles per second. Planes decode to the merged
polygons' triangles, so a mesh whose faces are polygons (a subdivided cube:
3072 triangles, 6 planes) gives far fewer triangles than Draco's; the ratio
of times for the same surface is printed too. Goal from issue 3: a
triangles-per-second ratio of at least 0.5.
"""

from __future__ import annotations

import argparse
import io
import os
import platform
import sys
import time
from pathlib import Path

from importlib.metadata import version

import numpy as np
import scipy

import planefmt
from planefmt import codec
from planefmt.container import quantize
from planefmt.model import Coding, GroupKind, Header, Mesh, Node, Scene
from planefmt.geometry.polygonize import polygonize

try:
    import DracoPy
except ImportError:  # the bench extra: pip install planefmt[bench]
    DracoPy = None

CORPUS = Path(__file__).resolve().parents[1] / "tests" / "corpus"


def best_time(fn, budget: float) -> float:
    """Best wall time (s) of ``fn()`` over repeats filling about ``budget`` seconds."""
    fn()
    best = float("inf")
    spent = 0.0
    runs = 0
    while runs < 3 or spent < budget:
        t = time.perf_counter()
        fn()
        dt = time.perf_counter() - t
        best = min(best, dt)
        spent += dt
        runs += 1
        if runs >= 200:
            break
    return best


def sphere_hull(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    from scipy.spatial import ConvexHull

    pts = np.random.default_rng(seed).normal(size=(n, 3))
    pts /= np.linalg.norm(pts, axis=1)[:, None]
    hull = ConvexHull(pts)
    faces = hull.simplices.copy()
    normals = np.cross(pts[faces[:, 1]] - pts[faces[:, 0]], pts[faces[:, 2]] - pts[faces[:, 0]])
    flip = np.einsum("ij,ij->i", normals, hull.equations[:, :3]) < 0
    faces[flip] = faces[flip][:, ::-1]
    return pts, faces


def meshes(quick: bool) -> list[tuple[str, np.ndarray, np.ndarray, bool]]:
    """``(name, vertices, faces, verified)``: verified meshes go through the encoder."""
    import trimesh

    out = []
    for path in sorted((CORPUS / "convex").glob("*")):
        m = trimesh.load(path, process=True, force="mesh")
        out.append((path.name, np.asarray(m.vertices, float), np.asarray(m.faces), True))
    out.append(("sphere hull 10k pts", *sphere_hull(10_000, 1), False))
    if not quick:
        out.append(("sphere hull 50k pts", *sphere_hull(50_000, 2), False))
    return out


def write_pln(name: str, v: np.ndarray, f: np.ndarray, verified: bool) -> tuple[bytes, Header]:
    """The .pln bytes of one mesh: through the encoder, or its polygon planes written as float32.

    The big hulls skip the encoder's verification: certifying the Hausdorff
    distance of 20,000-100,000 triangles takes longer than this bench.
    """
    sink = io.BytesIO()
    if verified:
        header = codec.encode_scene(Scene(nodes=(Node(name, None, None, Mesh(v, f)),)), sink)
        return sink.getvalue(), header
    poly = polygonize(v, f)
    header = Header(coding=Coding.FLOAT32, bbox=np.stack([v.min(axis=0), v.max(axis=0)]), tolerance=1e-6)
    with planefmt.Writer(sink, header) as w:
        obj = w.add_object(name)
        w.add_planes(poly.triplets)
        w.add_group(obj, GroupKind.CONVEX, np.arange(len(poly.h)))
    return sink.getvalue(), header


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller meshes and time budget")
    args = ap.parse_args(argv)
    if DracoPy is None:
        print("DracoPy is not installed (pip install planefmt[bench])", file=sys.stderr)
        return 2
    budget = 0.2 if args.quick else 1.0
    print(f"machine: {platform.machine()} {platform.processor() or ''}, {os.cpu_count()} cores, "
          f"{platform.system()} {platform.release()}; Python {platform.python_version()}, numpy "
          f"{np.__version__}, scipy {scipy.__version__} (Qhull), DracoPy {version('DracoPy')}, "
          f"planefmt {planefmt.__version__}")
    print("method: best of repeats (>= 3, ~%.1f s each), one thread, warm; pln at tolerance 1e-6 "
          "(coding chosen by the encoder), Draco at 14 bits; Mt/s = million output triangles/s" % budget)
    print()
    head = (f"{'mesh':22} {'planes':>7} {'coding':>14} {'pln tris':>8} {'draco tris':>10} "
            f"{'pln geom Mt/s':>13} {'pln file Mt/s':>13} {'draco Mt/s':>10} {'ratio t/s':>9} "
            f"{'ratio time':>10}")
    print(head)
    ratios = []
    for name, v, f, verified in meshes(args.quick):
        data, header = write_pln(name, v, f, verified)
        with planefmt.open(io.BytesIO(data)) as r:
            groups = list(r.part_groups())
            table = r.planes.copy()
        out = codec.decode_mesh(table, groups, header=header)
        t_geom = best_time(lambda t=table, g=groups, hd=header: codec.decode_mesh(t, g, header=hd), budget)
        t_file = best_time(lambda b=data: codec.decode_scene(io.BytesIO(b)), budget)
        drc = DracoPy.encode(v.astype(np.float32), f.astype(np.uint32), quantization_bits=14)
        d_tris = len(DracoPy.decode(drc).faces)
        t_draco = best_time(lambda b=drc: DracoPy.decode(b), budget)
        tps_geom, tps_file, tps_draco = len(out.faces) / t_geom, len(out.faces) / t_file, d_tris / t_draco
        ratio = tps_file / tps_draco
        ratios.append(ratio)
        coding = header.coding.name.lower()
        if header.quantization is not None:
            q = header.quantization
            coding = f"q{q.bits_nu}/{q.bits_phi}/{q.bits_h}"
        name += "" if verified else " *"
        print(f"{name[:22]:22} {len(table):7d} {coding:>14} {len(out.faces):8d} {d_tris:10d} "
              f"{tps_geom / 1e6:13.3f} {tps_file / 1e6:13.3f} {tps_draco / 1e6:10.3f} {ratio:9.3f} "
              f"{t_draco / t_file:10.3f}   ({len(data)} B pln, {len(drc)} B draco, "
              f"payload {quantize.payload_size(len(table), header.coding, header.quantization)} B)")
    print()
    print("* written without the encoder's verification (see write_pln)")
    print(f"triangles/s ratio pln file / draco: min {min(ratios):.3f}, geometric mean "
          f"{float(np.exp(np.mean(np.log(ratios)))):.3f} (goal >= 0.5)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
