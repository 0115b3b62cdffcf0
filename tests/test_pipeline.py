"""The paper's pipeline end to end on studies/quick.toml (issue 4)."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]
QUICK = ROOT / "studies" / "quick.toml"


def stages(path):
    data = json.loads(Path(path).read_text())
    return data, {s["name"]: s for s in data["stages"]}


@pytest.mark.slow
def test_quick_study_runs_the_three_steps(quick):
    out, _ = quick
    data, st = stages(out / "results.json")
    k = len(st["screen"]["variables"])
    assert st["screen"]["n_runs"] == 2 * k + 1
    sel = st["screen"]["selected"]
    assert 1 <= len(sel) <= 2 and set(sel) <= set(st["screen"]["variables"])
    assert set(st["screen"]["sensitivity"]) == set(st["screen"]["variables"])
    m = len(sel)
    assert st["doe"]["variables"] == sel
    assert st["doe"]["n_runs"] == 3**m
    assert set(st["doe"]["regression"]) == {"P1", "P2", "THD"}
    for reg in st["doe"]["regression"].values():
        assert len(reg["coefficients"]) == 1 + 2 * m + m * (m - 1) // 2
        assert reg["n_obs"] == 3**m
        for key in ("r2", "r2_adj", "q2", "f_stat", "f_pvalue"):
            assert key in reg
    # runs are counted once per unique key (the OAT nominal is also the FRF reference)
    keys = {r["key"] for s in data["stages"] for r in s["runs"]}
    assert data["runs"]["total"] == len(keys) and data["runs"]["failed"] == 0
    html = (out / "report.html").read_text()
    assert html.count("data:image/png;base64") >= 6  # Figs. 7-11 analogues


@pytest.mark.slow
def test_rerun_computes_nothing_and_gives_identical_results(quick, cli, tmp_path):
    out = tmp_path / "rerun"  # a copy: the session's folder stays as `sensfw run` left it
    shutil.copytree(quick[0], out)
    before = json.loads((out / "results.json").read_text())
    proc = cli("run", QUICK, "--out", out, "--no-progress", "--no-report")
    assert proc.returncode == 0, proc.stderr
    after = json.loads((out / "results.json").read_text())
    assert after["runs"]["new"] == 0
    assert after["runs"]["cached"] == before["runs"]["total"]
    assert after["stages"] == before["stages"]


def _running_quick(out, at_least: int):
    """``sensfw run`` of the quick study into ``out`` on 2 workers, in a session of its own,
    returned once ``at_least`` runs are stored (or after 120 s): (process, run store)."""
    proc = subprocess.Popen([sys.executable, "-m", "sensfw", "run", str(QUICK), "--out",
                             str(out), "--workers", "2", "--no-progress"], cwd=ROOT,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    store = out / "runs"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        if store.exists() and len(list(store.glob("*.json"))) >= at_least:
            break
        time.sleep(0.05)
    return proc, store


@pytest.mark.slow
def test_killed_run_resumes_with_only_the_missing_runs(quick, cli, tmp_path):
    ref, _ = quick
    out = tmp_path / "killed"
    proc, store = _running_quick(out, at_least=6)
    os.killpg(proc.pid, signal.SIGKILL)  # the CLI and its workers, at once
    proc.wait()
    done = len(list(store.glob("*.json")))
    assert done >= 6
    again = cli("run", QUICK, "--out", out, "--no-progress", "--no-report")
    assert again.returncode == 0, again.stderr
    data, _ = stages(out / "results.json")
    assert data["runs"]["cached"] >= done - 2  # a record may have been torn by the kill
    assert data["runs"]["new"] == data["runs"]["total"] - data["runs"]["cached"]
    assert data["runs"]["new"] < data["runs"]["total"]
    reference = json.loads((ref / "results.json").read_text())
    assert data["stages"] == reference["stages"]


FAULTY = """
[study]
name = "faulty"
[model]
name = "sensfw_test_models:FaultInjection"
options = {{ model = "two_dof", diverge = {{ parameter = "k1", above = 7000.0 }} }}
output = "a1"
[excitation]
f0 = "50 Hz"
f1 = "2 kHz"
duration = "0.3 s"
fs = "20 kHz"
amplitude = "1 N"
tail = "0.1 s"
[execution]
backend = "{backend}"
[[stages]]
name = "screen"
design = "oat"
scorers = [{{ name = "frf_db_rms", band = [60.0, 1900.0] }}]
select = {{ threshold = 0.1, max_variables = 2 }}
[[stages]]
name = "doe"
design = "full_factorial"
variables = "selected:screen"
scorers = [{{ name = "rms" }}]
surrogates = ["eq18"]
"""


@pytest.mark.slow  # real simulations through the CLI or a worker pool
def test_a_diverging_run_is_recorded_and_the_study_completes(cli, tmp_path):
    study = tmp_path / "faulty.toml"
    study.write_text(FAULTY.format(backend="serial"))
    proc = cli("run", study, "--out", tmp_path / "o", "--no-progress")
    assert proc.returncode == 0, proc.stderr
    data, st = stages(tmp_path / "o" / "results.json")
    assert data["runs"]["failed"] >= 1
    assert "k1:max" in st["screen"]["failed"]
    assert "diverged" in st["screen"]["failed"]["k1:max"]
    assert any("failed" in n for n in st["screen"]["notes"])
    assert st["screen"]["selected"]  # the analysis used the rest
    assert "failed" in (tmp_path / "o" / "report.html").read_text()


@pytest.mark.slow
def test_eq18_matches_an_independent_statsmodels_formula_fit(quick):
    import statsmodels.formula.api as smf

    out, _ = quick
    _, st = stages(out / "results.json")
    doe = st["doe"]
    names = doe["variables"]
    phys = pd.DataFrame([{n: r[n] for n in names} for r in doe["runs"]])
    phys.columns = [f"x{i + 1}" for i in range(len(names))]
    # the full factorial spans each variable's bounds: code them to [-1, 1] as Eq18 does
    coded = (phys - (phys.max() + phys.min()) / 2) / ((phys.max() - phys.min()) / 2)
    terms = list(phys.columns)
    inter = [f"{a}:{b}" for i, a in enumerate(terms) for b in terms[i + 1:]]
    formula = "y ~ " + " + ".join(terms + inter + [f"I({t}**2)" for t in terms])
    for label, reg in doe["regression"].items():
        y = np.array([doe["scores"][label][r["label"]] for r in doe["runs"]])
        fit = smf.ols(formula, data=coded.assign(y=y)).fit()
        # same term order: intercept, linear, interactions, squares
        for key, col in (("estimate", fit.params), ("se", fit.bse), ("t", fit.tvalues),
                         ("p", fit.pvalues)):
            ours = np.array([c[key] for c in reg["coefficients_coded"]])
            np.testing.assert_allclose(ours, col.to_numpy(), rtol=1e-10,
                                       atol=1e-10 * np.max(np.abs(col)))
        for key, ref in (("r2", fit.rsquared), ("r2_adj", fit.rsquared_adj),
                         ("f_stat", fit.fvalue), ("f_pvalue", fit.f_pvalue)):
            assert reg[key] == pytest.approx(ref, rel=1e-10), key
        n, p = fit.nobs, len(fit.params) - 1
        r2 = reg["r2"]
        assert reg["r2_adj"] == pytest.approx(1 - (1 - r2) * (n - 1) / (n - p - 1), rel=1e-12)
        assert reg["f_stat"] == pytest.approx((r2 / p) / ((1 - r2) / (n - p - 1)), rel=1e-10)
        # physical-unit coefficients (Fig. 10b's units): the same model, so a direct fit on
        # physical values agrees up to that fit's own ill-conditioning (x^2 ~ 1e13 here)
        direct = smf.ols(formula, data=phys.assign(y=y)).fit()
        ours = np.array([c["estimate"] for c in reg["coefficients"]])
        np.testing.assert_allclose(ours, direct.params.to_numpy(), rtol=1e-6)
        np.testing.assert_allclose(direct.fittedvalues, fit.fittedvalues, rtol=0,
                                   atol=1e-8 * np.max(np.abs(y)))


LIBRARY_STUDY = {
    "study": {"name": "library", "seed": 2},
    "model": {"name": "sensfw_test_models:NoisyQuadratic", "options": {"noise": 0.05}},
    "execution": {"backend": "serial"},
    "stages": [
        {"name": "screen", "design": "oat", "scorers": [{"name": "value", "label": "y"}],
         "select": {"threshold": 0.05, "max_variables": 2}},
        {"name": "doe", "design": "full_factorial", "variables": "selected:screen",
         "scorers": [{"name": "value", "label": "y"}], "surrogates": ["eq18"]},
    ],
}


def test_run_study_writes_the_folder_load_result_reads(tmp_path):
    """The library writes what `sensfw run` writes (issue 26, item 3): run_study(out=DIR)
    leaves the study file, results.json, timing.json and the report, and load_result
    rebuilds the same stages from them without simulating."""
    from sensfw.pipeline import load_result, results_json, run_study
    from sensfw.study import Study

    study = Study.from_dict(LIBRARY_STUDY)  # no file: study.toml is written from the spec
    result = run_study(study, out=tmp_path, report=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.json", "runs",
                                                          "study.toml", "timing.json"]
    written = json.loads((tmp_path / "results.json").read_text())
    assert written == json.loads(json.dumps(results_json(result)))
    # y = 1 + x1 - 2 x2 + 1.5 x1^2 + 0.5 x1 x3 (+ noise 0.05): one at a time over [-1, 1],
    # x1 moves y by up to 2.5, x2 by 2, x3 not at all; then 3^2 DoE runs on x1, x2
    assert written["stages"][0]["selected"] == ["x1", "x2"]
    assert written["stages"][1]["n_runs"] == 9
    # the DoE's centre and its four points on the axes are OAT runs, taken from the store
    assert json.loads((tmp_path / "timing.json").read_text())["runs"]["new"] == 7 + 9 - 5
    again = load_result(tmp_path)  # StoredRuns: would raise on a missing run
    assert json.loads(json.dumps(results_json(again)))["stages"] == written["stages"]


def test_a_rebuild_keeps_the_scores_of_every_stage_a_run_belongs_to(tmp_path):
    """The DoE's centre and axis points are the screen's runs; scored under another label in
    each stage, a rebuild (``sensfw report``) kept only the last stage's scores of a shared
    run and failed with KeyError on the screen's label."""
    from sensfw.pipeline import load_result, results_json, run_study
    from sensfw.study import Study

    spec = json.loads(json.dumps(LIBRARY_STUDY))
    spec["stages"][0]["scorers"] = [{"name": "value", "label": "y_screen"}]
    result = run_study(Study.from_dict(spec), out=tmp_path, report=False)
    again = load_result(tmp_path)
    def same(r):
        return json.loads(json.dumps(results_json(r)))["stages"]

    assert same(again) == same(result)
    assert again.stages[0].selected == ["x1", "x2"]


def test_a_rebuild_keeps_each_stages_scores_of_a_shared_run_under_one_label(tmp_path):
    """The screen scores ``rms`` of a1, the DoE ``rms`` of a2, both labelled "rms"; the
    DoE's centre and axis runs are the screen's. A rebuild merged the two stages' scores by
    run key, so the screen read the DoE's a2 values, selected other variables and asked
    for DoE runs that never existed."""
    from sensfw.pipeline import load_result, results_json, run_study
    from sensfw.study import Study

    spec = {"study": {"name": "same", "seed": 1},
            "model": {"name": "two_dof", "output": "a1"},
            "excitation": {"f0": "50 Hz", "f1": "2 kHz", "duration": "0.3 s", "fs": "20 kHz",
                           "amplitude": "1 N", "tail": "0.1 s"},
            "execution": {"backend": "serial"},
            "stages": [{"name": "screen", "design": "oat", "scorers": [{"name": "rms"}],
                        "select": {"threshold": 0.1, "max_variables": 2}},
                       {"name": "doe", "design": "full_factorial",
                        "design_options": {"levels": 3, "centre": "nominal"},
                        "variables": "selected:screen",
                        "scorers": [{"name": "rms", "channel": "a2"}],
                        "surrogates": ["eq18"]}]}
    result = run_study(Study.from_dict(spec), out=tmp_path, report=False)
    assert set(result.stages[0].keys) & set(result.stages[1].keys)  # runs are shared
    again = load_result(tmp_path)

    def same(r):
        return json.loads(json.dumps(results_json(r)))["stages"]

    assert same(again) == same(result)
    assert again.stages[0].selected == result.stages[0].selected


def test_a_group_screen_passes_the_members_of_its_selected_groups_on(tmp_path):
    """A screen by groups (``oat`` with ``groups``) selects groups; the next stage's
    ``selected:screen`` takes their members. y = 1 + x1 - 2 x2 + 1.5 x1^2 + 0.5 x1 x3: x1 and
    x2 moved together change y by 2.5 (to 3.5 at -1), x3 alone not at all."""
    from sensfw.pipeline import plan, run_study
    from sensfw.study import Study

    spec = json.loads(json.dumps(LIBRARY_STUDY))
    spec["stages"][0]["design_options"] = {"groups": {"x12": ["x1", "x2"], "x3": ["x3"]}}
    spec["stages"][0]["select"] = {"threshold": 0.05, "max_variables": 1}
    study = Study.from_dict(spec)
    assert [p["n_runs"] for p in plan(study)] == [5, 9]  # 2 G + 1; 3^2 on the largest group
    result = run_study(study, out=tmp_path, report=False)
    screen, doe = result.stages
    assert screen.selected == ["x12"]
    assert len(screen.table) == 5 and len(doe.table) == 9
    assert doe.space.names == ["x1", "x2"]


def test_a_rebuild_takes_the_stored_validation_of_the_same_fit(tmp_path, monkeypatch):
    """`sensfw report` does not cross-validate again (issue 26, item 6): each surrogate's
    validation comes from results.json when its fitted values are the refitted surrogate's
    predictions; a validation of another fit is not taken."""
    import sensfw.analysis.validation
    from sensfw.pipeline import load_result, run_study
    from sensfw.study import Study

    run_study(Study.from_dict(LIBRARY_STUDY), out=tmp_path, report=False)
    written = json.loads((tmp_path / "results.json").read_text())

    def refuse(*args, **kwargs):
        raise AssertionError("validated again")

    monkeypatch.setattr(sensfw.analysis.validation, "validate", refuse)
    again = load_result(tmp_path)
    stored = written["stages"][1]["validation"]["y"]["eq18"]
    assert again.stages[1].validation["y"]["eq18"] == stored
    written["stages"][1]["validation"]["y"]["eq18"]["fitted"][0] += 1.0  # another fit's
    (tmp_path / "results.json").write_text(json.dumps(written))
    with pytest.raises(AssertionError, match="validated again"):
        load_result(tmp_path)


def test_a_score_that_does_not_vary_gets_one_line_not_surrogates(tmp_path):
    """Ishigami with x1 = x2 = 0 is x3 times sin(0) = 0 whatever x3: the report showed five
    surrogates of a constant with R²adj=nan, t and p 'None', and Q² k-fold 'left out, too
    few runs'. Now no surrogate is fitted and one note says why."""
    from sensfw.pipeline import run_study
    from sensfw.study import Study

    spec = {"study": {"name": "const", "seed": 1}, "model": {"name": "ishigami"},
            "execution": {"backend": "serial"},
            "stages": [{"name": "doe", "design": "full_factorial",
                        "design_options": {"levels": 5}, "variables": ["x3"],
                        "scorers": [{"name": "value", "label": "y"}],
                        "surrogates": ["eq18", "gaussian_process"]}]}
    st = run_study(Study.from_dict(spec), out=tmp_path).stages[0]
    assert not st.surrogates.get("y") and not st.regression
    assert "y: the score does not vary over the 5 finished runs (every one 0)" in " ".join(
        st.notes)
    import re

    html = re.sub(r'src="data:image/png;base64,[^"]*"', "", (tmp_path / "report.html")
                  .read_text())
    assert "does not vary" in html and "nan" not in html.lower()


def test_a_study_that_stops_at_a_stage_keeps_the_stages_before_it(tmp_path):
    """Every DoE run diverges (x3 above 2.5 on its stage's bounds): the study stops with
    the DoE's error, and the screen that finished is written (results.json, report) and
    rebuilt by load_result. Before, the folder held only the runs and the study file."""
    from sensfw_test_models import FAULT_INJECTION

    from sensfw.errors import SensfwError
    from sensfw.pipeline import load_result, run_study
    from sensfw.study import Study

    faults = {"model": "ishigami", "diverge": {"parameter": "x3", "above": 2.5}}
    spec = {"study": {"name": "stops", "seed": 1},
            "model": {"name": FAULT_INJECTION, "options": faults},
            "execution": {"backend": "serial"},
            "stages": [{"name": "screen", "design": "oat", "variables": ["x1", "x2"],
                        "scorers": [{"name": "value", "label": "y"}],
                        "select": {"threshold": 0.05}},
                       {"name": "doe", "design": "full_factorial", "variables": ["x3"],
                        "bounds": {"x3": {"min": 2.6, "nominal": 2.8, "max": 3.0}},
                        "scorers": [{"name": "value", "label": "y"}],
                        "surrogates": ["eq18"]}]}
    with pytest.raises(SensfwError, match="doe"):
        run_study(Study.from_dict(spec), out=tmp_path)
    data = json.loads((tmp_path / "results.json").read_text())
    assert [s["name"] for s in data["stages"]] == ["screen"]
    assert data["stopped"]["stage"] == "doe"
    assert "The study stopped at stage " in (tmp_path / "report.html").read_text()
    again = load_result(tmp_path)
    assert [s.name for s in again.stages] == ["screen"] and again.stopped["stage"] == "doe"
    assert again.stages[0].selected == data["stages"][0]["selected"]


def _children(pid: int) -> list[int]:
    out = subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout
    return [int(x) for x in out.split()]


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL])
def test_a_run_stopped_by_a_signal_leaves_no_worker_behind(cli, tmp_path, sig):
    """SIGTERM (``timeout``, ``kill``, a batch scheduler) and SIGKILL to the CLI alone, not
    its process group: the workers, blocked on a result queue nobody read, and the
    forkserver stayed for good (130 MB each). Now SIGTERM stops the run as Ctrl-C does
    (exit 143, finished runs kept) and after either signal the forkserver's workers leave."""
    proc, _ = _running_quick(tmp_path / "sig", at_least=2)
    servers = _children(proc.pid)
    workers = [w for s in servers for w in _children(s)]
    assert workers, "no pool workers found"
    os.kill(proc.pid, sig)
    code = proc.wait(timeout=60)
    if sig == signal.SIGTERM:
        assert code == 143
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and any(os.path.exists(f"/proc/{w}") and
                                              "Z" not in open(f"/proc/{w}/stat").read().split()[2]
                                              for w in workers):
        time.sleep(0.2)
    left = [w for w in workers if os.path.exists(f"/proc/{w}")
            and open(f"/proc/{w}/stat").read().split()[2] != "Z"]
    for p in left + servers:  # leave nothing behind whatever the outcome
        try:
            os.kill(p, signal.SIGKILL)
        except ProcessLookupError:
            pass
    assert not left, f"workers {left} still running 30 s after the CLI was stopped"


def test_a_worker_count_below_one_is_refused():
    """``--workers -1`` started no worker and waited for ever on their results."""
    from typer.testing import CliRunner

    from sensfw.cli import app

    res = CliRunner().invoke(app, ["run", str(QUICK), "--workers", "-1", "--dry-run"])
    assert res.exit_code == 2 and "--workers" in res.output


TWO_VALUES = '''
import numpy as np
from sensfw.scorers import Scorer

class TwoValues(Scorer):
    name = "two_values_test"
    def score(self, signals, reference=None):
        x = self.signal(signals)
        return {"mean": float(np.mean(x)), "rms": float(np.sqrt(np.mean(x ** 2)))}
'''


@pytest.mark.parametrize("by", [None, "tv.rms", "tv"])
def test_a_scorer_of_several_values_feeds_a_selecting_stage(tmp_path, monkeypatch, by):
    """The scorer contract allows several values (columns ``label.key``): a selecting stage
    read ``scores[label]`` (a KeyError after every run), and ``select.by = "tv.mean"`` was
    refused at validation. Now the first value is read unless ``select.by`` names one;
    naming the scorer alone is an error listing its values."""
    from sensfw.errors import AnalysisError
    from sensfw.pipeline import run_study
    from sensfw.runs import Runner, RunStore
    from sensfw.study import Study

    (tmp_path / "twoval_mod.py").write_text(TWO_VALUES)
    monkeypatch.syspath_prepend(str(tmp_path))
    select = {"threshold": 0.05, **({"by": by} if by else {})}
    study = Study.from_dict({
        "study": {"name": "multi"}, "model": {"name": "ishigami"},
        "excitation": {"duration": "0.01 s"},
        "stages": [{"name": "screen", "design": "oat", "select": select,
                    "scorers": [{"name": "twoval_mod:TwoValues", "label": "tv"}]}]}, "m.toml")
    with Runner(RunStore(tmp_path / "runs"), backend="serial") as runner:
        if by == "tv":
            with pytest.raises(AnalysisError, match=r"scorer 'tv' gives several values "
                                                    r"\(tv\.mean, tv\.rms\): name one"):
                run_study(study, runner)
            return
        res = run_study(study, runner)
    (stage,) = res.stages
    assert stage.selected  # the OAT of Ishigami's function: x1 at least moves both values
    col = by or "tv.mean"
    y = stage.scores[col].to_numpy(float)
    assert np.ptp(y) > 0
