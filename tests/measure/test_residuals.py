"""Residual vectors of hypotheses against measurements (sensfw/measure/residuals.py): the
evidence kept for every variant and records of several kinds."""

import tomllib
from pathlib import Path

import numpy as np
import pytest

from sensfw.measure.io import write_csv
from sensfw.measure.prepared import load_measurements
from sensfw.measure.residuals import Residuals
from sensfw.measure.synthetic import Rig, synthesize
from sensfw.runs import Runner, RunStore
from sensfw.study import Study

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def study():
    data = tomllib.loads((ROOT / "studies" / "quick.toml").read_text())
    data["excitation"]["duration"] = "0.1 s"
    data["solver"]["step"] = "2e-5 s"
    return Study.from_dict(data, "quick-short")


@pytest.fixture(scope="module")
def runner(tmp_path_factory):
    with Runner(RunStore(tmp_path_factory.mktemp("runs")), backend="processes",
                workers=2) as r:
        yield r


@pytest.fixture(scope="module")
def records(study, tmp_path_factory):
    """A log chirp at 0.05 and 0.1 N and a random record at 0.1 N, 2 % noise."""
    tmp = tmp_path_factory.mktemp("records")
    files = []
    for i, (kind, level) in enumerate([(None, 0.05), (None, 0.1), ("random", 0.1)]):
        sig, _ = synthesize(study, amplitude=level, excitation=kind,
                            rig=Rig(noise=0.02, seed=i))
        files.append(str(write_csv(tmp / f"m{i}.csv", sig, level=level)))
    return load_measurements(study, files)


def test_records_of_two_kinds_count_alike(study, records, runner):
    """Two chirps and one random record: each kind's entries carry half the weight of the
    residual vector whatever their number (``n_k w_k^2 = n / 2``), so the correct model
    still leaves chi2 near n; the per-record list says which is which."""
    space = study.calibration_space(list(study.spec.calibration.parameters))
    res = Residuals(study, records, runner, space)
    (w,) = res.evaluate(None, [space.nominal_row()], "nominal")
    kinds = [r["kind"] for r in res.records()]
    assert sorted(set(kinds)) == ["log_chirp", "random"]
    sizes = [s.stop - s.start for s in res.level_slices()]
    n = sum(sizes)
    for kind in set(kinds):
        n_k = sum(size for size, k in zip(sizes, kinds, strict=True) if k == kind)
        assert n_k * res.kind_weights[kind] ** 2 == pytest.approx(n / 2)
    assert res.kind_weights["log_chirp"] != pytest.approx(res.kind_weights["random"])
    assert len(w) == n


def test_a_run_at_every_level_is_evidence_for_each_level(study, records, runner):
    """The residuals kept from a run at every level, cut to one level, are those of the run
    at that level alone (the same simulation from the run store, the same weights): the
    screen on one level reuses every run of "parameters only"."""
    space = study.calibration_space(list(study.spec.calibration.parameters))
    res = Residuals(study, records, runner, space)
    point = {**space.nominal_row(), "slide_stiffness": 9e5}
    res.evaluate(None, [space.nominal_row(), point], "all levels")
    (alone,) = res.evaluate(None, [point], "level 3", levels=[2])
    kept = [t for t in res.trials(None, levels=[2]) if t.values == point]
    assert len(kept) == 2  # the run at every level, cut, and the one at level 3
    for t in kept:
        assert np.allclose(t.w, alone, rtol=0, atol=1e-12)
    # with the neutral values of an effect, H0's trials stand for the candidate's
    extra = res.trials(None, levels=[2], extra={"added_mass": 0.0})
    assert all(t.values["added_mass"] == 0.0 for t in extra)


def test_thd_entries_that_compare_a_model_with_noise_are_named():
    """Two levels, one channel: two bands and a THD entry each. Where the measured THD is
    no more than the record's noise floor (0.22 % against 0.24 %) and its entry carries
    most of chi2 (the probe's linear 2-DOF model: 1151 of 1201), a note names it; where
    the measured THD stands above its floor, it is the model's misfit and no note."""
    from types import SimpleNamespace

    import numpy as np

    from sensfw.measure.discrepancy import Entries, noise_thd_note

    cs = [SimpleNamespace(level=0.5, thd_measured=0.22, thd_floor=0.24),
          SimpleNamespace(level=1.0, thd_measured=2.0, thd_floor=0.24)]
    e = Entries(bands=((100.0, 125.0), (100.0, 125.0)), thd=(True, True))
    w = np.array([0.5, -0.3, 20.0, 0.4, 0.2, 1.0])
    note = noise_thd_note(cs, e, w, ["a1"])
    assert note.startswith("400 of chi2 401.5 comes from THD entries") and "a1 at 0.5 " in note
    assert noise_thd_note(cs, e, np.array([0.5, -0.3, 1.0, 0.4, 0.2, 20.0]), ["a1"]) is None
    # the propagated noise model reads the model's THD against the floor: no bias to name
    assert noise_thd_note(cs, Entries(e.bands, e.thd, noise="propagated"), w, ["a1"]) is None


def test_the_thd_entry_adds_the_records_noise_to_the_models_thd():
    """Noise adds in power to every order of a record, so with the propagated noise model
    the THD entry compares the
    model's THD combined in power with the record's noise floor (``thd_floor``): a linear
    model (no THD) against a measured THD at its floor (0.24 %) is right to within the
    floor's own scatter (0 dB here, not the -47 dB of a model floored at 1e-3 %); a model
    whose THD is the measured 2 % with a floor of 0.24 % is 20 log10(hypot(2, 0.24) / 2)
    = +0.062 dB off, the noise's share."""
    import math
    from types import SimpleNamespace

    from sensfw.measure.discrepancy import Entries, residuals

    band = [{"centre_hz": 100.0, "mean_db": 0.3}]
    cs = [SimpleNamespace(bands=band, thd_model=None, thd_measured=0.24, thd_floor=0.24),
          SimpleNamespace(bands=band, thd_model=2.0, thd_measured=2.0, thd_floor=0.24),
          SimpleNamespace(bands=band, thd_model=0.5, thd_measured=2.0, thd_floor=None)]
    e = Entries(bands=((100.0,),) * 3, thd=(True,) * 3, sigma=((0.2, 1.5),) * 3,
                noise="propagated")
    r, s = residuals(cs, e)
    assert r[[0, 2, 4]] == pytest.approx([0.3] * 3)
    assert r[1] == pytest.approx(20 * math.log10(math.hypot(1e-3, 0.24) / 0.24), abs=1e-9)
    assert abs(r[1]) < 1e-4
    assert r[3] == pytest.approx(0.0619, abs=1e-3)
    assert r[5] == pytest.approx(20 * math.log10(0.25))  # no floor known: the model alone
    assert s.tolist() == [0.2, 1.5] * 3
    # the scatter noise model (the default) reads the model's THD alone
    r, _ = residuals(cs, Entries(bands=e.bands, thd=e.thd, sigma=e.sigma))
    assert r[1] == pytest.approx(20 * math.log10(1e-3 / 0.24))
    assert r[3] == pytest.approx(0.0, abs=1e-12)


def test_the_studys_noise_model_sets_the_band_errors(study, records, runner):
    """``[calibration] noise = "propagated"``: every band entry's standard error is the
    record's white noise carried through its H1 (``band_white_noise``, combined with the
    model-form floor), the nominal model is scored with the THD against the record's noise
    floor, and the same records' entries under the default scatter model differ."""
    import math

    from sensfw.measure.bands import analysis_bands, band_white_noise
    from sensfw.measure.discrepancy import MODEL_DB

    data = study.spec.model_dump(exclude_none=True)
    data.setdefault("calibration", {})["noise"] = "propagated"
    propagated = Study.from_dict(data, "quick-short-propagated")
    chirps = records[:2]  # one kind: no per-kind weights
    space = study.calibration_space(["slide_stiffness"])
    res = Residuals(propagated, chirps, runner, space)
    res.nominal()
    assert res.entries.noise == "propagated"
    scatter = Residuals(study, chirps, runner, space)
    scatter.nominal()
    assert scatter.entries.noise == "scatter"
    to_db = 20 / math.log(10) / math.sqrt(2)
    m, ch = chirps[0], res.channels[0]
    edges = analysis_bands(*res.bands[0])
    # the synthetic record is the study's sweep: the model's drive is the ideal sweep, and
    # the excitation's noise is the record's force less it (bands.band_white_noise's
    # lower bound), whose std is the rig's 2 % of the force's RMS
    sp = float(np.std(m.signals.force - m.drive.force(m.signals.t)))
    e = dict(zip([c for _, c, _ in edges],
                 band_white_noise(m.signals, ch, edges, res.bands[0], excitation_sigma=sp),
                 strict=True))
    sigma = res.entries.sigma[0]
    for centre, s in zip(res.entries.bands[0], sigma, strict=False):
        assert s == pytest.approx(math.hypot(to_db * e[centre], MODEL_DB), rel=1e-6)
    assert res.entries.sigma != scatter.entries.sigma


def test_widening_the_errors_keeps_the_noise_model(study, records, runner):
    """The model's scatter widens every error (``add_scatter``: diagnose does it after H0's
    first calibration) and keeps the study's noise model. Stop 61's option lost it there,
    so under ``"propagated"`` every evaluation after the widening read the THD entry
    without the record's noise floor (recovery seed 2026, no effect: chi2 at the true
    values 68.3 before the widening, 165.6 after it, against H0's 63.7). The dB residuals
    stay what they were; each weighted entry shrinks by exactly old error / new error."""
    data = study.spec.model_dump(exclude_none=True)
    data.setdefault("calibration", {})["noise"] = "propagated"
    propagated = Study.from_dict(data, "quick-short-propagated")
    space = study.calibration_space(["slide_stiffness"])
    res = Residuals(propagated, records[:2], runner, space)
    nominal, _ = res.nominal()
    (before,) = res.evaluate(None, [nominal], "before")
    old = np.array([x for part in res.entries.sigma for x in part])
    extra = np.full(len(old), 0.5)
    res.add_scatter(extra)
    assert res.entries.noise == "propagated"
    (after,) = res.evaluate(None, [nominal], "after")
    assert after == pytest.approx(before * old / np.hypot(old, extra), rel=1e-9)
