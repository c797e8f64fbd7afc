"""Non-convex solids and open surfaces as planes: the corpus table, CAD throughput, bun_zipper.

For every corpus mesh (or the paths given): the kind chosen per body, the
part groups, the distinct planes, their size (12 bytes per plane as float32,
24 as float64) and the group records' size (spec §9, with chunk
framing), the certified two-sided Hausdorff bound between decoded and source
surface relative to the bbox diagonal, the structural checks (watertight
inputs: decoded closed 2-manifold, volume, Euler characteristic; open
inputs: area), and encode / decode / measure times. Encoding uses float64
planes (the lossless coding); the codec's coding choice is not part of this
bench.

Loading: through the project's converters (``registry.read``, scene
flattened to world coordinates), then vertices merged by exact position.

Usage::

    python bench/bench_nonconvex.py                 # whole corpus, table + summary
    python bench/bench_nonconvex.py --cad           # encode/decode throughput on corpus/cad
    python bench/bench_nonconvex.py --bunny         # bun_zipper.ply, the 60 s budget
    python bench/bench_nonconvex.py FILE ...
"""

from __future__ import annotations

import argparse
import glob
import math
import os
import sys
import time
import warnings

import numpy as np

from planefmt.groups.bodies import MeshGroups, decode_groups, encode_groups
from planefmt.geometry.topology import euler_characteristic, is_closed_manifold, signed_volume
from planefmt.geometry.hausdorff import hausdorff
from planefmt.model import GroupKind
from planefmt.geometry.polygonize import weld

CORPUS = os.path.join(os.path.dirname(__file__), "..", "tests", "corpus")
TOLERANCE = 1e-6
#: Budget of the certified Hausdorff measure per mesh (pieces); beyond it the bound is reported
#: uncertified.
MEASURE_PIECES = 400_000


def load(path: str) -> tuple[np.ndarray, np.ndarray]:
    """A corpus mesh as ``(vertices, faces)`` in world coordinates, vertices merged by exact position.

    Through the project's own readers, as ``pln convert`` reads it (``trimesh.load`` needs PIL
    for the textured OBJ and PLY files of the corpus).
    """
    from planefmt_converters import registry
    from planefmt_converters.assemble import flatten

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene, _ = registry.read(path)
    mesh = flatten(scene)
    return weld(mesh.vertices, mesh.faces)


def corpus_files() -> list[str]:
    files = sorted(glob.glob(os.path.join(CORPUS, "*", "*")))
    return [f for f in files if not f.endswith((".md", ".bin"))]


def group_bytes(enc: MeshGroups) -> int:
    """Bytes of the GRUP chunks (spec §4.1, Appendix A.1): framing 12, head 16, refs, roles, kind data."""
    total = 0
    for g in enc.groups:
        m = len(g.refs)
        body = 4 + 4 * m + (m + 7) // 8
        if g.kind == GroupKind.BSP:
            body += 4 + 4 * len(g.tree)
        total += 12 + 16 + body
    return total


def area(v: np.ndarray, f: np.ndarray) -> float:
    return float(0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum())


def run(path: str) -> dict:
    """Encode, decode, measure one mesh; a row of the table."""
    v0, f0 = load(path)
    row: dict = {"file": os.path.relpath(path, CORPUS), "triangles": len(f0)}
    t0 = time.perf_counter()
    enc = encode_groups(v0, f0, tolerance=TOLERANCE)
    t1 = time.perf_counter()
    dv, df = decode_groups(enc.omega, enc.h, enc.groups)
    t2 = time.perf_counter()
    v, f = enc.vertices, enc.faces
    diag = float(np.linalg.norm(np.ptp(v[np.unique(f)], axis=0)))
    h = hausdorff(dv, df, v, f, target=TOLERANCE * diag, max_pieces=MEASURE_PIECES)
    t3 = time.perf_counter()
    kinds: dict[str, int] = {}
    for r in enc.reports:
        kinds[r.kind] = kinds.get(r.kind, 0) + 1
    groups: dict[str, int] = {}
    for g in enc.groups:
        name = GroupKind(g.kind).name.lower()
        groups[name] = groups.get(name, 0) + 1
    closed_in = is_closed_manifold(f, len(v))
    row.update(kinds=kinds, groups=groups, planes=len(enc.h), f32=12 * len(enc.h), f64=24 * len(enc.h),
               structure=group_bytes(enc), h_lower=h.lower / diag, h_upper=h.upper / diag,
               certified=h.certified, encode_s=t1 - t0, decode_s=t2 - t1, measure_s=t3 - t2,
               closed_in=closed_in, notes=[r.note for r in enc.reports if r.note])
    if closed_in:
        vs = signed_volume(v, f)
        row.update(closed_out=is_closed_manifold(df, len(dv)),
                   volume=abs(signed_volume(dv, df) - vs) / abs(vs) if vs else math.nan,
                   chi=(euler_characteristic(df), euler_characteristic(f)))
    a = area(v, f)
    row["area"] = abs(area(dv, df) - a) / a
    return row


def print_row(r: dict) -> None:
    # A bound the measure could not certify within its budget is reported as such (marked "?"),
    # not as a failure; a lower bound above the tolerance is one.
    ok = r["h_lower"] <= TOLERANCE and (not r["certified"] or r["h_upper"] <= TOLERANCE)
    checks = f"area {r['area']:.0e}"
    if r["closed_in"]:
        checks = (f"closed {'y' if r['closed_out'] else 'N'} vol {r['volume']:.0e} "
                  f"chi {r['chi'][0]}/{r['chi'][1]} " + checks)
    kinds = " ".join(f"{k}:{n}" for k, n in r["kinds"].items())
    groups = " ".join(f"{k}:{n}" for k, n in r["groups"].items())
    print(f"| {r['file']} | {r['triangles']} | {kinds} | {groups} | {r['planes']} | {r['f32']} | {r['f64']} | "
          f"{r['structure']} | {(r['f32'] + r['structure']) / r['triangles']:.1f} | "
          f"[{r['h_lower']:.1e}, {r['h_upper']:.1e}]{'' if r['certified'] else '?'}{'' if ok else ' FAIL'} | "
          f"{checks} | {r['encode_s']:.1f} | {r['decode_s']:.1f} | {r['measure_s']:.1f} |", flush=True)


HEADER = ("| mesh | triangles | bodies by kind | groups | planes | f32 B | f64 B | group B | B/tri (f32) | "
          "Hausdorff/diag [lower, upper] | checks | enc s | dec s | measure s |\n"
          "|---|---:|---|---|---:|---:|---:|---:|---:|---|---|---:|---:|---:|")


def throughput(files: list[str]) -> None:
    """Encode and decode throughput (input triangles per second) on the given meshes."""
    total_t = enc_s = dec_s = 0.0
    for path in files:
        v, f = load(path)
        t0 = time.perf_counter()
        enc = encode_groups(v, f, tolerance=TOLERANCE)
        t1 = time.perf_counter()
        decode_groups(enc.omega, enc.h, enc.groups)
        t2 = time.perf_counter()
        total_t += len(f)
        enc_s += t1 - t0
        dec_s += t2 - t1
        print(f"{os.path.basename(path)}: {len(f)} triangles, encode {len(f) / (t1 - t0):,.0f}/s, "
              f"decode {len(f) / (t2 - t1):,.0f}/s", flush=True)
    print(f"all: encode {total_t / enc_s:,.0f} triangles/s, decode {total_t / dec_s:,.0f} triangles/s")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*")
    ap.add_argument("--cad", action="store_true", help="throughput on the corpus CAD meshes")
    ap.add_argument("--bunny", action="store_true", help="bun_zipper.ply encode + decode time")
    args = ap.parse_args(argv)
    if args.cad:
        throughput(sorted(glob.glob(os.path.join(CORPUS, "cad", "*"))))
        return 0
    if args.bunny:
        path = os.path.join(CORPUS, "smooth_dense", "bun_zipper.ply")
        v, f = load(path)
        t0 = time.perf_counter()
        enc = encode_groups(v, f, tolerance=TOLERANCE)
        t1 = time.perf_counter()
        decode_groups(enc.omega, enc.h, enc.groups)
        t2 = time.perf_counter()
        r = enc.reports[0]
        print(f"bun_zipper: {len(f)} triangles, {len(enc.groups)} groups, {len(enc.h)} planes; "
              f"encode {t1 - t0:.1f} s, decode {t2 - t1:.1f} s, total {t2 - t0:.1f} s (budget 60 s); {r.details}")
        return 0 if t2 - t0 < 60 else 1
    print(HEADER)
    failed = 0
    for path in args.files or corpus_files():
        try:
            row = run(path)
        except Exception as exc:  # noqa: BLE001 - a bench reports every failure and goes on
            failed += 1
            print(f"| {os.path.relpath(path, CORPUS)} | FAILED: {type(exc).__name__}: {exc} |", flush=True)
            continue
        print_row(row)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
