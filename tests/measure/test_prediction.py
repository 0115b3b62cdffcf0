"""Prediction bands of a calibrated model (sensfw/measure/prediction.py)."""

import numpy as np
import pytest
import tomlkit
from scipy.linalg import eigh
from scipy.stats import chi2

from sensfw.measure.calibration import Coordinates
from sensfw.measure.compare import compare_measurements
from sensfw.measure.io import write_csv
from sensfw.measure.prediction import (
    FORM_Z,
    bands,
    calibration_result,
    ellipsoid_points,
    extrapolation,
    fitted_records,
    model_form,
)
from sensfw.measure.prepared import load_measurements
from sensfw.measure.synthetic import Rig, synthesize
from sensfw.models.analytic import TwoDOF
from sensfw.params import Parameter
from sensfw.runs import Runner, RunStore
from sensfw.study import Study
from sensfw.study.edit import set_calibration_result


def test_the_band_points_lie_on_the_95_percent_ellipsoid():
    """Each of the 2 d points is on the ellipsoid ``dz^T C^-1 dz = chi2_d(0.95)`` (7.81 for
    d = 3), along a principal axis (pairs symmetric about the centre)."""
    coords = Coordinates.of(None, [Parameter("a", "", 1.0, 0.5, 5.0),
                                   Parameter("b", "", 0.0, -1.0, 1.0),
                                   Parameter("c", "N/mm", 1e5, 1e4, 1e7)])
    z0 = np.array([0.1, -0.2, 0.3])
    A = np.array([[0.02, 0.01, 0.0], [0.01, 0.03, -0.005], [0.0, -0.005, 0.01]])
    points = ellipsoid_points(coords, z0, A)
    assert len(points) == 6
    inv = np.linalg.inv(A)
    for p in points:
        dz = coords.code(p) - z0
        assert dz @ inv @ dz == pytest.approx(chi2.ppf(0.95, 3), rel=1e-9)
    for p, q in zip(points[::2], points[1::2], strict=True):
        assert coords.code(p) + coords.code(q) == pytest.approx(2 * z0)


def test_a_record_unlike_the_calibrations_is_an_extrapolation():
    seen = [{"kind": "linear_sweep", "level": 0.05}, {"kind": "linear_sweep", "level": 0.3},
            {"kind": "random", "level": 0.1}]
    assert extrapolation("linear_sweep", 0.15, seen) is None
    assert extrapolation("random", 0.105, seen) is None  # within 10 %
    assert "outside" in extrapolation("random", 0.3, seen)
    assert "saw none" in extrapolation("stepped_sine", 0.1, seen)
    assert extrapolation("random", 5.0, []) is None  # nothing known of the calibration


def rig_data() -> dict:
    """A study of the 2-DOF chain whose [calibration] is k1 (its resonances in closed form)."""
    return {"study": {"name": "rig"}, "model": {"name": "two_dof", "output": "a1"},
            "excitation": {"kind": "log_chirp", "f0": "100 Hz", "f1": "400 Hz",
                           "duration": "1 s", "fs": "2 kHz", "amplitude": "0.1 N",
                           "tail": "0.5 s"},
            "stages": [{"name": "s", "design": "oat", "scorers": [{"name": "rms"}]}],
            "calibration": {"parameters": ["k1"]}}


def test_a_calibrated_study_predicts_a_band_that_holds_the_resonance(tmp_path):
    """End to end on the 2-DOF chain (its resonances known in closed form): a study carrying
    ``[calibration.result]`` for k1 (written by :func:`set_calibration_result`, read back by
    the study loader) predicts, for a record made at k1's nominal value, a resonance band
    whose ends are the first natural frequency at the two ends of k1's 95 % interval
    (+-1.96 sigma on its log axis), within the FRF's line spacing; the measured resonance
    lies inside; a record at a level the calibration did not see is an extrapolation."""
    data = rig_data()
    study = Study.from_dict(data)
    coords = Coordinates.of(None, [study.parameters["k1"]])
    sigma = 0.05  # coded
    text = set_calibration_result(tomlkit.dumps(data), {
        "parameters": ["k1"], "scales": [coords.axes[0].scale],
        "coded": [float(coords.code({"k1": 4000.0})[0])], "covariance": [[sigma**2]],
        "records": [{"kind": "log_chirp", "level": 0.1}]})
    (tmp_path / "s.toml").write_text(text)
    study = Study.load(tmp_path / "s.toml")
    cal = calibration_result(study)
    assert cal is not None and cal.covariance[0, 0] == pytest.approx(sigma**2)

    files = []
    for level in (0.1, 0.3):
        sig, info = synthesize(study, amplitude=level, rig=Rig(noise=0.005, seed=4))
        files.append(write_csv(tmp_path / f"m{level}.csv", sig, level=info["amplitude"]))
    with Runner(RunStore(tmp_path / "runs"), backend="serial") as runner:
        cmp = compare_measurements(study, load_measurements(study, [str(f) for f in files]),
                                   runner)
    band, far = cmp.bands
    ends = [cal.coords.decode(cal.z + s * 1.96 * sigma)["k1"] for s in (-1, 1)]
    model = TwoDOF()

    def first_mode(k1: float) -> float:
        M, K, _ = model.matrices(model.parameters().complete({"k1": k1}))
        return float(np.sqrt(eigh(K, M, eigvals_only=True)[0]) / (2 * np.pi))

    lo, hi = first_mode(ends[0]), first_mode(ends[1])
    spacing = float(np.median(np.diff(band.f[(band.f > 0.8 * lo) & (band.f < 1.2 * hi)])))
    assert band.resonance_low == pytest.approx(lo, abs=spacing)
    assert band.resonance_high == pytest.approx(hi, abs=spacing)
    assert band.contains_resonance and band.extrapolation is None
    assert "outside" in far.extrapolation


def test_a_local_recalibration_starts_from_the_studys_values(tmp_path):
    """``sensfw calibrate --local`` (``recalibrate(global_phase=False)``): no design, no
    surrogate search, DFO-LS from the study's nominal values. On the 2-DOF chain with a
    record made at k1 = 4000 N/mm (0.5 % noise) and the study starting 10 % off, the local
    calibration ends with the truth inside its 95 % interval, in fewer simulations than
    the global one's design alone would take (2 d + 1 = 3 points plus the search)."""
    from sensfw.measure.recalibrate import recalibrate

    data = rig_data()
    truth = Study.from_dict(data)
    sig, info = synthesize(truth, amplitude=0.1, rig=Rig(noise=0.005, seed=3))
    f = write_csv(tmp_path / "m.csv", sig, level=info["amplitude"])
    data["parameters"] = {"k1": {"nominal": "3600 N/mm", "min": "2000 N/mm",
                                 "max": "8000 N/mm"}}
    study = Study.from_dict(data)
    said: list[str] = []
    with Runner(RunStore(tmp_path / "runs"), backend="serial") as runner:
        out = recalibrate(study, load_measurements(study, [str(f)]), runner, budget=12,
                          global_phase=False, log=said.append)
    assert not [s for s in said if "design:" in s or "batch" in s]
    assert [s for s in said if "DFO-LS start 1" in s]
    (k1,) = out["calibration"]
    assert k1["interval"][0] <= 4000.0 <= k1["interval"][1]
    assert k1["value"] == pytest.approx(4000.0, rel=0.01)
    assert out["n_simulations"] <= 12 + 1  # the budget and the nominal run
    # the calibrated study keeps the model's misfit on the record it was fitted to: the
    # resonance shift of the calibrated comparison (model minus measured) and its error
    (cal,) = out["_comparisons"]["calibrated"]
    r = next(r for r in cal.resonances if r["measured_hz"] and r["model_hz"])
    (rec,) = out["uncertainty"]["records"]
    assert rec["resonance_shift_hz"] == pytest.approx(r["model_hz"] - r["measured_hz"])
    assert rec["error_db"] == pytest.approx(cal.error_db)


def _comparison(f, db, measured_hz, model_hz, error_db=0.5):
    from types import SimpleNamespace

    return SimpleNamespace(file="r", level=0.1, f=f, db_model=db, error_band=None,
                           error_db=error_db, resonances=[{"measured_hz": measured_hz,
                                                           "model_hz": model_hz}])


def test_the_model_form_term_is_the_fitted_records_rms_misfit():
    """The band's model-form part: the RMS of the fitted records' resonance shifts and FRF
    errors, of the records of the same kind where two or more were fitted, else of all;
    nothing where the calibration stored no misfit (a study written before it did)."""
    seen = [{"kind": "sweep", "level": 0.1, "resonance_shift_hz": 0.1, "error_db": 0.3},
            {"kind": "sweep", "level": 0.2, "resonance_shift_hz": -0.2, "error_db": 0.4},
            {"kind": "sweep", "level": 0.3, "resonance_shift_hz": 0.2, "error_db": 0.5},
            {"kind": "random", "level": 0.1, "resonance_shift_hz": 0.05, "error_db": 1.0},
            {"kind": "random", "level": 0.2, "resonance_shift_hz": -0.05, "error_db": 1.0}]
    assert model_form(seen, "sweep") == pytest.approx((np.sqrt(0.09 / 3), np.sqrt(0.5 / 3),
                                                       3))
    assert model_form(seen, "random") == pytest.approx((0.05, 1.0, 2))
    hz, db, n = model_form(seen, "stepped_sine")  # none of its kind: all five
    assert n == 5 and hz == pytest.approx(np.sqrt((0.09 + 0.005) / 5))
    assert db == pytest.approx(np.sqrt((0.09 + 0.16 + 0.25 + 2.0) / 5))
    assert model_form([{"kind": "sweep", "level": 0.1}], "sweep") == (0.0, 0.0, 0)
    # the band: the envelope of the runs, widened by FORM_Z times the term on each side
    f = np.linspace(90.0, 100.0, 11)
    c = _comparison(f, np.zeros(11), 95.0, 95.2)
    sample = _comparison(f, np.ones(11), 95.0, 95.4)
    (b,) = bands([c], [[sample]], seen, ["random"])
    assert b.resonance_low == pytest.approx(95.2 - FORM_Z * 0.05)
    assert b.resonance_high == pytest.approx(95.4 + FORM_Z * 0.05)
    assert b.db_low == pytest.approx(np.full(11, -FORM_Z * 1.0))
    assert b.db_high == pytest.approx(np.full(11, 1.0 + FORM_Z * 1.0))
    assert b.contains_resonance is False  # 95.0 < 95.2 - 0.098
    (b,) = bands([c], [[sample]], seen, ["sweep"])  # sweep's term 0.173 Hz reaches 95.0
    assert b.contains_resonance and b.form_records == 3


def test_fitted_records_carry_each_records_misfit():
    f = np.linspace(90.0, 100.0, 11)
    recs = fitted_records([{"file": "a", "kind": "sweep", "level": 0.1}],
                          [_comparison(f, np.zeros(11), 95.0, 94.75, error_db=0.7)])
    assert recs == [{"file": "a", "kind": "sweep", "level": 0.1,
                     "resonance_shift_hz": pytest.approx(-0.25), "error_db": 0.7}]
    assert fitted_records([{"kind": "sweep", "level": 0.1}], None) == [
        {"kind": "sweep", "level": 0.1}]
