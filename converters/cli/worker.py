"""The process that converts a batch run's inputs, one at a time, under the run's limits per input.

``python -m planefmt_converters.cli.worker`` reads jobs from standard input and writes one ledger
entry per job to standard output, both as length-prefixed pickles (its parent is the same program: the
pipe is trusted). It lives for many jobs, so the imports (about a second) are paid once per process,
not per input; :mod:`.engines` starts one per local job slot or per Dask worker thread, and kills and
replaces one that overruns its time or dies.

Each job converts into its own scratch folder (``.pln-batch-<token>`` beside the target, so that the
final rename stays on one file system; in the system's temporary folder for a URL target), whose files
are renamed onto their targets once whole, sidecars first. A job that fails or is interrupted removes
its scratch folder; one whose process is killed leaves it to the parent, or to ``--resume``.

Limits, per job: the address space may grow by ``max_memory_mb`` over what the process had before the
job (RLIMIT_AS, soft limit: the interpreter, numpy and the libraries it imported are not counted); an
allocation beyond it fails (MemoryError) and the job with it. ``timeout`` raises in the conversion
after that many seconds (SIGALRM); a conversion stuck in C code that does not return is killed by the
parent a little later.
"""

from __future__ import annotations

import contextlib
import math
import os
import pickle
import shutil
import signal
import struct
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

from .remote import SCRATCH_PREFIX


class JobTimeout(BaseException):
    """Raised by SIGALRM inside a conversion; a BaseException so that no converter's ``except
    Exception`` turns it into a conversion error."""


def send(stream: BinaryIO, message: object) -> None:
    data = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(struct.pack("<I", len(data)) + data)
    stream.flush()


def receive(read_exactly) -> object | None:
    """One message, read through ``read_exactly(n) -> bytes`` (short on end of stream); None at the end."""
    head = read_exactly(4)
    if len(head) < 4:
        return None
    (size,) = struct.unpack("<I", head)
    data = read_exactly(size)
    return pickle.loads(data) if len(data) == size else None


def scratch_for(job: dict) -> str:
    """The scratch folder of ``job``: beside a local target, in the temporary folder for a URL."""
    from .remote import is_url

    if is_url(job["output"]):
        return os.path.join(tempfile.gettempdir(), SCRATCH_PREFIX.lstrip(".") + job["token"])
    return os.path.join(os.path.dirname(job["output"]), SCRATCH_PREFIX + job["token"])


def failed_entry(job: dict, code: str, message: str, seconds: float = 0.0) -> dict:
    return {"source": job["source"], "output": job["output"], "status": "failed", "code": code,
            "message": message, "seconds": round(seconds, 3)}


def convert(job: dict) -> dict:
    """Run one job; the ledger entry of its outcome. Interrupts (KeyboardInterrupt) propagate."""
    from planefmt.errors import PlnError

    from ..failures import describe
    from . import remote

    start = time.monotonic()
    scratch = scratch_for(job)
    _reset_peak()
    try:
        try:
            with _limits(job.get("timeout"), job.get("max_memory_mb")):
                entry = _convert(job, scratch)
        # Outside the limits' block: an alarm due just as the conversion returned lands here too.
        except JobTimeout:
            entry = failed_entry(job, "TIMEOUT", f"{job['source']}: took longer than the "
                                 f"{job['timeout']:g} s allowed per input (--timeout)")
        except Exception as exc:  # noqa: BLE001 - a failed input is one ledger line, never a traceback
            if _out_of_memory(exc):
                entry = failed_entry(job, "MEMORY_LIMIT", f"{job['source']}: needed more than the "
                                     f"{job['max_memory_mb']:g} MB allowed per input (--max-memory)")
            elif isinstance(exc, PlnError):
                entry = failed_entry(job, exc.code, str(exc))
            elif isinstance(exc, OSError):
                entry = failed_entry(job, "CONVERSION_FAILED",
                                     f"{exc.filename or job['source']}: {exc.strerror or describe(exc)}")
            else:
                entry = failed_entry(job, "CONVERSION_FAILED", f"{job['source']}: {describe(exc)}")
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    entry["seconds"] = round(time.monotonic() - start, 3)
    entry["peak_mb"] = _peak_mb()
    if entry["status"] == "failed" and "size" not in entry:
        with contextlib.suppress(OSError, PlnError):
            entry["size"], entry["mtime_ns"] = remote.identity(job["source"])
    return entry


def _local_source(job: dict, scratch: str) -> str:
    from .remote import is_url

    return os.path.join(scratch, "source" + Path(job["source"]).suffix) if is_url(job["source"]) else job["source"]


def _convert(job: dict, scratch: str) -> dict:
    import planefmt
    from planefmt_converters import registry

    from . import remote
    from .convert import convert_one

    source, output = job["source"], job["output"]
    size, mtime_ns = remote.identity(source)  # before reading: a later change makes --resume convert again
    if not remote.is_url(output):
        os.makedirs(os.path.dirname(output), exist_ok=True)
    shutil.rmtree(scratch, ignore_errors=True)  # a Dask worker lost during this job's earlier attempt
    os.mkdir(scratch)
    local_src = _local_source(job, scratch)
    if local_src != source:
        remote.download(source, local_src)
    local_out = os.path.join(scratch, os.path.basename(output.rstrip("/")))
    facts: dict = {}
    warnings, lost = convert_one(local_src, local_out, job["to"], job["from_"], job["opts"], job["salvage"],
                                 src_name=source, dst_name=output, facts=facts)
    fmt_in = registry.get(job["from_"]) if job["from_"] else registry.detect(local_src)
    bytes_in = sum(os.path.getsize(path) for path in registry.input_files(local_src, fmt_in))
    fmt = registry.writer_for(local_out, job["to"])
    written = [*(fmt.sidecars(local_out) if fmt.sidecars else ()), local_out]  # sidecars first: see atomic.py
    written = [path for path in written if os.path.exists(path)]
    bytes_out = sum(os.path.getsize(path) for path in written)
    error_bound = None
    pln_side = local_out if fmt.name == "pln" else local_src if registry.detect(local_src).name == "pln" else None
    if pln_side is not None:
        with contextlib.suppress(planefmt.PlnError):
            with planefmt.open(pln_side) as f:
                error_bound = f.header.error_bound
    folder = output.rsplit("/", 1)[0] if remote.is_url(output) else os.path.dirname(output)
    for path in written:
        target = output if path == local_out else f"{folder}/{os.path.basename(path)}"
        if remote.is_url(output):
            remote.upload(path, target, job["token"])
        else:
            os.replace(path, target)
    return {"source": source, "output": output, "status": "ok", "code": None, "message": None,
            "warnings": warnings + [f"lost {line}" for line in lost], "lost": bool(lost),
            "size": size, "mtime_ns": mtime_ns, "triangles": facts.get("triangles"), "bytes_in": bytes_in,
            "bytes_out": bytes_out, "error_bound": None if error_bound is None or math.isnan(error_bound)
            else error_bound}


@contextlib.contextmanager
def _limits(timeout: float | None, max_memory_mb: float | None) -> Iterator[None]:
    import resource

    previous_as = resource.getrlimit(resource.RLIMIT_AS)
    if max_memory_mb:
        base = _status_kb("VmSize")
        if base is not None:
            soft = base * 1024 + int(max_memory_mb * 2**20)
            hard = previous_as[1]
            resource.setrlimit(resource.RLIMIT_AS, (soft if hard == resource.RLIM_INFINITY else min(soft, hard), hard))
    if timeout:
        signal.signal(signal.SIGALRM, _alarm)
        signal.setitimer(signal.ITIMER_REAL, timeout)
    try:
        yield
    finally:
        if timeout:
            signal.setitimer(signal.ITIMER_REAL, 0)
        resource.setrlimit(resource.RLIMIT_AS, previous_as)


def _alarm(signum: int, frame: object) -> None:
    raise JobTimeout


def _out_of_memory(exc: BaseException | None) -> bool:
    """A MemoryError anywhere in the chain: converters wrap what a library raised."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, MemoryError):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def _status_kb(field: str) -> int | None:
    """A ``kB`` field of /proc/self/status (Linux); None elsewhere."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except OSError:
        pass
    return None


def _reset_peak() -> None:
    """Start VmHWM (peak resident memory) again from the current size, so it is this job's peak."""
    with contextlib.suppress(OSError):
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")


def _peak_mb() -> float | None:
    kb = _status_kb("VmHWM")
    if kb is None:
        import resource

        kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return round(kb / 1024, 1)


def _die_with_parent() -> None:
    """Linux: be killed when the process that started this one dies, so that a SIGKILLed run leaves no
    worker converting on behind the resumed one."""
    with contextlib.suppress(OSError, AttributeError):
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        pr_set_pdeathsig = 1
        libc.prctl(pr_set_pdeathsig, signal.SIGKILL)
        if os.getppid() == 1:  # the parent died before prctl
            os._exit(1)


def _warm_up() -> None:
    """Convert a tetrahedron: what a conversion imports on first use (the codec, scipy's Qhull, the
    OBJ reader) is then imported before the first job's clock and memory limit start, and OpenBLAS
    has allocated its buffers, which it does on first use and, failing under a memory limit, aborts
    the process for. (A format's own reader, USD's above all, is still imported by its first input.)"""
    import numpy as np

    from .convert import convert_one

    square = np.eye(64) + 0.5
    np.linalg.svd(square @ square)
    with tempfile.TemporaryDirectory(prefix="pln-worker-") as folder:
        source = os.path.join(folder, "tetrahedron.obj")
        with open(source, "w") as f:
            f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
        convert_one(source, os.path.join(folder, "tetrahedron.pln"), "pln", None, {"tolerance": 1e-6})


def main() -> None:
    from planefmt_converters import interrupts
    from planefmt_converters.cli import quiet_library_warnings

    _die_with_parent()
    # The pipe to the parent is a private copy of stdout; whatever a library prints goes to stderr.
    out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)
    inp = sys.stdin.buffer
    quiet_library_warnings()
    _warm_up()

    send(out, "ready")
    with interrupts.handled():
        # Ctrl-C on a terminal reaches the whole process group: the parent decides what stops (it sends
        # SIGTERM, which interrupts the conversion and removes its scratch folder).
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            while (job := receive(inp.read)) is not None:
                send(out, convert(job))
        except KeyboardInterrupt:
            sys.exit(130)


if __name__ == "__main__":
    main()
