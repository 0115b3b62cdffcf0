"""Every registered surrogate passes the scikit-learn contract checks (issue 5)."""

import numpy as np
import pandas as pd
import pytest
from sklearn.base import clone

from sensfw.errors import SensfwError
from sensfw.plugins import surrogates
from sensfw.surrogates import make_surrogate

rng = np.random.default_rng(0)
X = pd.DataFrame(rng.uniform(-1, 1, (40, 3)), columns=["a", "b", "c"])
Y = 1 + 2 * X["a"] - X["b"] ** 2 + 0.5 * X["a"] * X["c"] + 0.01 * rng.standard_normal(40)


@pytest.mark.parametrize("name", surrogates.names())
def test_surrogate_contract(name):
    est = make_surrogate(name)
    Xc, yc = X.copy(), Y.copy()
    assert est.fit(X, Y) is est
    pd.testing.assert_frame_equal(X, Xc)  # inputs not mutated
    pd.testing.assert_series_equal(Y, yc)
    pred = est.predict(X)
    assert pred.shape == (40,)
    assert np.sqrt(np.mean((pred - Y) ** 2)) < 0.5 * np.std(Y)  # it learned something
    again = clone(est).fit(X, Y).predict(X)
    np.testing.assert_allclose(again, pred, rtol=1e-8, atol=1e-10)  # deterministic
    assert list(est.feature_names_in_) == ["a", "b", "c"]
    bad = X.copy()
    bad.iloc[3, 1] = np.nan
    with pytest.raises(SensfwError, match="NaN"):
        clone(est).fit(bad, Y)
    with pytest.raises((SensfwError, TypeError)):
        make_surrogate(name, colour="red")
