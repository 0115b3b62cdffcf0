"""Agreement of a cheaper design with the paper's pipeline (issue 28): the criteria on
responses with known terms, and a study report that measures it."""

import copy
import itertools
import json
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sensfw.analysis.agreement import Conclusions, agreement, replication_probability
from sensfw.errors import StudyError
from sensfw.study import Study

NAMES = ["a", "b", "c", "d"]


def grid(levels=3):
    return pd.DataFrame(list(itertools.product(np.linspace(-1, 1, levels), repeat=4)),
                        columns=NAMES, index=[f"ff:{i}" for i in range(levels**4)])


def response(X, noise, seed):
    rng = np.random.default_rng(seed)
    return (2 * X["a"] - 1.5 * X["a"] * X["b"] + 1.2 * X["c"] ** 2
            + noise * rng.standard_normal(len(X)))


def test_replication_probability_of_the_band():
    assert replication_probability(0.05) == pytest.approx(0.5)
    assert replication_probability(0.001) == pytest.approx(0.91, abs=0.005)
    assert replication_probability(0.5) == pytest.approx(0.10, abs=0.005)


def test_the_full_factorial_agrees_with_itself_and_a_fraction_is_judged_on_the_rest():
    X = grid()
    ref = Conclusions(names=NAMES, bounds=[(-1, 1)] * 4, table=X,
                      scores=pd.DataFrame({"y": response(X, 0.3, 0)}))
    _, must, _ = ref.classes("y")
    assert {"a", "a:b", "c^2"} <= must  # t of order 20 at noise 0.3
    self_ = agreement(ref, X, ref.scores)
    assert self_["held_out"] == 0 and self_["reached"] and self_["strict"]
    # a Box-Behnken-like subset that never varies c: c^2 cannot be estimated -> it fails
    sub = X[X["c"] == 0]
    with_c = agreement(ref, sub, ref.scores.loc[sub.index])
    assert not with_c["reached"] and with_c["held_out"] == 81 - 27
    assert "error" in with_c["scores"]["y"] or "c^2" in with_c["scores"]["y"]["missed"]


def test_a_design_that_flags_a_null_term_does_not_agree():
    X = grid()
    y = response(X, 0.3, 0)
    ref = Conclusions(names=NAMES, bounds=[(-1, 1)] * 4, table=X,
                      scores=pd.DataFrame({"y": y}))
    p = ref.p["y"]
    null = p.drop("(Intercept)").index[p.drop("(Intercept)") > 0.5][0]  # a null term
    # the same runs with that term added strongly: now it is flagged, which is wrong
    A = {t: (X[t.split(":")[0]] * X[t.split(":")[1]] if ":" in t else
             X[t[:-2]] ** 2 if t.endswith("^2") else X[t]) for t in [null]}
    y2 = y + 5 * A[null]
    got = agreement(ref, X, pd.DataFrame({"y": y2}, index=X.index))
    assert got["scores"]["y"]["wrong"] == [null] and not got["terms"]


QUAD = """
[study]
name = "{name}"
seed = 3
[model]
name = "sensfw_test_models:NoisyQuadratic"
options = {{ noise = 0.05 }}
[execution]
backend = "serial"
[[stages]]
name = "screen"
design = "oat"
scorers = [{{ name = "value", label = "Y" }}]
# threshold 0: the screen keeps all three; x3 acts only through x1 x3, which a screen one
# at a time about the centre cannot see (its ends change y by the noise alone: 1.2 % of x1)
select = {{ threshold = 0.0, max_variables = 3 }}
[[stages]]
name = "doe"
design = "{design}"
design_options = {options}
variables = "selected:screen"
scorers = [{{ name = "value", label = "Y" }}]
surrogates = ["eq18"]
"""


@pytest.mark.slow  # two studies (a few hundred function runs) and their HTML reports
def test_a_study_report_measures_its_agreement_with_a_finished_pipeline(tmp_path):
    from sensfw.pipeline import results_json, run_study
    from sensfw.report.study import write_study_report
    from sensfw.runs import Runner, RunStore

    full = tmp_path / "full.toml"
    full.write_text(QUAD.format(name="full", design="full_factorial", options="{ levels = 3 }"))
    fast = tmp_path / "fast.toml"
    fast.write_text(QUAD.format(name="fast", design="central_composite",
                                options='{ face = "ccf", center = [1, 0] }')
                    + '[agree_with]\nresults = "out_full"\n')
    with Runner(RunStore(tmp_path / "runs"), backend="serial") as runner:
        res_full = run_study(Study.load(full), runner)
    (tmp_path / "out_full").mkdir()
    (tmp_path / "out_full" / "results.json").write_text(json.dumps(results_json(res_full)))
    with Runner(RunStore(tmp_path / "runs"), backend="serial") as runner:
        res_fast = run_study(Study.load(fast), runner)
    from sensfw.analysis.agreement import agreement_for

    agr = agreement_for(res_fast)
    # OAT on 3 variables: 7 runs (the nominal = the centre, and the face centres), all of
    # them runs of the 3^3 full factorial and of the face-centred CCD (15 runs) too
    assert agr["reference_runs"] == 27 and agr["runs"] == 15
    assert agr["screen"] and agr["held_out"] == 27 - 15
    # Eq. 18 is the true model: on 15 runs it finds the strong terms (x1, x2, x1^2)
    assert not agr["scores"]["Y"]["missed"] and not agr["scores"]["Y"]["wrong"]
    html = write_study_report(res_fast, tmp_path / "fast.html").read_text()
    assert "Agreement with the full pipeline (out_full)" in html
    assert f"This study: {agr['runs']} runs; the full pipeline: {agr['reference_runs']}" in html
    # without the folder: a note in the report, not a crash
    (tmp_path / "out_full" / "results.json").unlink()
    html = write_study_report(res_fast, tmp_path / "fast.html").read_text()
    assert "Not measured:" in html


def test_agree_with_is_validated_with_the_study_file(tmp_path):
    data = tomllib.loads(QUAD.format(name="x", design="full_factorial", options="{}"))
    data["agree_with"] = {"results": "out", "screen": "doe", "stage": "nope"}
    with pytest.raises(StudyError) as info:
        Study.from_dict(copy.deepcopy(data), "x.toml")
    got = dict(info.value.problems)
    assert got["agree_with.screen"] == "stage 'doe' has no select"
    assert "no stage named 'nope'" in got["agree_with.stage"]


def test_the_shipped_fast_study_is_the_paper_screen_and_a_27_run_fraction():
    from sensfw.pipeline import plan

    study = Study.load(Path(__file__).resolve().parents[2] / "studies" / "paper_fast.toml")
    assert [p["n_runs"] for p in plan(study)] == [39, 27]  # 66 runs; the paper's: 39 + 81
    assert study.spec.agree_with.results == "out/paper"
