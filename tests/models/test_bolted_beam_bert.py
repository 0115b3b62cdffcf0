"""The bolted beam on the UNESP-BERT study and measurements (issue 14, items 2 and 4): the
study file, the measured softening, and the linear model driven by the measured voltage.
Tests that need ../shared/data/bert skip without it (the ``bert`` fixture)."""

from pathlib import Path

import numpy as np
import pytest

from sensfw.excitation import LinearSweep
from sensfw.measure.prepared import load_measurements
from sensfw.signal import frf, sdof_fit
from sensfw.study import Study

ROOT = Path(__file__).resolve().parents[2]
BERT = ROOT / "studies" / "bert.toml"


def laser_fit(sig):
    f, H = frf(sig.force, sig.channel("Laser"), sig.fs, estimator="H1")
    return sdof_fit(f, H, band=(86.0, 100.0), quantity="velocity", residual_terms=2)


def test_the_bert_study_is_the_rig():
    study = Study.load(BERT)
    assert study.model.name == "bolted_beam" and study.output == "Laser"
    ex = study.excitation
    assert isinstance(ex, LinearSweep) and ex.unit == "V"
    assert (ex.f0, ex.f1, ex.duration, ex.tail, ex.fs) == (70.0, 110.0, 8.0, 8.0, 1024.0)
    gain = study.parameters["excitation_gain"]
    assert gain.unit == "N/V" and gain.min < gain.nominal < gain.max
    assert study.solver.method == "GeneralizedAlpha" and study.solver.step == 1 / 8192
    assert "excitation_gain" in study.variable_names()


@pytest.fixture(scope="module")
def measured(bert):
    return load_measurements(Study.load(BERT), [str(bert)])


def test_the_measured_resonance_softens_with_level(measured):
    """The joint slips more as the level rises: the second mode's single-mode fit moves down
    at every step (95.6 Hz at 0.05 V, 91.1 Hz at 0.30 V), its damping stays ~1.5 %."""
    assert [round(m.level, 2) for m in measured] == [0.05, 0.1, 0.15, 0.2, 0.25, 0.3]
    fits = [laser_fit(m.signals) for m in measured]
    fn = np.array([x.frequency for x in fits])
    assert np.all(np.diff(fn) < 0), fn
    assert 94 < fn[0] < 97 and fn[0] - fn[-1] > 3.0, fn
    assert all(0.005 < x.damping_ratio < 0.03 for x in fits)


@pytest.mark.slow
def test_the_linear_model_driven_by_the_measured_voltage(measured, tmp_path):
    """Every level simulated with its own voltage record through the study's runner: the
    linear model's resonance is the same at the lowest and the highest level (within the
    fit's scatter) while the measured one moves down by 4.5 Hz."""
    from sensfw.measure.compare import compare_measurements
    from sensfw.runs import Runner, RunStore

    study = Study.load(BERT)
    pick = [measured[0], measured[-1]]
    with Runner(RunStore(tmp_path / "runs"), backend="serial") as runner:
        cmp = compare_measurements(study, pick, runner)
    (_, m_lo, s_lo), (_, m_hi, s_hi) = cmp.pairs
    # the model's input channel is the measured voltage (the force is gain x voltage)
    assert np.max(np.abs(s_lo.force)) == pytest.approx(np.max(np.abs(m_lo.force)), rel=0.01)
    f_lo, f_hi = laser_fit(s_lo).frequency, laser_fit(s_hi).frequency
    assert abs(f_lo - f_hi) < 0.02, (f_lo, f_hi)
    assert laser_fit(m_lo).frequency - laser_fit(m_hi).frequency > 3.0
