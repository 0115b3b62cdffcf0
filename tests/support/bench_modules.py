"""The benchmark scripts under ``bench/`` imported as modules by the tests that keep a
fixed-seed subset of them (``bench/`` is not a package, and its ``signal.py`` would shadow
the standard library's if the folder were put on ``sys.path``)."""

import importlib.util
import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parents[2] / "bench"


def load(name: str):
    """``bench/NAME.py`` as the module ``sensfw_bench_NAME`` (registered in
    ``sys.modules``: a dataclass looks its module up there)."""
    key = f"sensfw_bench_{name}"
    if key in sys.modules:
        return sys.modules[key]
    spec = importlib.util.spec_from_file_location(key, BENCH / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[key] = mod
    spec.loader.exec_module(mod)
    return mod
