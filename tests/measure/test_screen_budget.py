"""How the screen splits what is left among the finalists it calibrates on the level
(sensfw/measure/screening.py, :func:`least_shares`): never a better ranked one skipped
while a worse ranked one is calibrated."""

from types import SimpleNamespace

from sensfw.measure.screening import least_shares


def finalists(*ks: int) -> list[SimpleNamespace]:
    return [SimpleNamespace(k=k) for k in ks]


def test_every_finalist_gets_its_least_share_when_the_budget_allows():
    # the leader at least 24 (6 (d + 1), d = 3 base variables), the others 2 k + 2
    assert least_shares(finalists(6, 5, 5), 50, 24) == [24, 12, 12]


def test_a_short_budget_drops_the_lowest_ranked_first():
    # 40 points: the old even split gave the leader 24, the second 16 // 2 = 8 < 14
    # (skipped) and the third the 16 left: the third calibrated, the second not
    assert least_shares(finalists(6, 6, 5), 40, 24) == [24, 14]
    assert least_shares(finalists(6, 6, 5), 37, 24) == [24]
    # the leader always stays: its calibration is what the second look kept room for
    assert least_shares(finalists(6, 6, 5), 10, 24) == [24]
    assert least_shares([], 10, 24) == []


def looked(name: str, score: float) -> SimpleNamespace:
    return SimpleNamespace(name=name, screen={"score": score})


def test_the_fallback_calibrates_looks_that_nearly_tie_with_the_best():
    from sensfw.measure.diagnose import LOOK_TIE, fallback_finalists

    # the README's UNESP-BERT loop, round 2 (stop 48): H0 2646 on the level, first looks
    # 1033 / 1071 / 1079 / 1799: the second gained 98 % of the best's 1613, the fourth
    # 53 %; ``final`` = 2 caps the finalists at two
    race = [looked("friction@clamp", 1033), looked("dry_friction@beam1", 1071),
            looked("added_mass@beam1", 1079), looked("dry_friction@beam2", 1799)]
    names = [h.name for h in fallback_finalists(race, 2646.0, 2)]
    assert names == ["friction@clamp", "dry_friction@beam1"]
    assert len(fallback_finalists(race, 2646.0, 4)) == 4
    # a look that gained less than LOOK_TIE of the best's gain stays out
    far = 2646.0 - 0.9 * LOOK_TIE * 1613
    names = [h.name for h in fallback_finalists([race[0], looked("x", far)], 2646.0, 2)]
    assert names == ["friction@clamp"]
    # the best look gained nothing: the best alone, as before
    assert len(fallback_finalists([looked("a", 3000), looked("b", 3001)], 2646.0, 2)) == 1


class _Level:
    """One level of residuals: ``w0`` where no effect acts; candidate ``good`` removes the
    fraction ``a`` of it (its parameter), ``inert`` nothing. Counts its simulations."""

    def __init__(self, w0):
        import numpy as np

        self.w0, self.np = np.asarray(w0, float), np
        self.n_simulations, self.step, self.failures = 0, "", {}

    def level_slices(self):
        return [slice(0, self.w0.size)]

    def evaluate(self, effects, points, label, levels):
        self.n_simulations += len(points)
        scale = [1.0 - p["a"] if effects == ("good",) else 1.0 for p in points]
        return [s * self.w0 for s in scale]


def _candidate(name):
    axis = SimpleNamespace(name="a", low=0.0, high=1.0)
    effect = SimpleNamespace(name=name, neutral={"a": 0.0},
                             probes=lambda cmp: [{"a": 0.25}, {"a": 0.5}, {"a": 1.0}])
    return SimpleNamespace(name=name, effects=(name,), neutral={"a": 0.0}, effect=effect,
                           coords=SimpleNamespace(axes=[axis]), k=4, notes=[], screen={})


def test_a_first_look_that_gains_the_margin_is_calibrated_when_no_second_look_fits():
    """H0 passes the noise's test (``first_only``) and a first look gains the margin, but
    H0 and the first looks left exactly the calibrations' reserve (3 x 6 (d + 1) = 72
    points, d = 3): no second look fits beside it, and the reserve must go to the first
    looks that gained the margin, not go unspent (recovery seed 2041: looks 11.1 and
    13.5 against H0's 38.8 on the level, nothing calibrated, 108 of 250 simulations
    left, verdict "parameters" where the truth's values give chi2 23.5 against 55.2)."""
    import numpy as np

    from sensfw.measure.screening import screen

    res = _Level(np.full(8, 2.2))  # chi2 38.7 on the level
    h0 = SimpleNamespace(k=3, fit=SimpleNamespace(best=SimpleNamespace(w=res.w0),
                                                   jacobian=None, values={}),
                         coords=SimpleNamespace(axes=[], code=lambda v: np.zeros(3),
                                                  decode=lambda z: {}))
    hyps = [_candidate("inert"), _candidate("good"), _candidate("inert")]
    calibrated = []

    def calibrate_on(h, points, levels):
        calibrated.append((h.name, points))
        res.n_simulations += points
        return SimpleNamespace(chi2=0.5, values={"a": 1.0}, n_points=points,
                               best=SimpleNamespace(w=np.full(8, 0.25)))

    ranked = screen(res, h0, hyps, None, 0, calibrate_on, budget=len(hyps) + 72,
                    first_only=True)
    # the good candidate's first look (a = 0.5, scaled to a = 1 by the linearised fit)
    # reaches 0 against 38.7: it alone gained the margin, and gets the whole reserve
    assert calibrated == [("good", 72)]
    assert ranked[0].name == "good" and ranked[0].screen["calibrated"] == 0.5
    assert res.n_simulations == len(hyps) + 72


class _Race(_Level):
    """Candidates a1 and a2 remove the fraction ``0.9 a`` and ``0.8 a`` of ``w0``."""

    def evaluate(self, effects, points, label, levels):
        self.n_simulations += len(points)
        e = {"a1": 0.9, "a2": 0.8}.get(effects[0], 0.0)
        return [(1.0 - e * p["a"]) * self.w0 for p in points]


def _race(leader_chi2: float, monkeypatch):
    """A race whose second looks (``min_second`` = 1, ten inert candidates) spent the room
    of every calibration but the leader's; the stubbed calibration on the level ends at
    ``leader_chi2`` for the leader (8 entries) and at 2 for the runner-up."""
    import numpy as np

    from sensfw.measure import screening

    # the second look's surrogate (a Gaussian process on the runs) is not what is tested
    monkeypatch.setattr(screening, "_predict", lambda res, h, levels: h.screen.update(
        predicted=h.screen["score"], bound=0.0))
    res = _Race(np.full(8, 10.0))  # chi2 800 on the level
    h0 = SimpleNamespace(k=3, fit=SimpleNamespace(best=SimpleNamespace(w=res.w0),
                                                   jacobian=None, values={}),
                         coords=SimpleNamespace(axes=[], code=lambda v: np.zeros(3),
                                                  decode=lambda z: {}))
    hyps = [_candidate("a1"), _candidate("a2")] + [_candidate(f"inert{i}") for i in range(10)]
    calibrated = []

    def calibrate_on(h, points, levels):
        calibrated.append((h.name, points))
        res.n_simulations += points
        chi2 = leader_chi2 if h.name == "a1" else 2.0
        return SimpleNamespace(chi2=chi2, values={"a": 1.0}, n_points=points,
                               best=SimpleNamespace(w=np.full(8, np.sqrt(chi2 / 8))))

    # first looks 12; the leader's second look 3 beside the reserve of ``keep`` = 2
    # calibrations (2 x 24), the runner-up's 3 and the inert ones' 2 each while one
    # calibration's 24 stays: the race has 24 to 26 left
    budget = 12 + 3 + 48
    ranked = screening.screen(res, h0, hyps, None, 0, calibrate_on, budget=budget,
                              keep=2, min_second=1)
    return res, ranked, calibrated, budget


def test_a_race_whose_leader_misses_the_noise_calibrates_the_next_finalist(monkeypatch):
    """Recovery seeds 2069 and 2072 (stop 55): the truth among the finalists, but the
    second looks had spent the room of all calibrations on the level but the leader's,
    whose calibration ended at chi2 6996 and 1162 on a level of about 43 entries; the
    wrong effect was named. A leader that misses the noise on the level (chi-square test
    at 1e-3, and more chi2 per entry than a true hypothesis leaves) must not end the race:
    the next finalist gets the leader's points, beyond the budget, and is counted as
    such."""
    from scipy.stats import chi2 as chi2_dist

    from sensfw.measure.screening import TRUTH_PER_ENTRY

    # chi2 72 for 8 entries and k = 4: above the 0.999 quantile with 4 degrees of freedom
    # and above what a true hypothesis leaves per entry
    assert 72.0 > chi2_dist.ppf(0.999, 4) and 72.0 > TRUTH_PER_ENTRY * 8
    res, ranked, calibrated, budget = _race(72.0, monkeypatch)
    (lead, share), (second, points) = calibrated
    assert (lead, second) == ("a1", "a2") and points == share and 24 <= share <= 26
    assert ranked[0].name == "a2" and ranked[0].screen["calibrated"] == 2.0
    assert ranked[0].screen["beyond_budget"] == share
    assert res.n_simulations == budget + share


def test_a_race_whose_leader_reaches_the_noise_ends_with_it(monkeypatch):
    # chi2 8 for 8 entries: the leader explains the level, the runner-up stays a look
    res, ranked, calibrated, budget = _race(8.0, monkeypatch)
    assert [name for name, _ in calibrated] == ["a1"]
    # chi2 30 for 8 entries fails the chi-square test (18.5 with 4 degrees of freedom) but
    # leaves less per entry than a true hypothesis may (recovery seed 2045: the truth's
    # calibration at 77.6 for 43 entries cost 541 more simulations with the bare test)
    res, ranked, calibrated, budget = _race(30.0, monkeypatch)
    assert [name for name, _ in calibrated] == ["a1"]
    a2 = next(h for h in ranked if h.name == "a2")
    assert "calibrated" not in a2.screen and "beyond_budget" not in a2.screen
    assert any("budget was spent" in note for note in a2.notes)
    assert res.n_simulations <= budget
