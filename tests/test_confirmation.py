"""Regression validation in a study: confirmation runs and their prediction-interval
coverage on a test function with known noise (issue 5, item 4)."""

import json

import pytest

pytestmark = pytest.mark.slow  # studies with hundreds of runs and surrogate fits

STUDY = """
[study]
name = "confirm"
seed = 3
[model]
name = "sensfw_test_models:NoisyQuadratic"
options = { noise = 0.2 }
[execution]
backend = "serial"
[[stages]]
name = "doe"
design = "lhs"
design_options = { samples = 60 }
scorers = [{ name = "value", label = "y" }]
surrogates = ["eq18", "gaussian_process", "random_forest"]
confirmation_runs = 200
"""


def test_confirmation_coverage_is_near_its_nominal_level(cli, tmp_path):
    f = tmp_path / "s.toml"
    f.write_text(STUDY)
    proc = cli("run", f, "--out", tmp_path / "o", "--no-progress")
    assert proc.returncode == 0, proc.stderr
    st = json.loads((tmp_path / "o" / "results.json").read_text())["stages"][0]
    v = st["validation"]["y"]
    conf = v["eq18"]["confirmation"]
    assert conf["n"] == 200 and conf["level"] == 0.95
    # Eq. 18 is the true model and the noise is Gaussian: 95 % intervals cover ~95 % of new
    # runs (binomial spread +-1.5 points at n = 200), within the required 10 points
    assert abs(conf["coverage"] - 0.95) < 0.10
    assert conf["rmse"] < 1.3 * 0.2  # about the noise
    assert v["eq18"]["q2_loo"] > 0.8
    # every surrogate is validated side by side on the same data
    assert {"eq18", "gaussian_process", "random_forest"} <= set(v)
    assert v["random_forest"]["confirmation"]["coverage"] is None  # no intervals: said so
    html = (tmp_path / "o" / "report.html").read_text()
    assert "PI coverage" in html


AUTO = """
[study]
name = "auto"
seed = 3
[model]
name = "sensfw_test_models:NoisyQuadratic"
options = { noise = 0.05 }
[execution]
backend = "serial"
[[stages]]
name = "doe"
design = "lhs"
design_options = { samples = 30 }
scorers = [{ name = "value", label = "y" }]
surrogates = [{ name = "auto", candidates = ["eq18", "gaussian_process"] }]
confirmation_runs = 10
"""


def test_auto_in_a_study_when_eq18_wins(cli, tmp_path):
    """Auto passes on the chosen surrogate's declared members: when Eq. 18 wins (it is the
    true model here), its coefficient table and statistics reach results.json and the report
    (this ended in an AttributeError after every run before)."""
    f = tmp_path / "s.toml"
    f.write_text(AUTO)
    proc = cli("run", f, "--out", tmp_path / "o", "--no-progress")
    assert proc.returncode == 0, proc.stderr
    st = json.loads((tmp_path / "o" / "results.json").read_text())["stages"][0]
    reg = st["regression"]["y"]
    assert reg["surrogate"] == "auto" and reg["n_obs"] == 30
    terms = [c["term"] for c in reg["coefficients"]]
    assert terms[:4] == ["(Intercept)", "x1", "x2", "x3"] and len(terms) == 10
    v = st["validation"]["y"]["auto"]
    assert v["q2_loo_method"] == "hat matrix" and v["q2_loo"] > 0.9
    assert v["confirmation"]["coverage"] is not None  # Eq. 18's intervals, through auto
    html = (tmp_path / "o" / "report.html").read_text()
    assert "y: Eq. 18 (auto)" in html
