"""Model against measurement with a hidden physical effect (issue 6): diagnose names it,
augment calibrates it down to the noise floor; noise alone gives no verdict; two excitation
levels reveal and use the amplitude dependence."""

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from sensfw.measure.diagnose import Evaluator, augment, diagnose, rms
from sensfw.measure.io import write_csv
from sensfw.measure.session import Variant, load_measurements
from sensfw.measure.synthetic import synthesize
from sensfw.plugins import effects
from sensfw.runs import Runner, RunStore
from sensfw.study import Study

pytestmark = pytest.mark.slow  # calibrations with many shaft simulations

ROOT = Path(__file__).resolve().parents[2]
NOISE = 0.02  # noise std as a fraction of each channel's RMS
EFFECTS = ["friction", "contact_hardening", "preload", "added_mass", "flexible_mode",
           "damping"]


def short_quick() -> dict:
    """The quick study with a 0.15 s chirp and a 2e-5 s step (CI time; the synthetic
    measurements use the same settings, so the comparison is consistent)."""
    data = tomllib.loads((ROOT / "studies" / "quick.toml").read_text())
    data["excitation"]["duration"] = "0.15 s"
    data["solver"]["step"] = "2e-5 s"
    return data


@pytest.fixture(scope="module")
def study():
    return Study.from_dict(short_quick(), "quick-short")


@pytest.fixture(scope="module")
def runner(tmp_path_factory):
    with Runner(RunStore(tmp_path_factory.mktemp("runs")), backend="processes",
                workers=2) as r:
        yield r


def hidden_values(name: str, rng) -> dict[str, float]:
    """A random value inside each parameter's bounds (log-uniform over factor-10 ranges)."""
    out = {}
    for p in effects.get(name)().parameters():
        if p.min > 0 and p.max >= 10 * p.min:
            out[p.name] = float(np.exp(rng.uniform(np.log(p.min), np.log(p.max))))
        else:
            out[p.name] = float(rng.uniform(p.min, p.max))
    return out


def measurement(study, tmp_path, effect_text, seed, amplitude=None, name="m.csv"):
    sig, info = synthesize(study, effects=[effect_text] if effect_text else [],
                           noise=NOISE, seed=seed, amplitude=amplitude)
    return write_csv(tmp_path / name, sig, level=info["amplitude"])


@pytest.mark.parametrize("name", EFFECTS)
def test_hidden_effect_is_found_and_calibrated_to_the_noise_floor(name, study, runner,
                                                                   tmp_path):
    rng = np.random.default_rng(EFFECTS.index(name) + 11)
    truth = hidden_values(name, rng)
    text = name + ":" + ",".join(f"{k}={v!r}" for k, v in truth.items())
    meas = load_measurements(study, [str(measurement(study, tmp_path, text, seed=5))])
    result = diagnose(study, meas, runner)
    assert result["ranking"][0]["effect"] == name, [
        (r["effect"], round(r["error_after"], 3)) for r in result["ranking"][:3]]
    aug = augment(study, meas, runner, name, start=result["ranking"][0]["params"])
    # noise floor: the true model against the same noisy data
    spec = effects.get(name)().spec()
    floor = rms(Evaluator(study, meas, runner).evaluate([Variant.of([spec], truth)],
                                                        "truth")[0])
    errors = [t["error"] for t in aug["trajectory"]]
    assert errors[-1] <= 1.5 * floor, (errors, floor, aug["params"], truth)
    assert errors[-1] < errors[0]
    # the verdict names it unless the hidden value is too weak to stand out of the noise
    assert result["verdict"] == name or errors[0] < 3 * floor, (result["verdict"], errors,
                                                                floor)


def test_noise_only_gives_no_verdict(study, runner, tmp_path):
    meas = load_measurements(study, [str(measurement(study, tmp_path, None, seed=9))])
    result = diagnose(study, meas, runner)
    assert result["verdict"] == "none", [(r["effect"], r["delta_bic"], r["reduction"])
                                         for r in result["ranking"][:3]]
    assert result["n_simulations"] > 0


def test_two_levels_amplitude_dependence_reported_and_used(study, runner, cli, tmp_path):
    text = "contact_hardening:hardening_exponent=1.7"
    files = [measurement(study, tmp_path, text, seed=1, amplitude=0.05, name="lo.csv"),
             measurement(study, tmp_path, text, seed=2, amplitude=0.2, name="hi.csv")]
    study_file = tmp_path / "s.toml"
    from tomlkit import dumps

    study_file.write_text(dumps(short_quick()))
    args = [a for f in files for a in ("-m", f)]
    proc = cli("compare", study_file, *args, "--out", tmp_path / "cmp", "--no-progress")
    assert proc.returncode == 0, proc.stderr
    cmp = json.loads((tmp_path / "cmp" / "compare.json").read_text())
    assert [lv["level"] for lv in cmp["levels"]] == pytest.approx([0.05, 0.2], rel=1e-6)
    amp = cmp["amplitude_dependence"]
    assert amp["thd_ratio"]["measured"] > 2.0  # harmonics grow faster than the level
    assert any("nonlinear" in line for line in amp["summary"])
    meas = load_measurements(study, [str(f) for f in files])
    result = diagnose(study, meas, runner,
                      candidates=["contact_hardening", "added_mass", "preload", "damping"])
    assert result["verdict"] == "contact_hardening"
    # both levels enter the discrepancy: the baseline comparison has one entry per level
    assert len(result["baseline"]["comparison"]) == 2


def test_augment_start_from_a_diagnose_file_without_the_effect_is_a_clear_error(
        study, cli, tmp_path):
    meas = measurement(study, tmp_path, None, seed=3)
    study_file = tmp_path / "s.toml"
    from tomlkit import dumps

    study_file.write_text(dumps(short_quick()))
    diag = tmp_path / "diagnose.json"
    diag.write_text(json.dumps({"ranking": [{"effect": "damping", "attach": "slide",
                                             "params": {"damping_factor": 2.0}}]}))
    proc = cli("augment", study_file, "-m", meas, "--effect", "friction", "--start-from",
               diag, "--out", tmp_path / "aug", "--no-progress")
    assert proc.returncode == 2, proc.stderr
    assert "diagnose.json" in proc.stderr and "'friction'" in proc.stderr
    assert "Traceback" not in proc.stderr
    diag.write_text("{not json")
    proc = cli("augment", study_file, "-m", meas, "--effect", "friction", "--start-from",
               diag, "--out", tmp_path / "aug", "--no-progress")
    assert proc.returncode == 2 and "diagnose.json" in proc.stderr, proc.stderr
    assert "not a readable diagnose.json" in proc.stderr and "Traceback" not in proc.stderr
