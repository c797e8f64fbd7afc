"""Where a batch run's conversions run: a pool of worker processes here (``--engine local``), or the
workers of a Dask distributed cluster (``--engine dask``). Either way each conversion runs in a
:mod:`.worker` process, which holds the run's limits per input; an engine yields one ledger entry per
job as jobs finish, in any order.

:class:`Worker` is the parent's side of one such process: it sends a job, waits for its entry, and
kills and replaces the process when the job overruns ``timeout`` by :data:`GRACE` seconds (a
conversion stuck in C code that SIGALRM cannot stop) or when the process dies (a C library aborting,
the kernel's OOM killer). The local engine keeps one per ``--jobs`` slot; on Dask, each worker thread
keeps one, started on its first task.
"""

from __future__ import annotations

import contextlib
import logging
import os
import queue
import select
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator

from planefmt.errors import PlnError

from ..failures import describe
from .worker import failed_entry, receive, scratch_for, send

#: Seconds past --timeout after which a conversion that did not stop itself is killed.
GRACE = 5.0
#: The variables that set how many threads numpy's BLAS and OpenMP start.
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
#: Seconds a new worker process may take to import what it needs (a loaded machine: several).
STARTUP = 120.0


class Worker:
    """One worker process, started on the first job and again after it was lost."""

    def __init__(self) -> None:
        self.proc: subprocess.Popen | None = None
        self._job: dict | None = None

    def run(self, job: dict) -> dict:
        """Convert ``job`` in the worker process; its ledger entry, also when the process was lost."""
        start = time.monotonic()
        self._job = job
        try:
            if self.proc is None or self.proc.poll() is not None:
                self._start()
                start = time.monotonic()  # the job's time starts once its process is ready
            send(self.proc.stdin, job)
            deadline = start + job["timeout"] + GRACE if job.get("timeout") else None
            entry = receive(lambda n: self._read(n, deadline))
        except (BrokenPipeError, _Overdue) as exc:
            entry = None
            overdue = isinstance(exc, _Overdue)
        else:
            overdue = False
        finally:
            self._job = None
        if entry is not None:
            return entry
        how = self._kill()
        shutil.rmtree(scratch_for(job), ignore_errors=True)
        seconds = time.monotonic() - start
        if overdue:
            return failed_entry(job, "TIMEOUT", f"{job['source']}: took longer than the {job['timeout']:g} s "
                                "allowed per input (--timeout); its process was killed", seconds)
        hint = f" (more than --max-memory {job['max_memory_mb']:g} MB?)" if job.get("max_memory_mb") else ""
        return failed_entry(job, "WORKER_LOST", f"{job['source']}: the process converting it ended "
                            f"without reporting, {how}{hint}", seconds)

    def close(self) -> None:
        """End the process: at once if it is converting (its scratch folder removed), else when it
        has read the end of its input."""
        proc, job = self.proc, self._job
        if proc is None:
            return
        with contextlib.suppress(OSError):
            proc.stdin.close()
        if job is not None:
            proc.send_signal(signal.SIGTERM)  # it removes its scratch folder and exits
        try:
            proc.wait(timeout=2 if job is not None else 10)
        except subprocess.TimeoutExpired:
            self._kill()
        if job is not None:
            shutil.rmtree(scratch_for(job), ignore_errors=True)

    def _start(self) -> None:
        # One conversion per process, as many processes as cores asked for: threads inside one would
        # only oversubscribe the cores (and each reserves address space, which --max-memory counts).
        env = {**os.environ, **{name: "1" for name in THREAD_VARIABLES}}
        self.proc = subprocess.Popen([sys.executable, "-m", "planefmt_converters.cli.worker"], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, bufsize=0, env=env)
        # It answers the first job only once imported: give that time, outside the job's own limit.
        try:
            ready = receive(lambda n: self._read(n, time.monotonic() + STARTUP))
        except _Overdue:
            ready = None
        if ready != "ready":
            raise BrokenPipeError

    def _read(self, n: int, deadline: float | None) -> bytes:
        data = b""
        fd = self.proc.stdout.fileno()
        while len(data) < n:
            wait = None if deadline is None else deadline - time.monotonic()
            if wait is not None and wait <= 0:
                raise _Overdue
            ready, _, _ = select.select([fd], [], [], wait)
            if not ready:
                continue
            chunk = os.read(fd, n - len(data))
            if not chunk:
                break
            data += chunk
        return data

    def _kill(self) -> str:
        """Kill the process (if it still runs) and say how it ended."""
        proc, self.proc = self.proc, None
        if proc is None:
            return "not started"
        if proc.poll() is None:
            proc.kill()
        code = proc.wait()
        with contextlib.suppress(OSError):
            proc.stdin.close()
            proc.stdout.close()
        if code < 0:
            return f"killed by {signal.Signals(-code).name}"
        return f"exit status {code}"


class _Overdue(Exception):
    """The job overran its time and its grace."""


def local(jobs: list[dict], processes: int) -> Iterator[dict]:
    """Run ``jobs`` on ``processes`` worker processes on this machine."""
    todo: queue.Queue = queue.Queue()
    for job in jobs:
        todo.put(job)
    done: queue.Queue = queue.Queue()
    stopping = threading.Event()
    workers = [Worker() for _ in range(max(1, min(processes, len(jobs))))]

    def serve(worker: Worker) -> None:
        while not stopping.is_set():
            try:
                job = todo.get_nowait()
            except queue.Empty:
                return
            try:
                entry = worker.run(job)
            except Exception as exc:  # noqa: BLE001 - no process could be started: say so, never hang the run
                entry = failed_entry(job, "WORKER_LOST", f"{job['source']}: no worker process: {describe(exc)}")
            if not stopping.is_set():
                done.put(entry)

    threads = [threading.Thread(target=serve, args=(w,), name="pln-worker", daemon=True) for w in workers]
    for thread in threads:
        thread.start()
    try:
        for _ in jobs:
            while True:  # a bounded wait, so that Ctrl-C is seen at once
                try:
                    entry = done.get(timeout=0.5)
                    break
                except queue.Empty:
                    continue
            yield entry
    finally:
        stopping.set()
        for worker in workers:
            worker.close()
        for thread in threads:
            thread.join(timeout=5)


def dask(jobs: list[dict], scheduler: str | None, processes: int) -> Iterator[dict]:
    """Run ``jobs`` on the Dask cluster at ``scheduler``, or on a LocalCluster of ``processes`` workers
    started for the run (one thread each, no dashboard). Connects before returning, so that a cluster
    out of reach is an error before the run has begun (and its ledger been opened)."""
    try:
        from distributed import Client
    except ImportError as exc:
        raise PlnError("--engine dask needs Dask distributed: pip install 'planefmt[dask]'",
                       code="CONVERSION_FAILED") from exc

    # The cluster's own log lines (a worker lost and restarted...) are not the user's to act on: what
    # they mean for an input is in its ledger line.
    logging.getLogger("distributed").setLevel(logging.CRITICAL)
    stack = contextlib.ExitStack()
    with stack:
        if scheduler:
            try:
                client = stack.enter_context(Client(scheduler, timeout="30s"))
            except (OSError, TimeoutError) as exc:
                raise PlnError(f"cannot reach the Dask scheduler: {describe(exc)}", code="CONVERSION_FAILED",
                               file=scheduler) from exc
        else:
            client = stack.enter_context(Client(_local_cluster(stack, processes)))
        return _dask_results(stack.pop_all(), client, jobs)


def _local_cluster(stack: contextlib.ExitStack, processes: int):
    from dask import config as dask_config
    from distributed import LocalCluster

    # No statistical profiler in the workers: it samples every 10 ms, for a dashboard the run has not.
    stack.enter_context(dask_config.set({"distributed.worker.profile.enabled": False}))
    # No dashboard; the scheduler's HTTP server (health, metrics) still starts, on a free port rather
    # than 8787, which another cluster on the machine may hold.
    return stack.enter_context(LocalCluster(
        n_workers=processes, processes=True, threads_per_worker=1, dashboard_address=None,
        scheduler_kwargs={"dashboard_address": ":0"}, silence_logs=logging.CRITICAL, preload=[__name__]))


def dask_setup(worker: object) -> None:
    """Dask's preload hook, run in each worker process of a run's LocalCluster as it starts: Ctrl-C on a
    terminal reaches the whole process group, and it is the client's to act on (closing the cluster
    ends the workers); a worker would print a KeyboardInterrupt traceback."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _dask_results(stack: contextlib.ExitStack, client, jobs: list[dict]) -> Iterator[dict]:
    from distributed import as_completed
    from distributed.scheduler import KilledWorker

    with stack:
        # A few inputs per task: each task costs the scheduler, the client and the worker's comms a few
        # milliseconds, which on two cores busy with two conversions come out of the conversions (300
        # tiny meshes, bench/batch.py: 2 workers over 1 1.47x one input a task, 1.7x or more in tasks
        # of up to DASK_TASK_INPUTS), while at least 8 tasks a worker keep the ends of the run even.
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        size = max(1, min(DASK_TASK_INPUTS, len(jobs) // (8 * workers)))
        chunks = [jobs[i:i + size] for i in range(0, len(jobs), size)]
        futures = client.map(run_on_dask_worker, chunks, pure=False)
        chunk_of = {future.key: chunk for future, chunk in zip(futures, chunks)}
        for future in as_completed(futures):
            chunk = chunk_of[future.key]
            try:
                entries = future.result()
            except KilledWorker as exc:  # Dask gave up after losing several workers on these inputs
                entries = [failed_entry(job, "WORKER_LOST", f"{job['source']}: the Dask workers converting it "
                                        f"were lost: {describe(exc)}") for job in chunk]
            except Exception as exc:  # noqa: BLE001 - the task's own error: a worker without planefmt...
                entries = [failed_entry(job, "CONVERSION_FAILED", f"{job['source']}: on the Dask worker: "
                                        f"{describe(exc)}") for job in chunk]
            future.release()
            yield from entries


_on_this_thread = threading.local()


#: Inputs per Dask task, at most.
DASK_TASK_INPUTS = 8


def run_on_dask_worker(jobs: list[dict]) -> list[dict]:
    """The Dask task: convert ``jobs`` in turn in this worker thread's worker process."""
    worker = getattr(_on_this_thread, "worker", None)
    if worker is None:
        worker = _on_this_thread.worker = Worker()
    return [worker.run(job) for job in jobs]
