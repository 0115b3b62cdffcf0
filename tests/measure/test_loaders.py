"""Measurement files: every loader error names the file and the channel (issue 6)."""

import numpy as np
import pytest

from sensfw.errors import MeasurementError
from sensfw.excitation import Chirp
from sensfw.measure.checks import align_to_ideal, prepare, require_channels
from sensfw.measure.io import Measurement, load, write_csv
from sensfw.models.analytic import TwoDOF
from sensfw.models.base import Signals
from sensfw.signal.sweep import estimate_sweep

EX = Chirp(50, 2000, 0.3, 20000, 1.0, tail=0.05)


@pytest.fixture(scope="module")
def good():
    m = TwoDOF()
    s = m.simulate(m.parameters().nominal(), EX)
    return Signals(t=s.t, force=s.force, channels={"a1": s.channels["a1"]}, fs=s.fs)


def csv(tmp_path, sig, name="m.csv", **kw):
    return write_csv(tmp_path / name, sig, **kw)


def test_roundtrip_units_and_sidecar(tmp_path, good):
    f = csv(tmp_path, good, level=1.0)
    m = load(f)
    assert m.level == 1.0 and m.fs == pytest.approx(20000)
    np.testing.assert_allclose(m.signals.channels["a1"], good.channels["a1"], rtol=1e-9,
                               atol=1e-12)
    # accelerations in g in the header are converted to m/s^2
    text = f.read_text().replace("a1 [m/s^2]", "a1 [g]")
    g = tmp_path / "g.csv"
    g.write_text(text)
    assert load(g).signals.channels["a1"][100] == pytest.approx(
        good.channels["a1"][100] * 9.80665, rel=1e-8)


def test_nan_names_file_and_channel(tmp_path, good):
    x = good.channels["a1"].copy()
    x[123] = np.nan
    bad = Signals(t=good.t, force=good.force, channels={"a1": x}, fs=good.fs)
    f = csv(tmp_path, bad)
    with pytest.raises(MeasurementError, match=r"m\.csv, channel 'a1': 1 NaN/inf value"):
        load(f)


def test_non_uniform_sampling(tmp_path, good):
    t = good.t.copy()
    t[500:] += 1e-5
    f = csv(tmp_path, Signals(t=t, force=good.force, channels=good.channels, fs=good.fs))
    with pytest.raises(MeasurementError, match=r"m\.csv, channel 'time': non-uniform"):
        load(f)


def test_declared_rate_disagrees(tmp_path, good):
    f = csv(tmp_path, good)
    f.with_suffix(".toml").write_text("fs = 10000.0\n")
    with pytest.raises(MeasurementError, match=r"channel 'time': sample rate .* 20000 Hz but "
                                               r"the sidecar declares fs = 10000"):
        load(f)


def two_dof_study(drive="auto", output="a1"):
    """A study of the analytic 2-DOF model with the excitation ``EX``."""
    from sensfw.study import Study

    return Study.from_dict({
        "study": {"name": "t"}, "model": {"name": "two_dof", "output": output},
        "excitation": {"f0": "50 Hz", "f1": "2 kHz", "duration": "0.3 s", "fs": "20 kHz",
                       "amplitude": "1 N", "tail": "0.05 s", "drive": drive},
        "stages": [{"name": "s", "design": "oat", "scorers": [{"name": "rms"}]}]})


def test_missing_or_misnamed_channel(tmp_path, good):
    f = csv(tmp_path, good)
    with pytest.raises(MeasurementError, match=r"m\.csv, channel 'a2': missing channel"):
        prepare(load(f), two_dof_study(output="a2"))
    ren = Signals(t=good.t, force=good.force, channels={"crank_axal": good.channels["a1"]},
                  fs=good.fs)
    g = csv(tmp_path, ren, "r.csv")
    with pytest.raises(MeasurementError, match=r"channel 'crank_axial'.*did you mean "
                                               r"'crank_axal'"):
        require_channels(load(g), ["crank_axial"])
    ren = Signals(t=good.t, force=good.force, channels={"Crank_Axial": good.channels["a1"],
                                                        "crank_radial": good.channels["a1"]},
                  fs=good.fs)
    with pytest.raises(MeasurementError, match=r"did you mean 'Crank_Axial'"):
        require_channels(load(csv(tmp_path, ren, "c.csv")), ["crank_axial"])


def test_clipping(tmp_path, good):
    x = np.clip(good.channels["a1"], -0.5 * np.max(np.abs(good.channels["a1"])),
                0.5 * np.max(np.abs(good.channels["a1"])))
    f = csv(tmp_path, Signals(t=good.t, force=good.force, channels={"a1": x}, fs=good.fs))
    with pytest.raises(MeasurementError, match=r"m\.csv, channel 'a1': clipped"):
        prepare(load(f), two_dof_study())


def test_record_shorter_than_the_chirp(tmp_path, good):
    n = 4000  # 0.2 s of a 0.3 s chirp: not the study's sweep
    short = Signals(t=good.t[:n], force=good.force[:n], channels={"a1": good.channels["a1"][:n]},
                    fs=good.fs)
    f = csv(tmp_path, short)
    # the model can be driven by the measured force: a notice, not a refusal
    m = prepare(load(f), two_dof_study())
    assert m.drive.kind == "sampled" and len(m.drive.samples) == n
    # the truncated sweep ends at 50 (2000/50)^(0.2/0.3) = 584 Hz
    assert m.sweep.f1 == pytest.approx(50 * 40 ** (2 / 3), rel=0.02)
    assert m.sweep.duration == pytest.approx(0.2, rel=0.02)
    assert any("f1 = 58" in note and "driven by the measured record" in note
               for note in m.notes), m.notes
    # unless the study insists on its ideal sweep
    with pytest.raises(MeasurementError, match=r"channel 'force': the excitation is not the "
                                               r"study's \(f1 = 58\d"):
        prepare(load(f), two_dof_study(drive="ideal"))


def test_force_that_is_not_the_studys_chirp(tmp_path, good):
    other = Chirp(100, 1000, 0.3, 20000, 1.0, tail=0.05)
    sig = Signals(t=good.t, force=other.force(), channels=good.channels, fs=good.fs)
    f = csv(tmp_path, sig)
    m = prepare(load(f), two_dof_study())
    assert m.drive.kind == "sampled"
    assert m.sweep.f0 == pytest.approx(100, rel=0.02) and m.sweep.f1 == pytest.approx(
        1000, rel=0.02)
    assert any("f0 = 100" in note for note in m.notes), m.notes
    with pytest.raises(MeasurementError, match=r"channel 'force': the excitation is not the "
                                               r"study's \(f0 = 100\.?\d* differs"):
        prepare(load(f), two_dof_study(drive="ideal"))


def test_sweep_estimate_and_alignment(good):
    est = estimate_sweep(good.force, good.fs)
    assert est.kind == "log_chirp"
    # an exact sweep: the phase fit recovers its law far better than the 2 % bar
    assert est.f0 == pytest.approx(50, rel=2e-3) and est.f1 == pytest.approx(2000, rel=2e-3)
    assert est.duration == pytest.approx(0.3, rel=2e-3)
    d = 23  # samples of delay
    late = Signals(t=good.t, force=np.concatenate([np.zeros(d), good.force[:-d]]),
                   channels={"a1": np.concatenate([np.zeros(d), good.channels["a1"][:-d]])},
                   fs=good.fs)
    est = estimate_sweep(late.force, late.fs)
    assert est.t_start == pytest.approx(d / good.fs, abs=0.2 / good.fs)
    out = align_to_ideal(Measurement("x.csv", late), EX, est)
    assert out.meta["delay_s"] == pytest.approx(d / good.fs, abs=0.2 / good.fs)
    np.testing.assert_allclose(out.force[: len(good.force) - d],
                               good.force[: len(good.force) - d], atol=1e-9)
    # a different rate is resampled to the study's
    half = Signals(t=good.t[::2], force=good.force[::2],
                   channels={"a1": good.channels["a1"][::2]}, fs=good.fs / 2)
    meas = Measurement("y.csv", half)
    res = align_to_ideal(meas, EX, estimate_sweep(half.force, half.fs))
    assert res.fs == 20000 and len(res.force) == EX.n_samples
    assert any("resampled" in n for n in meas.notes)


def test_a_pre_trigger_longer_than_the_sweep_is_aligned_and_an_inverted_force_named(good):
    """The cross-correlation cut the record to the ideal sweep's length, so a sweep that
    starts later than that (here 0.5 s into a record of a 0.35 s chirp) had no lag to be
    found: a bogus negative delay, then the model compared with silence and a crash."""
    d = 10000  # 0.5 s at 20 kHz
    late = Signals(t=np.arange(len(good.t) + d) / good.fs,
                   force=np.concatenate([np.zeros(d), good.force]),
                   channels={"a1": np.concatenate([np.zeros(d), good.channels["a1"]])},
                   fs=good.fs)
    est = estimate_sweep(late.force, late.fs)
    out = align_to_ideal(Measurement("x.csv", late), EX, est)
    assert out.meta["delay_s"] == pytest.approx(0.5, abs=0.2 / good.fs)
    np.testing.assert_allclose(out.force, good.force[: EX.n_samples], atol=1e-9)
    flipped = Signals(t=good.t, force=-good.force, channels=good.channels, fs=good.fs)
    with pytest.raises(MeasurementError, match=r"channel 'force': .*sign inverted"):
        align_to_ideal(Measurement("x.csv", flipped), EX,
                       estimate_sweep(flipped.force, flipped.fs))


def test_uff58_roundtrip(tmp_path, good):
    import pyuff

    f = tmp_path / "m.uff"
    uff = pyuff.UFF(str(f))
    for name, y, unit in (("force", good.force, "N"), ("a1", good.channels["a1"], "m/s^2")):
        uff.write_sets(pyuff.prepare_58(
            func_type=1, id1=name, rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1, data=y,
            x=good.t, abscissa_spacing=1, abscissa_min=0.0, abscissa_inc=1 / good.fs,
            abscissa_spec_data_type=17, ordinate_spec_data_type=12 if name == "a1" else 13,
            orddenom_spec_data_type=13, ordinate_axis_units_lab=unit, binary=0), mode="add")
    m = load(f)
    assert m.fs == pytest.approx(good.fs, rel=1e-6)
    np.testing.assert_allclose(m.signals.channels["a1"], good.channels["a1"], rtol=1e-5,
                               atol=1e-9)
    np.testing.assert_allclose(m.signals.force, good.force, rtol=1e-5, atol=1e-9)


def test_sidecar_round_trips_any_string_and_refuses_null(tmp_path, good):
    """The sidecar goes through tomlkit (issue 26): a non-BMP character (written by the old
    json.dumps writer as an escaped surrogate pair that TOML rejects) and nested values come
    back as written, and load() reads the file; a None, which TOML cannot hold, is an error
    naming its key before anything is written."""
    import tomllib

    meta = {"note": "😀 Grüße", "effects": ["micro_slip@joint"], "rig": {"noise": 0.02}}
    f = csv(tmp_path, good, level=0.5, meta=meta)
    side = tomllib.loads(f.with_suffix(".toml").read_text(encoding="utf-8"))
    assert side == {"fs": pytest.approx(20000.0), "level": 0.5, **meta}
    assert load(f).level == 0.5
    for bad, where in (({"x": None}, r"meta\['x'\]"),
                       ({"effects": ["a", None]}, r"meta\['effects'\]\[1\]")):
        out = tmp_path / "null.csv"
        with pytest.raises(MeasurementError, match=rf"null\.toml: {where} is None, which TOML "
                                                   r"cannot hold"):
            csv(tmp_path, good, name="null.csv", meta=bad)
        assert not out.exists() and not out.with_suffix(".toml").exists()
    with pytest.raises(MeasurementError, match=r"meta\['level'\]: the sidecar's own key"):
        csv(tmp_path, good, name="own.csv", level=1.0, meta={"level": 2.0})


def test_a_velocity_channel_keeps_its_dimension(tmp_path, good):
    """A response is converted to the SI unit of its own dimension: the beam's laser
    velocity, written by ``sensfw simulate studies/bert.toml`` as ``Laser [m/s]``, was
    refused (converted to m/s^2); in mm/s it is scaled to m/s; an acceleration in g to
    m/s^2 as before."""
    v = good.channels["a1"]
    sig = Signals(t=good.t, force=good.force, channels={"Laser": v, "acc": v}, fs=good.fs,
                  units={"force": "V", "Laser": "m/s", "acc": "m/s^2"})
    f = csv(tmp_path, sig)
    m = load(f)
    assert m.signals.units == {"force": "V", "Laser": "m/s", "acc": "m/s^2"}
    g = tmp_path / "mm.csv"
    g.write_text(f.read_text().replace("Laser [m/s]", "Laser [mm/s]"))
    np.testing.assert_allclose(load(g).signals.channels["Laser"], 1e-3 * m.signals.channels[
        "Laser"], rtol=1e-9)


def test_a_channel_of_another_quantity_than_the_models_is_refused(tmp_path, good):
    """The 2-DOF model's a1 is an acceleration: the same record labelled m/s was compared
    as if it were one (80 dB off on the quick study, exit 0)."""
    f = csv(tmp_path, good)
    g = tmp_path / "v.csv"
    g.write_text(f.read_text().replace("a1 [m/s^2]", "a1 [m/s]"))
    with pytest.raises(MeasurementError, match=r"v\.csv, channel 'a1': recorded in m/s, but "
                                               r"the model two_dof's a1 is in m/s\^2"):
        prepare(load(g), two_dof_study())
    prepare(load(f), two_dof_study())  # the acceleration itself passes


def test_a_dead_sensor_is_named_and_channels_the_model_lacks_are_kept_as_they_are(
        tmp_path, good):
    dead = Signals(t=good.t, force=good.force, channels={"a1": np.zeros_like(good.t)},
                   fs=good.fs)
    with pytest.raises(MeasurementError, match=r"channel 'a1': the response is constant"):
        prepare(load(csv(tmp_path, dead, "dead.csv")), two_dof_study())
    # a torque in N m, a temperature held constant, a strain: no dimension of the model's,
    # read in their own units (SI where there is one) and neither converted nor checked
    sig = Signals(t=good.t, force=good.force, fs=good.fs,
                  channels={"a1": good.channels["a1"], "torque": 0.5 + 0 * good.t,
                            "temperature": 20.0 + 0 * good.t, "strain": 1e-6 + 0 * good.t},
                  units={"force": "N", "a1": "m/s^2", "torque": "N*cm", "temperature": "degC",
                         "strain": "m/m"})
    m = prepare(load(csv(tmp_path, sig, "extra.csv")), two_dof_study())
    assert m.signals.units["torque"] == "N*m"
    assert m.signals.channels["torque"][0] == pytest.approx(0.005)
    assert m.signals.channels["temperature"][0] == pytest.approx(20.0)


def test_a_record_sampled_slower_than_the_study_is_compared_on_its_own_band(tmp_path, good):
    """A 2-DOF record decimated to 4 kHz (scipy's anti-aliasing FIR): the model runs at the
    study's 20 kHz, the record is resampled to it, and the error figure takes the lines up
    to fs / 2.56 = 1562.5 Hz (the analyser's pass band), not the study's 2 kHz, where the
    record holds nothing. The model is the record's own: the error stays within the
    resampling's round trip (0.1 dB). Two periods of 50 Hz is the shortest record."""
    from scipy.signal import decimate

    from sensfw.measure.compare import compare_measurements
    from sensfw.runs import Runner, RunStore

    slow = Signals(t=good.t[::5], force=decimate(good.force, 5, ftype="fir"),
                   channels={"a1": decimate(good.channels["a1"], 5, ftype="fir")},
                   fs=good.fs / 5)
    study = two_dof_study()
    m = prepare(load(csv(tmp_path, slow, "slow.csv", level=1.0)), study)
    assert m.signals.fs == 20000 and any("fs / 2.56" in n for n in m.notes)
    # the study's sweep seen up to the record's band: the rig drove the whole sweep, so
    # the model is driven by the ideal one (the record, band-limited, would stop it early)
    assert isinstance(m.drive, Chirp), m.notes
    assert any("the record is the study's sweep" in n for n in m.notes)
    with Runner(RunStore(tmp_path / "runs"), backend="serial") as runner:
        c = compare_measurements(study, [m], runner).levels[0]
    assert c.error_band == pytest.approx((50.0, 1562.5))
    assert c.error_db < 0.1
    n = 700  # 35 ms of a 20 kHz record: less than two periods of 50 Hz (40 ms)
    short = Signals(t=good.t[:n], force=good.force[:n], channels={"a1": good.channels["a1"][:n]},
                    fs=good.fs)
    with pytest.raises(MeasurementError, match=r"channel 'time': the record is 0.035 s long"):
        prepare(load(csv(tmp_path, short, "short.csv")), study)


def test_a_sidecars_fs_and_level_may_carry_units_and_must_be_positive(tmp_path, good):
    f = csv(tmp_path, good)
    f.with_suffix(".toml").write_text('fs = "20 kHz"\nlevel = "100 mN"\n')
    m = load(f)
    assert m.level == pytest.approx(0.1) and m.fs == pytest.approx(20000)
    for text, match in (('level = -0.1\n', r"channel 'level': .* must be positive"),
                        ('fs = "fast"\n', r"channel 'fs': the sidecar's fs = 'fast' is not")):
        f.with_suffix(".toml").write_text(text)
        with pytest.raises(MeasurementError, match=match):
            load(f)


def test_csv_as_spreadsheets_write_it(tmp_path, good):
    """A byte-order mark (Excel's "CSV UTF-8"), quoted cells and capitalised Time / Force
    headers read as the plain file does (each refused before)."""
    f = csv(tmp_path, good)
    plain = load(f)
    rows = f.read_text().splitlines()
    head = rows[0].replace("time", "Time").replace("force", "FORCE")
    quoted = [",".join(f'"{c}"' for c in r.split(",")) for r in [head, *rows[1:]]]
    g = tmp_path / "excel.csv"
    g.write_text("\n".join(quoted) + "\n", encoding="utf-8-sig")
    m = load(g)
    assert m.fs == pytest.approx(plain.fs)
    np.testing.assert_array_equal(m.signals.channels["a1"], plain.signals.channels["a1"])
    np.testing.assert_array_equal(m.signals.force, plain.signals.force)


def test_a_slow_record_is_calibrated_on_its_own_band_as_compare_compares_it(tmp_path, good):
    """The residuals of calibrate/diagnose/augment cut a slow record's band as ``compare``
    does: the 4 kHz record of the test above enters with bands up to fs / 2.56 = 1562.5 Hz
    only. Above, the record holds its anti-aliasing filter's stop band, and the model
    (the record's own) would be charged for it."""
    from scipy.signal import decimate

    from sensfw.measure.residuals import Residuals
    from sensfw.runs import Runner, RunStore

    slow = Signals(t=good.t[::5], force=decimate(good.force, 5, ftype="fir"),
                   channels={"a1": decimate(good.channels["a1"], 5, ftype="fir")},
                   fs=good.fs / 5)
    study = two_dof_study()
    m = prepare(load(csv(tmp_path, slow, "slow.csv", level=1.0)), study)
    with Runner(RunStore(tmp_path / "runs"), backend="serial") as runner:
        res = Residuals(study, [m], runner, study.calibration_space(["k1"]))
        _, comps = res.nominal()
    centres = [f for b in res.entries.bands for f in b]
    assert centres and max(centres) < 1562.5
    w = res.weighted(comps)
    # the record's own model: chi2 / n ~ 1 for a correct model; 4 allows the resampling's
    # round trip near the band's top
    assert float(np.mean(w**2)) < 4.0


def test_an_error_band_with_no_line_of_the_record_is_refused_before_any_run(tmp_path, good):
    """``--error-band 6000,8000`` on a study swept to 2 kHz: an error naming the record
    and the band, raised before the model runs (the store stays empty)."""
    from sensfw.errors import SensfwError
    from sensfw.measure.compare import compare_measurements
    from sensfw.runs import Runner, RunStore

    study = two_dof_study()
    m = prepare(load(csv(tmp_path, good, "m.csv", level=1.0)), study)
    store = RunStore(tmp_path / "runs")
    with Runner(store, backend="serial") as runner, \
            pytest.raises(SensfwError, match=r"m.csv: the error band 6000-8000 Hz holds no line"):
        compare_measurements(study, [m], runner, error_band=(6000.0, 8000.0))
    assert not list((tmp_path / "runs").rglob("*.npz")) and not list(
        (tmp_path / "runs").rglob("*.json"))


def test_a_drive_longer_than_the_studys_excitation_gets_a_longer_timeout():
    """The study's solver.timeout is for its own 0.35 s excitation: an FRF-only record's
    stepped sine of 50 lines x 0.2 s (10 s of signal, 28.6 times longer) gets 28.6 times
    the timeout (the BERT beam's 161-line FRF.mat ran into the study's 300 s), a shorter
    drive the study's own."""
    from sensfw.evaluate import variant_spec
    from sensfw.excitation import SteppedSine
    from sensfw.study import Study

    data = two_dof_study().spec.model_dump(mode="json", exclude_none=True)
    data["solver"] = {**data.get("solver", {}), "timeout": "2 s"}
    study = Study.from_dict(data)
    long = SteppedSine.at(np.linspace(60.0, 1500.0, 50), 0.2, 20000.0, 1.0)
    assert variant_spec(study, {}, long).timeout == pytest.approx(2.0 * 10.0 / 0.35)
    short = SteppedSine.at([100.0, 200.0], 0.1, 20000.0, 1.0)
    assert variant_spec(study, {}, short).timeout == 2.0
    assert variant_spec(study, {}, long).key() == variant_spec(two_dof_study(), {}, long).key()


def test_a_slow_records_noise_and_harmonics_are_read_where_it_holds_lines(good):
    """The 2-DOF response with a quadratic distortion and white noise, decimated to 4 kHz
    and resampled to the study's 20 kHz as ``prepare`` does (``meta["recorded_fs"]``).

    - Noise: over every bin of the resampled record the 5 % quantile sat in the empty stop
      band above 2 kHz (nearly 0: a probe found "noise alone" 0.005 dB for 1.1 dB); over the
      bins below fs / 2.56 it is the white noise of the same density at 20 kHz, the noise
      added. Within 40 % (the local fit's residual on a linear record: 10 % above at the
      study's rate, 30 % at the slow rate, where no pure-noise bins lie above the sweep).
    - Harmonics: both sides of a comparison take the orders below the record's 1562.5 Hz;
      there the slow record's order amplitudes are the full-rate record's to 1 % (on the
      quick study a 5 kHz copy of a 20 kHz record read over the whole sweep, as before, put
      the model's H2 and H3 20.6 and 34.6 dB above the record's)."""
    from scipy.signal import decimate

    from sensfw.measure.bands import noise_sigma, usable_limit
    from sensfw.measure.checks import resample
    from sensfw.measure.distortion import harmonics

    a = good.channels["a1"]
    sigma = 0.01 * float(np.std(a))
    rng = np.random.default_rng(3)

    def records(k):
        y = a + k * a**2 / np.max(np.abs(a)) + sigma * rng.standard_normal(len(a))
        fast = Signals(t=good.t, force=good.force, channels={"a1": y}, fs=good.fs,
                       f_inst=EX.f_inst(good.t), sweep_end=EX.sweep_end)
        slow = resample(Signals(t=good.t[::5], force=decimate(good.force, 5, ftype="fir"),
                                channels={"a1": decimate(y, 5, ftype="fir")},
                                fs=good.fs / 5), good.fs)
        n = min(len(slow.force), len(good.t))
        back = Signals(t=good.t[:n], force=slow.force[:n], channels={"a1": slow.channels["a1"][:n]},
                       fs=good.fs, f_inst=EX.f_inst(good.t[:n]), meta=slow.meta,
                       sweep_end=EX.sweep_end)
        return fast, back

    fast, back = records(0.0)
    assert back.meta["recorded_fs"] == pytest.approx(4000.0)
    assert usable_limit(back) == pytest.approx(1562.5) and usable_limit(fast) == 10000.0
    assert sigma <= noise_sigma(back, "a1") <= 1.4 * sigma
    assert sigma <= noise_sigma(fast, "a1") <= 1.4 * sigma
    fast, back = records(0.05)
    top = usable_limit(back)
    hf, hb = harmonics(fast, "a1", f_max=top), harmonics(back, "a1", f_max=top)
    for k in (1, 2, 3):
        assert hb[k] == pytest.approx(hf[k], rel=0.01), k


def test_a_record_too_slow_for_the_studys_band_names_its_time_channel(tmp_path, good):
    """A time column in ms read as s (fs 20 Hz) or a 100 Hz logger: no line of the study's
    50-2000 Hz; an error naming the time channel (it was scipy's 'Wn[0] must be less than
    Wn[1]' from the sweep estimate's filter)."""
    study = two_dof_study()
    n = len(good.t)
    ms = Signals(t=good.t * 1e3, force=good.force, channels={"a1": good.channels["a1"]},
                 fs=good.fs / 1e3)
    with pytest.raises(MeasurementError, match=r"ms\.csv, channel 'time': sampled at 20 Hz.*"
                                               r"'time \[ms\]'"):
        prepare(load(csv(tmp_path, ms, "ms.csv")), study)
    slow = Signals(t=good.t[:n:200], force=good.force[::200],
                   channels={"a1": good.channels["a1"][::200]}, fs=good.fs / 200)
    with pytest.raises(MeasurementError, match=r"channel 'time': sampled at 100 Hz"):
        prepare(load(csv(tmp_path, slow, "s100.csv")), study)


def test_uff58_abscissa_units_are_read(tmp_path, good):
    """A UFF58 time record whose abscissa is labelled ms (values in ms) reads at 20 kHz,
    not 20 Hz; an abscissa label of no time unit is refused naming the channel."""
    import pyuff

    def write(path, label, scale):
        uff = pyuff.UFF(str(path))
        for name, y, unit in (("force", good.force, "N"), ("a1", good.channels["a1"], "m/s^2")):
            uff.write_sets(pyuff.prepare_58(
                func_type=1, id1=name, rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1, data=y,
                x=good.t * scale, abscissa_spacing=1, abscissa_min=0.0,
                abscissa_inc=scale / good.fs, abscissa_spec_data_type=17,
                ordinate_spec_data_type=12 if name == "a1" else 13, orddenom_spec_data_type=13,
                ordinate_axis_units_lab=unit, abscissa_axis_units_lab=label, binary=0),
                mode="add")
        return path

    for label in ("ms", "Time (ms)", "time [ms]"):
        m = load(write(tmp_path / f"{label[:2]}{len(label)}.uff", label, 1e3))
        assert m.fs == pytest.approx(good.fs, rel=1e-6), label
    assert load(write(tmp_path / "s.uff", "s", 1.0)).fs == pytest.approx(good.fs, rel=1e-6)
    with pytest.raises(MeasurementError, match=r"channel 'force': abscissa in 'Hz'"):
        load(write(tmp_path / "hz.uff", "Hz", 1.0))


def test_what_a_csv_says_against_itself_or_the_record_is_named(tmp_path, good):
    """A sidecar's level three times the record's sweep amplitude drives the ideal sweep
    three times too hard: a warning names both (the LMS reader's 5 % rule); sidecar units
    that contradict the header are refused naming the channel (the sidecar won, silently:
    19.8 dB on the quick study's own record); a record exported at half its rate sweeps
    25-1000 Hz, less than half of the study's band: with ``drive = "measured"`` it is
    driven as it is, with a warning."""
    study = two_dof_study()
    f = csv(tmp_path, good, "lv.csv")
    f.with_suffix(".toml").write_text("level = 3.0\n")
    m = prepare(load(f), study)
    assert m.drive.amplitude == 3.0
    assert any("declared level 3 N is not the record's sweep amplitude, 1" in w
               for w in m.warnings), m.warnings
    assert not prepare(load(csv(tmp_path, good, "ok.csv", level=1.0)), study).warnings
    f = csv(tmp_path, good, "u.csv")
    f.with_suffix(".toml").write_text('[units]\na1 = "g"\n')
    with pytest.raises(MeasurementError, match=r"u\.csv, channel 'a1': the header says "
                                               r"'m/s\^2', the sidecar u\.toml says 'g'"):
        load(f)
    half = Signals(t=good.t * 2, force=good.force, channels={"a1": good.channels["a1"]},
                   fs=good.fs / 2)
    m = prepare(load(csv(tmp_path, half, "half.csv")), two_dof_study(drive="measured"))
    assert any("less than half of the study's band 50-2000 Hz" in w for w in m.warnings)


def test_common_csv_shapes_are_read_or_named(tmp_path, good):
    """Tab separators and a separator at the end of every line are read; a file without a
    header row, decimal commas and a constant force are refused saying what they are (they
    gave 'duplicate column names', a NaN in the time column and 'clipped')."""
    f = csv(tmp_path, good, "c.csv")
    rows = f.read_text().splitlines()
    ref = load(f)
    tab = tmp_path / "tab.csv"
    tab.write_text("\n".join(r.replace(",", "\t") for r in rows) + "\n")
    trailing = tmp_path / "trail.csv"
    trailing.write_text("\n".join(r + "," for r in rows) + "\n")
    for g in (tab, trailing):
        m = load(g)
        np.testing.assert_array_equal(m.signals.channels["a1"], ref.signals.channels["a1"])
    bare = tmp_path / "bare.csv"
    bare.write_text("\n".join(rows[1:]) + "\n")
    with pytest.raises(MeasurementError, match="the first row holds numbers: no header row"):
        load(bare)
    comma = tmp_path / "comma.csv"
    comma.write_text("\n".join([rows[0].replace(",", ";")]
                               + [";".join(v.replace(".", ",") for v in r.split(","))
                                  for r in rows[1:]]) + "\n")
    with pytest.raises(MeasurementError, match="decimal commas"):
        load(comma)
    flat = Signals(t=good.t, force=np.full_like(good.force, 0.05), channels=dict(good.channels),
                   fs=good.fs)
    with pytest.raises(MeasurementError, match=r"channel 'force': the excitation is constant "
                                               r"\(0\.05\)"):
        prepare(load(csv(tmp_path, flat, "flat.csv")), two_dof_study())


def test_a_sidecar_unit_for_a_column_the_file_lacks_is_named(tmp_path, good):
    """A sidecar's ``[units]`` entry for a misspelt column was dropped without a word and
    the column read in the default unit: 'acc1 = "g"' for the column a1 left a1 in m/s^2,
    9.81 times too small against the g it was recorded in. It is refused naming the entry
    and the column meant; ``Force``/``TIME`` keys read as the header's do."""
    f = csv(tmp_path, good, "side.csv")
    text = f.read_text().replace("force [N]", "force").replace("a1 [m/s^2]", "a1")
    f.write_text(text)
    f.with_suffix(".toml").write_text('[units]\nacc1 = "g"\n')
    with pytest.raises(MeasurementError, match=r"side\.csv, channel 'acc1': the sidecar "
                                               r"gives the unit 'g' for a column the file "
                                               r"does not have .*did you mean 'a1'\?"):
        load(f)
    f.with_suffix(".toml").write_text('[units]\na1 = "g"\nForce = "kN"\n')
    m = load(f)
    np.testing.assert_allclose(m.signals.channels["a1"], good.channels["a1"] * 9.80665,
                               rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(m.signals.force, good.force * 1e3, rtol=1e-8, atol=1e-12)
    assert m.signals.units["force"] == "N"


def test_a_time_column_written_to_fewer_decimals_is_read_as_the_uniform_grid(tmp_path):
    """A 12.8 kHz record whose time column is written to six decimals (Excel's 0.000000,
    LabVIEW's %.6f) has steps of 7.8e-5 and 7.9e-5 s: it was refused as 'non-uniform
    sampling', with no way to load it (a sidecar's fs did not help). It is the uniform grid
    rounded to 1e-6 s: fs comes from the first and last time, within 1e-6 s / span of the
    true rate (or exactly the sidecar's fs), the values unchanged; a dropped sample in
    such a column is still refused."""
    fs, n = 12800.0, 4096
    t = np.arange(n) / fs
    force = np.sin(2 * np.pi * (60 * t + 400 * t**2))
    a1 = 3.0 * np.cos(2 * np.pi * 90 * t)
    f = tmp_path / "r.csv"

    def write(times, force, a1):
        rows = [f"{x:.6f},{y:.10g},{z:.10g}" for x, y, z in zip(times, force, a1, strict=True)]
        f.write_text("time [s],force [N],a1 [m/s^2]\n" + "\n".join(rows) + "\n")

    write(t, force, a1)
    m = load(f)
    span = t[-1] - t[0]
    assert m.fs == pytest.approx(fs, rel=1e-6 / span)
    assert len(m.signals.t) == n and m.signals.t[-1] == pytest.approx(span, abs=1e-6)
    np.testing.assert_allclose(np.diff(m.signals.t), 1 / m.fs, rtol=1e-9)  # the grid
    np.testing.assert_allclose(m.signals.channels["a1"], a1, rtol=1e-9, atol=1e-12)
    assert any("written to 1e-06 s" in note for note in m.notes), m.notes
    f.with_suffix(".toml").write_text("fs = 12800.0\n")
    assert load(f).fs == 12800.0
    f.with_suffix(".toml").unlink()
    keep = np.arange(n) != 2000  # one sample lost
    write(t[keep], force[keep], a1[keep])
    with pytest.raises(MeasurementError, match=r"r\.csv, channel 'time': non-uniform"):
        load(f)


def test_a_record_that_ends_before_the_study_tail_is_named(tmp_path, good):
    """The ideal drive cuts the record to the study's sweep and tail and pads what is
    missing with zeros: a record that stops 1 ms after the sweep lost the 0.05 s ring-down
    the model computes (measured on this 2-DOF model: up to 1.4 dB FRF bias near the
    sweep's end, 0.14 dB RMS over 60-1900 Hz), without a word. A warning now names the
    missing time; the whole record has none."""
    kept = round(EX.duration * EX.fs) + 20
    cut = Signals(t=good.t[:kept], force=good.force[:kept],
                  channels={"a1": good.channels["a1"][:kept]}, fs=good.fs)
    m = prepare(load(csv(tmp_path, cut, "cut.csv", level=1.0)), two_dof_study())
    missing = (EX.n_samples - kept) / EX.fs  # 0.049 s (no delay in this record)
    assert any(f"the record ends {missing:.4g} s before the study's" in w
               for w in m.warnings), m.warnings
    assert len(m.signals.t) == EX.n_samples and not m.signals.channels["a1"][kept:].any()
    assert not prepare(load(csv(tmp_path, good, "whole.csv", level=1.0)),
                       two_dof_study()).warnings
