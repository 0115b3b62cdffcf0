"""The paper beside a study (issue 28): the reference data as printed, the fit the way
Fig. 10b was made, the comparison and its validation in a study file."""

import copy
import itertools
import re
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import statsmodels.api as sm

from sensfw.analysis.paper_comparison import (
    available_references,
    compare,
    fit_as_published,
    load_reference,
)
from sensfw.errors import StudyError
from sensfw.study import Study
from sensfw.surrogates.eq18 import design_matrix

ROOT = Path(__file__).resolve().parents[2]
# the paper's text (never copied into the repository): ../shared/seed
SEED = ROOT.parent / "shared" / "seed" / "000_85d1a165c389df76.txt"
TABLE2 = [[1.0, 117.5, 234.0], [2.83e6, 3.16e6, 3.45e6], [0.1, 5.05, 10.0], [1.0, 258.0, 514.6]]
STUDY = tomllib.loads((ROOT / "studies" / "paper_table2.toml").read_text())


def table2_runs() -> pd.DataFrame:
    names = ["slide_damping", "clutch_drive_stiffness", "slide_friction_velocity",
             "clutch_drive_damping"]
    return pd.DataFrame(list(itertools.product(*TABLE2)), columns=names)


def test_the_data_file_holds_fig_10b_table_2_and_the_text_as_printed():
    if not SEED.is_file():
        pytest.skip(f"the paper's text is not at {SEED}")
    text = SEED.read_text()
    ref = load_reference("steinbach2025")
    assert "steinbach2025" in available_references()
    # Fig. 10b: 15 rows, 3 responses x (estimate, SE, tStat, pValue), cell by cell
    rows = [r for r in text.splitlines() if re.match(r"\| (\(Intercept\)|x\d)", r)]
    assert len(rows) == 15
    for i, row in enumerate(rows):
        cells = [c.strip() for c in row.strip("|").split("|")[1:]]
        values = [float("nan") if c == "NaN" else float(c) for c in cells]
        for k, key in enumerate(("base_frequency", "first_harmonic", "thd")):
            got = ref.responses[key].table.iloc[i].to_numpy()
            np.testing.assert_array_equal(got, values[4 * k:4 * k + 4])
    # R2adj and the terms the text names (Sect. 3.2)
    for key, r2 in (("base_frequency", 0.988), ("first_harmonic", 0.984), ("thd", 0.959)):
        assert ref.responses[key].r2_adj == r2
        assert f"R_a^2 = {r2}" in text
    assert "x_1, x_2, x_3, x_2 : x_3, x_3^2$, and x_4^2" in text
    assert ref.responses["base_frequency"].named == ("x1", "x2", "x3", "x2:x3", "x3^2", "x4^2")
    assert "$x_3, x_1 : x_3, x_2 : x_4$, and x_3^2" in text
    assert ref.responses["first_harmonic"].named == ("x3", "x1:x3", "x2:x4", "x3^2")
    assert "THD x_3 and x_1^2" in text
    assert ref.responses["thd"].named == ("x3", "x1^2")
    # Table 2's levels (lower / medium / upper)
    assert [ref.factors[x]["levels"] for x in ("x1", "x2", "x3", "x4")] == TABLE2
    assert "| Medium value | 117.5 N mm s ⁻¹ | 3.16×10^6" in text


def test_fig_10b_table_flags_more_terms_than_its_text_names():
    ref = load_reference("steinbach2025")
    base = ref.responses["base_frequency"]
    # the text's list is a subset of the table's p < 0.05 (Sect. 3.2 names 6 of 11)
    assert set(base.named) < set(base.significant(0.05))
    assert base.significant(0.05) == ["x1", "x2", "x3", "x1:x3", "x2:x3", "x2:x4", "x3:x4",
                                      "x1^2", "x2^2", "x3^2", "x4^2"]
    assert ref.responses["thd"].significant(0.05) == ["x3", "x1^2", "x3^2"]


def test_fit_as_published_is_ordinary_least_squares_when_nothing_is_dropped():
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, (40, 3))
    y = 1 + X[:, 0] + X[:, 1] * X[:, 2] + 0.1 * rng.standard_normal(40)
    got = fit_as_published(X, y, ["a", "b", "c"])
    A, _ = design_matrix(X, ["a", "b", "c"])
    ols = sm.OLS(y, A).fit()  # an independent implementation
    assert got["dropped"] == []
    np.testing.assert_allclose(got["table"]["estimate"], ols.params, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(got["table"]["se"], ols.bse, rtol=1e-10)
    np.testing.assert_allclose(got["table"]["p"], ols.pvalues, rtol=1e-8, atol=1e-14)
    assert got["r2_adj"] == pytest.approx(ols.rsquared_adj, rel=1e-12)


def test_the_rank_check_drops_the_intercept_on_table_2_values_as_fig_10b_shows():
    X = table2_runs().to_numpy()
    y = np.random.default_rng(1).standard_normal(81)
    got = fit_as_published(X, y, ["x1", "x2", "x3", "x4"])
    # Fig. 10b prints the intercept as 0 / 0 / NaN / NaN: the same rank rule on the same
    # physical values drops exactly that column (R diagonal 0.04, tolerance 1.3)
    assert got["dropped"] == ["(Intercept)"]
    assert got["r_diagonal"]["(Intercept)"] < 0.1 * got["rank_tolerance"]
    row = got["table"].loc["(Intercept)"]
    assert row["estimate"] == 0 and row["se"] == 0 and np.isnan(row["t"])
    # the same values coded to [-1, 1] keep every column
    Z = (X - X.mean(axis=0)) / (X.max(axis=0) - X.mean(axis=0))
    assert fit_as_published(Z, y, ["x1", "x2", "x3", "x4"])["dropped"] == []


def test_compare_finds_the_terms_of_a_known_response_and_says_what_the_paper_has_more():
    runs = table2_runs()
    lo, hi = runs.min(), runs.max()
    z = (2 * runs - (lo + hi)) / (hi - lo)
    rng = np.random.default_rng(2)
    y = 1 + 0.5 * z.iloc[:, 0] - 0.8 * z.iloc[:, 2] ** 2 + 0.3 * z.iloc[:, 0] * z.iloc[:, 2] \
        + 0.01 * rng.standard_normal(81)
    factors = dict(zip(["x1", "x2", "x3", "x4"], runs.columns, strict=True))
    comp = compare(load_reference("steinbach2025"), runs, pd.DataFrame({"y": y}), factors,
                   {"base_frequency": "y"}, bounds={c: (lo[c], hi[c]) for c in runs},
                   model="shaft_assembly")
    terms = comp.terms["base_frequency"]
    # the true terms have t of order 100 (effects 0.3-0.8, noise 0.01); each of the 11 null
    # terms falls below p = 1e-3 with probability 1e-3
    true = ["(Intercept)", "x1", "x1:x3", "x3^2"]
    assert terms.loc[true, "sensfw p, coded"].max() < 1e-10
    assert terms["sensfw p, coded"].drop(true).min() > 1e-3
    row = comp.summary.loc["base_frequency"]
    assert row["R²adj paper"] == 0.988 and row["R²adj sensfw"] > 0.99
    assert row["significant: paper text"] == "x1, x2, x3, x2:x3, x3^2, x4^2"
    # y has no term of x2 or x4 (x1 and x3 are linear in physical units as z3^2 expands)
    assert row["named in the text, not by sensfw"] == "x2, x2:x3, x4^2"
    assert row["rank check drops"] == "(Intercept)"
    # factors absent from y have no main effect; the reasons name the intercept and x4
    assert comp.effects.loc["x4 clutch_drive_damping", "y"] < 0.01
    assert comp.reasons[0].startswith("The intercept.")
    assert any(r.startswith("x4 (clutch_drive_damping) has no significant term")
               for r in comp.reasons)
    assert comp.reasons[-1].startswith("The model is an analogue")


def test_the_clutch_damping_cannot_act_at_table_2_medium_values():
    """Pins the data file's claim: the clutch-driveshaft contact sits so shallow that its
    damping ramp (Eq. 2, Adams STEP over dmax) passes about 6e-6 of the coefficient."""
    from sensfw.models.planar import statics
    from sensfw.models.shaft_assembly import ShaftAssembly

    model = ShaftAssembly()
    p = model.parameters().complete({"slide_damping": 117.5, "clutch_drive_stiffness": 3.16e6,
                                     "slide_v_friction": 5.05, "slide_v_stiction": 0.505,
                                     "clutch_drive_damping": 258.0})
    mech = model.mechanism(p)
    contacts = statics.linear_contacts(mech, model.equilibrium(p, mech))
    _, _, c, _ = contacts.table["clutch_drive"]
    share = c / mech.laws["clutch_drive"].c
    assert 3e-6 < share < 1e-5  # "passes 6e-6 of the damping coefficient"
    claim = load_reference("steinbach2025").analogues["shaft_assembly"]["differences"][1]
    assert "6e-6 of the damping coefficient" in claim


def with_compare(**changes):
    """paper_table2.toml with ``[compare_with]`` entries changed (None deletes one)."""
    data = copy.deepcopy(STUDY)
    for path, value in changes.items():
        *parents, leaf = path.split("__")
        node = data["compare_with"]
        for part in parents:
            node = node[part]
        if value is None:
            del node[leaf]
        else:
            node[leaf] = value
    return data


@pytest.mark.parametrize("changes,where,message", [
    ({"reference": "steinbach2024"}, "reference", "available: steinbach2025"),
    ({"reference": "mine.toml"}, "reference", "not found"),
    ({"stage": "screen"}, "stage", "no stage named 'screen'"),
    ({"factors__x4": None}, "factors", "map x4 to design variables"),
    ({"factors__x9": "slide_stiffness"}, "factors.x9", "has no factor 'x9'"),
    ({"factors__x1": "slide_exponent"}, "factors.x1",
     "'slide_exponent' is not a variable of stage 'doe'"),
    ({"responses__thd": "THDX"}, "responses.thd", "no scorer labelled 'THDX'"),
    ({"responses__sound": "P1"}, "responses.sound", "has no response 'sound'"),
    ({"colour": "red"}, "colour", "unknown key; known: reference, stage, factors"),
])
def test_compare_with_is_validated_with_the_study_file(changes, where, message):
    assert Study.load(ROOT / "studies" / "paper_table2.toml").spec.compare_with.stage == "doe"
    with pytest.raises(StudyError) as info:
        Study.from_dict(with_compare(**changes), str(ROOT / "studies" / "x.toml"))
    assert message in dict(info.value.problems)[f"compare_with.{where}"]


REFERENCE = """
[reference]
key = "toy"
citation = "A toy reference."
model = "y = 1 + x1 - 2 x2 + 1.5 x1^2 + 0.5 x1 x3 + noise"
[doe]
source = "Table 1"
factors = ["x1", "x2", "x3"]
""" + "".join(f'[doe.x{i}]\nname = "factor {i}"\nunit = ""\nlevels = [-1.0, 0.0, 1.0]\n'
              for i in (1, 2, 3)) + """
[responses.y]
name = "the response"
r2_adj = 0.99
r2_adj_source = "Sect. 1"
named_significant = ["x1", "x2", "x1^2", "x3^2"]
named_source = "Sect. 1"
source = "Fig. 1"
terms = ["(Intercept)", "x1", "x2", "x3", "x1:x2", "x1:x3", "x2:x3", "x1^2", "x2^2", "x3^2"]
estimate = [1.0, 1.0, -2.0, 0.0, 0.0, 0.5, 0.0, 1.5, 0.0, 0.4]
se = [0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1]
t = [10.0, 10.0, -20.0, 0.0, 0.0, 5.0, 0.0, 15.0, 0.0, 4.0]
p = [1e-9, 1e-9, 1e-12, 1.0, 1.0, 1e-4, 1.0, 1e-10, 1.0, 1e-3]
"""

TOY = {
    "study": {"name": "toy", "seed": 3},
    "model": {"name": "sensfw_test_models:NoisyQuadratic", "options": {"noise": 0.05}},
    "execution": {"backend": "serial"},
    "stages": [{"name": "doe", "design": "full_factorial", "surrogates": ["eq18"],
                "scorers": [{"name": "value", "label": "Y"}]}],
    "compare_with": {"reference": "toy.toml", "stage": "doe", "responses": {"y": "Y"},
                     "factors": {"x1": "x1", "x2": "x2", "x3": "x3"}},
}


@pytest.mark.slow  # a study of 27 function runs and its HTML report
def test_a_study_report_sets_its_stage_beside_the_reference(tmp_path):
    from sensfw.pipeline import run_study
    from sensfw.report.study import write_study_report
    from sensfw.runs import Runner, RunStore

    (tmp_path / "toy.toml").write_text(REFERENCE)
    study = Study.from_dict(TOY, str(tmp_path / "s.toml"))  # the path is the study file's
    with Runner(RunStore(tmp_path / "runs"), backend="serial") as runner:
        result = run_study(study, runner)
    html = write_study_report(result, tmp_path / "report.html").read_text()
    assert "Beside the paper: stage doe and toy" in html
    assert "named in the text, not by sensfw" in html
    # the toy model has no x3^2 term: the reference's x3^2 is named and not found
    from sensfw.analysis.paper_comparison import comparison_for

    comp = comparison_for(result)
    assert comp.summary.loc["y", "named in the text, not by sensfw"] == "x3^2"
    assert comp.summary.loc["y", "rank check drops"] == "none"
    # no confirmation runs: the empty columns are left out, with the reason
    assert "<th>confirm RMSE</th>" not in html and "<th>PI coverage</th>" not in html
    assert "confirm RMSE and PI coverage: left out, the stage has no confirmation runs" in html


def test_a_dropped_coefficients_p_reads_dropped_in_the_report():
    """MATLAB reports a coefficient it dropped as estimate 0, SE 0, t and p NaN (the
    paper's intercept): the terms table says "dropped" there, keeps every other p, and
    leaves a term the paper's table does not hold (estimate NaN) as it is."""
    from sensfw.report.study import _dropped_shown

    frame = pd.DataFrame({"paper estimate": [0.0, 1.2, np.nan],
                          "paper p": [np.nan, 0.03, np.nan],
                          "as Fig. 10b: estimate": [0.0, 1.1, 0.5],
                          "as Fig. 10b: p": [np.nan, 0.04, 0.2]},
                         index=["(Intercept)", "x1", "x9"])
    shown = _dropped_shown(frame)
    assert list(shown["paper p"][:2]) == ["dropped", 0.03] and np.isnan(shown["paper p"].iloc[2])
    assert list(shown["as Fig. 10b: p"]) == ["dropped", 0.04, 0.2]
    assert np.isnan(frame["paper p"].iloc[0])  # the analysis's frame is not changed
