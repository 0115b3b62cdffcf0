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
