"""Bench (a): plane payloads through planefmt's reader vs numpy.fromfile over the same bytes.

Writes one file per triplet coding (N planes, default 4,000,000), then times
(best of R runs, page cache warm) iterating the reader over every PLNS block
against ``numpy.fromfile`` reading the whole file as raw bytes, and prints
the ratio fromfile_time / reader_time (1.0 = as fast as a raw read; the
issue's goal is >= 0.5), once with the page cache warm and once cold (the
file's pages evicted with posix_fadvise before every run). The reader does
strictly more than fromfile: CRC-32 of every chunk, a range check of every
triplet, widening to float64 and dequantization.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import tempfile
import time

import numpy as np

import planefmt
from planefmt.model import Coding, Header, PlaneBlock, Quantization


def make_triplets(n: int, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(0, math.pi, n), rng.uniform(0, 2 * math.pi, n), rng.uniform(-10, 10, n)])


def evict(path: str) -> None:
    """Drop the file's pages from the page cache, so the next read comes from the disk."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
        os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
    finally:
        os.close(fd)


def best(fn, runs: int, cold_path: str | None = None) -> float:
    times = []
    for _ in range(runs):
        if cold_path:
            evict(cold_path)
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def read_planes(path: str) -> int:
    n = 0
    with planefmt.open(path, retain_planes=False) as r:
        for rec in r:
            if isinstance(rec, PlaneBlock):
                n += len(rec.triplets)
    return n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--planes", type=int, default=4_000_000)
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    t = make_triplets(args.planes)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"numpy {np.__version__}; {args.planes:,} planes, best of {args.runs}")
    print(f"{'coding':<22} {'file MB':>8} {'warm: reader s':>15} {'fromfile s':>11} {'ratio':>6}"
          f" {'cold: reader s':>15} {'fromfile s':>11} {'ratio':>6}")
    codings = [(Coding.FLOAT32, None, "<f4"), (Coding.FLOAT64, None, "<f8"),
               (Coding.QUANTIZED, Quantization(16, 16, 16, -10.0, 10.0), "<u2")]
    with tempfile.TemporaryDirectory() as tmp:
        for coding, q, dtype in codings:
            path = os.path.join(tmp, f"{coding.name}.pln")
            with planefmt.Writer(path, Header(coding=coding, quantization=q)) as w:
                w.add_planes(t)
            assert read_planes(path) == args.planes
            row = []
            for cold in (None, path):
                t_reader = best(lambda: read_planes(path), args.runs, cold)
                t_raw = best(lambda: np.fromfile(path, dtype=np.uint8), args.runs, cold)
                row.append(f"{t_reader:>15.4f} {t_raw:>11.4f} {t_raw / t_reader:>6.2f}")
            name = coding.name.lower() + ("" if q is None else f" {q.bits_nu}/{q.bits_phi}/{q.bits_h}")
            print(f"{name:<22} {os.path.getsize(path) / 1e6:>8.1f} {row[0]} {row[1]}")


if __name__ == "__main__":
    main()
