"""The compare report a rig engineer reads at a glance (issue 27, item 6): one error figure
per record, defined once; a random record's level as its RMS in the band; a section with
nothing to show says so in one line instead of drawing axes."""

import re

import numpy as np
import pytest

from sensfw.measure.compare import compare_measurements
from sensfw.measure.io import write_csv
from sensfw.measure.prepared import load_measurements
from sensfw.measure.synthetic import Rig, synthesize
from sensfw.report.measure import write_compare_report
from sensfw.runs import Runner, RunStore
from sensfw.study import Study


def two_dof(kind: str) -> Study:
    return Study.from_dict({
        "study": {"name": "rig"}, "model": {"name": "two_dof", "output": "a1"},
        "excitation": {"kind": kind, "f0": "50 Hz", "f1": "2 kHz", "duration": "0.25 s",
                       "fs": "5 kHz", "amplitude": "0.2 N", "tail": "0.05 s"},
        "stages": [{"name": "s", "design": "oat", "scorers": [{"name": "rms"}]}]})


@pytest.fixture(scope="module")
def runner(tmp_path_factory):
    with Runner(RunStore(tmp_path_factory.mktemp("runs")), backend="serial") as r:
        yield r


def test_a_random_record_reads_at_a_glance(tmp_path, runner):
    """A random record whose file states the rig's setting 0.3 (as the BERT folders do):
    its level is reported as its RMS in the study's band, computed independently here by
    Parseval; one FRF error per record, in the summary and in its heading, the same number;
    no harmonics, order spectra or jumps drawn, each said in one line."""
    study = two_dof("random")
    sig, _ = synthesize(study, rig=Rig(noise=0.01, seed=2))
    f = write_csv(tmp_path / "random.csv", sig, level=0.3)
    (m,) = load_measurements(study, [str(f)])
    X = np.fft.rfft(sig.force - sig.force.mean())
    fr = np.fft.rfftfreq(len(sig.force), 1 / sig.fs)
    sel = (fr >= 50) & (fr <= 2000)
    rms = np.sqrt(2 * np.sum(np.abs(X[sel]) ** 2)) / len(sig.force)
    cmp = compare_measurements(study, [m], runner)
    (c,) = cmp.levels
    assert c.kind == "random" and c.level_rms == pytest.approx(rms, rel=1e-6)
    assert c.level_text == f"random, RMS {rms:.3g} N in 50-2000 Hz"  # 0.135 N, not "0.3"
    assert any("the sidecar" not in n and "RMS" in n for n in m.notes)
    html = write_compare_report(study, cmp, tmp_path / "r.html").read_text()
    assert html.count("FRF error: the RMS") == 1  # defined once
    error = f"{c.error_db:.2f}"
    assert re.search(rf"<td>{re.escape(error)}</td>", html)  # the summary
    assert f"FRF error {error} dB</h3>" in html  # the record's heading: the same figure
    assert "Harmonics: none for a random record" in html
    assert "THD measured / model" not in html  # a summary column empty for every record
    assert re.search(r"Order spectra</h2>\s*<p>None: no record holds the time data of a "
                     r"sweep", html)
    assert "Up and down sweeps" not in html  # no stepped record: no such section
    assert "One level only: nothing to compare across levels." in html
    # drawn: the FRFs, the band errors, the spectrograms; nothing else
    assert html.count("<img") == 3


def test_a_sweep_record_keeps_its_sections(tmp_path, runner):
    """A log sweep at two levels: order spectra and the amplitude dependence are drawn, the
    level is the sine's amplitude."""
    study = two_dof("log_chirp")
    files = []
    for level in (0.1, 0.3):
        sig, info = synthesize(study, amplitude=level, rig=Rig(noise=0.01, seed=3))
        files.append(write_csv(tmp_path / f"s{level}.csv", sig, level=info["amplitude"]))
    cmp = compare_measurements(study, load_measurements(study, [str(x) for x in files]),
                               runner)
    assert [c.level_text for c in cmp.levels] == ["log sweep 0.1 N", "log sweep 0.3 N"]
    html = write_compare_report(study, cmp, tmp_path / "s.html").read_text()
    assert re.search(r"Order spectra</h2>\s*<figure>", html)
    assert "One level only" not in html
    # the summary names which resonance it shows, printed as the record's own table does
    # (the FRF's lines are Hz apart: 1592.59 Hz said two digits too many)
    r = next(r for r in cmp.levels[0].resonances if r["measured_hz"] and r["model_hz"])
    assert "strongest resonance, measured (Hz)" in html
    assert "<th>THD measured / model (%)</th>" in html
    assert not re.search(r"<td>\d+\.\d\d</td><td>\d+\.\d\d</td><td>[\d.]+ / ", html)
    assert html.count(f"<td>{r['measured_hz']:.4g}</td>") >= 1
    # amplitudes and DC offsets carry the compared channel's unit
    unit = cmp.levels[0].output_unit
    assert unit and f"<th>model P_k ({unit})</th>" in html
    assert f"<th>DC measured ({unit})</th>" in html
    # how the model was driven: the estimated level and offset with the force's unit
    assert re.search(r"level 0\.3\d* N, drift \+-\d+%, offset -?[\d.e-]+ N\)", html)


def test_resonances_pair_in_order_of_frequency():
    """The quick model against its flexible-mode record at 0.05 N: measured 3863 and 4463 Hz,
    model 3519 and 4189 Hz. Nearest-first pairing gave 3863 <-> 4189 and then 4463 <-> 3519
    (-21 %, crossed), which the report's summary showed as the record's resonance while the
    amplitude table paired them in order."""
    from sensfw.measure.resonance import match_resonances

    peaks = lambda *f: [{"frequency": x, "damping_ratio": 0.01} for x in f]  # noqa: E731
    rows = match_resonances(peaks(1504.0, 3519.0, 4189.0),
                            peaks(1593.0, 1726.0, 1919.0, 3863.0, 4463.0))
    pairs = [(r["measured_hz"], r["model_hz"]) for r in rows]
    assert pairs == [(1593.0, 1504.0), (1726.0, None), (1919.0, None), (3863.0, 3519.0),
                     (4463.0, 4189.0)]
    # a lone model resonance goes to the nearer of two measured ones, either order
    assert [(r["measured_hz"], r["model_hz"]) for r in
            match_resonances(peaks(105.0), peaks(100.0, 110.0))] == [(100.0, None),
                                                                     (110.0, 105.0)]


def test_the_band_error_legend_shows_each_record_s_colour():
    """Its entries took the colour of each record's first bar, grey where the measurement
    cannot speak for the lowest band (the quick study's records): three grey entries."""
    from types import SimpleNamespace

    from matplotlib.colors import to_hex

    from sensfw.report.measure_figures import band_errors

    bands = [{"centre_hz": c, "mean_db": 1.0, "noise_db": 0.5} for c in (63.1, 100.0, 1000.0)]
    records = [SimpleNamespace(bands=bands, used_bands=bands[1:], level=x, unit="N",
                               level_text=f"sweep {x} N")
               for x in (0.05, 0.1)]
    legend = band_errors(records).axes[0].get_legend()
    got = {t.get_text(): to_hex(h.get_facecolor())
           for t, h in zip(legend.get_texts(), legend.legend_handles, strict=True)}
    assert got == {"sweep 0.05 N": "#1f77b4", "sweep 0.1 N": "#ff7f0e",
                   "cannot speak for": "#cccccc"}


def test_a_missing_start_from_file_is_named_with_what_to_give(tmp_path):
    """`augment --start-from` a mistyped path printed Python's '[Errno 2] No such file or
    directory' inside its message."""
    from sensfw.errors import SensfwError
    from sensfw.measure.augment import diagnosed_start

    with pytest.raises(SensfwError) as info:
        diagnosed_start(tmp_path / "diagnse.json", "flexible_mode")
    assert "--start-from" in str(info.value) and "no such file" in str(info.value)
    assert "(DIR/diagnose.json)" in str(info.value) and "Errno" not in str(info.value)


def test_the_model_s_own_scatter_is_printed_to_the_hundredth_of_a_percent():
    """Twin runs that differ by round-off gave cells of 1.538e-13 and 4.787e-10 (%) beside
    0 in the amplitude table; the criterion is 0.5 %."""
    from sensfw.report.measure import amplitude_frames

    def level(x, scatter):
        return {"level": x, "measured_hz": 1594.0, "model_hz": 1506.0, "shift_pct": 5.7,
                "measured_damping": 0.005, "model_damping": 0.0045, "damping_ratio": 1.2,
                "method": "mode fit", "model_scatter_pct": scatter}

    amplitude = {"table": {"harmonics": [], "resonances": [
        {"id": "R3", "kind": "paired",
         "levels": [level(0.05, 4.787e-10), level(0.1, 1.234), level(0.2, float("inf"))]}]}}
    res, _ = amplitude_frames(amplitude)
    assert list(res["model's own scatter %"]) == ["0.00", "1.23", "a twin has none"]
