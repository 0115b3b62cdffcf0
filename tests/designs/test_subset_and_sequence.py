"""The 3-level fractions, Table 2's printed medium values and uncertainty sampling (issue 28)."""

import numpy as np
import pandas as pd
import pytest

from sensfw.designs import DesignError, make_design
from sensfw.designs.sequential import propose, uncertainty
from sensfw.models.shaft_assembly import GROUPS, PARAMETERS
from sensfw.params import DesignSpace

TABLE2 = ["slide_damping", "clutch_drive_stiffness", "slide_friction_velocity",
          "clutch_drive_damping"]


def table2_space():
    bounds = {"slide_damping": {"min": 1.0, "nominal": 117.5, "max": 234.0},
              "clutch_drive_stiffness": {"min": 2.83e6, "nominal": 3.16e6, "max": 3.45e6},
              "slide_v_friction": {"min": 0.1, "nominal": 5.05, "max": 10.0},
              "slide_v_stiction": {"min": 0.01, "nominal": 0.505, "max": 1.0},
              "clutch_drive_damping": {"min": 1.0, "nominal": 258.0, "max": 514.6}}
    return DesignSpace.from_parameters(PARAMETERS, GROUPS, select=TABLE2, bounds=bounds)


def test_full_factorial_with_the_printed_medium_values_of_table_2():
    space = table2_space()
    table = make_design("full_factorial", centre="nominal").generate(space)
    assert len(table) == 81
    # Table 2 as printed: 3.16e6 is not the mid-point (3.14e6) of the clutch stiffness
    assert sorted(set(table["clutch_drive_stiffness"])) == [2.83e6, 3.16e6, 3.45e6]
    assert sorted(set(table["clutch_drive_damping"])) == [1.0, 258.0, 514.6]
    mid = make_design("full_factorial").generate(space)
    assert sorted(set(mid["clutch_drive_stiffness"]))[1] == pytest.approx(3.14e6)
    # the stiction velocity is 10 % of the friction velocity at every level (footnote)
    for v in sorted(set(table["slide_friction_velocity"])):
        full = space.to_parameters({**table.iloc[0].to_dict(), "slide_friction_velocity": v})
        assert full["slide_v_stiction"] == pytest.approx(0.1 * full["slide_v_friction"])
    # five levels: the middle one at the nominal, evenly spaced on either side
    five = make_design("full_factorial", levels=5, centre="nominal").grids(space)[1]
    np.testing.assert_allclose(five, [2.83e6, 2.995e6, 3.16e6, 3.305e6, 3.45e6])
    with pytest.raises(DesignError, match="odd number of levels") as err:
        make_design("full_factorial", levels=4, centre="nominal")
    assert err.value.option == "centre"


def test_subset_fractions_partition_the_full_factorial_and_are_balanced():
    space = table2_space()
    full = make_design("full_factorial").generate(space)
    rows = {tuple(r) for r in full.to_numpy()}
    parts = [make_design("subset", fraction=f).generate(space) for f in range(3)]
    assert [len(p) for p in parts] == [27, 27, 27]
    got = [tuple(r) for p in parts for r in p.to_numpy()]
    assert sorted(got) == sorted(rows)  # the three fractions are the 81 runs, once each
    for p in parts:  # balanced: every level of every factor 9 times
        for col in p:
            assert p[col].value_counts().tolist() == [9, 9, 9]
    # in the first fraction the last level index is the sum of the others' mod 3
    idx = make_design("subset").generate(space)
    levels = [np.searchsorted(sorted(set(full[c])), idx[c]) for c in idx]
    assert np.all((levels[0] + levels[1] + levels[2] - levels[3]) % 3 == 0)
    assert make_design("subset").n_runs(space) == 27
    with pytest.raises(DesignError, match="fraction must be"):
        make_design("subset", fraction=3)


@pytest.mark.parametrize("design,options", [("box_behnken", {}),
                                            ("central_composite", {"center": [1, 0]}),
                                            ("definitive_screening", {}), ("subset", {})])
def test_three_level_designs_are_runs_of_the_full_factorial(design, options):
    """Coded -1 / 0 / 1 are the bounds and the mid-point exactly: mid + c * half misses
    1.2 (slide_exponent) by 2e-16, and a run at 1.2000000000000002 is another run in the
    run store than the full factorial's at 1.2 (and lies outside the bounds)."""
    space = DesignSpace.from_parameters(PARAMETERS, GROUPS, select=[
        "slide_stiffness", "slide_exponent", "slide_friction_velocity",
        "clutch_drive_stiffness"])
    assert space["slide_exponent"].decode(-1.0) != 1.2  # the rounding this guards against
    full = {tuple(r) for r in make_design("full_factorial").generate(space).to_numpy()}
    table = make_design(design, **options).generate(space)
    assert all(tuple(r) in full for r in table.to_numpy())
    assert table["slide_exponent"].min() == 1.2 and table["slide_friction_velocity"].min() == 0.1


def test_uncertainty_sampling_picks_the_candidate_farthest_from_the_runs():
    grid = pd.DataFrame({"x": np.linspace(-1, 1, 9)}, index=[f"g{i}" for i in range(9)])
    runs = pd.DataFrame({"x": [-1.0, -0.9, -0.8]}, index=["r0", "r1", "r2"])
    y = pd.DataFrame({"a": np.sin(3 * runs["x"]), "b": 10 + 100 * runs["x"] ** 2})
    # runs bunched at one end: a stationary GP is least certain at the other end, and
    # (noise-free) certain at a run
    fast = {"noise": False, "n_restarts_optimizer": 0}
    u = uncertainty(runs, y, grid, bounds=[(-1, 1)], options=fast)
    assert u.idxmax() == "g8" and u["g0"] < 1e-3 * u["g8"]
    assert np.all(np.diff(u.to_numpy()[2:]) > 0)  # grows with the distance from the runs
    nxt = propose(runs, y, grid, n=1, bounds=[(-1, 1)], options=fast)
    assert list(nxt.index) == ["g8"]
    # a candidate already run (g0 = -1) is never proposed again
    assert set(propose(runs, y, grid, n=20, options=fast).index) == set(grid.index) - {"g0"}


@pytest.mark.parametrize("name", ["central_composite", "subset"])
def test_a_design_of_two_or_more_variables_refuses_one(name):
    """pyDOE3 asserted ('"n" must be an integer greater than 1', 'Orthogonal array
    indexing does not match partition structure'): a traceback in ``validate``."""
    one = DesignSpace.from_parameters(PARAMETERS, GROUPS, select=["slide_damping"])
    with pytest.raises(DesignError, match=rf"'{name}' needs at least 2 variables, got 1"):
        make_design(name).n_runs(one)


@pytest.mark.parametrize("name", ["full_factorial", "subset", "optimal"])
def test_a_nominal_centre_on_a_bound_is_refused(name):
    """``centre = "nominal"`` with a nominal on its min: the levels were [min, min, max],
    9 runs planned, 6 distinct, and Eq. 18 then refused the squares."""
    bounds = {"slide_damping": {"min": 1.0, "nominal": 1.0, "max": 468.0}}
    space = DesignSpace.from_parameters(PARAMETERS, GROUPS,
                                        select=["slide_damping", "slide_stiffness"],
                                        bounds=bounds)
    with pytest.raises(DesignError, match=r"slide_damping has it on a bound") as info:
        make_design(name, centre="nominal").n_runs(space)
    assert info.value.option == "centre"
