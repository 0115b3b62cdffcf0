"""The measurement loop on real data (issue 14, item 4): the bolted lap-joint beam of
UNESP-BERT (``../shared/data/bert``; skipped when absent), six amplifier levels 0.05-0.30 V.

The calibrations themselves (``sensfw calibrate`` at 0.05 V: 64 simulations, 3.5 minutes on
2 cores; ``sensfw diagnose`` and ``sensfw augment`` on 0.05, 0.15 and 0.30 V: 28 and 14
minutes for the first round, 44 and 22 for the second) are too slow for the suite; their
results are stored here (``LINEAR``, ``AUGMENTED``, ``AUGMENTED2``; README "worked
example") and the tests run what follows from them: ``sensfw compare`` of the calibrated
linear and augmented models on all six levels.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from sensfw.models.bolted_beam import BoltedBeam
from sensfw.study import Study
from sensfw.study.edit import set_nominals

ROOT = Path(__file__).resolve().parents[2]

LEVELS = ("0p05", "0p10", "0p15", "0p20", "0p25", "0p30")
#: the linear model calibrated on the 0.05 V record by ``sensfw calibrate`` (README)
LINEAR = {"excitation_gain": 55.70350233912158, "clamp_stiffness": 39876.46024473123,
          "joint_stiffness": 1.0e7, "damping_ratio": 0.01544341637800723}
#: where ``sensfw augment ... --effect micro_slip@joint`` on 0.05, 0.15 and 0.30 V put the base
#: variables before adding the effect (its recalibration, 117 simulations; README)
AUGMENT_BASE = {"excitation_gain": 52.237, "clamp_stiffness": 15832.75,
                "joint_stiffness": 5746559.6, "damping_ratio": 0.0214}


def calibrated_study(tmp, values: dict) -> Path:
    """studies/bert.toml with ``values`` as nominal values (what calibrate writes)."""
    src = ROOT / "studies" / "bert.toml"
    params = Study.load(src).parameters
    path = tmp / "study.toml"
    path.write_text(set_nominals(src.read_text(encoding="utf-8"), values,
                                 {k: (params[k].min, params[k].max) for k in values}),
                    encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def linear(bert, cli, tmp_path_factory):
    """compare.json of the calibrated linear model on the six levels, 80-105 Hz error band."""
    tmp = tmp_path_factory.mktemp("bert_linear")
    return compare_six_levels(cli, bert, calibrated_study(tmp, LINEAR), tmp / "cmp")


def compare_six_levels(cli, bert, study: Path, out: Path) -> dict:
    """``sensfw compare`` of ``study`` on the six levels, 80-105 Hz error band."""
    args = [a for lv in LEVELS for a in ("-m", bert / f"level_{lv}")]
    proc = cli("compare", study, *args, "--out", out, "--error-band", "80,105",
               "--workers", 2, "--no-progress", "--twins", 0, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return json.loads((out / "compare.json").read_text())


def resonance(level: dict) -> dict:
    (row,) = [r for r in level["resonances"] if r["measured_hz"] and r["model_hz"]]
    return row


@pytest.mark.slow
def test_the_linear_model_fails_more_as_the_level_rises(linear):
    levels = linear["levels"]
    assert [round(c["level"], 2) for c in levels] == [0.05, 0.10, 0.15, 0.20, 0.25, 0.30]
    err = np.array([c["frf_error_db"]["rms_in_band"] for c in levels])
    # the error over 80-105 Hz grows at every step (measured: 0.82, 1.82, 2.65, 3.46, 4.19,
    # 4.87 dB) and the top level's is several times the calibration level's
    assert np.all(np.diff(err) > 0), err
    assert err[-1] > 4 * err[0], err
    res = [resonance(c) for c in levels]
    meas = np.array([r["measured_hz"] for r in res])
    model = np.array([r["model_hz"] for r in res])
    # the measured resonance falls at every step, by 4.4 Hz in all (95.88 -> 91.50 Hz on
    # the 1/16 Hz lines of the smoothed FRF); the linear model's stays where it is (a
    # linear model driven by each level's voltage has one resonance: within a line)
    assert np.all(np.diff(meas) < 0), meas
    assert meas[0] - meas[-1] > 3.5, meas
    assert np.ptp(model) <= 1 / 16 + 1e-9, model
    # so the gap between them grows with the level
    assert np.all(np.diff(model - meas) > 0), model - meas


def test_micro_slip_has_a_lever_from_the_calibrated_joint():
    """micro_slip splits the joint's calibrated stiffness between what stays (``residual``)
    and Jenkins elements that lose it as they slip, so it acts from wherever a linear
    calibration put the joint (README). Its lever, on the linearised model's second bending
    mode: from all stuck (the joint as calibrated) to all slipping."""
    model = BoltedBeam()

    def mode2(values, **kw):
        p = {k: v for k, v in {**values, **kw}.items() if k != "excitation_gain"}
        return model.eigenfrequencies(p, 2)[1]

    # the measured resonance falls 4.4 Hz (95.88 -> 91.50 Hz); with the calibrated clamp the
    # joint must soften from ~1e6 to ~1.5e5 N/mm for a fall of that size
    assert 3.5 < mode2(LINEAR, joint_stiffness=1e6) - mode2(LINEAR, joint_stiffness=1.5e5) < 4.5
    # where augment's base recalibration left the joint (5.7e6 N/mm, the clamp softened
    # instead): a tenth of it left when all elements slip (the effect's nominal residual)
    # moves the mode by half the measured fall, 3 % by more than all of it
    k = AUGMENT_BASE["joint_stiffness"]
    assert 2.0 < mode2(AUGMENT_BASE) - mode2(AUGMENT_BASE, joint_stiffness=0.1 * k) < 2.5
    assert mode2(AUGMENT_BASE) - mode2(AUGMENT_BASE, joint_stiffness=0.03 * k) > 4.4


#: micro_slip@joint and the base variables as ``sensfw augment`` calibrated them on the
#: 0.05, 0.15 and 0.30 V records, started from ``sensfw diagnose`` (README, worked example)
AUGMENTED = {"excitation_gain": 56.44588735429049,
             "clamp_stiffness": 50196.564383352146,
             "joint_stiffness": 9316438.496776246,
             "damping_ratio": 0.006178238766704232,
             "microslip_residual": 0.011327077278339391,
             "microslip_force": 766.1277256619672,
             "microslip_exponent": -0.35974676134868544}


def augmented_study(tmp, values: dict,
                    effects: tuple = (("micro_slip", "joint"),)) -> Path:
    """studies/bert.toml with ``effects`` (``(name, place)`` or ``(name, place,
    options)``) and ``values`` as nominal values (what augment writes)."""
    import tomllib

    from sensfw.study.edit import add_effect

    text = (ROOT / "studies" / "bert.toml").read_text(encoding="utf-8")
    for name, place, *options in effects:
        text = add_effect(text, name, place, {}, options=options[0] if options else None)
    params = Study.from_dict(tomllib.loads(text), "bert").parameters
    path = tmp / "augmented.toml"
    path.write_text(set_nominals(text, values, {k: (params[k].min, params[k].max)
                                                for k in values}), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def augmented(bert, cli, tmp_path_factory):
    """compare.json of the augmented model on the six levels, 80-105 Hz error band."""
    tmp = tmp_path_factory.mktemp("bert_augmented")
    return compare_six_levels(cli, bert, augmented_study(tmp, AUGMENTED), tmp / "cmp")


@pytest.mark.slow
def test_the_augmented_model_predicts_every_level(linear, augmented):
    """Issue 14's bar on all six levels, three of them (0.10, 0.20, 0.25 V) predicted
    without refitting, for the first round (micro_slip@joint): the resonance (compare's peak
    of the 1/24-octave Hv FRF, 1/16 Hz lines) within 0.5 Hz of the measured one at every
    level (measured: 0.37, 0.13, 0.25, 0, 0, 0.50 Hz), and the laser FRF error over 80-105 Hz
    at most half the calibrated linear model's above the lowest level (measured 0.78, 0.57,
    0.32, 0.22, 0.63 dB against 1.82, 2.65, 3.46, 4.19, 4.87). At 0.05 V, the level the
    linear model was calibrated on, micro-slip alone gives 0.49 dB, 60 % of the linear
    model's 0.82 dB (the second round's drive-point friction meets the half there: below);
    the test holds it below 70 %."""
    lin = {round(c["level"], 2): c for c in linear["levels"]}
    for c in augmented["levels"]:
        level = round(c["level"], 2)
        res = resonance(c)
        assert res["measured_hz"] == resonance(lin[level])["measured_hz"]
        assert abs(res["model_hz"] - res["measured_hz"]) <= 0.5 + 1e-9, (level, res)
        err, err_lin = (x["frf_error_db"]["rms_in_band"] for x in (c, lin[level]))
        assert err <= (0.7 if level == 0.05 else 0.5) * err_lin, (level, err, err_lin)


#: the second round: ``sensfw diagnose`` of the micro-slip study on the same three levels
#: names Coulomb friction at the shaker's drive point (dry_friction@beam1) and ``sensfw
#: augment`` calibrates it with the seven parameters of the first round (README)
AUGMENTED2 = {"excitation_gain": 55.14400290635046,
              "clamp_stiffness": 22445.563091436146,
              "joint_stiffness": 8772824.664864901,
              "damping_ratio": 0.005957605086537058,
              "microslip_force": 887.4686832208563,
              "microslip_exponent": -0.6540052126823261,
              "microslip_residual": 0.013854410605406056,
              "dry_friction_force": 0.5184444838314798,
              "dry_friction_stiffness": 10.335684361846223}


@pytest.fixture(scope="module")
def augmented2(bert, cli, tmp_path_factory):
    """compare.json of the second round's model on the six levels, 80-105 Hz error band."""
    tmp = tmp_path_factory.mktemp("bert_augmented2")
    study = augmented_study(tmp, AUGMENTED2, (("micro_slip", "joint"),
                                              ("dry_friction", "beam1")))
    return compare_six_levels(cli, bert, study, tmp / "cmp")


@pytest.mark.slow
def test_the_second_round_meets_the_bar_at_every_level(linear, augmented2):
    """Issue 14's bar, all of it, after the second round (micro-slip at the joint and
    friction at the drive point, calibrated on 0.05, 0.15 and 0.30 V; 0.10, 0.20 and 0.25 V
    predicted): at every level the resonance within 0.5 Hz of the measured one (measured:
    0, -0.19, +0.31, 0, 0, +0.25 Hz) and the laser FRF error over 80-105 Hz at most half
    the calibrated linear model's (measured 0.30, 0.65, 0.57, 0.38, 0.31, 0.54 dB against
    0.82, 1.82, 2.65, 3.46, 4.19, 4.87)."""
    lin = {round(c["level"], 2): c for c in linear["levels"]}
    assert sorted(lin) == [round(c["level"], 2) for c in augmented2["levels"]]
    for c in augmented2["levels"]:
        level = round(c["level"], 2)
        res = resonance(c)
        assert abs(res["model_hz"] - res["measured_hz"]) <= 0.5 + 1e-9, (level, res)
        err, err_lin = (x["frf_error_db"]["rms_in_band"] for x in (c, lin[level]))
        assert err <= 0.5 * err_lin, (level, err, err_lin)


#: issue 27: the micro-slip model with 6 Jenkins elements per interface point (3 left no
#: slip force between the random records' sub-newton forces and the sweeps'; README), the
#: second round's Coulomb friction at the shaker's drive point (dry_friction@beam1) and
#: Young's modulus free (66-74 GPa: wrought aluminium 68.9-71.7 GPa, and +-3 % in E for the
#: beams' thickness tolerance), calibrated by ``sensfw calibrate --local`` on the sweeps AND
#: the random records at 0.05, 0.15 and 0.30 V, from the 6-element model's calibration on
#: the same records with the second round's friction (348 simulations; README)
BOTH_KINDS = {"excitation_gain": 56.489254761548125, "clamp_stiffness": 17689.440757235585,
              "joint_stiffness": 3074093.803839377, "damping_ratio": 0.00898317665496985,
              "microslip_residual": 0.02198804648521152,
              "microslip_force": 571.9819765479715, "microslip_exponent": -0.9,
              "youngs_modulus": 73.64626083772563,
              "dry_friction_force": 0.4482015502507226,
              "dry_friction_stiffness": 5.40195241613668}
BOTH_KINDS_EFFECTS = (("micro_slip", "joint", {"elements": 6}), ("dry_friction", "beam1"))


@pytest.mark.slow
def test_calibrated_on_both_kinds_the_beam_predicts_the_other_records(bert, cli,
                                                                      tmp_path):
    """The six records the BOTH_KINDS calibration did not see (sweeps and random records at
    0.10, 0.20 and 0.25 V), as the README's table has them: issue 27's bar, resonance
    within 0.3 Hz and laser error at most 1.0 dB on every one (measured at stop 54, model
    version 3: +0.13, +0.06, +0.25 Hz and 0.86, 0.45, 0.36 dB on the sweeps, -0.13, +0.19,
    +0.19 Hz and 0.53, 0.94, 0.84 dB on the random records, the 0.20 one with 0.33 dB of
    the model's own scatter: its friction under a random drive; every sweep-fitted model
    was 0.7-1.2 Hz and 1.5-2.3 dB off on the random ones, the micro-slip model alone +0.44
    Hz on the 0.10 V sweep). Shifts are whole 1/16 Hz lines of a simulation that is
    deterministic on one machine."""
    src = augmented_study(tmp_path, BOTH_KINDS, BOTH_KINDS_EFFECTS)
    random = bert.parent / "random"
    args = [a for lv in ("0p10", "0p20", "0p25") for folder in (bert, random)
            for a in ("-m", folder / f"level_{lv}")]
    out = tmp_path / "cmp"
    proc = cli("compare", src, *args, "--out", out, "--error-band", "80,105",
               "--workers", 2, "--no-progress", "--twins", 0, timeout=900)
    assert proc.returncode == 0, proc.stderr
    levels = json.loads((out / "compare.json").read_text())["levels"]
    assert len(levels) == 6
    assert sorted(c["excitation"]["kind"] for c in levels) == ["linear_sweep"] * 3 + \
        ["random"] * 3
    for c in levels:
        res = resonance(c)
        shift = res["model_hz"] - res["measured_hz"]
        err = c["frf_error_db"]["rms_in_band"]
        assert err <= 1.0, (c["excitation"]["kind"], c["level"], err)
        assert abs(shift) <= 0.3, (c["excitation"]["kind"], c["level"], shift)
