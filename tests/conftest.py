"""Shared fixtures: the quick study is run once per test session and reused.

Test-only models (fault injection, a noisy quadratic) live in ``tests/support`` and are named
``"sensfw_test_models:FaultInjection"`` etc. in studies and run specs. That folder is put on
``sys.path`` here and on ``PYTHONPATH`` for every process the tests start (``python -m sensfw``
subprocesses, forkserver and spawned workers, Dask workers and their run subprocesses), so each
of them imports the module by that name (see ``tests/support/sensfw_test_models.py``).
"""

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "studies" / "quick.toml"
# real measurements (never copied into the repository): $SENSFW_BERT_DATA or ../shared/data/bert
BERT = Path(os.environ.get("SENSFW_BERT_DATA") or ROOT / ".." / "shared" / "data" / "bert")
SUPPORT = ROOT / "tests" / "support"

if str(SUPPORT) not in sys.path:
    sys.path.insert(0, str(SUPPORT))
os.environ["PYTHONPATH"] = os.pathsep.join(
    [str(SUPPORT), *filter(None, [os.environ.get("PYTHONPATH")])])


#: the files that take longest (pytest --durations on 2 cores, stop 38: 150-600 s each, the
#: rest of the suite about 700 s together): collected first, so that the two test processes
#: (pytest-xdist with ``--dist loadfile --no-loadscope-reorder``, pyproject.toml) start on
#: them and the short files fill in after, instead of a long file starting last beside an
#: idle process
LONGEST_FIRST = ("measure/test_diagnose.py", "measure/test_bert_loop.py",
                 "measure/test_stepped_models.py", "measure/test_recovery_cases.py")


def pytest_collection_modifyitems(config, items):
    def rank(item) -> int:
        path = item.path.as_posix()
        return next((i for i, f in enumerate(LONGEST_FIRST) if path.endswith(f)),
                    len(LONGEST_FIRST))

    items.sort(key=rank)  # stable: each file's tests keep their order


def run_cli(*args, timeout=300):
    return subprocess.run([sys.executable, "-m", "sensfw", *map(str, args)],
                          capture_output=True, text=True, timeout=timeout, cwd=ROOT)


@pytest.fixture(scope="session")
def quick(tmp_path_factory):
    """(output folder, wall seconds) of ``sensfw run studies/quick.toml`` (processes)."""
    out = tmp_path_factory.mktemp("quick")
    t0 = time.perf_counter()
    proc = run_cli("run", QUICK, "--out", out, "--workers", 2, "--no-progress")
    wall = time.perf_counter() - t0
    assert proc.returncode == 0, proc.stderr
    return out, wall


@pytest.fixture(scope="session")
def cli():
    """Run ``python -m sensfw ARGS`` from the repository root."""
    return run_cli


@pytest.fixture(scope="session")
def bert():
    """The UNESP-BERT swept-sine folder (``T5Nm/chirp_70_110Hz`` with ``level_0p05`` ...
    ``level_0p30``); the test is skipped when the data are absent."""
    chirp = BERT / "T5Nm" / "chirp_70_110Hz"
    if not chirp.is_dir():
        pytest.skip(f"UNESP-BERT data not found at {BERT} (set SENSFW_BERT_DATA)")
    return chirp
