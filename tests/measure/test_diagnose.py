"""Diagnosis when the model's own parameters are also off (issue 16): synthetic measurements
of the quick study with base parameters off their nominal values, with or without a hidden
effect at a chosen place, and rig noise. The base parameters are recalibrated with every
hypothesis; the verdict is "parameters", an effect at a place, or "none".

The hand-picked verdict cases live in ``bench/verdicts.py`` (each a verdict that once failed
or that a change once broke); the suite runs the ones it marks ``suite``, the script runs
them all (README, "Benchmarks"). Every diagnosis here names a few candidates (the truth, the
same effect at another place, and other effects) to keep the suite's time in bounds;
``bench/recovery.py`` runs the full candidate set on random cases.
"""

import json
import tomllib
from pathlib import Path

import bench_modules
import numpy as np
import pytest

from sensfw.measure.diagnose import diagnose
from sensfw.measure.io import write_csv
from sensfw.measure.prepared import load_measurements
from sensfw.measure.synthetic import Rig, synthesize
from sensfw.runs import Runner, RunStore
from sensfw.study import Study

pytestmark = pytest.mark.slow


VERDICTS = bench_modules.load("verdicts")
OFFSETS, CALIBRATED = VERDICTS.OFFSETS, VERDICTS.CALIBRATED
short_quick, measure = VERDICTS.short_quick, VERDICTS.measure


@pytest.fixture(scope="module")
def study():
    return VERDICTS.study()


@pytest.fixture(scope="module")
def runner(tmp_path_factory):
    with Runner(RunStore(tmp_path_factory.mktemp("runs")), backend="processes",
                workers=2) as r:
        yield r


def check_nested(result):
    """No calibrated candidate ends worse than the hypothesis it extends (each starts where
    it vanishes exactly, and only improving steps are taken)."""
    assert not VERDICTS.nested(result), (VERDICTS.nested(result), result.rows[0]["chi2"])


def test_offsets_without_an_effect_give_parameters_and_recover_them(study, runner, tmp_path):
    meas = measure(study, tmp_path)
    res = diagnose(study, meas, runner, candidates=["added_mass@crankshaft",
                                                    "damping@bearing_l3",
                                                    "preload@crankshaft"])
    assert res.verdict == "parameters", (res.reason, [(r["hypothesis"], r["chi2"])
                                                      for r in res.rows])
    values = {c["name"]: c for c in res.rows[0]["calibration"]}
    for name, truth in CALIBRATED.items():
        assert values[name]["value"] == pytest.approx(truth, rel=0.15), values[name]
    # the recalibrated parameters explain the records to their noise (the chi-square test
    # the verdict uses, 3 variables); the RMS dB error over every entry is no reference for
    # it: on one machine it was below half the nominal model's, on another (other round-off)
    # the same calibration, 0.04-1.4 % from the true values, reads 1.68 dB against the true
    # values' 0.31 dB, in entries the calibration's standard errors discount (chi2 5.1)
    from scipy.stats import chi2 as chi2_dist

    assert res.rows[0]["chi2"] <= chi2_dist.ppf(1 - 1e-3, res.n_entries - 3)
    assert res.errors["parameters"] < res.errors["nominal"]
    check_nested(res)
    # every simulation is counted against one step of the method, H0's calibration and
    # the screen's first look among them
    assert sum(res.simulations_by_step.values()) == res.n_simulations
    assert {"H0", "first look"} <= set(res.simulations_by_step)


def test_calibrate_recovers_the_offsets_in_two_searches(study, runner, tmp_path):
    """``sensfw calibrate`` (``recalibrate``, two searches of 30 points) on the offsets-only
    record: the base values recovered as diagnosis's H0 recovers them (within 15 %), the
    fit within the noise, the budget held."""
    from sensfw.measure.recalibrate import recalibrate

    log = []
    out = recalibrate(study, measure(study, tmp_path), runner, log=log.append)
    for name, truth in CALIBRATED.items():
        assert out["params"][name] == pytest.approx(truth, rel=0.15), (name, out["params"])
    assert out["fits_noise"], out["chi2"]
    # on top of the budget: the nominal and the calibrated model's runs, and the model's
    # scatter around the optimum (2 d, d variables)
    assert out["n_simulations"] <= out["budget"] + 2 + 2 * len(out["variables"])
    assert any("local searches from the design" in line for line in log)


SUITE = [c for c in VERDICTS.CASES if c.suite]


@pytest.mark.parametrize("case", SUITE, ids=[c.id for c in SUITE])
def test_a_verdict_case_ends_as_expected(case, study, runner, tmp_path):
    """An effect at a place named (and the best fit better than the base parameters'), or
    noise and offsets alone giving "parameters" or "none", never an effect."""
    res = VERDICTS.run(case, study, runner, tmp_path)
    wrong = VERDICTS.problems(case, res)
    assert not wrong, (wrong, [(r["hypothesis"], round(r["chi2"], 1)) for r in res.rows])


def test_cli_diagnose_and_augment_write_the_calibrated_study(study, cli, tmp_path):
    """The commands end to end on a flexible mode measured at two levels: diagnose.json
    names it, with the held-out-level error of each calibrated hypothesis next to its BIC;
    augment starts from it, writes a study with the effect, its values and [calibration]
    (the base variables and the effect's parameters),
    and the error falls at each level along nominal -> base recalibrated -> jointly
    calibrated."""
    import tomlkit

    hidden = "flexible_mode@driveshaft:flex_frequency=1800,flex_damping=0.02,flex_mass=0.03"
    files = []
    for i, level in enumerate((0.05, 0.1)):
        sig, _ = synthesize(study, sets=OFFSETS, effects=[hidden], amplitude=level,
                            rig=Rig(noise=0.02, seed=5 + i))
        files += ["-m", write_csv(tmp_path / f"m{i}.csv", sig, level=level)]
    study_file = tmp_path / "s.toml"
    study_file.write_text(tomlkit.dumps(short_quick()))
    proc = cli("diagnose", study_file, *files, "--out", tmp_path / "d", "--no-progress",
               "--candidates", "flexible_mode@driveshaft", "--budget", 150,
               timeout=1800)
    assert proc.returncode == 0, proc.stderr
    diag = json.loads((tmp_path / "d" / "diagnose.json").read_text())
    assert diag["verdict"] == "flexible_mode@driveshaft"
    winner = next(r for r in diag["ranking"] if r["hypothesis"] == diag["verdict"])
    assert winner["heldout_chi2_per_entry"] < diag["parameters_only"]["heldout_chi2_per_entry"]
    html = (tmp_path / "d" / "report.html").read_text()
    assert "data:image/png;base64" in html and "held-out" in html
    assert sum(diag["simulations_by_step"].values()) == diag["n_simulations"]
    proc = cli("augment", study_file, *files, "--effect", "flexible_mode@driveshaft",
               "--start-from", tmp_path / "d" / "diagnose.json", "--out", tmp_path / "a",
               "--budget", 120, "--no-progress", timeout=1800)
    assert proc.returncode == 0, proc.stderr
    aug = json.loads((tmp_path / "a" / "augment.json").read_text())
    steps = {t["step"]: t for t in aug["trajectory"]}
    for i in range(2):  # at each level: nominal > base recalibrated > jointly calibrated
        per = [steps[k]["error_per_level"][i] for k in ("nominal model", "base recalibrated",
                                                        "jointly calibrated")]
        assert per[0] > per[1] > per[2], per
    written = tomllib.loads((tmp_path / "a" / "study.toml").read_text())
    assert written["model"]["options"]["effects"] == [{"name": "flexible_mode",
                                                       "attach": "driveshaft"}]
    # the base variables and the effect's parameters: the next round recalibrates them all
    assert written["calibration"]["parameters"] == [
        *short_quick()["calibration"]["parameters"], "flex_frequency", "flex_damping",
        "flex_mass"]
    assert written["parameters"]["flex_frequency"]["nominal"] == pytest.approx(
        aug["params"]["flex_frequency"])
    Study.load(tmp_path / "a" / "study.toml")


def test_augment_start_from_a_diagnose_file_without_the_effect_is_a_clear_error(
        study, cli, tmp_path):
    sig, _ = synthesize(study, amplitude=0.1)
    meas = write_csv(tmp_path / "m.csv", sig, level=0.1)
    study_file = tmp_path / "s.toml"
    import tomlkit

    study_file.write_text(tomlkit.dumps(short_quick()))
    diag = tmp_path / "diagnose.json"
    diag.write_text(json.dumps({"ranking": [{"effect": "damping", "place": "bearing_l3",
                                             "params": {"extra_damping": 2.0}}]}))
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


def test_discrepancy_along_the_friction_velocity_at_a_stick_slip_setting(study, runner,
                                                                         tmp_path):
    """How smooth is the discrepancy in a stick-slip parameter? Scan the friction
    transition velocity (the stick band's width, Eq. 3) finely around a low value, where the
    crankshaft sticks and slips within each cycle, and compare the point-to-point scatter of
    chi2 (second differences) with its trend: over 5 % of the coded range (the scale a
    calibration's surrogate and local refinement work at) the trend must dominate the
    scatter. Calibrating the velocity (globally, 20 points) from a start off by a factor 2
    then measures the model's own scatter at its optimum
    (:func:`~sensfw.measure.scatter.roughness`)
    and widens the entries' errors by it: the truth must lie inside the widened 95 %
    interval, that interval must exclude the start (the data reject the factor 2), and the
    widened chi2 must be consistent with the noise (the roughness is not left for an effect
    to explain)."""
    from sensfw.measure import discrepancy
    from sensfw.measure.calibration import Coordinates, calibrate
    from sensfw.measure.residuals import Residuals
    from sensfw.measure.scatter import widen_for_roughness

    truth = 0.25
    sets = {"slide_v_friction": truth, "slide_v_stiction": truth / 10}
    sig, _ = synthesize(study, sets=sets, amplitude=0.1, rig=Rig(noise=0.02, seed=2))
    meas = load_measurements(study, [str(write_csv(tmp_path / "m.csv", sig, level=0.1))])
    space = study.calibration_space(["slide_friction_velocity"])
    ev = Residuals(study, meas, runner, space)
    coords = Coordinates.of(space)
    z0 = coords.code({"slide_friction_velocity": truth})[0]
    grid = z0 + np.linspace(-0.1, 0.1, 11)  # 1 % steps of the coded range
    ws = ev.evaluate(None, [coords.decode([z]) for z in grid], "scan")
    chi2 = np.array([float(w @ w) for w in ws])
    trend = np.polyval(np.polyfit(grid, chi2, 2), grid)
    scatter = float(np.std(chi2 - trend))
    # the scatter (the stick-slip roughness plus the noise's chi2 scatter) is small
    # against the change of chi2 over 5 % of the coded range
    slope = float(np.max(np.abs(np.diff(trend)) / np.diff(grid)))
    assert scatter < 0.25 * slope * 0.05, (scatter, slope, chi2)
    start = {"slide_friction_velocity": 2 * truth}
    ev.evaluate(None, [start], "start")
    # the calibration's evidence is the start alone (not the scan around the truth)
    fit = calibrate(lambda pts: ev.evaluate(None, pts, "calibrate"), coords, 20,
                    evidence=[t for t in ev.trials() if t.values == start])
    widen_for_roughness(ev, fit, lambda s: None)
    (row,) = fit.summary()
    lo, hi = row["interval"]
    assert lo <= truth <= hi, (row["value"], row["interval"])
    assert hi < start["slide_friction_velocity"], row["interval"]
    assert discrepancy.fits(fit.best.w, 1), fit.chi2


def test_a_clearance_crossed_between_two_levels_is_found_with_its_gap(study, runner,
                                                                      tmp_path):
    """A limit stop (``limit_stop``, a clearance about the rest position) 0.06 um either
    side of where the crankshaft's end rests, stiffness 1.5e3 N/mm, with the base offsets,
    measured at 0.03 N (end motion 0.06 um peak: the gap is not crossed) and 0.1 N (0.2 um:
    well across it). Neither value is the effect's nominal or a probe's. The verdict names
    the stop at the crankshaft, its gap within 30 % (the issue's bar; measured 6.28e-5 mm,
    +5 %) and the base parameters recovered within 15 % as in the offsets-only case."""
    hidden = "limit_stop@crankshaft:stop_stiffness=1.5e3,stop_gap=6e-5"
    meas = measure(study, tmp_path, hidden, levels=(0.03, 0.1))
    res = diagnose(study, meas, runner, candidates=["limit_stop@crankshaft",
                                                    "limit_stop@driveshaft",
                                                    "contact_hardening@bearing_l1"], final=1)
    assert res.verdict == "limit_stop@crankshaft", (
        res.reason, [(r["hypothesis"], round(r["chi2"], 1)) for r in res.rows])
    row = next(r for r in res.rows if r["hypothesis"] == res.verdict)
    values = {c["name"]: c for c in row["calibration"]}
    assert values["stop_gap"]["value"] == pytest.approx(6e-5, rel=0.3), values["stop_gap"]
    for name, truth in CALIBRATED.items():
        assert values[name]["value"] == pytest.approx(truth, rel=0.15), values[name]
    assert "hardening" in res.signature_classes
    check_nested(res)


def test_a_second_round_leaves_out_the_effects_the_model_already_has():
    """Diagnosing an augmented study (the bolted beam with micro_slip at its joint): the
    same effect cannot be added again, at its place or another (its parameters are the
    model's), so it is left out with the reason; the other candidates stay, pruned by the
    signature classes unless ``prune=False`` (``--no-prune``)."""
    from sensfw.measure.calibration import Coordinates
    from sensfw.measure.hypotheses import candidates
    from sensfw.study.edit import add_effect

    root = Path(__file__).resolve().parents[2]
    text = add_effect((root / "studies" / "bert.toml").read_text(encoding="utf-8"),
                      "micro_slip", "joint", {})
    augmented = Study.from_dict(tomllib.loads(text), "bert")
    said = []
    hyps = candidates(augmented, ["micro_slip@joint", "dry_friction"], {}, Coordinates([]),
                       said.append)
    assert [h.name for h in hyps] == ["dry_friction@beam1", "dry_friction@beam2"]
    assert any("micro_slip: the model has it already (micro_slip@joint)" in s for s in said)
    # the classes the levels show prune the candidates, unless told not to
    found = {"even_harmonics": []}
    assert candidates(augmented, ["dry_friction@beam1"], found, Coordinates([]),
                       said.append) == []
    kept = candidates(augmented, ["dry_friction@beam1"], found, Coordinates([]), said.append,
                       prune=False)
    assert [h.name for h in kept] == ["dry_friction@beam1"]


def test_a_candidate_on_an_augmented_model_keeps_the_models_effects():
    """The run a worker rebuilds for a candidate of the second round is the augmented model
    plus the candidate (both effects, the parameters of both), not the candidate alone: the
    first version passed only the candidate's effect to the worker, whose model then refused
    the first effect's parameters and every run of the round failed."""
    from sensfw.evaluate import model_with_effects, variant_spec
    from sensfw.runs.spec import build_model
    from sensfw.study.edit import add_effect

    root = Path(__file__).resolve().parents[2]
    text = add_effect((root / "studies" / "bert.toml").read_text(encoding="utf-8"),
                      "micro_slip", "joint", {})
    augmented = Study.from_dict(tomllib.loads(text), "bert")
    effects = [{"name": "dry_friction", "attach": "beam1"}]
    spec = variant_spec(augmented, {"dry_friction_force": 0.3}, augmented.excitation, effects)
    rebuilt = build_model(spec)
    names = [(e.name, e.attach) for e in rebuilt.effects]
    assert names == [("micro_slip", "joint"), ("dry_friction", "beam1")]
    assert set(rebuilt.parameters()) == set(model_with_effects(augmented, effects)
                                            .parameters())
    assert {"microslip_residual", "dry_friction_force"} <= set(spec.params)
