"""A batch run of ``pln convert``: many inputs into ``-d OUTDIR``, with a ledger, resumable.

    pln convert A.obj B.ply meshes/ -d OUTDIR [--to FORMAT] [--from-list FILE] [--report FILE.jsonl]
        [--resume] [--timeout S] [--max-memory MB] [--engine local|dask] [--scheduler ADDRESS] [--jobs N]

Inputs are files, folders (their mesh files, the layout kept under OUTDIR: :mod:`.sources`) and the
paths of a list file. Each input's outcome is a line of the ledger (:mod:`.ledger`) as it finishes;
``--resume`` skips inputs an earlier run converted (output present, ledger says ok for a source of the
same size and mtime, converted with the same options) and removes the scratch folders a killed run
left. A failed input is one line on stderr and in the ledger, and the run goes on.

Exit status: 0 when every input was converted or skipped, 1 when any failed (its reason is in the
ledger) or lost parts (``--salvage``), 2 for a usage error or an input named that does not exist.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import sys
import time
from typing import TYPE_CHECKING

from planefmt.errors import PlnError

from . import ledger, remote
from .progress import RunBar

# The engines (subprocess, threads) and the sources (pathlib) are imported by a batch run only: every
# command builds the parser of ``pln convert``, whose options this module adds, ``pln --version`` too.
if TYPE_CHECKING:
    from . import sources


def run(args: argparse.Namespace, opts: dict) -> int:
    import secrets

    from planefmt_converters import registry

    from . import engines, sources
    from .convert import _refuse_conflicts, refuse_protected

    on_dask = args.engine == "dask" or (args.engine is None and args.scheduler is not None)
    if args.scheduler and not on_dask:
        raise PlnError("--scheduler names a Dask cluster: it goes with --engine dask", code="CONVERSION_FAILED")
    to = args.to or "pln"
    ext = registry.get(to).extensions[0]
    outdir = args.outdir if remote.is_url(args.outdir) else os.path.abspath(args.outdir)
    names = list(args.paths) + (sources.listed(args.from_list) if args.from_list else [])
    if not names:
        raise PlnError("no inputs: name files or folders, or a list of them with --from-list FILE",
                       code="CONVERSION_FAILED")
    missing = [name for name in names if not remote.is_url(name) and not os.path.lexists(name)]
    found = _unique(sources.expand([name for name in names if name not in missing], outdir))
    pairs = [(_absolute(src.path), _join(outdir, src.rel + ext)) for src in found]
    _refuse_conflicts([pair for pair in pairs if not any(map(remote.is_url, pair))], args)

    report = args.report or (_join(outdir, ledger.DEFAULT_NAME) if not remote.is_url(outdir) else ledger.DEFAULT_NAME)
    if args.resume:
        _remove_scratch(outdir, remote.SCRATCH_PREFIX)
    done = ledger.completed(report) if args.resume else {}
    if not remote.is_url(outdir):
        os.makedirs(outdir, exist_ok=True)
    # What the outputs depend on besides the source: an output made with other options is not skipped.
    settings = ",".join(f"{key}={value}" for key, value in sorted({**opts, "to": to, "from": args.from_}.items()))
    run_id = secrets.token_hex(4)
    jobs, skipped = [], []
    for i, (src, dst) in enumerate(pairs):
        earlier = done.get(src)
        if earlier is not None and earlier.get("output") == dst and earlier.get("settings") == settings and \
                _unchanged(src, earlier) and remote.exists(dst):
            skipped.append({**earlier, "status": "skipped", "seconds": 0.0, "peak_mb": None, "warnings": []})
        else:
            jobs.append({"source": src, "output": dst, "to": to, "from_": args.from_, "opts": opts,
                         "salvage": args.salvage, "timeout": args.timeout, "max_memory_mb": args.max_memory,
                         "token": f"{run_id}-{i}"})

    refuse_protected([job["output"] for job in jobs if not remote.is_url(job["output"])], args)
    # Before the ledger is opened: a cluster out of reach stops the run before it began. (Nothing left
    # to convert starts no cluster; the local engine starts its processes on the first job.)
    engine = engines.dask(jobs, args.scheduler, args.jobs) if on_dask and jobs else \
        engines.local(jobs, args.jobs)
    tally = {"ok": 0, "failed": 0, "skipped": 0, "lost": 0}
    bar = RunBar(sys.stderr, len(missing) + len(pairs), enabled=sys.stderr.isatty())
    with ledger.Ledger(report, resume=args.resume) as book:
        def record(entry: dict) -> None:
            entry["settings"], entry["finished"] = settings, round(time.time(), 3)
            book.append(entry)
            tally[entry["status"]] += 1
            tally["lost"] += bool(entry.get("lost"))
            bar.add(entry["status"] == "failed", entry.get("bytes_in") or 0, entry.get("bytes_out") or 0)
            lines = [f"pln: {entry['message']}"] if entry["status"] == "failed" else []
            lines += [f"pln: warning: {line}" for line in entry.get("warnings") or [] if entry["status"] == "ok"]
            if lines:
                bar.clear()
                print("\n".join(lines), file=sys.stderr)

        for name in missing:
            record({"source": _absolute(name), "output": None, "status": "failed", "code": "CONVERSION_FAILED",
                    "message": f"{name}: cannot open: no such file or folder", "seconds": 0.0})
        for entry in skipped:
            record(entry)
        try:
            with contextlib.closing(engine):
                for entry in engine:
                    record(entry)
        finally:
            bar.close()
            _remove_scratch(outdir, f"{remote.SCRATCH_PREFIX}{run_id}-")  # of Dask workers lost mid-job
    if bar.enabled or args.verbose:
        print(f"pln: {tally['ok']} converted, {tally['skipped']} skipped (done before), {tally['failed']} failed; "
              f"{bar.bytes_in:,} B in, {bar.bytes_out:,} B out; report {report}", file=sys.stderr)
    return 2 if missing else 1 if tally["failed"] or tally["lost"] else 0


def add_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("batch (with -d OUTDIR)")
    g.add_argument("--from-list", metavar="FILE", help="also convert the paths in FILE, one a line (- reads stdin)")
    g.add_argument("--report", metavar="FILE.jsonl",
                   help=f"the run's ledger, one JSON line per input (default OUTDIR/{ledger.DEFAULT_NAME}); "
                        "pln report FILE.jsonl summarises it")
    g.add_argument("--resume", action="store_true",
                   help="skip the inputs the ledger says were converted (same source size and mtime, output "
                        "present), append to it, and remove what a killed run left")
    g.add_argument("--timeout", type=_positive, metavar="S", help="fail an input whose conversion takes longer")
    g.add_argument("--max-memory", type=_positive, metavar="MB",
                   help="fail an input whose conversion needs more memory (address space) than this")
    g.add_argument("--engine", choices=["local", "dask"],
                   help="local: --jobs worker processes here (the default, unless --scheduler names a cluster); "
                        "dask: a Dask distributed cluster")
    g.add_argument("--scheduler", metavar="ADDRESS",
                   help="--engine dask: the scheduler of an existing cluster (tcp://host:8786); without it a "
                        "LocalCluster of --jobs workers is started for the run")


def _positive(text: str) -> float:
    value = float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"{text} is not a positive number")
    return value


def _unique(found: list[sources.Source]) -> list[sources.Source]:
    """Each source once, where a file was named twice or also lies in a folder named."""
    seen: dict[str, sources.Source] = {}
    for src in found:
        seen.setdefault(_absolute(src.path), src)
    return list(seen.values())


def _absolute(name: str) -> str:
    """Paths as Dask workers and later runs see them: absolute (URLs as named)."""
    return name if remote.is_url(name) else os.path.abspath(name)


def _join(outdir: str, rel: str) -> str:
    return f"{outdir.rstrip('/')}/{rel}" if remote.is_url(outdir) else os.path.join(outdir, rel)


def _unchanged(src: str, earlier: dict) -> bool:
    try:
        size, mtime_ns = remote.identity(src)
    except (OSError, PlnError):
        return False
    return earlier.get("size") == size and earlier.get("mtime_ns") == mtime_ns


def _remove_scratch(outdir: str, prefix: str) -> None:
    """Remove scratch folders (and URL temporaries) whose names start with ``prefix`` under ``outdir``."""
    if remote.is_url(outdir):
        if prefix == remote.SCRATCH_PREFIX:
            remote.remove_scratch(outdir)
        return
    for folder, dirs, _ in os.walk(outdir):
        for name in [d for d in dirs if d.startswith(prefix)]:
            shutil.rmtree(os.path.join(folder, name), ignore_errors=True)
            dirs.remove(name)
