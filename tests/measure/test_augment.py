"""``sensfw augment`` without start values: both calibrations global (the base variables,
then the effect jointly with them), on a synthetic record of the short quick study with
the base offsets of ``bench/verdicts.py`` and a hidden added mass. The rate over random
cases is ``bench/augment_search.py``'s (``bench/RECOVERY.md``, stop 43); here one case end
to end. No test ran augment's global path before."""

import bench_modules
import pytest

from sensfw.measure.augment import augment
from sensfw.runs import Runner, RunStore

pytestmark = pytest.mark.slow
MASS = 0.04  # kg, the hidden added mass at the driveshaft


@pytest.fixture(scope="module")
def augmented(tmp_path_factory):
    tmp_path = tmp_path_factory.mktemp("augment")
    verdicts = bench_modules.load("verdicts")
    study = verdicts.study()
    meas = verdicts.measure(study, tmp_path / "m", f"added_mass@driveshaft:added_mass={MASS}")
    with Runner(RunStore(tmp_path / "runs"), backend="processes", workers=2) as runner:
        return augment(study, meas, runner, "added_mass", "driveshaft", budget=100)


def test_augment_from_no_start_explains_what_the_base_variables_could_not(augmented):
    out = augmented
    # the effect explains what the base variables alone could not: the joint fit's error
    # (dB RMS over every entry) falls below the base recalibration's and to a fifth of the
    # nominal model's (measured: 3.75 -> 2.91 -> 0.44 dB on one machine, 2.96 -> 0.28 on
    # another; the rig noise alone, 2 %, is 0.17 dB)
    errors = {s["step"]: s["error"] for s in out["trajectory"]}
    assert errors["jointly calibrated"] < errors["base recalibrated"], errors
    assert errors["jointly calibrated"] < 0.2 * errors["nominal model"], errors
    # on top of the budget: the nominal model's run, and the model's scatter around the
    # base optimum (2 d, d variables)
    assert out["n_simulations"] <= out["budget"] + 1 + 2 * len(out["variables"])


@pytest.mark.xfail(strict=False, reason=(
    "issue 25: where the joint calibration stops depends on round-off. On an AVX-512 "
    "machine (stop 55) this case ends at 0.44 dB (the true values: 0.28) with the slide "
    "friction velocity at 1.01 for 0.65 and the damping at 122 for 234 (budget 100); at "
    "budgets 150 and 200 at 0.34 and 0.70 dB with the mass 0.031 and 0.045 for 0.04. On "
    "the machines of stops 43-54 it recovered every value within 15 %."))
def test_augment_from_no_start_recovers_the_mass_and_the_offsets(augmented):
    out = augmented
    verdicts = bench_modules.load("verdicts")
    assert out["params"]["added_mass"] == pytest.approx(MASS, rel=0.15), out["params"]
    for name, truth in verdicts.CALIBRATED.items():
        assert out["base"][name] == pytest.approx(truth, rel=0.15), (name, out["base"])
