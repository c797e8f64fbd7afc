"""Bench (b): peak RSS of ``pln info -`` reading a >= 500 MB .pln file from a pipe.

Writes a file of float32 planes and convex groups (default 520 MB), pipes it
through ``cat`` into ``pln info -`` and reads the child's peak RSS (ru_maxrss
of RUSAGE_CHILDREN, measured for each child on its own), next to the peak RSS
of an empty interpreter (``python -c pass``) and of one that only imports the
CLI. Goal: pln info - at most 64 MB above the empty interpreter.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

import planefmt
from planefmt.model import Coding, GroupKind, Header

PLN = [sys.executable, "-m", "planefmt_converters.cli"]


def peak_rss_mb(cmd: list[str], stdin=None) -> tuple[float, float]:
    """(peak RSS in MB, wall seconds) of one child process, measured in a fresh grandchild."""
    probe = ("import resource, subprocess, sys, time; t = time.perf_counter(); "
             "p = subprocess.run(sys.argv[1:], stdin=sys.stdin, stdout=subprocess.DEVNULL); "
             "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024, "
             "time.perf_counter() - t, p.returncode)")
    out = subprocess.run([sys.executable, "-c", probe, *cmd], stdin=stdin, capture_output=True, text=True,
                         check=True).stdout.split()
    if out[2] != "0":
        raise SystemExit(f"{cmd} exited with {out[2]}")
    return float(out[0]), float(out[1])


def write_big(path: str, megabytes: int) -> None:
    rng = np.random.default_rng(0)
    block = np.column_stack([rng.uniform(0.1, 3.0, 65536), rng.uniform(0, 6.2, 65536), rng.uniform(-1, 1, 65536)])
    with planefmt.Writer(path, Header(coding=Coding.FLOAT32)) as w:
        obj = w.add_object("big")
        while w.bytes_written < megabytes * 1_000_000:
            first = w.add_planes(block)
            w.add_group(obj, GroupKind.CONVEX, np.arange(first, first + 4096))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--megabytes", type=int, default=520)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "big.pln")
        t0 = time.perf_counter()
        write_big(path, args.megabytes)
        size = os.path.getsize(path)
        print(f"wrote {size / 1e6:.0f} MB in {time.perf_counter() - t0:.1f} s; machine: {os.cpu_count()} cores")
        empty, _ = peak_rss_mb([sys.executable, "-c", "pass"])
        imported, _ = peak_rss_mb([*PLN, "--help"])
        cat = subprocess.Popen(["cat", path], stdout=subprocess.PIPE)
        info, secs = peak_rss_mb([*PLN, "info", "-"], stdin=cat.stdout)
        cat.wait()
        print(f"peak RSS: empty interpreter {empty:.1f} MB; pln --help {imported:.1f} MB; "
              f"pln info - on the pipe {info:.1f} MB ({secs:.1f} s, {size / 1e6 / secs:.0f} MB/s)")
        print(f"pln info - above the empty interpreter: {info - empty:.1f} MB (goal <= 64 MB)")


if __name__ == "__main__":
    main()
