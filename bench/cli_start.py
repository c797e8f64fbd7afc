"""How long the command line takes to start (issue 55): wall and CPU time of ``pln --version`` and of
``pln info FILE`` on .pln files made from corpus meshes, the median of 10 runs each, beside the issue's
targets (0.15 s and 0.3 s of wall time, on a quiet machine).

Each run is a fresh process of the ``pln`` script beside this interpreter (or ``--pln``, e.g. another
checkout's, to compare two versions in one run). Beside the median wall time: the least of the runs,
and the median CPU time (user + system, from the child's rusage), which say less about the machine's load
than the median; the load average is printed with the figures.

Usage: ``python bench/cli_start.py [--runs 10] [--pln PATH ...] [--mesh CORPUS_FILE ...]``
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: The meshes whose .pln files ``pln info`` reads: the smallest convex solid, a glTF scene of several
#: objects, and the corpus's densest mesh (the largest .pln of these).
MESHES = ("convex/cylinder.stl", "gltf_scene/CesiumMilkTruck.glb", "smooth_dense/bun_zipper.ply")
TARGETS = {"--version": 0.15, "info": 0.3}


def timed(command: list[str]) -> tuple[float, float]:
    """Wall and CPU (user + system) seconds of one run of ``command``, which must succeed."""
    start = time.perf_counter()
    child = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(child.pid, 0)
    wall = time.perf_counter() - start
    child.returncode = os.waitstatus_to_exitcode(status)
    err = child.stderr.read().decode(errors="replace")
    child.stderr.close()
    if child.returncode != 0:
        raise SystemExit(f"{' '.join(command)} exited {child.returncode}: {err.strip()}")
    return wall, usage.ru_utime + usage.ru_stime


def medians(command: list[str], runs: int) -> tuple[float, float, float]:
    """Median wall, least wall and median CPU seconds of ``runs`` runs."""
    times = [timed(command) for _ in range(runs)]
    walls = [w for w, _ in times]
    return statistics.median(walls), min(walls), statistics.median(c for _, c in times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=10, help="runs per command (default 10)")
    ap.add_argument("--pln", nargs="+", default=[str(Path(sys.executable).parent / "pln")],
                    help="the pln scripts to time (default: the one beside this interpreter)")
    ap.add_argument("--mesh", nargs="+", default=list(MESHES), help="corpus meshes (under tests/corpus) to "
                    "convert with the first --pln and describe with pln info")
    args = ap.parse_args()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}; "
          f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(f"median of {args.runs} runs; targets (wall): --version {TARGETS['--version']} s, info {TARGETS['info']} s")
    with tempfile.TemporaryDirectory(prefix="cli-start-") as folder:
        files = []
        for mesh in args.mesh:
            out = Path(folder) / (Path(mesh).stem + ".pln")
            subprocess.run([args.pln[0], "convert", str(ROOT / "tests" / "corpus" / mesh), str(out)], check=True,
                           stderr=subprocess.DEVNULL)
            files.append((mesh, out))
        print(f"{'pln':<40} {'command':<48} {'wall s':>7} {'least':>7} {'cpu s':>7} {'target':>7}")
        for pln in args.pln:
            rows = [("--version", [pln, "--version"], TARGETS["--version"])]
            rows += [(f"info {mesh} ({out.stat().st_size:,} B)", [pln, "info", str(out)], TARGETS["info"])
                     for mesh, out in files]
            for label, command, target in rows:
                wall, least, cpu = medians(command, args.runs)
                print(f"{pln:<40} {label:<48} {wall:7.3f} {least:7.3f} {cpu:7.3f} "
                      f"{'ok' if wall <= target else 'MISS':>7}", flush=True)
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
