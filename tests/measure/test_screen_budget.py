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
