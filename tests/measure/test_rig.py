"""Measurements as a rig produces them (issue 13): noisy, offset, drifting, delayed forces are
accepted and their sweep estimated; other excitations drive the model with the measured
record; a voltage drives it through a gain; several levels in one call."""

import json
from pathlib import Path

import numpy as np
import pytest

from sensfw.errors import MeasurementError
from sensfw.excitation import Chirp, LinearSweep, RandomForce, SampledForce, SteppedSine
from sensfw.measure.io import load_all, write_csv
from sensfw.measure.prepared import load_measurements
from sensfw.measure.synthetic import Rig, synthesize
from sensfw.signal.sweep import estimate_sweep
from sensfw.study import Study

ROOT = Path(__file__).resolve().parents[2]
QUICK_EX = {"f0": "50 Hz", "f1": "5 kHz", "duration": "0.25 s", "fs": "20 kHz",
            "amplitude": "0.1 N", "tail": "0.02 s"}


TWO_DOF_TOML = """
[study]
name = "rig"
[model]
name = "two_dof"
output = "a1"
[excitation]
f0 = "50 Hz"
f1 = "5 kHz"
duration = "0.25 s"
fs = "20 kHz"
amplitude = "0.1 N"
tail = "0.02 s"
[[stages]]
name = "s"
design = "oat"
scorers = [{ name = "rms" }]
"""


def two_dof(**excitation) -> Study:
    """The analytic 2-DOF model with the quick study's excitation (fast, exact)."""
    return Study.from_dict({
        "study": {"name": "rig"}, "model": {"name": "two_dof", "output": "a1"},
        "excitation": {**QUICK_EX, **excitation},
        "stages": [{"name": "s", "design": "oat", "scorers": [{"name": "rms"}]}]})


@pytest.mark.parametrize("noise", [0.05, 0.10])
def test_twenty_seeds_of_a_rig_force_are_accepted_and_the_chirp_estimated(noise, tmp_path):
    """Noise (5 %, 10 % of each channel's RMS), a DC offset of 30 % of the level, a +-20 %
    amplitude drift and a 1 ms delay: every file is accepted and f0, f1 and the duration come
    out within 2 % (the bar); the start within 0.1 ms of the delay."""
    study = two_dof()
    worst = np.zeros(4)
    files = []
    for seed in range(20):
        rig = Rig(noise=noise, offset=0.3, drift=0.2, delay=1e-3, seed=seed)
        sig, _ = synthesize(study, rig=rig)
        files.append(write_csv(tmp_path / f"m{seed}.csv", sig))
    meas = load_measurements(study, [str(f) for f in files])  # raises on a refusal
    assert len(meas) == 20
    for m in meas:
        est = m.sweep
        assert est.kind == "log_chirp"
        err = [est.f0 / 50 - 1, est.f1 / 5000 - 1, est.duration / 0.25 - 1,
               (est.t_start - 1e-3) / 1e-4]
        worst = np.maximum(worst, np.abs(err))
        # the record is the study's sweep, but a nonlinear model feels a +-20 % drift:
        # the model is driven by the measured record, with a notice
        assert m.drive.kind == "sampled" and m.drive.sweep["kind"] == "log_chirp"
        assert any("drifts by" in n for n in m.notes), m.notes
        # the level is the median envelope: with a +-20 % drift over 1.3 cycles of a random
        # phase it lies within the drift's range
        assert m.level == pytest.approx(0.1, rel=0.2)
    assert np.all(worst[:3] < 0.02) and worst[3] < 1.0, worst


def test_sweep_estimate_tells_the_kinds_apart():
    """Exact signals: log and linear sweeps by their phase law, a stepped sine by its
    dwells, band-limited noise as broadband."""
    rng = np.random.default_rng(0)
    for ex, kind in ((Chirp(70, 110, 8, 1024, 0.2), "log_chirp"),
                     (LinearSweep(70, 110, 8, 1024, 0.2), "linear_sweep"),
                     (LinearSweep(50, 5000, 0.25, 20000, 0.1), "linear_sweep"),
                     (SteppedSine(50, 5000, 10, 0.5, 20000, 0.1), "stepped_sine"),
                     (RandomForce(50, 5000, 0.25, 20000, 0.1), "random")):
        x = ex.force() + 0.02 * ex.amplitude * rng.standard_normal(ex.n_samples)
        est = estimate_sweep(x, ex.fs, band=(ex.f0, ex.f1))
        assert est.kind == kind, (ex, est)
        if est.is_sweep:
            assert est.f0 == pytest.approx(ex.f0, rel=0.01)
            assert est.f1 == pytest.approx(ex.f1, rel=0.01)
            assert est.duration == pytest.approx(ex.duration, rel=0.01)


def test_a_silent_or_unsweepable_force_is_a_clear_error(tmp_path):
    study = two_dof()
    sig, _ = synthesize(study)
    sig.force[:] = 0.0
    f = write_csv(tmp_path / "silent.csv", sig)
    with pytest.raises(MeasurementError, match=r"silent\.csv, channel 'force': the excitation "
                                               r"channel is silent"):
        load_measurements(study, [str(f)])


def test_voltage_needs_the_gain_and_drives_through_it(tmp_path):
    """A rig that records the amplifier voltage: without a gain the study cannot drive the
    model (clear error); with it, the model is driven by gain x voltage and its input
    record is the voltage, as measured."""
    rig = Rig(noise=0.0, gain=2.0)
    sig, info = synthesize(two_dof(), rig=rig)
    assert sig.units["force"] == "V" and info["amplitude"] == pytest.approx(0.05)
    f = write_csv(tmp_path / "v.csv", sig, level=info["amplitude"])
    with pytest.raises(MeasurementError, match=r"v\.csv, channel 'force': the excitation is "
                                               r"recorded in V.*gain"):
        load_measurements(two_dof(), [str(f)])
    study = two_dof(gain={"nominal": "2 N/V", "min": "0.5 N/V", "max": "8 N/V"})
    (m,) = load_measurements(study, [str(f)])
    assert m.excitation == "voltage" and m.drive.unit == "V"
    from sensfw.models.drive import apply_gain

    driving, params = apply_gain(m.drive, study.parameters.nominal())
    assert "excitation_gain" not in params and driving.unit == "N"
    np.testing.assert_allclose(driving.force(), 2.0 * m.drive.force(), rtol=1e-12)


def test_levels_in_one_call_as_csv_files_and_as_one_uff(cli, tmp_path):
    study_file = tmp_path / "s.toml"
    study_file.write_text(TWO_DOF_TOML)
    proc = cli("simulate", study_file, "--out", tmp_path / "m.csv", "--levels", "0.1,0.3,1.0",
               "--noise", "0.02")
    assert proc.returncode == 0, proc.stderr
    files = sorted(tmp_path.glob("m_*.csv"))
    # named as the levels were written (1.0, not 1)
    assert [f.name for f in files] == ["m_0.1.csv", "m_0.3.csv", "m_1.0.csv"]
    # one UFF file with every level (what --out u.uff writes)
    from sensfw.measure.io import write_uff

    study = two_dof()
    records = [(synthesize(study, amplitude=lv)[0], lv) for lv in (0.1, 0.3)]
    write_uff(tmp_path / "u.uff", records)
    found = load_all(tmp_path / "u.uff")
    assert [m.level for m in found] == [0.1, 0.3]
    # the records scale with the level (the 2-DOF model is linear)
    assert np.max(np.abs(found[1].signals.channels["a1"])) == pytest.approx(
        3 * np.max(np.abs(found[0].signals.channels["a1"])), rel=1e-6)
    from typer.testing import CliRunner

    from sensfw.cli import app

    res = CliRunner().invoke(app, ["simulate", str(study_file), "--out", str(tmp_path / "x.csv"),
                                   "--levels", "0.1,-2"])
    assert res.exit_code == 2 and "levels must be positive" in res.output
    res = CliRunner().invoke(app, ["simulate", str(study_file), "--out", str(tmp_path / "x.csv"),
                                   "--levels", "0.5, .5"])
    assert res.exit_code == 2 and "a level is given twice" in res.output


def test_the_measured_record_drives_an_exudyn_model_like_the_closed_form():
    """The per-step quadratic interpolation of a sampled record (models/drive.py) against
    the closed-form chirp, both through Exudyn, on a planar mass-spring: the records differ
    only by the band-limited interpolation of the samples (resample_poly's filter: about
    2e-4 of the amplitude inside the sweep, measured) and its Gibbs ringing at the sweep's
    abrupt start and end, so the responses agree to 1e-3 relative (RMS over the sweep)."""
    import exudyn as exu

    from sensfw.models.contact import symbolic_ops
    from sensfw.models.drive import LoadSignal
    from sensfw.models.planar import Body, Link, Mechanism
    from sensfw.models.planar import exudyn as pe
    from sensfw.models.stepsize import grid_step

    def spring(ops, u, v, contact):
        return -4e4 * u[0] - 20 * v[0], -4e4 * u[1] - 20 * v[1]

    ch = Chirp(50, 5000, 0.1, 20000, 0.1, tail=0.01)
    out = {}
    for name, ex in (("closed", ch), ("sampled", SampledForce(ch.force(), ch.fs, 0.1))):
        mech = Mechanism([Body("M", 2, 1.0)], [Link("k", "H", (0, 0), "M", (0, 0), spring)],
                         {}, {})
        sig = LoadSignal(ex, 1e-5)
        built = pe.build(mech, np.zeros(2), None, symbolic_ops(),
                         [("M", (0.0, 0.0), lambda ops, t, sig=sig: (sig.value(ops, t), 0.0))],
                         [("a", "M", (0.0, 0.0), 0)])
        built.keep += sig.install(built.mbs)
        exu.config.printToConsole = False
        channels, _ = pe.solve(built, ch.fs, ch.n_samples, grid_step(1e-5, ch.fs))
        out[name] = channels["a"]
    a, b = out["closed"], out["sampled"]
    inner = slice(int(0.01 * ch.fs), int(0.09 * ch.fs))
    rel = np.sqrt(np.mean((a[inner] - b[inner]) ** 2) / np.mean(a[inner] ** 2))
    assert rel < 1e-3, rel
    # and the pre-step's timing is right: with the step's end time instead of its start,
    # the force would lead by one step (10 us, 18 degrees at 5 kHz) and this fails
    assert np.corrcoef(a[inner], b[inner])[0, 1] > 0.99999


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["linear_sweep", "random"])
def test_other_excitations_drive_the_model_and_it_agrees_with_itself(kind, cli, tmp_path):
    """A linear sweep and band-limited random force from `simulate --excitation` (2 %
    noise): `compare` drives the model with the measured record (a notice, not a refusal)
    and the model compared with itself stays below the noise floor compare states
    (the band error a correct model exceeds with 0.1 % probability given the measurement's
    own noise, LevelComparison.noise_floor_db)."""
    m = tmp_path / "m.csv"
    proc = cli("simulate", ROOT / "studies" / "quick.toml", "--out", m, "--excitation", kind,
               "--noise", "0.02", "--seed", "4", "--offset", "0.2", "--delay", "0.001")
    assert proc.returncode == 0, proc.stderr
    proc = cli("compare", ROOT / "studies" / "quick.toml", "-m", m, "--out", tmp_path / "c",
               "--no-progress", "--workers", "1")
    assert proc.returncode == 0, proc.stderr
    said = " ".join(proc.stderr.split())  # the terminal wraps lines anywhere
    assert "notice" in said and "driven by the measured record" in said
    level = json.loads((tmp_path / "c" / "compare.json").read_text())["levels"][0]
    err = level["frf_error_db"]
    assert err["bands_rms"] < err["noise_floor_db"], err
    assert sum(b["used"] for b in err["bands"]) >= 6  # the comparison is not empty
    # the record's one error figure is what its noise alone gives a correct model (within
    # the spread of three noise draws)
    assert err["value"] < 1.3 * err["noise_alone"], err


@pytest.mark.slow  # five CLI processes
def test_simulate_refuses_rig_settings_that_cannot_be(cli, tmp_path):
    """Each failed deep inside (a negative delay: numpy's "negative dimensions"), was taken
    silently (a negative noise, a gain of 0) or wrote CSV text into a .mat file."""
    study = ROOT / "studies" / "quick.toml"
    for args, message in ((["--delay", "-0.01"], "--delay -0.01: must be >= 0"),
                          (["--noise", "-0.1"], "--noise -0.1: must be >= 0"),
                          (["--amplitude", "-0.1"], "--amplitude -0.1: must be positive"),
                          (["--channel-gain", "0"], "--channel-gain 0.0: a shaker gain"),
                          (["--out", tmp_path / "m.mat"], "write a .csv")):
        out = [] if "--out" in args else ["--out", tmp_path / "m.csv"]
        proc = cli("simulate", study, *out, *args)
        assert proc.returncode == 2 and message in proc.stderr, (args, proc.stderr)
        assert "Traceback" not in proc.stderr


def test_a_voltage_studys_gain_is_its_parameter_and_drift_stays_below_one():
    """``simulate --channel-gain`` on a study that drives a voltage (the beam's) was
    dropped without a word (byte-identical records): refused, naming the parameter that
    sets it. A drift of 1 or more turns the envelope through zero: refused."""
    from pathlib import Path

    from sensfw.errors import SensfwError
    from sensfw.study import Study

    beam = Study.load(Path(__file__).parents[2] / "studies" / "bert.toml")
    with pytest.raises(SensfwError, match=r"drives a voltage \(V\).*--set excitation_gain"):
        synthesize(beam, rig=Rig(gain=2.0))
    with pytest.raises(SensfwError, match="rig drift must be below 1"):
        Rig(drift=1.0)


def test_an_effects_options_pass_through_simulate_and_a_function_model_is_refused():
    """``--effect micro_slip:elements=6`` was 'unknown parameter elements': the effect's
    options (as ``augment --option`` takes them) go into its spec, the rest are parameter
    values. A function model (Ishigami: one value per run) wrote a one-sample 'log chirp'
    record."""
    from sensfw.errors import SensfwError
    from sensfw.measure.synthetic import parse_effect
    from sensfw.study import Study

    assert parse_effect("micro_slip@joint:elements=6,microslip_force=800") == (
        {"name": "micro_slip", "attach": "joint", "elements": 6}, {"microslip_force": 800.0})
    assert parse_effect("added_mass:added_mass=0.01") == ({"name": "added_mass"},
                                                          {"added_mass": 0.01})
    ishigami = Study.from_dict({"study": {"name": "i"}, "model": {"name": "ishigami"},
                                "excitation": {"duration": "0.01 s"},
                                "stages": [{"name": "s", "design": "oat",
                                            "scorers": [{"name": "rms"}]}]}, "i.toml")
    with pytest.raises(SensfwError, match="gives one value per run, not a time response"):
        synthesize(ishigami)
