"""Decode speed against DracoPy, measured in one run (issue 55): for every corpus mesh of at least
1,000 triangles, the time of ``flatten(decode_scene(bytes))`` (what bench/compare.py times for a pln
column) beside ``DracoPy.decode`` of the same welded mesh encoded at 14 bits, compression level 10;
the ratio of Draco's time to pln's per mesh and their geometric mean.

``--old ROOT`` times a second planefmt (e.g. a frozen copy of main: a folder holding its ``planefmt``
and ``converters`` packages, built) on the same bytes in a worker process, mesh by mesh beside this
one, and checks that both decode the same arrays bit for bit (a digest of vertices, faces and face
colours). Each time is the least of up to ``--repeats`` runs (5, as bench/compare.py) within
``REPEAT_BUDGET`` seconds. The .pln files are encoded once with this checkout's encoder at the default tolerance
(``pln convert``'s) and kept in ``--cache``; clear it when the encoder changes.

Usage: ``python bench/decode_speed.py [--corpus DIR] [--old ROOT] [--repeats N] [--only SUBSTRING ...]``
"""

from __future__ import annotations

import argparse
import hashlib
import io
import json
import math
import os
import statistics
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
CORPUS = ROOT / "tests" / "corpus"
SIDECARS = (".md", ".bin", ".png", ".jpg", ".jpeg")
MIN_TRIANGLES = 1000
REPEATS = 5
REPEAT_BUDGET = 2.0


def timed(call, repeats: int = REPEATS):
    """``(least seconds, result)`` over up to ``repeats`` runs of ``call()`` within :data:`REPEAT_BUDGET`."""
    times = []
    while True:
        t = time.perf_counter()
        result = call()
        times.append(time.perf_counter() - t)
        if len(times) >= repeats or sum(times) >= REPEAT_BUDGET:
            return min(times), result


def pln_decode(data: bytes):
    from planefmt import codec
    from planefmt_converters.assemble import flatten

    return flatten(codec.decode_scene(io.BytesIO(data)))


def digest(mesh) -> str:
    h = hashlib.sha256()
    for a in (mesh.vertices, mesh.faces, mesh.face_colours):
        if a is not None:
            a = np.ascontiguousarray(a)
            h.update(f"{a.dtype}{a.shape}".encode())
            h.update(a.tobytes())
    return h.hexdigest()


def measure(path: str, repeats: int = REPEATS) -> dict:
    data = Path(path).read_bytes()
    seconds, mesh = timed(lambda: pln_decode(data), repeats)
    return {"seconds": seconds, "digest": digest(mesh), "triangles": len(mesh.faces)}


def worker() -> None:
    """Answer one JSON line per .pln path read from stdin."""
    for line in sys.stdin:
        path, repeats = line.split("\t")
        print(json.dumps(measure(path, int(repeats))), flush=True)


def meshes(corpus: Path, only: list[str]) -> list[Path]:
    return sorted(p for p in corpus.glob("*/*") if p.suffix.lower() not in SIDECARS and p.is_file()
                  and (not only or any(s in str(p) for s in only)))


def encoded(source: Path, corpus: Path, cache: Path) -> tuple[Path, np.ndarray, np.ndarray]:
    """The cached .pln of ``source`` (encoded here if missing) and its welded world mesh."""
    from planefmt import codec
    from planefmt.geometry.polygonize import weld
    from planefmt_converters import registry
    from planefmt_converters.assemble import flatten

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene, _ = registry.read(str(source))
    mesh = flatten(scene)
    v, f = weld(mesh.vertices, mesh.faces)
    rel = source.relative_to(corpus)
    out = cache / (str(rel).replace("/", "__") + f"-{source.stat().st_size}.pln")
    if not out.exists():
        buf = io.BytesIO()
        codec.encode_scene(scene, buf, compress=True, compact=True)
        out.write_bytes(buf.getvalue())
    return out, v, f


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--corpus", type=Path, default=CORPUS)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/pln-decode-speed"))
    ap.add_argument("--old", type=Path, help="root of another planefmt to time beside this one")
    ap.add_argument("--only", nargs="*", default=[], help="meshes whose path holds one of these")
    ap.add_argument("--repeats", type=int, default=REPEATS, help=f"runs per timing at most (default {REPEATS}, "
                    "bench/compare.py's; more say less about a loaded machine)")
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        worker()
        return
    import DracoPy

    corpus = args.corpus.resolve()
    cache = args.cache / corpus.name
    cache.mkdir(parents=True, exist_ok=True)
    old = None
    if args.old:
        env = dict(os.environ, PYTHONPATH=str(args.old.resolve()))
        old = subprocess.Popen([sys.executable, __file__, "--worker"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                               text=True, env=env, cwd=str(args.old.resolve()))
    print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())} ({os.cpu_count()} cores)")
    print(f"{'mesh':<44} {'tri':>7} {'draco ms':>9} {'pln ms':>9} {'ratio':>6}"
          + (f" {'old ms':>9} {'old ratio':>9} {'same':>5}" if old else ""))
    ratios, old_ratios = [], []
    for source in meshes(corpus, args.only):
        try:
            path, v, f = encoded(source, corpus, cache)
        except Exception as exc:  # a mesh the converters or encoder refuse is reported, not timed
            print(f"{str(source.relative_to(corpus)):<44} skipped: {type(exc).__name__}: {exc}")
            continue
        if len(f) < MIN_TRIANGLES:
            continue
        draco = DracoPy.encode(v, f, quantization_bits=14, compression_level=10)

        def draco_decode():
            m = DracoPy.decode(draco)
            return np.asarray(m.points, dtype=np.float64), np.asarray(m.faces, dtype=np.int64)

        draco_s, _ = timed(draco_decode, args.repeats)
        new = measure(str(path), args.repeats)
        ratios.append(draco_s / new["seconds"])
        line = (f"{str(source.relative_to(corpus)):<44} {len(f):>7} {1e3 * draco_s:9.2f} {1e3 * new['seconds']:9.2f} "
                f"{ratios[-1]:6.3f}")
        if old:
            old.stdin.write(f"{path}\t{args.repeats}\n")
            old.stdin.flush()
            before = json.loads(old.stdout.readline())
            old_ratios.append(draco_s / before["seconds"])
            line += (f" {1e3 * before['seconds']:9.2f} {old_ratios[-1]:9.3f} "
                     f"{'yes' if before['digest'] == new['digest'] else 'NO':>5}")
        print(line, flush=True)

    def geo(xs):
        return math.exp(statistics.fmean(math.log(x) for x in xs)) if xs else float("nan")

    print(f"geometric mean of draco / pln decode time over {len(ratios)} meshes: {geo(ratios):.3f}"
          + (f" (old: {geo(old_ratios):.3f})" if old else ""))
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    if old:
        old.stdin.close()
        old.wait()


if __name__ == "__main__":
    main()
