"""Bytes of .pln at Draco's measured error, per mesh and per category: the headline ratio of
``bench/compare.py`` without its peers, timings and measures of .pln's own error (quick enough for the
bench corpus's 144 meshes in one sitting).

For each mesh (loaded, flattened and welded as ``bench/compare.py``'s ``load`` does):

* Draco at ``--bits`` (default 14; DracoPy, compression level 10): its bytes, and its error, the
  certified upper bound of the two-sided Hausdorff distance between its decoding and the source over the
  source's bbox diagonal (``relative_hausdorff(..., tolerance=MEASURE_GAP)``, as ``bench/compare.py``
  measures), cached in ``--cache`` (JSON, keyed by path and bits, with DracoPy's version: an entry of
  another version is measured again) so that a second run, of another planefmt, measures Draco once;
  ``bench/draco-errors.json`` holds the bench corpus's at 14 bits (DracoPy 2.2.0);
* .pln: ``planefmt.codec.encode_scene(scene, buf, tolerance=e)`` with e Draco's error (at least
  ``MEASURE_RESOLUTION``), its bytes. Its error is not measured again: the encoder certifies it by
  construction and records it (``error_bound`` ≤ tolerance, spec §5), and ``make test-slow`` checks
  the recorded bound against an independent measure over the corpus.

Printed: one row per mesh (triangles, Draco bytes and error, .pln bytes, ratio; a failure, timeout or a
recorded bound above the tolerance is reported and counts as infinitely large), then per category the
median ratio, how many meshes .pln is the smaller on, and the same over all. ``--json`` keeps the rows.

Usage::

    python bench/at_draco.py --corpus ../shared/bench-corpus --max-triangles 30000
    python bench/at_draco.py --corpus ../shared/bench-corpus --categories cad,usd --bits 11
"""

from __future__ import annotations

import argparse
import io
import json
import math
import multiprocessing
import os
import statistics
import sys
import time
import warnings

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
from compare import CORPUS, MEASURE_GAP, MEASURE_RESOLUTION, load  # noqa: E402


def _draco(path: str, bits: int) -> dict:
    import DracoPy

    from planefmt.geometry.hausdorff import relative_hausdorff

    _, v, f = load(path)
    data = DracoPy.encode(v, f, quantization_bits=bits, compression_level=10)
    back = DracoPy.decode(data)
    err = relative_hausdorff((v, f), (np.asarray(back.points, dtype=np.float64), np.asarray(back.faces, dtype=np.int64)),
                             tolerance=MEASURE_GAP).upper
    return {"triangles": int(len(f)), "draco": len(data), "error": float(err), "dracopy": _dracopy()}


def _dracopy() -> str:
    from importlib import metadata

    return metadata.version("DracoPy")


def _pln(path: str, tolerance: float) -> dict:
    from planefmt import codec

    scene, _, _ = load(path)
    buf = io.BytesIO()
    t = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        header = codec.encode_scene(scene, buf, tolerance=tolerance)
    return {"pln": len(buf.getvalue()), "seconds": time.perf_counter() - t,
            "bound": float(header.error_bound), "tolerance": tolerance}


def _in_child(fn, args, timeout: float) -> dict:
    """``fn(*args)`` in a forked child, so a crash or a timeout loses one row, not the run."""
    with multiprocessing.get_context("fork").Pool(1) as pool:
        try:
            return pool.apply_async(fn, args).get(timeout)
        except multiprocessing.TimeoutError:
            return {"failed": f"timeout after {timeout:g} s"}
        except Exception as err:  # noqa: BLE001 - a row reports any failure of the codec it measures
            return {"failed": f"{type(err).__name__}: {str(err)[:120]}"}


def _meshes(corpus: str, categories: list[str] | None) -> list[str]:
    out = []
    for cat in sorted(os.listdir(corpus)):
        folder = os.path.join(corpus, cat)
        if not os.path.isdir(folder) or (categories and cat not in categories):
            continue
        for name in sorted(os.listdir(folder)):
            path = os.path.join(folder, name)
            if name.endswith(".md"):
                continue
            if os.path.isdir(path):
                inner = [os.path.join(path, n) for n in sorted(os.listdir(path))
                         if n.lower().endswith((".gltf", ".glb", ".usd", ".usda", ".usdc", ".usdz", ".obj"))]
                if not inner:
                    continue
                path = inner[0]
            out.append(path)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--corpus", default=CORPUS)
    ap.add_argument("--categories", help="comma-separated folders of the corpus (default: all)")
    ap.add_argument("--bits", type=int, default=14, help="Draco's quantization bits (default 14)")
    ap.add_argument("--max-triangles", type=int, default=0, help="skip meshes with more triangles (0: none)")
    ap.add_argument("--cache", default=os.path.join(os.path.dirname(__file__), "draco-errors.json"),
                    help="Draco's bytes and errors by mesh and bits, measured again where DracoPy's version differs")
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per measurement (default 600)")
    ap.add_argument("--json", help="write the rows here")
    args = ap.parse_args(argv)
    cache = json.load(open(args.cache)) if os.path.exists(args.cache) else {}
    rows = []
    for path in _meshes(args.corpus, args.categories.split(",") if args.categories else None):
        rel = os.path.relpath(path, args.corpus)
        key = f"{rel}@{args.bits}"
        if key not in cache or cache[key].get("dracopy") != _dracopy():
            cache[key] = _in_child(_draco, (path, args.bits), args.timeout)
            with open(args.cache, "w") as fh:
                json.dump(cache, fh, indent=0, sort_keys=True)
        d = cache[key]
        row = {"mesh": rel, "category": rel.split(os.sep)[0], **d}
        if "failed" in d:
            print(f"{rel}: draco failed ({d['failed']})", flush=True)
            continue
        if args.max_triangles and d["triangles"] > args.max_triangles:
            continue
        p = _in_child(_pln, (path, max(d["error"], MEASURE_RESOLUTION)), args.timeout)
        row.update({"pln_" + k if k == "failed" else k: v for k, v in p.items()})
        ok = "pln" in p and p["bound"] <= p["tolerance"]
        row["ratio"] = p["pln"] / d["draco"] if ok else math.inf
        rows.append(row)
        print(f"{rel}: {d['triangles']} triangles, draco-{args.bits} {d['draco']:,} B at {d['error']:.2g}, "
              f"pln {p.get('pln', 0):,} B ({p.get('seconds', 0):.1f} s), ratio {row['ratio']:.3f}"
              + (f" [{p.get('failed', 'recorded bound above the tolerance')}]" if not ok else ""), flush=True)
    print(f"\nmedian .pln / draco-{args.bits} at draco-{args.bits}'s error (a failure counts as infinite):")
    for cat in sorted({r["category"] for r in rows}) + ["all"]:
        sel = [r["ratio"] for r in rows if cat in ("all", r["category"])]
        print(f"  {cat:22s} {len(sel):4d} meshes  median {statistics.median(sel):.3f}  "
              f".pln smaller on {sum(x < 1 for x in sel)}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
