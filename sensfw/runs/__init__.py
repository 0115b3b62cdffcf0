"""Runs: what identifies a simulation (spec), where finished ones live (store) and how they
are executed (serial, local processes, Dask)."""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from ..errors import SensfwError
from .executor import BACKENDS, ProcessPool, default_workers, run
from .spec import RunResult, RunSpec, execute
from .store import RunStore

__all__ = ["BACKENDS", "ProcessPool", "RunCounts", "RunResult", "RunSpec", "RunStore",
           "Runner", "StoredRuns", "default_workers", "execute"]


@dataclass
class RunCounts:
    total: int = 0
    new: int = 0
    cached: int = 0
    failed: int = 0

    def as_dict(self) -> dict[str, int]:
        return {"total": self.total, "new": self.new, "cached": self.cached,
                "failed": self.failed}


class Progress:
    """Progress reporting interface (the CLI plugs in a rich progress bar)."""

    def start(self, label: str, total: int, cached: int, failed: int = 0) -> None:
        """A batch of ``total`` runs, ``cached`` of them already stored, ``failed`` of
        those failed (and not retried)."""

    def advance(self, ok: bool) -> None: ...

    def stop(self) -> None: ...


def _outgrown(rec: dict, spec: RunSpec) -> bool:
    """A stored failure that was a timeout shorter than ``spec``'s: the timeout is not part
    of a run's key (it is the machine's limit, not the run's), so a run stopped at 0.3 s is
    tried again under 120 s, or with no timeout at all, instead of being handed back as
    failed."""
    error = str(rec.get("error") or "")
    if not error.startswith("timeout:"):
        return False
    if not spec.timeout:  # no limit now: longer than any it ran out of
        return True
    before = rec.get("timeout")
    if before is None:  # stored before the timeout was: read it from the message
        m = re.search(r"after ([0-9.eE+-]+) s", error)
        before = float(m.group(1)) if m else None
    return before is not None and float(spec.timeout) > float(before) * (1 + 1e-9)


@dataclass
class Runner:
    """Runs specs through the store: finished runs are loaded, missing ones computed and
    saved as each finishes. ``counts`` accumulates over every call (one study)."""

    store: RunStore
    backend: str = "processes"
    workers: int | None = None
    scheduler: str | None = None
    progress: Progress = field(default_factory=Progress)
    retry_failed: bool = False
    counts: RunCounts = field(default_factory=RunCounts)
    _seen: set = field(default_factory=set)
    _pool: ProcessPool | None = None

    def run(self, specs: Sequence[RunSpec], label: str = "runs",
            on_result: Callable[[RunSpec, RunResult], None] | None = None) -> dict[str, str]:
        """Make sure every spec has a stored result; returns key -> "ok" | "failed"."""
        unique: dict[str, RunSpec] = {}
        for s in specs:
            unique.setdefault(s.key(), s)
        todo, status, stored_failed = [], {}, 0
        for key, spec in unique.items():
            rec = self.store.record(key)
            if rec is not None and rec["status"] != "ok" and _outgrown(rec, spec):
                rec = None  # it ran out of a shorter time than it has now: run it again
            if rec is not None and (rec["status"] == "ok" or not self.retry_failed):
                status[key] = rec["status"]
                stored_failed += rec["status"] == "failed"
                if key not in self._seen:
                    self.counts.cached += 1
                    self.counts.failed += rec["status"] == "failed"
            else:
                todo.append(spec)
        for key in unique:
            if key not in self._seen:
                self._seen.add(key)
                self.counts.total += 1
        self.progress.start(label, len(unique), len(unique) - len(todo), stored_failed)

        def done(spec: RunSpec, result: RunResult) -> None:
            self.store.save(spec, result)
            status[result.key] = "ok" if result.ok else "failed"
            self.counts.new += 1
            self.counts.failed += not result.ok
            self.progress.advance(result.ok)
            if on_result is not None:
                on_result(spec, result)

        try:
            if todo:
                if self.backend == "processes" and self._pool is None:
                    self._pool = ProcessPool(self.workers)
                run(todo, done, backend=self.backend, workers=self.workers,
                    scheduler=self.scheduler, pool=self._pool)
        finally:
            self.progress.stop()
        return status

    def close(self) -> None:
        """Stop the worker processes (a Runner is reusable until then)."""
        if self._pool is not None:
            self._pool.close()
            self._pool = None

    def __enter__(self) -> Runner:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def load(self, key: str) -> RunResult | None:
        return self.store.load(key)


class MissingRunError(SensfwError):
    """A run that should be in the run store is not (``StoredRuns`` never simulates)."""


@dataclass
class StoredRuns:
    """The :class:`Runner` interface over a run store that never simulates: :meth:`run`
    checks that every spec has a stored result and raises :class:`MissingRunError` if not.
    Used to rebuild a report from an output folder (``sensfw report DIR``)."""

    store: RunStore
    counts: RunCounts = field(default_factory=RunCounts)

    def run(self, specs: Sequence[RunSpec], label: str = "runs",
            on_result: Callable[[RunSpec, RunResult], None] | None = None) -> dict[str, str]:
        status = {}
        for s in specs:
            key = s.key()
            rec = self.store.record(key)
            if rec is None:
                if self.store.damaged(key):
                    raise MissingRunError(f"{label}: run {key} in the run store "
                                          f"{self.store.folder} is damaged (its signal file "
                                          "is missing or fails its checksum); rerun the study "
                                          "to simulate it again")
                raise MissingRunError(f"{label}: run {key} is not in the run store "
                                      f"{self.store.folder} (the study, the model or sensfw "
                                      "changed since it ran?); rerun the study")
            status[key] = rec["status"]
        return status

    def load(self, key: str) -> RunResult | None:
        return self.store.load(key)

    def close(self) -> None:
        pass
