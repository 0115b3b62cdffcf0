"""The screen is informative (issue 3, item 4): an OAT screen of the 19 design variables of
Table 1, scored by the FRF scalar, keeps between 3 and 12 variables above 10 %
normalised sensitivity (the paper kept 6). Here with a 0.25 s chirp for CI time; the 1 s
chirp of the paper's study is run by bench/paper.py."""

import json
import tomllib
from pathlib import Path

import pytest
from tomlkit import dumps

pytestmark = pytest.mark.slow  # a 39-run screen of the shaft model

ROOT = Path(__file__).resolve().parents[2]


def test_oat_screen_of_19_variables_is_informative(cli, tmp_path):
    data = tomllib.loads((ROOT / "studies" / "paper.toml").read_text())
    data["excitation"]["duration"] = "0.25 s"
    data["stages"] = data["stages"][:1]
    data["stages"][0]["select"]["max_variables"] = 19
    f = tmp_path / "screen.toml"
    f.write_text(dumps(data))
    proc = cli("run", f, "--out", tmp_path / "o", "--workers", 2, "--no-progress",
               "--no-report", timeout=600)
    assert proc.returncode == 0, proc.stderr
    st = json.loads((tmp_path / "o" / "results.json").read_text())["stages"][0]
    assert st["n_runs"] == 39 and not st["failed"]
    above = [v for v, s in st["sensitivity"].items() if s > 0.10]
    assert 3 <= len(above) <= 12, st["sensitivity"]
    assert above and set(st["selected"]) == set(above)
