"""Scale-out and faults (issue 7): Dask gives the same results as local processes, a killed
Dask worker loses nothing, analyses say what is missing or refuse clearly."""

import json
import os
import signal
import threading
import time
from pathlib import Path

import pytest
from sensfw_test_models import FAULT_INJECTION

from sensfw.excitation import Chirp
from sensfw.models.base import SolverSettings
from sensfw.plugins import models
from sensfw.runs import Runner, RunSpec, RunStore

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "studies" / "quick.toml"


@pytest.fixture(scope="module")
def cluster():
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as c:
        yield c


@pytest.mark.slow
def test_dask_backend_gives_identical_results(quick, cli, cluster, tmp_path):
    ref, _ = quick
    proc = cli("run", QUICK, "--out", tmp_path, "--scheduler", cluster.scheduler_address,
               "--no-progress", "--no-report")
    assert proc.returncode == 0, proc.stderr
    got = json.loads((tmp_path / "results.json").read_text())
    want = json.loads((ref / "results.json").read_text())
    assert got["runs"]["new"] == want["runs"]["total"] and got["runs"]["failed"] == 0
    assert got["stages"] == want["stages"]


@pytest.mark.slow
def test_killed_dask_worker_loses_and_duplicates_nothing(cluster, tmp_path):
    from distributed import Client

    opts = {"model": "two_dof", "slow_seconds": 0.4}
    m = models.get(FAULT_INJECTION)(**opts)
    ex = Chirp(50, 500, 0.05, 4000, 1.0)
    specs = [RunSpec.create(m, m.parameters().complete({"k1": 2000.0 + 100 * i}), ex,
                            SolverSettings(), {"name": FAULT_INJECTION, "options": opts})
             for i in range(12)]
    with Client(cluster) as client:
        pids = client.run(os.getpid)
    victim = sorted(pids.values())[0]
    results = []

    def killer():
        while len(results) < 2:
            time.sleep(0.02)
        os.kill(victim, signal.SIGKILL)  # a worker dies in the middle of its next run

    t = threading.Thread(target=killer, daemon=True)
    t.start()
    store = RunStore(tmp_path)
    runner = Runner(store, backend="dask", scheduler=cluster.scheduler_address)
    runner.run(specs, on_result=lambda s, r: results.append(r.key))
    t.join(timeout=5)
    assert sorted(results) == sorted(s.key() for s in specs)  # each run exactly once
    assert runner.counts.new == 12 and runner.counts.failed == 0
    assert len(store.keys()) == 12 and all(store.load(s.key()).ok for s in specs)
    with Client(cluster) as client:
        client.wait_for_workers(2, timeout=30)  # the nanny restarted the killed worker


STUDY = """
[study]
name = "refuse"
[model]
name = "sensfw_test_models:FaultInjection"
options = {{ model = "two_dof", diverge = {{ parameter = "k1", above = {above}, below = 2500.0 }} }}
output = "a1"
[excitation]
f0 = "50 Hz"
f1 = "2 kHz"
duration = "0.2 s"
fs = "20 kHz"
[execution]
backend = "serial"
[[stages]]
name = "screen"
design = "oat"
scorers = [{{ name = "frf_db_rms", band = [60.0, 1900.0] }}]
select = {{ threshold = 0.1 }}
"""


@pytest.mark.slow  # real simulations through the CLI or a worker pool
def test_oat_refuses_a_variable_with_no_run_but_keeps_the_runs(cli, tmp_path):
    study = tmp_path / "s.toml"
    study.write_text(STUDY.format(above=7000.0))  # k1 fails at both its min and its max
    proc = cli("run", study, "--out", tmp_path / "o", "--no-progress")
    assert proc.returncode == 2
    assert "variable 'k1' has neither its min nor its max run" in proc.stderr
    assert "Traceback" not in proc.stderr
    records = list((tmp_path / "o" / "runs").glob("*.json"))
    assert len(records) == 13  # 2 x 6 + nominal: every run, failed or not, is kept


@pytest.mark.slow  # real simulations through the CLI or a worker pool
def test_a_stage_whose_every_run_fails_says_so_and_keeps_them(cli, tmp_path):
    study = tmp_path / "s.toml"
    # every k1 diverges, the nominal's too; a scorer without a reference run (with one, its
    # failure is reported first)
    text = STUDY.format(above=1.0).replace('name = "frf_db_rms", band = [60.0, 1900.0]',
                                           'name = "rms"')
    assert 'name = "rms"' in text
    study.write_text(text)
    proc = cli("run", study, "--out", tmp_path / "o", "--no-progress")
    assert proc.returncode == 2, proc.stderr
    assert "stage 'screen': all 13 runs failed" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert len(list((tmp_path / "o" / "runs").glob("*.json"))) == 13


@pytest.mark.slow  # real simulations through the CLI or a worker pool
def test_oat_uses_one_end_and_says_so(cli, tmp_path):
    study = tmp_path / "s.toml"
    study.write_text(STUDY.format(above=1e9))  # only k1's min run fails
    proc = cli("run", study, "--out", tmp_path / "o", "--no-progress")
    assert proc.returncode == 0, proc.stderr
    st = json.loads((tmp_path / "o" / "results.json").read_text())["stages"][0]
    assert list(st["failed"]) == ["k1:min"]
    assert any("k1: only its max run finished" in n for n in st["notes"])
