"""Executors: run independent simulations serially, on a local process pool, or on Dask.

Every backend calls ``on_result(spec, result)`` in the calling process as each run finishes,
so results stream into the run store one by one and a study killed at any moment keeps what
has finished. A run that fails, hangs past its timeout or kills its worker process becomes a
failed :class:`RunResult` with the reason; the others go on.
"""

from __future__ import annotations

import json
import math
import multiprocessing as mp
import os
import pickle
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


#: the child of :func:`_execute_subprocess`: the result goes to its own copy of stdout,
#: and whatever the model prints (Python or C, e.g. a plugin's print or a solver's
#: console output) to stderr, so that it cannot corrupt the pickle
_CHILD = ("import os, pickle, sys\n"
          "out = os.fdopen(os.dup(1), 'wb')\n"
          "os.dup2(2, 1)\n"
          "sys.stdout = sys.stderr\n"
          "from sensfw.runs.spec import execute\n"
          "result = execute(pickle.loads(sys.stdin.buffer.read()))\n"
          "out.write(pickle.dumps(result))\n"
          "out.flush()\n")


def _execute_subprocess(spec: RunSpec) -> RunResult:
    """:func:`execute` in a fresh interpreter (for daemonic processes such as Dask workers,
    which may not fork children), killed after ``spec.timeout`` seconds."""
    import subprocess
    import sys

    t0 = time.perf_counter()
    try:
        proc = subprocess.run([sys.executable, "-c", _CHILD], input=pickle.dumps(spec),
                              capture_output=True, timeout=spec.timeout)
    except subprocess.TimeoutExpired:
        return RunResult(spec.key(), False, error=f"timeout: no result after {spec.timeout:g} s",
                         wall=time.perf_counter() - t0)
    if proc.returncode != 0:
        tail = proc.stderr.decode(errors="replace").strip().splitlines()[-1:] or [""]
        return RunResult(spec.key(), False, wall=time.perf_counter() - t0,
                         error=f"worker process died (exit code {proc.returncode}) {tail[0]}")
    return pickle.loads(proc.stdout)


def execute_guarded(spec: RunSpec) -> RunResult:
    """:func:`execute`, in a child process killed after ``spec.timeout`` seconds if set
    (a hung simulation cannot be interrupted from Python otherwise)."""
    if not spec.timeout:
        return execute(spec)
    if mp.current_process().daemon:
        return _execute_subprocess(spec)
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
        try:
            spec = tasks.recv()
        except (EOFError, OSError):  # the parent is gone (killed): nothing left to do
            # and nobody reads what this worker put last: exit without waiting for the
            # queue's feeder thread to write it (it would wait for ever, the worker with it)
            results.cancel_join_thread()
            return
        if spec is None:
            return
        results.put((wid, _pickled(execute(spec))))


def _pickled(result: RunResult) -> bytes:
    """``result`` pickled here, in the worker: a queue pickles what it is given in a
    thread of its own, which drops what it cannot pickle with a traceback and no result,
    and the pool waited for it for ever (or until the run's timeout, reported as one).
    :func:`~sensfw.runs.spec.execute` leaves out the ``meta`` entries that cannot be
    pickled; a result that still cannot be becomes a failure that says why."""
    try:
        return pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception as err:
        return pickle.dumps(RunResult(
            result.key, False, wall=result.wall,
            error=f"the run's result cannot be sent back from its worker process ("
                  f"{type(err).__name__}: {err}): a model's Signals must hold plain data "
                  "(arrays, numbers, strings)"))


def _context():
    """Forkserver: workers fork from a server that has already imported numpy, scipy, Exudyn
    and sensfw, so starting (or replacing) a worker costs milliseconds, and no thread of the
    parent (progress bar) is forked."""
    ctx = mp.get_context("forkserver")
    ctx.set_forkserver_preload(["numpy", "scipy.signal", "exudyn", "sensfw.runs.spec",
                                "sensfw.models"])
    return ctx


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


def run_kind(spec: RunSpec) -> str:
    """What a run's cost depends on besides its parameter values: model, options, excitation
    and solver (the runs of one record by one model cost about the same)."""
    ident = spec.identity()
    ident.pop("params")
    return json.dumps(ident, sort_keys=True, separators=(",", ":"))


class ProcessPool:
    """A pool of worker processes fed one run at a time. A worker that exceeds a run's
    timeout, or dies, is killed and replaced; its run is recorded as failed. Reusable across
    batches (stages) of a study; close it (or use it as a context manager) at the end.

    A batch goes out longest first (Graham's LPT rule: its wall time is then within 4/3 of
    the shortest possible for independent runs on ``n`` workers), each run's length expected
    from the last run of its kind (:func:`run_kind`) this pool made, kinds it has not seen
    first. A calibration's point is one run per record, and its records differ in cost (a
    slipping joint at the highest level takes three times the lowest): in the given order
    the longest would often start last."""

    def __init__(self, workers: int | None = None):
        self.n = workers or default_workers()
        self._ctx = self._results = None
        self._pool: dict[int, _Worker] = {}
        self._walls: dict[str, float] = {}  # run kind -> wall seconds of its last run

    def _start(self, n: int) -> None:
        if self._ctx is None:
            self._ctx = _context()
            self._results = self._ctx.Queue()
        for wid in range(n):
            if wid not in self._pool or not self._pool[wid].proc.is_alive():
                self._pool[wid] = _Worker(self._ctx, self._results, wid)

    def order(self, specs: Sequence[RunSpec], kinds: dict[int, str] | None = None
              ) -> list[RunSpec]:
        """``specs`` longest expected first (kinds not yet seen first; stable otherwise)."""
        kinds = kinds or {id(s): run_kind(s) for s in specs}
        return sorted(specs, key=lambda s: -self._walls.get(kinds[id(s)], math.inf))

    def map(self, specs: Sequence[RunSpec], on_result: OnResult, poll: float = 0.1) -> None:
        if not specs:
            return
        kinds = {id(s): run_kind(s) for s in specs}
        pending = deque(self.order(specs, kinds))
        self._start(min(self.n, len(pending)))
        busy: dict[int, tuple[RunSpec, float]] = {}
        clean = False
        try:
            while pending or busy:
                for wid, w in self._pool.items():
                    if wid not in busy and pending:
                        spec = pending.popleft()
                        w.tasks.send(spec)
                        busy[wid] = (spec, time.monotonic())
                # every result that has come, before any run is judged timed out: a run
                # whose result waited while another was saved has finished in time
                try:
                    item = self._results.get(timeout=poll)
                    while True:
                        wid, res = item[0], pickle.loads(item[1])
                        if wid in busy and busy[wid][0].key() == res.key:
                            spec, _ = busy.pop(wid)
                            if res.wall:
                                self._walls[kinds[id(spec)]] = res.wall
                            on_result(spec, res)
                        item = self._results.get_nowait()
                except queue.Empty:
                    pass
                now = time.monotonic()
                for wid, (spec, start) in list(busy.items()):
                    w = self._pool[wid]
                    reason = None
                    if not w.proc.is_alive():
                        reason = f"worker process died (exit code {w.proc.exitcode})"
                    elif spec.timeout and now - start > spec.timeout:
                        reason = f"timeout: no result after {spec.timeout:g} s"
                    if reason:
                        w.stop(kill=True)
                        self._pool[wid] = _Worker(self._ctx, self._results, wid)
                        busy.pop(wid)
                        on_result(spec, RunResult(spec.key(), False, error=reason,
                                                  wall=now - start))
            clean = True
        finally:
            if not clean:  # interrupted: do not leave runs going
                self.close(kill=True)

    def close(self, kill: bool = False) -> None:
        for w in self._pool.values():
            w.stop(kill=kill)
        self._pool.clear()

    def __enter__(self) -> ProcessPool:
        return self

    def __exit__(self, *exc) -> None:
        self.close(kill=exc[0] is not None)


def run_processes(specs: Sequence[RunSpec], on_result: OnResult,
                  workers: int | None = None) -> None:
    """One-off :class:`ProcessPool` run."""
    with ProcessPool(workers) as pool:
        pool.map(specs, on_result)


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
        workers: int | None = None, scheduler: str | None = None,
        pool: ProcessPool | None = None) -> None:
    """Run ``specs`` on ``backend`` ("serial", "processes" or "dask"); ``pool`` reuses a
    process pool across calls."""
    if backend == "serial":
        run_serial(specs, on_result)
    elif backend == "processes":
        if pool is not None:
            pool.map(specs, on_result)
        else:
            run_processes(specs, on_result, workers)
    elif backend == "dask":
        run_dask(specs, on_result, scheduler)
    else:
        raise SensfwError(f"unknown execution backend {backend!r}; available: "
                          f"{', '.join(BACKENDS)}")
