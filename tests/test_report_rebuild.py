"""`sensfw report DIR` rebuilds a study's report from its output folder without simulating
(issue 12, item 5)."""

import json
import re
import shutil

import pytest

import sensfw.runs
import sensfw.runs.executor
import sensfw.runs.spec
from sensfw.errors import SensfwError
from sensfw.pipeline import load_result, results_json
from sensfw.report.study import write_study_report

pytestmark = pytest.mark.slow  # uses the quick study's session fixture (simulations)

IMG = re.compile(r'src="data:image/png;base64,[^"]*"')


def text_of(html):
    """The report without its embedded images (titles, captions, tables, notes)."""
    return IMG.sub('src="IMG"', html)


def sections(html):
    return re.findall(r"<h[23]>(.*?)</h[23]>", html)


@pytest.fixture
def folder(quick, tmp_path):
    """A copy of the quick study's output folder (the session fixture stays untouched)."""
    out, _ = quick
    dst = tmp_path / "quick"
    shutil.copytree(out, dst)
    return dst


@pytest.fixture
def no_simulation(monkeypatch):
    def refuse(*args, **kwargs):
        raise AssertionError("a simulation was started")

    monkeypatch.setattr(sensfw.runs.spec, "execute", refuse)
    monkeypatch.setattr(sensfw.runs.executor, "execute", refuse)
    monkeypatch.setattr(sensfw.runs.executor, "run", refuse)
    monkeypatch.setattr(sensfw.runs.Runner, "run", refuse)


def test_report_is_rebuilt_from_the_folder_without_simulating(folder, no_simulation):
    original = (folder / "report.html").read_text()
    before = json.loads((folder / "results.json").read_text())
    assert (folder / "study.toml").exists()  # `sensfw run` keeps the study with its results
    (folder / "report.html").unlink()
    result = load_result(folder)
    write_study_report(result, folder / "report.html")
    rebuilt = (folder / "report.html").read_text()
    # the same sections with the same R²adj, Q², F and n in their titles
    assert sections(rebuilt) == sections(original)
    assert any("R²adj=" in s for s in sections(rebuilt))
    # and the same text everywhere else (tables, notes, captions), the same figures
    assert text_of(rebuilt) == text_of(original)
    assert len(IMG.findall(rebuilt)) == len(IMG.findall(original)) >= 6
    # the rebuilt result is the result: results.json would be written identically
    assert results_json(result)["stages"] == before["stages"]


def test_sensfw_report_command(folder, cli):
    (folder / "report.html").unlink()
    store = sorted((folder / "runs").glob("*.json"))
    proc = cli("report", folder)
    assert proc.returncode == 0, proc.stderr
    assert "no simulation" in proc.stdout
    assert "sensfw study report" in (folder / "report.html").read_text()
    assert sorted((folder / "runs").glob("*.json")) == store  # nothing added


def test_a_run_missing_from_the_store_is_a_clear_error(folder, no_simulation):
    data = json.loads((folder / "results.json").read_text())
    key = data["stages"][1]["runs"][0]["key"]
    (folder / "runs" / f"{key}.json").unlink()
    with pytest.raises(SensfwError, match=f"run {key} is not in the run store"):
        load_result(folder)


def test_a_scorer_changed_in_the_study_file_is_scored_again(folder, no_simulation):
    """The screen's band narrowed to 50-300 Hz in DIR/study.toml under the same label: the
    rebuild showed the stored 50-5000 Hz scores. Now results.json says what each score
    is, and a label whose scorer changed is scored again from the stored runs; the
    unchanged DoE scores are reused as stored."""
    before = json.loads((folder / "results.json").read_text())
    screen = before["stages"][0]
    assert screen["scorers"]["frf_scalar"]["band"] == [50.0, 5000.0]
    text = (folder / "study.toml").read_text()
    assert "band = [50.0, 5000.0]" in text
    (folder / "study.toml").write_text(text.replace("band = [50.0, 5000.0]",
                                                    "band = [50.0, 300.0]", 1))
    result = load_result(folder)
    new = results_json(result)["stages"]
    assert new[0]["scorers"]["frf_scalar"]["band"] == [50.0, 300.0]
    assert new[0]["scores"]["frf_scalar"] != screen["scores"]["frf_scalar"]
    # the rebuild is what a fresh run of the edited study gives: its scores are those of
    # the scorer as the file now has it, on the same stored runs
    from sensfw.scorers import make_scorer
    from sensfw.study import Study

    study = Study.load(folder / "study.toml")
    sc = study.stages[0].scorers[0]
    scorer = make_scorer(sc.name, channel=sc.channel or study.output, **sc.options())
    ref = sensfw.runs.RunStore(folder / "runs").load(screen["reference_key"]).signals
    run = screen["runs"][1]
    got = scorer.score(sensfw.runs.RunStore(folder / "runs").load(run["key"]).signals, ref)
    assert new[0]["scores"]["frf_scalar"][run["label"]] == pytest.approx(
        next(iter(got.values())), rel=1e-12)


def test_a_spectrogram_is_titled_with_the_values_its_run_ran_at():
    """Fig. 11's two panels were titled 'run ff:1' and 'run ff:9' alone: which corner of the
    design each is was nowhere on the page."""
    from types import SimpleNamespace

    import pandas as pd

    from sensfw.report.study import _run_title

    var = lambda name, unit: SimpleNamespace(name=name, unit=unit)  # noqa: E731
    stage = SimpleNamespace(
        space=SimpleNamespace(variables=(var("slide_stiffness", "N/mm"), var("ratio", ""))),
        table=pd.DataFrame({"slide_stiffness": [70500.0], "ratio": [0.5]}, index=["ff:1"]))
    assert _run_title(stage, "ff:1") == "run ff:1\nslide_stiffness = 7.05e+04 N/mm\nratio = 0.5"


def test_a_folder_without_results_is_named_with_what_to_do(tmp_path):
    """`sensfw report` on a mistyped folder printed Python's '[Errno 2] No such file or
    directory' inside its message."""
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "sensfw", "report", str(tmp_path / "oot")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "oot: no results.json, not the output folder of a finished `sensfw run`" \
        in proc.stderr.replace("\n", " ")
    assert "Errno" not in proc.stderr and "Traceback" not in proc.stderr
