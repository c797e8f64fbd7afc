"""Batch conversion throughput: files per second with 1 and 2 workers, on the local engine and on a
Dask LocalCluster, over one generated dataset (tests/meshsets.py: tiny boxes, tetrahedra and prisms in
OBJ, PLY, STL, OFF and GLB), in one run.

    python bench/batch.py [--count 300] [--workers 1,2] [--engines local,dask]

Each configuration is ``pln convert DATASET -d OUT --engine E --jobs N`` in a subprocess, timed from
start to exit ("wall": process and cluster start-up included) and, from the ledger's ``finished`` times,
between its first and last finished input ("steady": the rate once running). Prints the table, the
ratio of 2 workers to 1 per engine, and the load average (``uptime``) before and after: on a machine
shared with other work, the ratio says as much about the others as about the engines. As a control,
the same pure-Python loop is timed in 1 and in 2 processes at once, before and after: the ratio the
machine itself gives two processes at that moment (2.0 on two free cores).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import meshsets  # noqa: E402

PLN = [sys.executable, "-m", "planefmt_converters.cli"]


def _uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def _spin(loops: int) -> None:
    total = 0
    for i in range(loops):
        total += i


def control(loops: int = 10_000_000) -> float:
    """Work per second of 2 processes over 1, for a loop that shares nothing."""
    from multiprocessing import Process

    seconds = []
    for n in (1, 2):
        start = time.monotonic()
        processes = [Process(target=_spin, args=(loops,)) for _ in range(n)]
        for p in processes:
            p.start()
        for p in processes:
            p.join()
        seconds.append(time.monotonic() - start)
    return 2 * seconds[0] / seconds[1]


def measure(dataset: Path, out: Path, engine: str, workers: int) -> dict:
    start = time.monotonic()
    run = subprocess.run([*PLN, "convert", str(dataset), "-d", str(out), "--engine", engine, "--jobs", str(workers)],
                         capture_output=True, text=True)
    wall = time.monotonic() - start
    if run.returncode != 0:
        raise SystemExit(f"{engine} x{workers} failed ({run.returncode}): {run.stderr}")
    entries = [json.loads(line) for line in (out / "pln-report.jsonl").read_text().splitlines()]
    finished = sorted(e["finished"] for e in entries)
    steady = (len(finished) - 1) / (finished[-1] - finished[0]) if finished[-1] > finished[0] else float("nan")
    return {"engine": engine, "workers": workers, "files": len(entries), "wall": wall,
            "per_second": len(entries) / wall, "steady": steady}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=300, help="generated meshes (default 300)")
    parser.add_argument("--workers", default="1,2", help="worker counts (default 1,2)")
    parser.add_argument("--engines", default="local,dask", help="engines (default local,dask)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="pln-bench-batch-") as folder:
        dataset = Path(folder) / "dataset"
        meshsets.build(dataset, count=args.count, broken=0)
        print(f"{args.count} generated meshes; {os.cpu_count()} cores; before: {_uptime()}; "
              f"control: 2 processes / 1 = {control():.2f}x")
        rows = []
        for engine in args.engines.split(","):
            for workers in map(int, args.workers.split(",")):
                rows.append(measure(dataset, Path(folder) / f"out-{engine}-{workers}", engine, workers))
                row = rows[-1]
                print(f"  {engine:<6} {workers} workers: {row['files']} files in {row['wall']:6.1f} s wall, "
                      f"{row['per_second']:5.1f} files/s; steady {row['steady']:5.1f} files/s", flush=True)
        print(f"after: {_uptime()}; control: 2 processes / 1 = {control():.2f}x")
    print("\n| engine | workers | files | wall s | files/s (wall) | files/s (steady) |")
    print("|---|---|---|---|---|---|")
    for row in rows:
        print(f"| {row['engine']} | {row['workers']} | {row['files']} | {row['wall']:.1f} | {row['per_second']:.1f} | "
              f"{row['steady']:.1f} |")
    for engine in args.engines.split(","):
        by = {row["workers"]: row for row in rows if row["engine"] == engine}
        if 1 in by and 2 in by:
            print(f"{engine}: 2 workers / 1 = {by[2]['per_second'] / by[1]['per_second']:.2f}x (wall), "
                  f"{by[2]['steady'] / by[1]['steady']:.2f}x (steady)")


if __name__ == "__main__":
    main()
