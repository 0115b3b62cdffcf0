"""Every registered scorer passes the same checks (issue 5: plugin contract)."""

import copy

import numpy as np
import pytest

from sensfw.errors import SensfwError
from sensfw.excitation import Chirp
from sensfw.models.analytic import TwoDOF
from sensfw.plugins import scorers
from sensfw.scorers import Scorer, make_scorer

EX = Chirp(50, 2000, 0.3, 20000, 1.0, tail=0.05)


@pytest.fixture(scope="module")
def runs():
    m = TwoDOF()
    p = m.parameters().nominal()
    stiffer = dict(p, k1=5000.0)
    return m.simulate(p, EX), m.simulate(stiffer, EX)


@pytest.mark.parametrize("name", scorers.names())
def test_scorer_contract(name, runs):
    ref, run = runs
    s = make_scorer(name, channel="a1")
    assert isinstance(s, Scorer) and s.outputs
    before = copy.deepcopy(run.channels), copy.deepcopy(ref.channels)
    a = s.score(run, ref)
    b = make_scorer(name, channel="a1").score(run, ref)
    assert set(a) == set(s.outputs)
    assert all(np.isfinite(v) for v in a.values())
    assert a == b  # deterministic
    for ch in run.channels:  # inputs not mutated
        assert np.array_equal(run.channels[ch], before[0][ch])
        assert np.array_equal(ref.channels[ch], before[1][ch])
    if s.needs_reference:
        assert all(v == 0 for v in s.score(ref, ref).values())  # no change against itself
    with pytest.raises(SensfwError, match=f"scorer '{name}': colour: unknown option; known: "):
        make_scorer(name, colour="red")
