"""FRF-only records (issue 27, item 5): a rig's FRFs without time data (an LMS ``FRF.mat``
alone, UFF58 FRF records, a stepped-sine test) load as a measurement of FRFs per channel,
with its level and sweep direction where the file says them."""

from pathlib import Path

import numpy as np
import pytest
from scipy.io import savemat

from sensfw.errors import MeasurementError
from sensfw.measure.io import FRFRecord, load, load_all, write_uff
from sensfw.measure.lms import lms_struct, run_excitation

LEVELS = ("0p05", "0p10", "0p15", "0p20", "0p25", "0p30")
#: the laser/voltage H1 peak of the second bending mode at 0.05 and 0.30 V as the data
#: set's README states it (``data/bert/README.md``: "the sweeps: 95.5 -> 91.25 Hz")
README_PEAKS = {"0p05": 95.5, "0p30": 91.25}


def sdof(f, fn=97.0, zeta=0.015):
    """A single mode's mobility-like FRF (an analytic shape for synthetic files)."""
    return 1j * f / (fn**2 - f**2 + 2j * zeta * fn * f)


# --- the real FRF.mat files of the sweeps --------------------------------------------------

@pytest.mark.parametrize("level", LEVELS)
def test_bert_sweep_frf_mat_reads_on_its_own(bert, level):
    """Each sweep folder's FRF.mat alone: five FRFs per volt on 8193 lines of 0.0625 Hz,
    the level from the folder name, 'sweep, driven up' from Test.Lab's run name, no time
    data."""
    m = load(bert / f"level_{level}" / "FRF.mat")
    r = m.frf
    assert r is not None and m.fs is None
    assert m.level == pytest.approx(float(level.replace("p", ".")))
    assert list(r.channels) == ["Acc1", "Acc2", "Acc3", "Acc4", "Laser"]
    assert r.units == {"force": "V", "Acc1": "m/s^2", "Acc2": "m/s^2", "Acc3": "m/s^2",
                       "Acc4": "m/s^2", "Laser": "m/s"}
    assert m.units["Acc1"] == "g" and m.excitation == "voltage"
    assert (len(r.f), r.f[1] - r.f[0], r.f[-1]) == (8193, 0.0625, 512.0)
    assert (r.kind, r.direction, r.estimator, r.averages) == ("sweep", "up", "H1", 54)
    if level in README_PEAKS:
        sel = (r.f >= 80) & (r.f <= 105)
        peak = r.f[sel][np.argmax(np.abs(r.channels["Laser"][sel]))]
        assert peak == README_PEAKS[level]


def test_bert_random_frf_mat_says_random(bert):
    m = load(bert.parent / "random" / "level_0p30" / "FRF.mat")
    assert (m.frf.kind, m.frf.direction) == ("random", None)
    # its 0.3 is the generator's setting (the record's RMS in the band is about 3 mV): the
    # stepped drive at 0.3 V says so rather than pass for the rig's drive
    from sensfw.measure.lines import frf_drive
    from sensfw.study import Study

    frf_drive(m, Study.load(Path(__file__).parents[2] / "studies" / "bert.toml"))
    assert any("random test" in n and "rig's setting" in n for n in m.notes), m.notes


def test_run_names():
    assert run_excitation("Round1_Chirp0p05_70to110Hz_1") == ("sweep", "up")
    assert run_excitation("Round1_Rand0p30_0to110Hz_1") == ("random", None)
    assert run_excitation("Stepped_110to70Hz") == ("stepped_sine", "down")
    assert run_excitation("Run 3") == (None, None)


# --- synthetic files ----------------------------------------------------------------------

def test_synthetic_lms_frf_mat(tmp_path):
    """An LMS FRF struct (accelerations in g per volt, stored in SI) with its coherence in
    the same folder: values in SI, coherence attached, names and units as Test.Lab's."""
    f = np.arange(0, 2049) * 0.125
    h = np.column_stack([sdof(f), 2 * sdof(f)])
    folder = tmp_path / "level_0p20"
    folder.mkdir()
    savemat(folder / "FRF.mat", {"FRF": lms_struct(h, 0.125, ["Acc1:+X", "Acc2:+X"], "g",
                                                   kind="FRF", per="V",
                                                   run="Step_110to70Hz")})
    savemat(folder / "Coherence.mat", {"Coherence": {
        **lms_struct(np.full((len(f), 2), 0.99), 0.125, ["Acc1:+X", "Acc2:+X"], "g",
                     kind="FRF", per="V"), "function_record": {
            "type": "Coherence", "primary_channel": {"label": np.array(["Acc1:+X", "Acc2:+X"],
                                                                       dtype=object)}}}})
    m = load(folder)
    r = m.frf
    assert m.level == 0.2 and (r.kind, r.direction) == ("stepped_sine", "down")
    np.testing.assert_allclose(r.channels["Acc2"], 2 * sdof(f), rtol=1e-12)
    assert r.units["Acc1"] == "m/s^2" and m.units["Acc1"] == "g"
    np.testing.assert_allclose(m.frf.coherence["Acc1"], 0.99)


def test_uff58_frf_written_by_pyuff_reads_back(tmp_path):
    """Stepped-sine FRFs up and down at two levels in one UFF file (pyuff type-58 records,
    function type 4, uneven lines, level and direction in id2): four measurements, each
    channel's FRF back to 1e-9 (ASCII UFF), lines given downwards stored increasing."""
    f = np.linspace(85.0, 105.0, 41)
    units = {"force": "V", "Laser": "m/s", "Acc1": "m/s^2"}
    written = []
    for level in (0.05, 0.3):
        for direction, scale in (("up", 1.0), ("down", 1.02)):
            lines = f if direction == "up" else f[::-1]
            h = scale * level * sdof(lines)
            written.append((FRFRecord.checked("x", lines, {"Laser": h, "Acc1": 3j * h}, units,
                                              kind="stepped_sine", direction=direction),
                            level))
    path = write_uff(tmp_path / "ss.uff", written)
    found = load_all(path)
    assert [(m.level, m.frf.direction) for m in found] == [
        (0.05, "down"), (0.05, "up"), (0.3, "down"), (0.3, "up")]
    for m in found:
        scale = 1.02 if m.frf.direction == "down" else 1.0
        np.testing.assert_allclose(m.frf.channels["Laser"], scale * m.level * sdof(f),
                                   rtol=1e-9)
        np.testing.assert_allclose(m.frf.f, f)
        assert m.frf.kind == "stepped_sine" and m.frf.units == units
        assert m.file.endswith(f"(level {m.level:g}, {m.frf.direction})")
    with pytest.raises(MeasurementError, match="holds 4 measurements"):
        load(path)


def test_uff58_frf_units_and_errors(tmp_path):
    """An FRF in mm/s per N is read in (m/s)/N; a NaN names the channel and the line."""
    import pyuff

    f = np.linspace(10, 50, 5)
    path = tmp_path / "mm.uff"
    pyuff.UFF(str(path)).write_sets(pyuff.prepare_58(
        func_type=4, id1="tip", id2="level=2", rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1,
        data=np.ones(5) * (1 + 1j), x=f, abscissa_spacing=0, abscissa_spec_data_type=18,
        ordinate_spec_data_type=11, orddenom_spec_data_type=13,
        ordinate_axis_units_lab="mm/s", orddenom_axis_units_lab="N", binary=0), mode="add")
    m = load(path)
    assert m.frf.units == {"force": "N", "tip": "m/s"} and m.level == 2.0
    np.testing.assert_allclose(m.frf.channels["tip"], 1e-3 * (1 + 1j))
    with pytest.raises(MeasurementError, match=r"x, channel 'tip': 1 NaN/inf value\(s\), "
                                               r"first at 30 Hz"):
        FRFRecord.checked("x", f, {"tip": np.array([1, 1, np.nan, 1, 1])}, {})


# --- compared with a model ----------------------------------------------------------------

def two_dof_study(f0=100.0, f1=600.0):
    from sensfw.study import Study

    return Study.from_dict({
        "study": {"name": "t"}, "model": {"name": "two_dof", "output": "a1"},
        "excitation": {"f0": f"{f0} Hz", "f1": f"{f1} Hz", "duration": "0.3 s",
                       "fs": "2 kHz", "amplitude": "1 N", "tail": "0.05 s"},
        "stages": [{"name": "s", "design": "oat", "scorers": [{"name": "rms"}]}]})


def stepped_record(lines, direction, dwell=0.6, **params):
    """The 2-DOF model's stepped-sine FRF (0.6 s per step: 7.5 decay times to settle) as
    a rig would export it."""
    from sensfw.excitation import SteppedSine
    from sensfw.models.analytic import TwoDOF
    from sensfw.signal.stepped import stepped_frf, steps_of

    m = TwoDOF()
    sig = m.simulate({**m.parameters().nominal(), **params},
                     SteppedSine.at(lines, dwell, 2000.0, 1.0, direction=direction))
    r = stepped_frf(sig.force, sig.channels, sig.fs, steps_of(sig.f_inst, sig.fs))
    return FRFRecord.checked("x", r.f, r.frf, {"force": "N", "a1": "m/s^2", "a2": "m/s^2"},
                             kind="stepped_sine", direction=direction)


@pytest.fixture(scope="module")
def runner(tmp_path_factory):
    from sensfw.runs import Runner, RunStore

    with Runner(RunStore(tmp_path_factory.mktemp("runs")), backend="serial") as r:
        yield r


def test_an_frf_only_record_of_the_model_is_the_model(tmp_path, runner):
    """Stepped-sine FRFs of the 2-DOF model, up and down, 20 Hz lines over both modes,
    exported as UFF: ``compare`` drives the model by a stepped sine on those lines, each
    step 8 decay times long (from the record's own resonance fit), and reads its
    steady state. The record and the model then agree to 0.02 dB (the record settled for
    7.5 decay times, the model for 4: e^-4 of a step's transient at the fit's start); the
    resonances fall on the same lines; up and down agree (a linear model: no jump)."""
    from sensfw.measure.compare import compare_measurements
    from sensfw.measure.prepared import load_measurements

    lines = np.arange(150.0, 551.0, 20.0)
    path = write_uff(tmp_path / "ss.uff", [(stepped_record(lines, d), 1.0)
                                           for d in ("up", "down")])
    study = two_dof_study()
    meas = load_measurements(study, [str(path)])
    assert [m.drive.direction for m in meas] == ["down", "up"]
    # eight decay times of the first mode from the record's fit on 20 Hz lines (0.044 s,
    # the model's own 1 / (zeta omega) is 0.040 s)
    assert meas[0].drive.dwell == pytest.approx(8 * 0.044, rel=0.02)
    cmp = compare_measurements(study, meas, runner)
    for c in cmp.levels:
        assert c.kind == "stepped_sine" and c.error_db < 0.02, c.error_db
        assert [(r["measured_hz"], r["model_hz"]) for r in c.resonances] == [
            (230.0, 230.0), (450.0, 450.0)]  # the lines nearest 225 and 450 Hz
    (j,) = cmp.jumps
    assert j["measured"]["hysteresis_hz"] is None and j["model"]["hysteresis_hz"] is None
    assert abs(j["model"]["max_difference_db"]) < 0.1
    data = cmp.to_dict()
    assert data["levels"][0]["frf_error_db"]["value"] == pytest.approx(cmp.levels[0].error_db)
    assert data["levels"][0]["excitation"] == {"kind": "stepped_sine", "direction": "down",
                                               "level": 1.0, "unit": "N", "rms_in_band": None}


def test_a_stiffer_rig_shows_in_the_error_and_the_resonance(tmp_path, runner):
    """The record of a model whose ground spring is 20 % stiffer (k1 4800 N/mm; modes 238
    and 466 Hz instead of 225 and 450): the first mode's peak moves up by a 10 Hz line or
    more and the error is far above the 0.02 dB of the model against itself. A linear
    model is determined by its drive: its twin (the drive x (1 + 1e-9)) scatters by no more
    than round-off."""
    from sensfw.measure.compare import compare_measurements
    from sensfw.measure.prepared import load_measurements

    lines = np.arange(150.0, 551.0, 10.0)
    path = write_uff(tmp_path / "k.uff", [(stepped_record(lines, "up", k1=4800.0), 1.0)])
    cmp = compare_measurements(two_dof_study(), load_measurements(two_dof_study(),
                                                                  [str(path)]), runner,
                               twins=1)
    (c,) = cmp.levels
    assert c.error_db > 1.0
    assert c.error_scatter_db < 1e-6
    assert all(r["model_scatter_pct"] < 1e-6 for r in c.resonances if r["model_hz"])
    first = c.resonances[0]
    assert first["measured_hz"] - first["model_hz"] >= 10.0


def test_compare_level_takes_an_frf_record_as_the_measured_side(tmp_path, runner):
    """What a calibration calls (``compare_level(m.signals, sig, ...)``, detail=False)
    works on an FRF-only measurement: its ``signals`` is the FRF record."""
    from sensfw.evaluate import simulate, variant_spec
    from sensfw.measure.compare import compare_level
    from sensfw.measure.prepared import load_measurements

    lines = np.arange(150.0, 551.0, 20.0)
    path = write_uff(tmp_path / "one.uff", [(stepped_record(lines, "up"), 1.0)])
    study = two_dof_study()
    (m,) = load_measurements(study, [str(path)])
    (sig,), _ = simulate(runner, [variant_spec(study, {}, m.drive)])
    c = compare_level(m.signals, sig, "a2", (100.0, 600.0), m.level, m.file, detail=False)
    assert c.resonances == [] and c.error_db < 0.02 and len(c.used_bands) >= 5


def test_the_drive_thins_a_fine_record_and_needs_lines_in_the_band():
    """An FRF of 1/16 Hz lines (an LMS FRF.mat) over the study's band: every k-th line, at
    most 200 steps, each settling for four decay times of the record's resonance (97 Hz,
    damping ratio 0.015: 0.109 s); a record outside the band is an error naming the
    file."""
    from sensfw.measure.lines import frf_drive
    from sensfw.measure.measurement import Measurement

    f = np.arange(0, 8193) * 0.0625
    rec = FRFRecord.checked("r.mat", f, {"a1": sdof(f)}, {"force": "N", "a1": "m/s^2"},
                            direction="down")
    m = Measurement("r.mat", rec, level=0.5)
    ex = frf_drive(m, two_dof_study(70.0, 110.0))  # 641 lines: every 4th
    assert ex.steps == 161 and ex.direction == "down" and ex.amplitude == 0.5
    np.testing.assert_allclose(np.diff(ex.lines), 0.25)
    assert ex.dwell == pytest.approx(8 / (2 * np.pi * 97 * 0.015), rel=0.02)
    with pytest.raises(MeasurementError, match=r"r\.mat: fewer than two FRF lines inside"):
        frf_drive(Measurement("r.mat", FRFRecord.checked(
            "r.mat", f[:100], {"a1": sdof(f[:100])}, {"force": "N", "a1": "m/s^2"}),
            level=1.0), two_dof_study())
