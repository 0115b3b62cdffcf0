"""Executors: run independent simulations serially, on a local process pool, or on Dask.

Every backend calls ``on_result(spec, result)`` in the calling process as each run finishes,
so results stream into the run store one by one and a study killed at any moment keeps what
has finished. A run that fails, hangs past its timeout or kills its worker process becomes a
failed :class:`RunResult` with the reason; the others go on.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import queue
import time
from collections import deque
from collections.abc import Callable, Sequence

from ..errors import SensfwError
from .spec import RunResult, RunSpec, execute

OnResult = Callable[[RunSpec, RunResult], None]
BACKENDS = ("serial", "processes", "dask")


def default_workers() -> int:
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
               else os.cpu_count() or 1)


def _child(conn, spec: RunSpec) -> None:
    conn.send(execute(spec))
    conn.close()


def execute_guarded(spec: RunSpec) -> RunResult:
    """:func:`execute`, in a child process killed after ``spec.timeout`` seconds if set
    (a hung simulation cannot be interrupted from Python otherwise)."""
    if not spec.timeout:
        return execute(spec)
    ctx = mp.get_context("spawn")
    recv, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_child, args=(send, spec), daemon=True)
    t0 = time.perf_counter()
    proc.start()
    send.close()
    try:
        if recv.poll(spec.timeout):
            return recv.recv()
        return RunResult(spec.key(), False, error=f"timeout: no result after {spec.timeout:g} s",
                         wall=time.perf_counter() - t0)
    except EOFError:
        return RunResult(spec.key(), False, wall=time.perf_counter() - t0,
                         error=f"worker process died (exit code {proc.exitcode})")
    finally:
        if proc.is_alive():
            proc.kill()
        proc.join()


def run_serial(specs: Sequence[RunSpec], on_result: OnResult) -> None:
    for spec in specs:
        on_result(spec, execute_guarded(spec))


# ---- local process pool ----------------------------------------------------------------------
def _worker_main(tasks, results, wid: int) -> None:
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides what to do on Ctrl-C
    while True:
        spec = tasks.recv()
        if spec is None:
            return
        results.put((wid, execute(spec)))


class _Worker:
    def __init__(self, ctx, results, wid: int):
        self.tasks, child_end = ctx.Pipe()
        self.proc = ctx.Process(target=_worker_main, args=(child_end, results, wid), daemon=True)
        self.proc.start()
        self.wid = wid

    def stop(self, kill: bool = False) -> None:
        if kill:
            self.proc.kill()
        else:
            try:
                self.tasks.send(None)
            except (BrokenPipeError, OSError):
                pass
        self.proc.join(timeout=5)
        if self.proc.is_alive():
            self.proc.kill()
            self.proc.join()


def run_processes(specs: Sequence[RunSpec], on_result: OnResult, workers: int | None = None,
                  poll: float = 0.1) -> None:
    """Local pool of worker processes fed one run at a time. A worker that exceeds a run's
    timeout, or dies, is killed and replaced; its run is recorded as failed."""
    pending = deque(specs)
    if not pending:
        return
    ctx = mp.get_context("spawn")
    results = ctx.Queue()
    n = min(workers or default_workers(), len(pending))
    pool = {i: _Worker(ctx, results, i) for i in range(n)}
    busy: dict[int, tuple[RunSpec, float]] = {}
    try:
        while pending or busy:
            for wid, w in pool.items():
                if wid not in busy and pending:
                    spec = pending.popleft()
                    w.tasks.send(spec)
                    busy[wid] = (spec, time.monotonic())
            try:
                wid, res = results.get(timeout=poll)
                if wid in busy and busy[wid][0].key() == res.key:
                    spec, _ = busy.pop(wid)
                    on_result(spec, res)
            except queue.Empty:
                pass
            now = time.monotonic()
            for wid, (spec, start) in list(busy.items()):
                w = pool[wid]
                reason = None
                if not w.proc.is_alive():
                    reason = f"worker process died (exit code {w.proc.exitcode})"
                elif spec.timeout and now - start > spec.timeout:
                    reason = f"timeout: no result after {spec.timeout:g} s"
                if reason:
                    w.stop(kill=True)
                    pool[wid] = _Worker(ctx, results, wid)
                    busy.pop(wid)
                    on_result(spec, RunResult(spec.key(), False, error=reason, wall=now - start))
    finally:
        for w in pool.values():
            w.stop(kill=bool(busy))


# ---- Dask ------------------------------------------------------------------------------------
def run_dask(specs: Sequence[RunSpec], on_result: OnResult, scheduler: str | None = None,
             retries: int = 2, client=None) -> None:
    """Submit every run as an independent Dask task (with retries); results stream back as
    they finish. ``scheduler`` is a ``tcp://host:port`` address (dask-jobqueue and Kubernetes
    clusters expose one); ``client`` an existing ``distributed.Client``."""
    try:
        from distributed import Client, as_completed
    except ImportError as err:  # pragma: no cover - dask is a dependency
        raise SensfwError("the dask backend needs 'distributed' installed") from err
    own = client is None
    if own:
        if not scheduler:
            raise SensfwError("the dask backend needs a scheduler address "
                              "(--scheduler tcp://host:port or [execution] scheduler)")
        try:
            client = Client(scheduler, timeout="20s")
        except OSError as err:
            raise SensfwError(f"cannot reach Dask scheduler {scheduler}: {err}") from None
    try:
        by_key = {}
        futures = []
        for spec in specs:
            fut = client.submit(execute_guarded, spec, key=f"sensfw-run-{spec.key()}",
                                retries=retries, pure=False)
            by_key[fut.key] = spec
            futures.append(fut)
        for fut in as_completed(futures):
            spec = by_key[fut.key]
            try:
                res = fut.result()
            except Exception as err:  # lost to repeated worker deaths etc.
                res = RunResult(spec.key(), False, error=f"dask task failed: {err}")
            on_result(spec, res)
            fut.release()
    finally:
        if own:
            client.close()


def run(specs: Sequence[RunSpec], on_result: OnResult, backend: str = "processes",
        workers: int | None = None, scheduler: str | None = None) -> None:
    """Run ``specs`` on ``backend`` ("serial", "processes" or "dask")."""
    if backend == "serial" or (backend == "processes" and (workers == 1 or len(specs) <= 1)
                               and not any(s.timeout for s in specs)):
        run_serial(specs, on_result)
    elif backend == "processes":
        run_processes(specs, on_result, workers)
    elif backend == "dask":
        run_dask(specs, on_result, scheduler)
    else:
        raise SensfwError(f"unknown execution backend {backend!r}; available: "
                          f"{', '.join(BACKENDS)}")
