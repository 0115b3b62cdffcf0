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
