"""The run store: atomic, checksummed entries; anything not intact reads as absent."""

import json

import numpy as np
import pytest
from sensfw_test_models import FAULT_INJECTION

from sensfw.excitation import Chirp
from sensfw.models.base import SolverSettings
from sensfw.plugins import models
from sensfw.runs import RunSpec, RunStore, execute

EX = Chirp(50, 500, 0.05, 4000, 1.0)


def spec(**params):
    m = models.get("two_dof")()
    return RunSpec.create(m, m.parameters().complete(params), EX, SolverSettings())


def test_key_depends_on_everything_that_changes_results():
    base = spec()
    assert base.key() == spec().key()
    assert spec(k1=5000.0).key() != base.key()
    other_ex = RunSpec.create(models.get("two_dof")(), dict(base.params),
                              Chirp(50, 500, 0.05, 4000, 2.0), SolverSettings())
    assert other_ex.key() != base.key()
    other_solver = RunSpec.create(models.get("two_dof")(), dict(base.params), EX,
                                  SolverSettings(step=2e-6))
    assert other_solver.key() != base.key()
    fixed = RunSpec.create(models.get("two_dof")(), dict(base.params), EX,
                           SolverSettings(auto_step=False))
    assert fixed.key() != base.key()
    # the timeout is not part of the result, so not part of the key
    timed = RunSpec.create(models.get("two_dof")(), dict(base.params), EX,
                           SolverSettings(timeout=10.0))
    assert timed.key() == base.key()


def test_roundtrip_is_bitwise(tmp_path):
    store = RunStore(tmp_path)
    s = spec()
    res = execute(s)
    store.save(s, res)
    back = store.load(s.key())
    assert back.ok and back.cached
    for ch, x in res.signals.channels.items():
        assert np.array_equal(back.signals.channels[ch], x)
    assert np.array_equal(back.signals.force, res.signals.force)
    assert not list(tmp_path.glob("*.tmp"))


def test_corrupt_or_half_written_entries_read_as_absent(tmp_path):
    store = RunStore(tmp_path)
    s = spec()
    store.save(s, execute(s))
    data = tmp_path / f"{s.key()}.npz"
    blob = data.read_bytes()
    data.write_bytes(blob[: len(blob) // 2])  # truncated signal file
    assert store.load(s.key()) is None
    data.write_bytes(blob)
    assert store.load(s.key()) is not None
    (tmp_path / f"{s.key()}.json").write_text('{"status": "ok", "sha2')  # torn record
    assert store.load(s.key()) is None
    (tmp_path / f"{s.key()}.json").unlink()  # killed before the commit record
    assert store.load(s.key()) is None and not store.has(s.key())


def test_a_store_reads_another_store_and_writes_only_its_own(tmp_path):
    """`augment --start-from` reads the diagnosis's runs: found there, bitwise, never
    written there; a corrupt entry there reads as absent."""
    first, second = RunStore(tmp_path / "diagnose"), RunStore(tmp_path / "augment",
                                                              read_also=[tmp_path / "diagnose"])
    s, t = spec(), spec(k1=5000.0)
    res = execute(s)
    first.save(s, res)
    back = second.load(s.key())
    assert back is not None and back.cached and second.has(s.key())
    assert np.array_equal(back.signals.channels["a1"], res.signals.channels["a1"])
    second.save(t, execute(t))
    assert second.has(t.key()) and not first.has(t.key())
    assert first.keys() == [s.key()] and second.keys() == [t.key()]
    data = tmp_path / "diagnose" / f"{s.key()}.npz"
    data.write_bytes(data.read_bytes()[:100])
    assert second.load(s.key()) is None


def test_failed_runs_are_recorded_with_their_reason(tmp_path):
    store = RunStore(tmp_path)
    m = models.get(FAULT_INJECTION)(model="two_dof", diverge={"parameter": "k1",
                                                                 "above": 4500.0})
    s = RunSpec.create(m, m.parameters().complete({"k1": 6000.0}), EX, SolverSettings(),
                       {"name": FAULT_INJECTION, "options": {
                           "model": "two_dof", "diverge": {"parameter": "k1", "above": 4500.0}}})
    res = execute(s)
    assert not res.ok and "diverged" in res.error and "k1=6000" in res.error
    assert "at step 1e-05, 5e-06 s" in res.error  # retried once at half the step
    store.save(s, res)
    meta = json.loads((tmp_path / f"{s.key()}.json").read_text())
    assert meta["status"] == "failed" and "diverged" in meta["error"]
    assert store.load(s.key()).ok is False


@pytest.mark.parametrize("bad", ["", "{}", '{"status": "weird"}', "null", "[]", "3",
                                 '"ok"'])
def test_garbage_records_are_ignored(tmp_path, bad):
    # JSON that is not an object (null, a list, a number) raised AttributeError out of
    # record(), stopping the study on one damaged entry; it reads as absent like the rest
    (tmp_path / "abc.json").write_text(bad)
    assert RunStore(tmp_path).record("abc") is None
    assert not RunStore(tmp_path).damaged("abc")


def test_a_run_that_timed_out_is_run_again_under_a_longer_timeout(tmp_path):
    """The timeout is not part of a run's key, so a run stored as failed after 0.3 s was
    handed back as failed under 120 s ('timeout: no result after 0.3 s'). Now it is run
    again when the timeout has grown, and handed back when it has not; other failures
    (a divergence) stay failed until --retry-failed."""
    from sensfw.runs import Runner, RunResult

    m = models.get("two_dof")()
    short = RunSpec.create(m, m.parameters().complete({}), EX, SolverSettings(timeout=0.3))
    long = RunSpec.create(m, m.parameters().complete({}), EX, SolverSettings(timeout=120.0))
    assert short.key() == long.key()
    store = RunStore(tmp_path)
    store.save(short, RunResult(short.key(), False, error="timeout: no result after 0.3 s"))
    with Runner(store, backend="serial") as runner:
        assert runner.run([short]) == {short.key(): "failed"}
        assert runner.counts.new == 0
        assert runner.run([long]) == {long.key(): "ok"}
        assert runner.counts.new == 1
    other = spec(k1=5100.0)
    store.save(other, RunResult(other.key(), False, error="diverged at step 1e-05"))
    with Runner(store, backend="serial") as runner:
        assert runner.run([other]) == {other.key(): "failed"}


def test_a_damaged_entry_is_named_damaged_not_missing(tmp_path):
    """A truncated signal file read as 'not in the run store (the study, the model or
    sensfw changed since it ran?)': the wrong cause. It is named damaged."""
    from sensfw.runs import MissingRunError, StoredRuns

    store = RunStore(tmp_path)
    s = spec()
    store.save(s, execute(s))
    assert not store.damaged(s.key())
    (tmp_path / f"{s.key()}.npz").write_bytes(b"cut")
    assert store.damaged(s.key()) and store.record(s.key()) is None
    with pytest.raises(MissingRunError, match="is damaged"):
        StoredRuns(store).run([s])
    with pytest.raises(MissingRunError, match="is not in the run store"):
        StoredRuns(store).run([spec(k1=5100.0)])


def test_a_run_that_timed_out_is_run_again_without_a_timeout(tmp_path):
    """A study file without a timeout means no limit ("leave it out for no timeout"), the
    longest there is: a run stored as 'timeout: no result after 0.3 s' was handed back as
    failed there (until --retry-failed), although it had only run out of a shorter limit."""
    from sensfw.runs import Runner, RunResult

    m = models.get("two_dof")()
    short = RunSpec.create(m, m.parameters().complete({}), EX, SolverSettings(timeout=0.3))
    unlimited = RunSpec.create(m, m.parameters().complete({}), EX, SolverSettings())
    assert unlimited.timeout is None and short.key() == unlimited.key()
    store = RunStore(tmp_path)
    store.save(short, RunResult(short.key(), False, error="timeout: no result after 0.3 s"))
    with Runner(store, backend="serial") as runner:
        assert runner.run([unlimited]) == {unlimited.key(): "ok"}
        assert runner.counts.new == 1
    assert store.load(unlimited.key()).ok


def test_a_failure_does_not_replace_a_finished_run_of_the_same_key(tmp_path):
    """Two writers of one store (a study run twice at once, on a loaded machine): one
    finishes the run, the other's copy of it times out and is saved after it. The finished
    run was overwritten by the failure ('failed', handed back as such on resume); it
    stays."""
    from sensfw.runs import RunResult

    store = RunStore(tmp_path)
    s = spec()
    done = execute(s)
    store.save(s, done)
    store.save(s, RunResult(s.key(), False, error="timeout: no result after 0.3 s"))
    assert store.record(s.key())["status"] == "ok"
    back = store.load(s.key())
    assert back.ok and np.array_equal(back.signals.channels["a1"], done.signals.channels["a1"])
    # a failure still replaces a failure, and a success a failure
    other = spec(k1=5100.0)
    store.save(other, RunResult(other.key(), False, error="timeout: no result after 0.3 s"))
    store.save(other, RunResult(other.key(), False, error="worker process died (exit code -9)"))
    assert "died" in store.record(other.key())["error"]
    store.save(other, execute(other))
    assert store.record(other.key())["status"] == "ok"
