"""Every registered design passes the same checks (issue 5: plugin contract)."""

import copy

import numpy as np
import pandas as pd
import pytest

from sensfw.designs import DesignError, make_design
from sensfw.models.shaft_assembly import GROUPS, PARAMETERS
from sensfw.params import DesignSpace
from sensfw.plugins import designs

SPACE = DesignSpace.from_parameters(PARAMETERS, GROUPS, select=[
    "slide_stiffness", "slide_damping", "slide_friction_velocity", "bearing_preload",
    "clutch_drive_stiffness", "spring_stiffness"])


@pytest.mark.parametrize("name", designs.names())
def test_design_contract(name):
    design = make_design(name)
    before = copy.deepcopy(SPACE.variables), copy.deepcopy(SPACE.fixed)
    n = design.n_runs(SPACE)
    a = design.generate(SPACE, seed=3)
    b = design.generate(SPACE, seed=3)
    assert isinstance(a, pd.DataFrame) and len(a) == n
    assert list(a.columns) == SPACE.names and a.index.is_unique
    pd.testing.assert_frame_equal(a, b)  # deterministic for a seed
    lo, hi = SPACE.bounds_array().T
    assert np.all(a.to_numpy() >= lo - 1e-9 * np.abs(lo)) and \
        np.all(a.to_numpy() <= hi + 1e-9 * np.abs(hi))
    assert (SPACE.variables, SPACE.fixed) == before  # the space is not mutated
    # every row maps to a full parameter set inside the bounds
    SPACE.to_parameters(a.iloc[0].to_dict())
    # the analysis of a linear response ranks the dominant variable first
    Z = SPACE.code(a).to_numpy()
    y = 5 * Z[:, 0] + 0.5 * Z[:, 3] + 0.01 * np.sin(np.arange(len(Z)))
    res = design.analyze(SPACE, a, y)
    assert res.ranking[0] == SPACE.names[0], res.table
    with pytest.raises(DesignError, match=f"design '{name}': colour: unknown option; known: "):
        make_design(name, colour="red")


@pytest.mark.parametrize("name", designs.names())
def test_responses_that_are_no_numbers_or_none_at_all_are_analysis_errors(name):
    """Strings were numpy's bare ValueError; no runs at all gave the definitive screening
    design importances of 0 for every variable, and Sobol' a numpy reduction ValueError."""
    from sensfw.errors import AnalysisError

    design = make_design(name)
    table = design.generate(SPACE, seed=3)
    with pytest.raises(AnalysisError, match="responses must be numbers"):
        design.analyze(SPACE, table, np.array(["fast"] * len(table)))
    with pytest.raises(AnalysisError, match="no runs to analyse"):
        design.analyze(SPACE, table.iloc[:0], np.zeros(0))


@pytest.mark.parametrize("name", ["morris", "definitive_screening", "sobol"])
def test_a_table_without_a_variable_is_a_parameter_error(name):
    """The coded analyses raised a bare KeyError: 'slide_damping'."""
    from sensfw.errors import ParameterError

    design = make_design(name)
    table = design.generate(SPACE, seed=3)
    with pytest.raises(ParameterError, match=r"no column for design variable\(s\) "
                                             r"\['slide_damping'\]"):
        design.analyze(SPACE, table.drop(columns="slide_damping"), np.ones(len(table)))
