"""D- and I-optimal designs on the 3^k grid, augmenting the OAT screen's runs (issue 28)."""

import itertools
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sensfw.designs import DesignError, make_design
from sensfw.designs.optimal import _swap_gains, criterion_value, eq18_columns, exchange
from sensfw.models.shaft_assembly import GROUPS, PARAMETERS
from sensfw.params import DesignSpace

TOP4 = ["slide_stiffness", "slide_exponent", "slide_friction_velocity",
        "clutch_drive_stiffness"]
GRID2 = np.array(list(itertools.product([-1.0, 0.0, 1.0], repeat=2)))


def brute_force(F, n, fixed, criterion):
    """The best criterion value over every n-subset of the candidates (independent of the
    exchange: enumeration)."""
    base = np.zeros((F.shape[1],) * 2) if fixed is None else fixed.T @ fixed
    moments = F.T @ F / len(F)
    return max(float(criterion_value(base + F[list(s)].T @ F[list(s)], criterion, moments))
               for s in itertools.combinations(range(len(F)), n))


@pytest.mark.parametrize("criterion", ["D", "I"])
@pytest.mark.parametrize("n,fixed_rows", [(6, []), (7, []), (8, []), (5, [[0.3, -0.8]]),
                                          (4, [[-0.82, -0.82], [1.0, -0.82]])])
def test_exchange_finds_the_optimum_that_enumeration_finds(criterion, n, fixed_rows):
    F = eq18_columns(GRID2)  # 6 coefficients of Eq. 18 in two variables, 9 candidates
    fixed = eq18_columns(np.array(fixed_rows)) if fixed_rows else None
    idx, value = exchange(F, n, fixed, criterion, starts=5, seed=0)
    assert len(set(idx)) == n  # no replicates
    assert value == pytest.approx(brute_force(F, n, fixed, criterion), rel=1e-9)


def test_swap_gains_are_the_criterion_change_of_each_swap():
    """Fedorov's delta (D) and the Woodbury update (I) against recomputing the criterion."""
    F = eq18_columns(np.array(list(itertools.product([-1.0, 0.0, 1.0], repeat=3))))
    rng = np.random.default_rng(0)
    idx = rng.choice(len(F), 14, replace=False)
    info, moments = F[idx].T @ F[idx], F.T @ F / len(F)
    x = F[idx[3]]
    for criterion in ("D", "I"):
        gains = _swap_gains(np.linalg.inv(info), F, x, criterion, moments)
        swapped = info - np.outer(x, x) + np.einsum("ni,nj->nij", F, F)
        direct = criterion_value(swapped, criterion, moments) - criterion_value(
            info, criterion, moments)
        fine = np.isfinite(direct)
        np.testing.assert_allclose(gains[fine], direct[fine], rtol=1e-9, atol=1e-12)
        assert np.all(np.isneginf(gains[~fine]))


def test_d_optimal_three_point_design_in_one_variable_is_min_centre_max():
    """For y = a + b x + c x^2 on [-1, 1] the D-optimal 3-point design is {-1, 0, 1}
    (Atkinson et al. 2007, Sect. 11.3): det of its information matrix is 4, the largest."""
    F = eq18_columns(np.linspace(-1, 1, 11)[:, None])
    idx, value = exchange(F, 3, criterion="D", starts=3)
    np.testing.assert_allclose(F[idx, 1], [-1.0, 0.0, 1.0], atol=1e-12)
    assert value == pytest.approx(np.log(4.0))


def space4():
    return DesignSpace.from_parameters(PARAMETERS, GROUPS, select=TOP4)


def test_optimal_design_on_the_grid_and_around_the_oat_runs():
    space = space4()
    grid = {tuple(r) for r in make_design("full_factorial").generate(space).to_numpy()}
    plain = make_design("optimal", runs=21).generate(space, seed=2)
    assert len(plain) == 21 and all(tuple(r) in grid for r in plain.to_numpy())
    aug = make_design("optimal", runs=21, criterion="I", augment="oat")
    table = aug.generate(space, seed=2)
    oat = make_design("oat").generate(space)
    assert aug.n_runs(space) == len(table) == 21 + 9
    pd.testing.assert_frame_equal(table.iloc[:9], oat)  # the screen's runs, exactly
    new = table.iloc[9:]
    assert all(tuple(r) in grid for r in new.to_numpy())
    assert not {tuple(r) for r in new.to_numpy()} & {tuple(r) for r in oat.to_numpy()}
    # the OAT's runs count: the 21 chosen around them beat 21 chosen without them, with them
    F = eq18_columns(space.code(make_design("full_factorial").generate(space)).to_numpy())
    F0 = eq18_columns(space.code(oat).to_numpy())
    moments = F.T @ F / len(F)

    def avg_var(t):
        G = eq18_columns(space.code(t).to_numpy())
        return criterion_value(F0.T @ F0 + G.T @ G, "I", moments)

    assert avg_var(new) > avg_var(make_design("optimal", runs=21, criterion="I")
                                  .generate(space, seed=2))


@pytest.mark.parametrize("options,option", [({"criterion": "A"}, "criterion"),
                                            ({"runs": 0}, "runs"),
                                            ({"augment": "morris"}, "augment"),
                                            ({"starts": 0}, "starts")])
def test_optimal_design_refuses_bad_options(options, option):
    with pytest.raises(DesignError) as err:
        make_design("optimal", **options)
    assert err.value.option == option


def test_too_few_runs_for_eq18_is_an_error_naming_runs():
    # refused when counted (a study's validation), before an exchange that cannot end well
    # (it searched for ever where the runs could not estimate every term)
    with pytest.raises(DesignError, match=r"12 runs cannot estimate Eq\. 18's 15 terms") as err:
        make_design("optimal", runs=12).n_runs(space4())  # 15 coefficients
    assert err.value.option == "runs"
    with pytest.raises(DesignError, match=r"100 runs asked, the grid has 81 points"):
        make_design("optimal", runs=100).n_runs(space4())
    # enough runs, a grid that cannot hold the squares (two levels): the exchange says so
    with pytest.raises(DesignError, match=r"estimates every Eq\. 18 term"):
        make_design("optimal", runs=15, levels=2).generate(space4())
    # with the OAT's 9 runs, 6 more estimate the 15 coefficients
    assert len(make_design("optimal", runs=6, augment="oat").generate(space4())) == 15


def test_the_screen_runs_are_runs_of_the_nominal_grid_not_of_the_papers_grid():
    """The OAT screen's runs of the four variables it selects have the run keys of the same
    runs in the second stage's space (so a second stage that includes them costs nothing
    for them), and they are points of the 3^4 grid whose middle level is the nominal, none of
    the paper's 3^4 grid (middle level the mid-point: the nominal of a factor-10 variable is
    at coded -0.82)."""
    from sensfw.evaluate import make_specs
    from sensfw.study import Study

    study = Study.load(Path(__file__).resolve().parents[2] / "studies" / "paper.toml")
    screen, doe = study.stages
    everything = study.space(screen, None)
    screen_keys = {s.key() for s in make_specs(study, everything,
                                               make_design("oat").generate(everything))}
    space = study.space(doe, TOP4)

    def keys(table):
        return {s.key() for s in make_specs(study, space, table)}

    oat = keys(make_design("oat").generate(space))
    assert len(oat) == 9 and oat <= screen_keys
    assert oat <= keys(make_design("full_factorial", centre="nominal").generate(space))
    assert not oat & keys(make_design("full_factorial").generate(space))
    np.testing.assert_allclose(space.code(pd.DataFrame([space.nominal_row()])).to_numpy(),
                               [[-9 / 11, 0.0, -9 / 11, -9 / 11]], atol=1e-12)


def test_an_oat_augmented_design_counts_the_grid_points_the_oat_leaves():
    """Two variables, ``augment = "oat"``, ``centre = "nominal"``: the OAT's 5 runs are 5 of
    the 3^2 grid's 9 points, so 4 remain. The default asked min(6 + 5, 9) = 9 and
    validation passed it, then the stage failed ('9 runs asked, the grid has 4
    candidates'). Now the plan counts what the stage runs: 5 + 4."""
    space = DesignSpace.from_parameters(PARAMETERS, GROUPS,
                                        select=["slide_stiffness", "slide_damping"])
    d = make_design("optimal", augment="oat", centre="nominal")
    table = d.generate(space, seed=0)
    assert d.n_runs(space) == len(table) == 9
    assert len({tuple(r) for r in table.to_numpy(float)}) == 9
    with pytest.raises(DesignError, match="5 runs asked, the grid has 4 points besides the "
                                          "runs already made"):
        make_design("optimal", augment="oat", centre="nominal", runs=5).n_runs(space)
