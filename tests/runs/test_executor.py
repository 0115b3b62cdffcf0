"""Executors: results stream back one by one; hangs, crashes and failures become failed runs
without losing the others."""

import time

import pytest
from sensfw_test_models import FAULT_INJECTION

from sensfw.excitation import Chirp
from sensfw.models.base import SolverSettings
from sensfw.plugins import models
from sensfw.runs import Progress, Runner, RunSpec, RunStore
from sensfw.runs.executor import run_processes

EX = Chirp(50, 500, 0.05, 4000, 1.0)
FAULTS = {"model": "ishigami", "crash": {"parameter": "x1", "above": 2.5},
          "hang": {"parameter": "x2", "above": 2.5}, "hang_seconds": 60.0,
          "diverge": {"parameter": "x3", "above": 2.5}}


def specs(points, timeout=None):
    m = models.get(FAULT_INJECTION)(**FAULTS)
    ref = {"name": FAULT_INJECTION, "options": FAULTS}
    return [RunSpec.create(m, m.parameters().complete(p), EX, SolverSettings(timeout=timeout),
                           ref) for p in points]


@pytest.mark.slow  # real simulations through the CLI or a worker pool
def test_process_pool_survives_crash_hang_and_divergence():
    points = [{"x1": 0.1}, {"x1": 3.0}, {"x2": 3.0}, {"x3": 3.0}, {"x1": -1.0}, {"x2": 1.0}]
    got = {}
    run_processes(specs(points, timeout=8.0), lambda s, r: got.__setitem__(s.key(), r),
                  workers=2)
    results = [got[s.key()] for s in specs(points)]
    # every run has its result: the two after the crash, the hang and the divergence ran on
    # replaced workers and finished
    assert [r.ok for r in results] == [True, False, False, False, True, True]
    assert "died" in results[1].error
    # the 60 s hang was cut at the run's own 8 s timeout (a hang that ran out by itself
    # would have returned a result, not this error)
    assert results[2].error == "timeout: no result after 8 s"
    assert "diverged" in results[3].error


def test_runner_caches_and_counts(tmp_path):
    store = RunStore(tmp_path)
    points = [{"x1": v} for v in (-1.0, 0.0, 1.0)] + [{"x3": 3.0}]
    r1 = Runner(store, backend="serial")
    status = r1.run(specs(points))
    assert sorted(status.values()) == ["failed", "ok", "ok", "ok"]
    assert r1.counts.as_dict() == {"total": 4, "new": 4, "cached": 0, "failed": 1}
    r2 = Runner(store, backend="serial")
    r2.run(specs(points))
    assert r2.counts.as_dict() == {"total": 4, "new": 0, "cached": 4, "failed": 1}
    class Seen(Progress):
        def start(self, label, total, cached, failed=0):
            self.batch = (total, cached, failed)

    r4 = Runner(store, backend="serial", progress=Seen())
    r4.run(specs(points))
    # the bar's "failed" counts the stored failure it does not retry (it showed 0)
    assert r4.progress.batch == (4, 4, 1)
    r3 = Runner(store, backend="serial", retry_failed=True)
    r3.run(specs(points))
    assert r3.counts.new == 1 and r3.counts.cached == 3


def test_unknown_backend_is_a_clear_error(tmp_path):
    from sensfw.errors import SensfwError

    with pytest.raises(SensfwError, match=r"unknown execution backend 'gpu'.*serial"):
        Runner(RunStore(tmp_path), backend="gpu").run(specs([{"x1": 0.0}, {"x1": 1.0}]))


def test_a_pool_sends_the_longest_runs_first():
    """Graham's LPT rule: a batch goes out longest first, each run's length expected from
    the last run of its kind (everything but the parameter values) the pool made; kinds it
    has not seen go first, and runs the pool cannot tell apart keep their order."""
    from sensfw.runs.executor import ProcessPool, run_kind

    m = models.get(FAULT_INJECTION)(**FAULTS)
    ref = {"name": FAULT_INJECTION, "options": FAULTS}

    def spec(x1, ex):
        return RunSpec.create(m, m.parameters().complete({"x1": x1}), ex, SolverSettings(),
                              ref)

    short, long_, new = EX, Chirp(50, 500, 0.1, 4000, 1.0), Chirp(50, 500, 0.2, 4000, 1.0)
    with ProcessPool(1) as pool:
        first = [spec(0.1, short), spec(0.2, long_)]
        pool.map(first, lambda s, r: None)
        # what the pool learnt: the wall time of each kind's run
        assert set(pool._walls) == {run_kind(s) for s in first}
        pool._walls[run_kind(first[0])], pool._walls[run_kind(first[1])] = 0.1, 5.0
        batch = [spec(0.3, short), spec(0.4, long_), spec(0.5, short), spec(0.6, new),
                 spec(0.7, long_)]
        got = [s.params["x1"] for s in pool.order(batch)]
    assert got == [0.6, 0.4, 0.7, 0.3, 0.5]


@pytest.mark.slow  # a worker pool
def test_a_run_whose_result_waits_behind_another_is_not_timed_out():
    """The pool read one result per round and then judged the busy runs' timeouts: a run
    that finished in 1 s of its 3 s, while the result before it was being saved (5 s here:
    a slow disk, a large signal file), was killed and recorded as 'timeout: no result after
    3 s', its result in the queue thrown away. Every result that has come is now taken
    first."""
    from sensfw.runs.executor import ProcessPool

    faults = {"model": "ishigami", "hang": {"parameter": "x2", "above": 2.5},
              "hang_seconds": 1.0}
    m = models.get(FAULT_INJECTION)(**faults)
    ref = {"name": FAULT_INJECTION, "options": faults}

    def spec(p):
        return RunSpec.create(m, m.parameters().complete(p), EX,
                              SolverSettings(timeout=3.0), ref)

    got = {}

    def slow_save(spec, res):
        got[spec.key()] = res
        if len(got) == 1:  # the first result of the batch takes 5 s to save
            time.sleep(5.0)

    with ProcessPool(2) as pool:
        pool.map([spec({"x1": 0.2}), spec({"x1": 0.3})], lambda s, r: None)  # started
        quick, waits = spec({"x1": 0.1}), spec({"x2": 3.0})
        pool.map([quick, waits], slow_save)
    assert got[quick.key()].ok
    assert got[waits.key()].ok, got[waits.key()].error


def test_a_run_in_a_fresh_interpreter_survives_what_its_model_prints():
    """Under Dask (daemonic workers) a run with a timeout executes in a fresh interpreter
    that sent its result pickled on stdout: a model that printed anything (a plugin's
    print, a solver's console output) corrupted it ('UnpicklingError: Memo value not
    found'), the task failed and was retried for nothing. The model's output goes to
    stderr now and the result arrives intact."""
    from sensfw.runs.executor import _execute_subprocess
    from sensfw.runs.spec import execute

    faults = {"model": "two_dof", "chatter": "hello from the model"}
    m = models.get(FAULT_INJECTION)(**faults)
    spec = RunSpec.create(m, m.parameters().complete({}), EX, SolverSettings(timeout=120.0),
                          {"name": FAULT_INJECTION, "options": faults})
    res = _execute_subprocess(spec)
    assert res.ok, res.error
    here = execute(spec)
    for ch, x in here.signals.channels.items():
        assert (res.signals.channels[ch] == x).all()


@pytest.mark.slow  # a worker pool
def test_a_result_the_pool_cannot_pickle_whole_is_sent_without_what_it_cannot():
    """A model whose signals hold a function (in ``meta``): the worker's queue thread could
    not pickle the result, dropped it with a traceback on stderr, and the pool waited for
    it until the run's timeout ('timeout: no result after 20 s'; without a timeout, for
    ever), where the serial backend stored the run. The meta entry is left out by every
    backend (the store keeps none such) and the run arrives, its signals those of the
    serial backend; a result that cannot be pickled at all (its error, here) fails at once
    saying why."""
    from sensfw.runs.executor import ProcessPool
    from sensfw.runs.spec import RunResult, execute

    bad_opts = {"model": "two_dof", "unpicklable": True}
    bad_model = models.get(FAULT_INJECTION)(**bad_opts)
    bad = RunSpec.create(bad_model, bad_model.parameters().complete({}), EX,
                         SolverSettings(timeout=20.0),
                         {"name": FAULT_INJECTION, "options": bad_opts})
    got = {}
    with ProcessPool(1) as pool:
        pool.map([bad], lambda s, r: got.__setitem__(s.key(), r))
    res = got[bad.key()]
    assert res.ok, res.error  # a lost result ends as 'timeout: no result after 20 s'
    assert res.signals.meta["unpicklable_meta"] == ["callback"]
    serial = execute(bad)
    assert serial.signals.meta["unpicklable_meta"] == ["callback"]
    for ch, x in serial.signals.channels.items():
        assert (res.signals.channels[ch] == x).all()
    import pickle

    from sensfw.runs.executor import _pickled

    lost = pickle.loads(_pickled(RunResult("k", False, error=lambda: None)))
    assert not lost.ok and "cannot be sent back from its worker process" in lost.error
