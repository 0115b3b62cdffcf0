"""Private input checks shared by the public signal functions."""

from __future__ import annotations

import numpy as np

from ..errors import SignalError


def as_signal(x, name: str, min_len: int = 8) -> np.ndarray:
    arr = np.asarray(x, dtype=float)
    if arr.ndim != 1:
        raise SignalError(f"{name} must be one-dimensional, got shape {arr.shape}")
    if len(arr) < min_len:
        raise SignalError(f"{name} has {len(arr)} samples; need at least {min_len}")
    if not np.all(np.isfinite(arr)):
        raise SignalError(f"{name} contains NaN or inf (first at sample "
                          f"{int(np.argmax(~np.isfinite(arr)))})")
    return arr


def check_fs(fs: float) -> float:
    try:
        value = float(fs)
    except (TypeError, ValueError):
        value = float("nan")
    if not (np.isfinite(value) and value > 0):
        raise SignalError(f"sample rate fs must be a positive number, got {fs!r}")
    return value


def same_length(a: np.ndarray, b: np.ndarray, na: str, nb: str) -> None:
    if len(a) != len(b):
        raise SignalError(f"{na} has {len(a)} samples but {nb} has {len(b)}")
