"""Run one .pln file through a reader in a child process under CPU-time and address-space caps,
and say how it ended: a result, the reader's own error, or something else (a crash, a foreign
exception, a cap). Shared by ``tests/test_hostile.py`` (caps as hang guards) and
``bench/hostile.py`` (figures).

    python fuzz/capped.py py FILE     # the Python side: decode_mesh, one JSON line on stdout
"""

from __future__ import annotations

import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


@dataclass(frozen=True)
class Outcome:
    reader: str
    kind: str  # "result", "error" (the reader's own, with a code), "crash", "cap"
    detail: str  # result counts, error code, or what went wrong
    seconds: float  # Python: decode_mesh's own; node: the process's (its start ~0.2 s)
    rss_mb: float  # peak RSS of the child above the interpreter's own at start
    area: float | None = None  # of a result: the triangles' area (Python: in world coordinates; JS: each group's
    # in its object's, the same for the translations hostile files use)


def node() -> str | None:
    return shutil.which("node")


def _limits(cpu_s: int, mem_mb: int):
    def apply() -> None:
        resource.setrlimit(resource.RLIMIT_CPU, (cpu_s, cpu_s))
        if mem_mb:
            resource.setrlimit(resource.RLIMIT_AS, (mem_mb << 20, mem_mb << 20))
    return apply


def run(reader: str, path: Path, cpu_s: int = 20, mem_mb: int = 1024) -> Outcome:
    """``reader`` "py" (planefmt.decode_mesh) or "js" (node js/cli.mjs) on ``path``. Node reserves
    far more address space than it touches, so its cap is its heap (--max-old-space-size) and the
    CPU time, not RLIMIT_AS."""
    if reader == "py":
        cmd = [sys.executable, str(Path(__file__).resolve()), "py", str(path)]
        limits = _limits(cpu_s, mem_mb)
    else:
        cmd = [node(), f"--max-old-space-size={mem_mb}", str(ROOT / "js" / "cli.mjs"), str(path)]
        limits = _limits(cpu_s, 0)
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=out, stderr=err, preexec_fn=limits, cwd=ROOT)
        _, status, usage = os.wait4(proc.pid, 0)  # this child's own peak RSS, not the largest so far
        proc.returncode = os.waitstatus_to_exitcode(status)
        seconds = time.perf_counter() - t0
        out.seek(0)
        err.seek(0)
        text, errors = out.read().decode(errors="replace"), err.read().decode(errors="replace")
    return _judge(reader, proc.returncode, text, errors, seconds, usage.ru_maxrss / 1024)


def _judge(reader: str, code: int, out: str, err: str, seconds: float, rss: float) -> Outcome:
    try:
        report = json.loads(out.strip().splitlines()[-1]) if out.strip() else None
    except json.JSONDecodeError:
        report = None
    base = 0.0
    if isinstance(report, dict) and "baseline_mb" in report:
        base, seconds = report["baseline_mb"], report["seconds"]
    if code < 0 or code in (137, 152):  # a signal: SIGXCPU, SIGKILL, SIGSEGV ...
        return Outcome(reader, "cap" if code in (-24, -9) else "crash", f"signal {-code}: {err[-200:]}", seconds, rss - base)
    if isinstance(report, dict) and "error" in report and code in (1, 2) and "foreign" not in report:
        return Outcome(reader, "error", str(report["error"]), seconds, report.get("rss_mb", rss) - base)
    if isinstance(report, dict) and code == 0:
        counts = report.get("counts") or _js_counts(report)
        area = report["area"] if "area" in report else _js_area(report)
        return Outcome(reader, "result", counts, seconds, report.get("rss_mb", rss) - base, area)
    if "heap out of memory" in err or "MemoryError" in err:
        return Outcome(reader, "cap", f"out of memory: {err.strip().splitlines()[-1][:160]}", seconds, rss - base)
    return Outcome(reader, "crash", (report or {}).get("foreign") or err.strip()[-300:] or f"exit {code}", seconds, rss - base)


def _js_counts(report: dict) -> str:
    groups = (report.get("geometry") or {}).get("groups") or []
    v = sum(g["vertices"] for g in groups if g and g.get("vertices") is not None)
    t = sum(g["triangles"] for g in groups if g and g.get("triangles") is not None)
    return f"{v} vertices, {t} triangles"


def _js_area(report: dict) -> float:
    groups = (report.get("geometry") or {}).get("groups") or []
    return float(sum(g["area"] for g in groups if g and g.get("area") is not None))


def _area(vertices, faces) -> float:
    """The area of triangles ``faces`` (T, 3) over ``vertices`` (V, 3)."""
    import numpy as np
    p = np.asarray(vertices, dtype=np.float64)[np.asarray(faces, dtype=np.int64)]
    # at unit size: a squared edge of a cube of side 7e-102 (fuzz/hostile.py i8_tiny_cube) underflows to 0
    scale = float(np.abs(p).max(initial=0.0)) or 1.0
    p = p / scale
    return float(np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum() / 2) * scale * scale


def _python_side(path: str) -> int:
    """decode_mesh on ``path``; one JSON line: counts, or the PlnError's code, or a foreign exception."""
    import planefmt
    from planefmt.codec import decode_mesh
    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # the interpreter with planefmt loaded

    t0 = time.perf_counter()

    def line(**fields) -> None:
        fields["seconds"] = time.perf_counter() - t0  # the decode's, without the interpreter's start
        fields["baseline_mb"] = base
        fields["rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        print(json.dumps(fields), flush=True)

    try:
        mesh = decode_mesh(path)
    except planefmt.PlnError as exc:
        line(error=exc.code)
        return 1
    except MemoryError:
        line(error="MemoryError", foreign="MemoryError")
        return 3
    except Exception as exc:  # noqa: BLE001 - the point: anything outside PlnError is reported as foreign
        line(error=type(exc).__name__, foreign=f"{type(exc).__module__}.{type(exc).__name__}: {exc}"[:300])
        return 3
    vertices, faces = mesh if isinstance(mesh, tuple) else (mesh.vertices, mesh.faces)
    line(counts=f"{len(vertices)} vertices, {len(faces)} triangles", area=_area(vertices, faces))
    return 0


if __name__ == "__main__":
    sys.exit(_python_side(sys.argv[2]))
