"""sensfw compare-designs on the quick study (issue 5, item 3)."""

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_compare_designs_writes_table_and_plot(quick, cli):
    out, _ = quick  # shares the quick study's run store: its OAT runs are reused
    proc = cli("compare-designs", ROOT / "studies" / "quick.toml", "--out", out,
               "--designs", "oat,morris,definitive_screening,fractional_factorial",
               "--option", "morris.trajectories=2", "--reference-runs", "20",
               "--no-progress", timeout=600)
    assert proc.returncode == 0, proc.stderr
    data = json.loads((out / "designs.json").read_text())
    by = {d["design"]: d for d in data["designs"]}
    assert set(by) == {"oat", "morris", "definitive_screening", "fractional_factorial"}
    k = len(data["variables"])
    assert by["oat"]["runs"] == 2 * k + 1
    assert by["morris"]["runs"] == 2 * (k + 1)
    assert by["definitive_screening"]["runs"] == 13  # 5 variables: order-6 conference matrix
    for d in by.values():
        assert sorted(d["ranking"]) == sorted(data["variables"])
        assert 0.0 <= d["top_k_overlap"] <= 1.0
    ref = data["reference"]
    assert ref["runs"] == 20 and ref["q2_kfold"] is not None  # its Q2 is stated
    assert sorted(ref["ranking"]) == sorted(data["variables"])
    html = (out / "designs.html").read_text()
    assert "Kendall tau" in html and "data:image/png;base64" in html
    # the study report next to it is untouched
    assert "sensfw study report" in (out / "report.html").read_text()
