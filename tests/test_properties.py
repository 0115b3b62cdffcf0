"""Property-based tests (hypothesis): any input to the study parser or the measurement
loaders gives a valid object or a clean sensfw error, never another exception."""

import copy
import tomllib
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sensfw.errors import SensfwError
from sensfw.measure.io import load
from sensfw.study import Study

ROOT = Path(__file__).resolve().parents[1]
QUICK = tomllib.loads((ROOT / "studies" / "quick.toml").read_text())

scalars = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6),
                    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=12),
                    st.sampled_from(["3 kg", "5 kHz", "1e-5 s", "0.1 N", "N/mm", "", "-1 s",
                                     "nan mm", "1e400 N", "7.05e5 N/mm"]))
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=3), st.dictionaries(st.text(max_size=8), inner, max_size=3)),
    max_leaves=8)


def paths(d, prefix=()):
    if isinstance(d, dict):
        for k, v in d.items():
            yield (*prefix, k)
            yield from paths(v, (*prefix, k))
    elif isinstance(d, list):
        for i, v in enumerate(d):
            yield (*prefix, i)
            yield from paths(v, (*prefix, i))


ALL_PATHS = list(paths(QUICK))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.sampled_from(ALL_PATHS), values), max_size=4))
def test_mutated_study_files_are_valid_or_a_clean_error(mutations):
    data = copy.deepcopy(QUICK)
    for path, value in mutations:
        node = data
        try:
            for part in path[:-1]:
                node = node[part]
            node[path[-1]] = value
        except (KeyError, IndexError, TypeError):
            continue
    try:
        Study.from_dict(data, "mutated.toml")
    except SensfwError:
        pass


@settings(max_examples=100, deadline=None)
@given(st.dictionaries(st.text(max_size=10), values, max_size=6))
def test_arbitrary_documents_are_a_clean_error(data):
    try:
        Study.from_dict(data, "random.toml")
    except SensfwError:
        pass


header = st.lists(st.sampled_from(["time [s]", "force [N]", "crank_axial [m/s^2]", "time",
                                   "force", "a [g]", "b [furlong]", "x [", "force [kg]", ""]),
                  min_size=1, max_size=5)
cells = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(),
                  st.sampled_from(["", "nan", "abc", "1e5", "-0"]))


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(header, st.lists(st.lists(cells, min_size=0, max_size=6), max_size=8),
       st.sampled_from([",", ";"]))
def test_csv_loader_valid_or_clean_error(tmp_path, cols, rows, sep):
    text = sep.join(cols) + "\n" + "\n".join(sep.join(map(str, r)) for r in rows)
    f = tmp_path / "m.csv"
    f.write_text(text)
    try:
        m = load(f)
    except SensfwError as err:
        assert str(f) in str(err)
    else:
        assert len(m.signals.t) == len(m.signals.force) >= 2


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.binary(max_size=300))
def test_uff_loader_valid_or_clean_error(tmp_path, blob):
    f = tmp_path / "m.uff"
    f.write_bytes(blob)
    try:
        load(f)
    except SensfwError as err:
        assert str(f) in str(err)
