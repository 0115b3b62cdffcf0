"""Property-based tests (hypothesis): any input to the study parser or the measurement
loaders gives a valid object or a clean sensfw error, never another exception; an invalid
plugin option is reported at its dotted path."""

import copy
import tomllib
from pathlib import Path

from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from sensfw.errors import SensfwError, StudyError
from sensfw.measure.io import load
from sensfw.plugins import designs
from sensfw.study import Study

ROOT = Path(__file__).resolve().parents[1]
QUICK = tomllib.loads((ROOT / "studies" / "quick.toml").read_text())
# the options each stage's design knows (an "unknown option" must be none of them)
KNOWN_DESIGN_OPTIONS = [set(designs.get(stage["design"]).Options.model_fields)
                        for stage in QUICK["stages"][:2]]

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


names = st.text(alphabet="abcdefghijklmnopqrstuvwxyz_", min_size=1, max_size=10)
not_int = st.one_of(st.floats(allow_nan=True), st.text(max_size=5), st.none(),
                    st.lists(st.integers(), max_size=2), st.booleans())


def _set(*path, value):
    def apply(data):
        node = data
        for part in path[:-1]:
            node = node[part]
        node[path[-1]] = value
    return apply


@st.composite
def bad_option(draw):
    """(mutation, dotted path, fragment of the message) of one invalid option of the quick
    study (stage 0: oat + frf_scalar; stage 1: full_factorial + order_amplitude x2, thd +
    eq18)."""
    kind = draw(st.sampled_from(["design_key", "levels", "band", "order", "scorer_key",
                                 "interaction", "surrogate_key", "thd_unit"]))
    if kind == "design_key":
        i = draw(st.sampled_from([0, 1]))
        key = draw(names.filter(lambda k: k not in KNOWN_DESIGN_OPTIONS[i]))
        return (lambda d: d["stages"][i].setdefault("design_options", {}).__setitem__(key, 1),
                f"stages[{i}].design_options.{key}", "unknown option; known: ")
    if kind == "levels":  # an integer >= 2 (or a list of them per variable)
        v = draw(st.one_of(st.integers(max_value=1), st.floats(allow_nan=True),
                           st.text(max_size=5), st.none()))
        return _set("stages", 1, "design_options", "levels", value=v), \
            "stages[1].design_options.levels", "levels must be"
    if kind == "band":  # must be 0 <= lo < hi, inside the sweep 50 Hz .. 5 kHz
        lo = draw(st.one_of(st.floats(allow_nan=True), st.integers(-10, 10**5)))
        hi = draw(st.one_of(st.floats(allow_nan=True), st.integers(-10, 10**5)))
        assume(not 50 <= lo < hi <= 5000)
        return _set("stages", 0, "scorers", 0, "band", value=[lo, hi]), \
            "stages[0].scorers[0].band", "band"
    if kind == "order":  # an integer >= 1
        v = draw(st.one_of(st.integers(max_value=0), not_int))
        return _set("stages", 1, "scorers", 1, "order", value=v), \
            "stages[1].scorers[1].order", "order must be an integer >= 1"
    if kind == "scorer_key":
        key = draw(names.filter(lambda k: k not in ("name", "label", "channel", "n_harmonics",
                                                    "unit", "detrend")))
        return _set("stages", 1, "scorers", 2, key, value=1), \
            f"stages[1].scorers[2].{key}", "unknown option; known: detrend, n_harmonics, unit"
    if kind == "thd_unit":
        v = draw(st.text(max_size=6).filter(lambda u: u not in ("percent", "dBc")))
        return _set("stages", 1, "scorers", 2, "unit", value=v), \
            "stages[1].scorers[2].unit", "unit must be"
    if kind == "interaction":
        v = draw(st.one_of(st.text(max_size=8), st.integers(), st.none())
                 .filter(lambda x: x not in ("product", "ratio")))
        return _set("stages", 1, "surrogates", 0, value={"name": "eq18", "interaction": v}), \
            "stages[1].surrogates[0].interaction", "interaction must be 'product' or 'ratio'"
    key = draw(names.filter(lambda k: k not in ("name", "label", "interaction", "coding",
                                                "bounds", "log_features", "log_response")))
    return _set("stages", 1, "surrogates", 0, value={"name": "eq18", key: 1}), \
        f"stages[1].surrogates[0].{key}", "unknown option; known: bounds, coding"


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(bad_option(), min_size=1, max_size=4, unique_by=lambda m: m[1]))
def test_every_invalid_option_is_reported_at_its_path(mutations):
    # the surrogate mutations replace the same list entry: keep one of them
    sur = [m for m in mutations if m[1].startswith("stages[1].surrogates")]
    mutations = [m for m in mutations if m not in sur[1:]]
    data = copy.deepcopy(QUICK)
    for apply, _, _ in mutations:
        apply(data)
    try:
        Study.from_dict(data, "mutated.toml")
    except StudyError as err:
        got = dict(err.problems)
    else:
        raise AssertionError(f"accepted {[m[1] for m in mutations]}")
    for _, path, fragment in mutations:
        assert path in got, (path, got)
        assert fragment in got[path], (path, got[path])


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
