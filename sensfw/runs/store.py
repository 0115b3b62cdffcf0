"""The run store: one folder, one entry per run key; the single source of truth of a study.

An entry is ``<key>.json`` (status, parameters, wall time, error, the SHA-256 of the signal
file) plus, for a finished run, ``<key>.npz`` (the signals). Both are written to a temporary
file in the same folder and renamed into place (atomic on POSIX), the signal file first; the
JSON is the commit record. A run is complete only when its JSON exists and the checksum in it
matches the signal file; anything else (killed writer, truncated or corrupted file) reads as
absent and is recomputed. Two writers of the same key write identical content, so concurrent
workers cannot corrupt an entry; a failure (a timeout, a dead worker) never replaces a
finished run of the same key (:meth:`RunStore.save`).
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..models.base import Signals
from .spec import RunResult, RunSpec


def _atomic_write(path: Path, data: bytes) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def _read_record(path: Path) -> dict | None:
    """The JSON object in ``path``, or None (absent, not JSON, or JSON but not an object:
    ``null``, a list, a number)."""
    try:
        meta = json.loads(path.read_text())
    except (FileNotFoundError, json.JSONDecodeError, UnicodeDecodeError):
        return None
    return meta if isinstance(meta, dict) else None


class RunStore:
    """Run entries in ``folder`` (created on first write). ``read_also``: other run stores'
    folders read (never written) where ``folder`` lacks a run, e.g. the runs of the
    diagnosis an ``augment`` starts from."""

    def __init__(self, folder: str | os.PathLike, read_also: Sequence[str | os.PathLike] = ()):
        self.folder = Path(folder)
        self.read_also = [RunStore(f) for f in read_also]

    def _paths(self, key: str) -> tuple[Path, Path]:
        return self.folder / f"{key}.json", self.folder / f"{key}.npz"

    def record(self, key: str) -> dict | None:
        """The committed record of ``key``, or None if absent or not intact."""
        return next((m for _, m in self._found(key)), None)

    def _found(self, key: str):
        for store in (self, *self.read_also):
            meta = store._own_record(key)
            if meta is not None:
                yield store, meta

    def _own_record(self, key: str) -> dict | None:
        meta_path, data_path = self._paths(key)
        meta = _read_record(meta_path)
        if meta is None:
            return None
        if meta.get("status") == "ok":
            try:
                digest = hashlib.sha256(data_path.read_bytes()).hexdigest()
            except FileNotFoundError:
                return None
            if digest != meta.get("sha256"):
                return None
        elif meta.get("status") != "failed":
            return None
        return meta

    def damaged(self, key: str) -> bool:
        """Whether the store holds a record of ``key`` whose signal file is missing or fails
        its checksum (a disk full, a copy cut short): read as absent, named as damaged."""
        meta = _read_record(self._paths(key)[0])
        return meta is not None and meta.get("status") == "ok" and \
            self._own_record(key) is None

    def has(self, key: str, include_failed: bool = True) -> bool:
        meta = self.record(key)
        return meta is not None and (include_failed or meta["status"] == "ok")

    def load(self, key: str) -> RunResult | None:
        """The stored result of ``key`` (signals loaded), or None if absent/corrupt."""
        store, meta = next(self._found(key), (None, None))
        if meta is None:
            return None
        if meta["status"] == "failed":
            return RunResult(key, False, error=meta.get("error"), wall=meta.get("wall", 0.0),
                             cached=True)
        _, data_path = store._paths(key)
        with np.load(data_path, allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in npz.files}
        return RunResult(key, True, signals=Signals.from_arrays(arrays),
                         wall=meta.get("wall", 0.0), cached=True)

    def save(self, spec: RunSpec, result: RunResult) -> None:
        """Commit ``result`` of ``spec`` (signal file first, then the JSON record). A failure
        never replaces an intact finished run of the same key: a run's signals follow from
        its key, so a failure after a success is the machine's (another writer's run that
        timed out or whose worker died), and the finished run stays."""
        if not result.ok:
            held = self._own_record(result.key)
            if held is not None and held["status"] == "ok":
                return
        self.folder.mkdir(parents=True, exist_ok=True)
        meta_path, data_path = self._paths(result.key)
        meta = {"key": result.key, "status": "ok" if result.ok else "failed",
                "wall": round(float(result.wall), 6), "spec": spec.identity()}
        if result.ok:
            buf = io.BytesIO()
            np.savez(buf, **result.signals.to_arrays())
            data = buf.getvalue()
            _atomic_write(data_path, data)
            meta["sha256"] = hashlib.sha256(data).hexdigest()
            # the step actually used: chosen by the model (auto_step), halved after divergence;
            # the integrator and, for adaptive runs, its tolerance and the steps it took
            for k in ("step", "substeps", "step_limited_by", "step_halvings", "integrator",
                      "tolerance", "steps", "rejected_steps", "mean_step"):
                if k in result.signals.meta:
                    meta[k] = result.signals.meta[k]
        else:
            meta["error"] = result.error
            if spec.timeout:  # the machine's limit, not the run's: a longer one may pass
                meta["timeout"] = float(spec.timeout)
        _atomic_write(meta_path, json.dumps(meta, indent=1, sort_keys=True).encode())

    def keys(self) -> list[str]:
        if not self.folder.exists():
            return []
        return sorted(p.stem for p in self.folder.glob("*.json"))


def run_step(store: RunStore, key: str) -> dict:
    """The time step a stored run used, what set it, and the integrator (adaptive runs: at
    most ``step``, with ``mean_step``); ``{}`` for models without one."""
    rec = store.record(key) or {}
    return {k: rec[k] for k in ("step", "step_limited_by", "integrator", "mean_step")
            if k in rec}
