"""Study files: every problem reported at once with its dotted path; exit code 2, no
traceback."""

import copy
import os
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from sensfw.errors import StudyError
from sensfw.study import Study, to_unit

ROOT = Path(__file__).resolve().parents[1]
QUICK = tomllib.loads((ROOT / "studies" / "quick.toml").read_text())


def problems(data) -> dict[str, str]:
    with pytest.raises(StudyError) as info:
        Study.from_dict(data, "x.toml")
    return dict(info.value.problems)


def test_shipped_studies_are_valid():
    """Each shipped study loads with what its file says: the quick study's five screened
    variables and the calibration it names; Table 1 in the paper's."""
    quick = Study.load(ROOT / "studies" / "quick.toml")
    assert quick.stages[0].variables == ["slide_stiffness", "slide_damping",
                                         "slide_friction_velocity", "bearing_preload",
                                         "spring_damping"]
    assert quick.excitation.duration == 0.25 and quick.excitation.tail == 0.02
    assert quick.spec.calibration.parameters == ["slide_stiffness", "slide_friction_velocity",
                                                 "slide_damping"]
    # the model's 21 parameters, nominal values as the model declares them (no overrides)
    assert quick.parameters.nominal() == quick.model.parameters().nominal()
    assert len(quick.parameters) == 21
    bert = Study.load(ROOT / "studies" / "bert.toml")
    assert bert.gain.unit == "N/V" and "excitation_gain" in bert.parameters
    paper = Study.load(ROOT / "studies" / "paper.toml")
    assert len(paper.variable_names()) == 19  # Table 1: 21 parameters, two pairs grouped
    assert paper.parameters["clutch_drive_stiffness"].nominal == pytest.approx(3.14e6)
    assert paper.excitation.f1 == 5000 and paper.excitation.fs == 20000


def test_units_are_converted_and_checked():
    assert to_unit("7.05e8 N/m", "N/mm") == pytest.approx(7.05e5)
    assert to_unit("0.234 N*s/m", "N*s/mm") == pytest.approx(2.34e-4)
    assert to_unit("5 kHz", "Hz") == 5000
    assert to_unit(3, "mm") == 3.0
    # a bare number in a string means the unit too ("cannot convert '1e6' to N/mm" before)
    assert to_unit("1e6", "N/mm") == to_unit(1e6, "N/mm") == 1e6
    assert to_unit(" 7 ", "Hz") == 7.0 and to_unit("0.5", "") == 0.5
    assert to_unit("50 %", "") == 0.5
    with pytest.raises(ValueError, match="cannot convert '3 kg' to N/mm"):
        to_unit("3 kg", "N/mm")
    # what pint's tokenizer or arithmetic raises is a ValueError naming the value too (an
    # unmatched bracket raised tokenize.TokenError: Hypothesis, test_properties.py)
    for bad in ("[", "5 Hz)", "{", "1 / 0 Hz"):
        with pytest.raises(ValueError, match=f"cannot read '{re.escape(bad)}' as a quantity"):
            to_unit(bad, "Hz")


def test_all_problems_reported_at_once_with_dotted_paths():
    data = copy.deepcopy(QUICK)
    data["parameters"] = {
        "clutch_drive_damping": {"min": "600 N*s/mm", "max": "514.6 N*s/mm"},  # min > max
        "slide_stiffness": {"max": "3 kg"},  # wrong unit
        "bearing_preload": {"nominal": "500 N"},  # nominal outside bounds
        "no_such_parameter": {"max": 1.0},
    }
    data["excitation"]["colour"] = "red"  # unknown key
    data["stages"][0]["design"] = "oatt"  # unknown plugin
    data["stages"][1]["surrogates"] = ["eq19"]
    got = problems(data)
    assert "below min" in got["parameters.clutch_drive_damping.max"]
    assert "cannot convert '3 kg' to N/mm" in got["parameters.slide_stiffness.max"]
    assert "outside" in got["parameters.bearing_preload.nominal"]
    assert "unknown parameter" in got["parameters.no_such_parameter"]
    assert got["excitation.colour"].startswith("unknown key; known: kind, f0, f1, duration")
    assert "unknown design 'oatt'; available:" in got["stages[0].design"]
    assert "oat" in got["stages[0].design"]
    assert "unknown surrogate 'eq19'; available:" in got["stages[1].surrogates[0]"]


def test_a_range_beyond_what_the_model_accepts_is_refused_before_anything_runs():
    # the model checks every value against its own table when it simulates: a study range
    # beyond it would fail in the middle of a design or a calibration
    from sensfw.plugins import models

    declared = models.get(QUICK["model"]["name"])().parameters()["slide_stiffness"]
    data = copy.deepcopy(QUICK)
    data["parameters"] = {"slide_stiffness": {"max": f"{declared.max * 10:g} N/mm"}}
    got = problems(data)
    assert "outside the range the model" in got["parameters.slide_stiffness.max"]
    assert f"{declared.max:g}" in got["parameters.slide_stiffness.max"]


def test_stage_references_and_channels_are_checked():
    data = copy.deepcopy(QUICK)
    data["stages"][1]["variables"] = "selected:sreen"
    data["stages"][0]["scorers"][0]["channel"] = "crank_axail"
    data["model"]["output"] = "nope"
    data["stages"][0]["variables"] = ["slide_damping", "slide_dampin"]
    got = problems(data)
    assert "no earlier stage named 'sreen'" in got["stages[1].variables"]
    assert "unknown channel 'crank_axail'" in got["stages[0].scorers[0].channel"]
    assert "unknown channel 'nope'" in got["model.output"]
    assert "unknown design variable 'slide_dampin'" in got["stages[0].variables"]


def test_model_options_and_effects_are_reported_at_their_paths():
    """Every problem of the model's options at once, each effect's at its index."""
    data = copy.deepcopy(QUICK)
    data["model"]["options"] = {"effects": [{"name": "flexible_mood"}, "added_mass",
                                            {"name": "clearance", "attach": "moon"},
                                            {"name": "damping", "at": "bearing_l1"}],
                                "linearised": "no"}
    got = problems(data)
    assert "unknown effect 'flexible_mood'; available:" in got["model.options.effects[0].name"]
    assert "cannot attach to 'moon'" in got["model.options.effects[2].attach"]
    assert got["model.options.effects[3].at"] == "unknown option; known: attach"
    assert got["model.options.linearised"] == "linearised must be true or false, got 'no'"
    assert "model.options.effects[1].attach" not in got  # the model's preferred place
    data["model"]["options"] = {"colour": "red"}
    assert problems(data) == {"model.options.colour":
                              "unknown option; known: effects, geometry, linearised"}


def test_automatic_step_only_with_the_integrators_it_is_calibrated_for():
    """The step limits (models/stepsize.py) hold inside RK4's stability region; explicit
    Euler is unstable on the imaginary axis at any step, so auto_step must not pretend."""
    data = copy.deepcopy(QUICK)
    data["solver"] = {"method": "ExplicitEuler"}
    assert "calibrated for RK44, RK67, DOPRI5, not ExplicitEuler" in \
        problems(data)["solver.auto_step"]
    data["solver"]["auto_step"] = False
    assert not Study.from_dict(data, "x.toml").solver.auto_step
    data["solver"] = {"method": "RK67"}
    assert Study.from_dict(data, "x.toml").solver.auto_step


def test_adaptive_tolerance_is_passed_on_and_checked():
    """solver.tolerance (the absolute error tolerance of the runs the model integrates
    adaptively, models/stepsize.py) reaches the solver settings and enters the run hash."""
    data = copy.deepcopy(QUICK)
    assert Study.from_dict(data, "x.toml").solver.tolerance == 1e-9
    data["solver"] = {"tolerance": 5e-10}
    solver = Study.from_dict(data, "x.toml").solver
    assert solver.tolerance == 5e-10 and solver.to_dict()["tolerance"] == 5e-10
    for bad in (0.0, -1e-9, 0.1):
        data["solver"] = {"tolerance": bad}
        assert "solver.tolerance" in problems(data)


def test_stiff_method_is_passed_on_and_checked():
    """solver.stiff_method (how the runs whose friction stick band lies beyond RK4's
    stability are integrated, models/stepsize.py) reaches the solver settings and the run
    hash; an unknown one is named."""
    data = copy.deepcopy(QUICK)
    solver = Study.from_dict(data, "x.toml").solver
    assert solver.stiff_method == "DOPRI5"
    assert "stiff_method" not in solver.to_dict()  # runs of the default keep their hashes
    data["solver"] = {"stiff_method": "VelocityVerlet"}
    solver = Study.from_dict(data, "x.toml").solver
    assert solver.to_dict()["stiff_method"] == "VelocityVerlet"
    data["solver"] = {"stiff_method": "Euler"}
    assert "solver.stiff_method" in problems(data)


def test_missing_sections_and_bad_toml(tmp_path):
    got = problems({"stages": []})
    assert "study" in got and "stages" in got
    bad = tmp_path / "bad.toml"
    bad.write_text("[study\nname='x'")
    with pytest.raises(StudyError, match="not valid TOML"):
        Study.load(bad)
    with pytest.raises(StudyError, match="file not found"):
        Study.load(tmp_path / "missing.toml")


def test_cli_reports_errors_with_exit_code_2_and_no_traceback(tmp_path):
    bad = tmp_path / "bad.toml"
    text = (ROOT / "studies" / "quick.toml").read_text()
    bad.write_text(text + '\n[parameters.clutch_drive_damping]\nmax = "0.5 N*s/mm"\n')
    proc = subprocess.run([sys.executable, "-m", "sensfw", "run", str(bad), "--out",
                           str(tmp_path / "o")], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "parameters.clutch_drive_damping" in proc.stderr
    assert "Traceback" not in proc.stderr + proc.stdout


def test_dry_run_prints_the_plan_without_running(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "sensfw", "run", str(ROOT / "studies" /
                           "paper.toml"), "--dry-run", "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "COLUMNS": "200"})
    assert proc.returncode == 0, proc.stderr
    assert "39" in proc.stdout and "81" in proc.stdout  # 2 x 19 + 1 and 3^4
    assert "at most 120 runs" in proc.stdout
    assert not (tmp_path / "o").exists()


def test_plugin_options_are_checked_before_anything_runs():
    """Every design, scorer and surrogate is built with its options when the study loads;
    each bad option is reported at its dotted path, all at once (issue 12, item 2)."""
    data = copy.deepcopy(QUICK)
    data["stages"][1]["design_options"] = {"levelz": 3}
    data["stages"][0]["scorers"][0]["band"] = [5000.0, 50.0]
    data["stages"][1]["scorers"][2]["unit"] = "dB"
    data["stages"][1]["surrogates"] = [{"name": "eq18", "interaction": "bogus"},
                                       {"name": "gaussian_process", "noise": "yes",
                                        "n_restarts_optimizer": -1}]
    got = problems(data)
    assert got["stages[1].design_options.levelz"] == "unknown option; known: centre, levels"
    assert "fmin < fmax" in got["stages[0].scorers[0].band"]
    assert "unit must be 'percent' or 'dBc'" in got["stages[1].scorers[2].unit"]
    assert "'product'" in got["stages[1].surrogates[0].interaction"]
    assert "'bogus'" in got["stages[1].surrogates[0].interaction"]
    assert got["stages[1].surrogates[1].noise"] == "noise must be true or false, got 'yes'"
    assert got["stages[1].surrogates[1].n_restarts_optimizer"] == \
        "n_restarts_optimizer must be an integer >= 0, got -1"
    assert len(got) == 6


@pytest.mark.parametrize("band, why", [
    ([20.0, 5000.0], "not inside the excitation's sweep f0..f1 = [50, 5000] Hz"),
    ([50.0, 6000.0], "not inside the excitation's sweep"),
    ([50.0, 12000.0], "above the Nyquist frequency 10000 Hz"),
])
def test_a_scorer_band_is_checked_against_the_excitation(band, why):
    data = copy.deepcopy(QUICK)
    data["stages"][0]["scorers"][0]["band"] = band
    assert why in problems(data)["stages[0].scorers[0].band"]


def test_options_that_fail_only_together_and_designs_that_do_not_fit_the_space():
    data = copy.deepcopy(QUICK)
    data["stages"][0]["design"] = "morris"
    data["stages"][0]["design_options"] = {"trajectories": 3, "optimal_trajectories": 5}
    data["stages"][1]["surrogates"] = [{"name": "eq18", "interaction": "ratio"}]
    got = problems(data)
    assert got["stages[0].design_options.optimal_trajectories"] == \
        "optimal_trajectories must be an integer in [2, trajectories) = [2, 3), got 5"
    assert "coding='physical'" in got["stages[1].surrogates[0].interaction"]
    data = copy.deepcopy(QUICK)
    data["stages"][0]["design"] = "box_behnken"
    data["stages"][0]["variables"] = ["slide_stiffness", "slide_damping"]
    assert "needs at least 3 variables, got 2" in problems(data)["stages[0].design"]
    data = copy.deepcopy(QUICK)  # groups that do not cover the stage's variables
    data["stages"][0]["variables"] = ["slide_stiffness", "slide_damping"]
    data["stages"][0]["design_options"] = {"groups": {"a": ["slide_stiffness", "nope"]}}
    assert problems(data)["stages[0].design_options.groups"] == (
        "design 'oat': unknown variables in groups: ['nope']")
    data["stages"][0]["design"] = "morris"  # Morris's groups too (they failed at the run)
    assert problems(data)["stages[0].design_options.groups"] == (
        "design 'morris': unknown variables in groups: ['nope']")


def test_seeds_amplitudes_timeouts_and_variable_lists_that_cannot_work_are_refused():
    # each failed only later (numpy refuses a negative seed, SALib an empty design, a zero
    # drive gives no FRF) or was silently taken ("7", true and 1.0 as seeds, a timeout of 0)
    for section, field, value, message in (
            ("study", "seed", -1, "greater than or equal to 0"),
            ("study", "seed", "7", "valid integer"),
            ("study", "seed", True, "valid integer"),
            ("study", "seed", 1.0, "valid integer"),
            ("excitation", "amplitude", "0 N", "must be positive"),
            ("excitation", "amplitude", "-0.1 N", "must be positive"),
            ("solver", "timeout", "0 s", "must be positive")):
        data = copy.deepcopy(QUICK)
        data.setdefault(section, {})[field] = value
        got = problems(data)
        assert message in got[f"{section}.{field}"], (field, value, got)
    data = copy.deepcopy(QUICK)
    data["stages"][0]["variables"] = []
    assert "at least one variable" in problems(data)["stages[0].variables"]


def test_a_stages_bounds_are_held_to_the_models_range_like_the_parameters():
    # Table 1's slide damping spans 1-468 N s/mm, the range the shaft model accepts: a stage
    # that widened it ran every run into the model's refusal and failed after them
    data = copy.deepcopy(QUICK)
    data["stages"][0]["bounds"] = {"slide_damping": {"max": "1000 N*s/mm"}}
    assert "outside the range the model shaft_assembly accepts, [1, 468]" in problems(
        data)["stages[0].bounds.slide_damping.max"]
    data = copy.deepcopy(QUICK)
    data["parameters"] = {"slide_damping": {"min": float("nan")}}
    assert problems(data) == {"parameters.slide_damping.min": "nan is not a finite number"}


def test_a_gaussian_process_kernel_in_a_study_file_is_refused_when_checked():
    # a kernel is a scikit-learn object (passed by code); a string passed validation and
    # failed in scikit-learn at the fit, after every run of the stage
    data = copy.deepcopy(QUICK)
    data["stages"][1]["surrogates"] = [{"name": "gaussian_process", "kernel": "foo"}]
    assert "got 'foo'" in problems(data)["stages[1].surrogates[0].kernel"]


def test_the_groups_table_is_checked_at_its_dotted_path():
    # each a StudyError naming groups.NAME (before, an unknown member or a doubly grouped
    # parameter escaped as a bare ParameterError, and a group named like a parameter outside
    # it silently removed that parameter from the design)
    cases = {
        "g": (["slide_damping", "nope"], "unknown parameter 'nope'"),
        "h": (["slide_damping", "slide_damping"], "parameter 'slide_damping' is listed twice"),
        "slide_stiffness": (["slide_damping", "spring_damping"],
                            "the group's name is the parameter 'slide_stiffness'"),
    }
    for name, (members, message) in cases.items():
        data = copy.deepcopy(QUICK)
        data["groups"] = {name: members}
        got = problems(data)
        assert list(got) == [f"groups.{name}"], got
        assert message in got[f"groups.{name}"]


def test_cli_validate_reports_bad_options(tmp_path):
    bad = tmp_path / "bad.toml"
    text = (ROOT / "studies" / "quick.toml").read_text()
    bad.write_text(text.replace("design_options = { levels = 3 }",
                                "design_options = { levelz = 3 }")
                   .replace('surrogates = ["eq18"]',
                            'surrogates = [{ name = "eq18", interaction = "bogus" }]'))
    proc = subprocess.run([sys.executable, "-m", "sensfw", "validate", str(bad)],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "COLUMNS": "200"})
    assert proc.returncode == 2
    assert "stages[1].design_options.levelz: unknown option; known: centre, levels" in proc.stderr
    assert "stages[1].surrogates[0].interaction" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_cli_messages_keep_square_brackets(tmp_path):
    """Errors, notices and progress lines are printed as they are: a ``[calibration]`` or
    ``[excitation]`` in them is text, not rich markup that would vanish."""
    from sensfw.cli.common import console, say

    with console.capture() as cap:
        say("H0: calibrating a, b ([calibration] parameters)")
    assert "([calibration] parameters)" in cap.get()
    bad = tmp_path / "bad[x].toml"
    bad.write_text("[study]\nname = 'x'\n")
    proc = subprocess.run([sys.executable, "-m", "sensfw", "validate", str(bad)],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "COLUMNS": "300"})
    assert proc.returncode == 2
    assert "bad[x].toml" in proc.stderr, proc.stderr


@pytest.mark.parametrize("command", ["diagnose", "augment"])
def test_a_budget_below_one_is_refused_naming_the_option(cli, command):
    """A calibration budget of 0 would calibrate nothing and report the start as the result;
    the CLI refuses it before loading anything."""
    extra = ["--effect", "dry_friction"] if command == "augment" else []
    proc = cli(command, "studies/bert.toml", "-m", "nowhere.csv", *extra, "--budget", 0)
    assert proc.returncode != 0
    assert "--budget" in proc.stderr and "greater than or equal to 1" in proc.stderr


def test_a_design_variable_that_cannot_vary_is_refused():
    """min = max on a stage's variable: a design would code it to 0 and rank it last, as if
    it had been screened and found to do nothing."""
    data = copy.deepcopy(QUICK)
    data["stages"][0]["bounds"] = {"slide_damping": {"min": "10 N*s/mm", "max": "10 N*s/mm",
                                                     "nominal": "10 N*s/mm"}}
    assert "['slide_damping'] have min = max: they cannot vary" in problems(data)[
        "stages[0].design"]
    data["stages"][0]["variables"] = ["slide_stiffness", "spring_damping"]
    assert Study.from_dict(data, "x.toml").stages[0].variables == ["slide_stiffness",
                                                                   "spring_damping"]


@pytest.mark.parametrize("stage,scorer,path,message", [
    (1, {"name": "order_amplitude", "order": 6}, "stages[1].scorers[0].order",
     "order 6 is above the highest unaliased order 5"),
    (0, {"name": "frf_scalar", "band": [100.0, 2000.0], "nperseg": 100000},
     "stages[0].scorers[0].nperseg", "nperseg 100000 is longer than the record"),
    (0, {"name": "frf_db_rms", "band": [100.5, 101.5]}, "stages[0].scorers[0].band",
     "holds no line of the FRF, whose lines are 2.5 Hz apart"),
])
def test_scorer_options_that_the_excitation_cannot_serve_are_refused_at_validation(
        stage, scorer, path, message):
    """Each passed validation and failed after every run of the study (or gave NaN scores
    and blamed the nominal run). The 2-DOF study: 20 kHz, swept to 2 kHz, 0.4 s (2.5 Hz
    lines): order 5 is the highest below Nyquist."""
    data = {"study": {"name": "t"}, "model": {"name": "two_dof", "output": "a1"},
            "excitation": {"f0": "50 Hz", "f1": "2 kHz", "duration": "0.3 s", "fs": "20 kHz",
                           "amplitude": "1 N", "tail": "0.1 s"},
            "stages": [{"name": "s", "design": "oat", "select": {"threshold": 0.1},
                        "scorers": [{"name": "frf_scalar", "band": [60.0, 1900.0]}]},
                       {"name": "d", "design": "full_factorial", "variables": "selected:s",
                        "scorers": [{"name": "thd"}]}]}
    Study.from_dict(copy.deepcopy(data), "x.toml")  # valid as it is
    data["stages"][stage]["scorers"] = [scorer]
    assert message in problems(data)[path]
    data["excitation"]["f1"] = "6 kHz"  # THD: the second harmonic of 6 kHz is above 10 kHz
    data["stages"][0]["scorers"] = [{"name": "frf_scalar", "band": [60.0, 1900.0]}]
    data["stages"][1]["scorers"] = [{"name": "thd"}]
    assert "lies above the Nyquist frequency 10000 Hz" in problems(data)["stages[1].scorers[0]"]


def test_a_threshold_that_selects_nothing_is_refused():
    """Importance is normalised to at most 1 and selection is strictly above the
    threshold: 1.0 passed validation, selected nothing and stopped the next stage."""
    data = copy.deepcopy(QUICK)
    data["stages"][0]["select"]["threshold"] = 1.0
    assert problems(data)["stages[0].select.threshold"].startswith(
        "1 selects nothing: importance is normalised to at most 1")
    data["stages"][0]["select"]["threshold"] = 0.99
    Study.from_dict(data, "x.toml")


def test_a_calibration_parameter_listed_twice_is_refused():
    # it passed validate, then calibrate failed with a bare "duplicate design variable"
    data = copy.deepcopy(QUICK)
    data["calibration"]["parameters"] = ["slide_stiffness", "slide_damping", "slide_stiffness"]
    assert problems(data) == {"calibration.parameters[2]": "'slide_stiffness' is listed twice"}


def test_an_empty_calibration_list_is_refused():
    # it behaved as if the section were missing: a screen ran to choose the parameters
    data = copy.deepcopy(QUICK)
    data["calibration"]["parameters"] = []
    assert problems(data)["calibration.parameters"].startswith(
        "an empty list calibrates nothing")


def test_true_where_a_quantity_is_expected_is_an_error_not_one():
    """pydantic's lax mode made ``max = true`` the bound 1.0 mm/s, ``amplitude = true`` 1 N
    and ``timeout = true`` 1 s, silently (or reported a bound it had made 1 at the
    nominal's path)."""
    data = copy.deepcopy(QUICK)
    data["parameters"] = {"slide_damping": {"max": True}}
    data["excitation"]["amplitude"] = True
    data.setdefault("solver", {})["timeout"] = False
    got = problems(data)
    for path, word in (("parameters.slide_damping.max", "true"),
                       ("excitation.amplitude", "true"), ("solver.timeout", "false")):
        assert got[path] == ("expected a number or a quantity with its unit (\"1e6 N/mm\"), "
                             f"got {word}"), got


def test_a_parameter_pinned_by_min_equal_max_is_fixed_not_refused():
    """min = max in ``[parameters]`` for a parameter no stage names (a Table 1 style
    override that fixes it) was refused with 'leave them out of the stage's variables',
    which it already was. It is a fixed parameter: 'all' leaves it out; a stage that names
    it is still refused (the test above)."""
    data = copy.deepcopy(QUICK)
    data["parameters"] = {"l1_damping": {"min": 0.01, "max": 0.01, "nominal": 0.01}}
    study = Study.from_dict(data, "x.toml")
    assert "l1_damping" not in study.variable_names()
    assert len(study.variable_names()) == 18


def test_a_stage_on_a_selection_no_design_of_it_can_take_is_refused():
    """``box_behnken`` (3 variables at least) on a screen that keeps at most 2: validation
    passed it, ``run`` spent the screen and then stopped. A selection that may fit (at most
    5 for a 3-variable design) passes."""
    data = copy.deepcopy(QUICK)
    data["stages"][0]["select"] = {"threshold": 0.05, "max_variables": 2}
    data["stages"][1]["design"] = "box_behnken"
    data["stages"][1]["design_options"] = {}
    got = problems(data)
    assert got["stages[1].design"] == ("design 'box_behnken' needs at least 3 variables, "
                                       "got 2 (this stage takes the at most 2 variable(s) "
                                       "that stage 'screen' selects)")
    data["stages"][0]["select"]["max_variables"] = 5
    Study.from_dict(data, "x.toml")


def test_validate_prints_the_plan_and_run_refuses_a_file_as_its_folder(tmp_path):
    """``validate`` said it printed the plan and printed one line; ``run --out FILE`` was a
    FileExistsError traceback."""
    from typer.testing import CliRunner

    from sensfw.cli import app

    res = CliRunner().invoke(app, ["validate", str(ROOT / "studies" / "quick.toml")],
                             env={"COLUMNS": "200"})
    assert res.exit_code == 0
    assert "plan of study 'quick'" in res.output and "at most 20 runs" in res.output
    afile = tmp_path / "afile"
    afile.write_text("x")
    res = CliRunner().invoke(app, ["run", str(ROOT / "studies" / "quick.toml"), "--out",
                                   str(afile)])
    assert res.exit_code == 2 and "a file of that name exists" in res.output


@pytest.mark.parametrize("edit,where,message", [
    (lambda d: d["excitation"].update(durration="0.25 s"), "excitation.durration",
     "unknown key (did you mean 'duration'?); known: kind, f0, f1, duration,"),
    (lambda d: d.update(excitaton={}), "excitaton", "did you mean 'excitation'?"),
    (lambda d: d["stages"][0]["select"].update(treshold=0.1), "stages[0].select.treshold",
     "did you mean 'threshold'?"),
    (lambda d: d.update(parameters={"slide_stiffness": {"maxx": 1.0}}),
     "parameters.slide_stiffness.maxx", "did you mean 'max'?); known: nominal, min, max"),
])
def test_a_misspelt_key_names_the_keys_its_table_knows(edit, where, message):
    # pydantic's own "Extra inputs are not permitted" says nothing of what to write instead
    data = copy.deepcopy(QUICK)
    edit(data)
    got = problems(data)
    assert message in got[where]


def test_an_unknown_backend_is_refused_naming_the_option_before_anything_runs(cli, tmp_path):
    """It was refused only once the runner started, below a progress bar already drawn."""
    out = tmp_path / "o"
    proc = cli("compare", "studies/quick.toml", "-m", "nowhere.csv", "--backend", "thread",
               "--out", out)
    assert proc.returncode == 2
    assert "--backend" in proc.stderr and "use one of serial, processes, dask" in proc.stderr
    assert "Traceback" not in proc.stderr and not out.exists()


@pytest.mark.parametrize("command", ["compare", "calibrate", "diagnose", "augment"])
def test_the_measured_option_names_every_kind_of_record_it_reads(command):
    """-m reads LMS .mat exports and folders too (README, "Model against measurement"); its
    help said ".csv or .uff"."""
    proc = subprocess.run([sys.executable, "-m", "sensfw", command, "--help"],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "COLUMNS": "400"})
    assert proc.returncode == 0
    assert ".csv, .uff, an LMS .mat export or a folder of them" in proc.stdout


@pytest.mark.parametrize("command,text", [
    ("simulate", "NAME[@PLACE][:KEY=VALUE,...] hidden physical effect"),
    ("augment", "effect to add, NAME[@PLACE]"),
])
def test_help_keeps_the_place_of_an_effect(command, text):
    """rich took "[@PLACE]" for markup and dropped it: the help read NAME[:KEY=VALUE,...]."""
    proc = subprocess.run([sys.executable, "-m", "sensfw", command, "--help"],
                          capture_output=True, text=True, timeout=120,
                          env={**os.environ, "COLUMNS": "400"})
    assert text in proc.stdout


def test_a_value_of_the_wrong_type_does_not_hide_the_other_problems():
    """Three mistakes, three problems: a seed written "7" (pydantic refuses it) hid the
    frequency in kg and the misspelt parameter (1 problem reported); a string where
    ``halvings`` wants an integer hid an unknown design and a scorer's bad option."""
    data = copy.deepcopy(QUICK)
    data["study"]["seed"] = "7"
    data["excitation"]["f0"] = "50 kg"
    data["parameters"] = {"slide_stifness": {"max": "1 N/mm"}}
    data["solver"]["halvings"] = "two"
    data["stages"][0]["design"] = "oatt"
    data["stages"][1]["scorers"][0]["order"] = "x"
    with pytest.raises(StudyError) as info:
        Study.from_dict(data, "x.toml")
    got = info.value.problems
    assert [path for path, _ in got] == [
        "study.seed", "solver.halvings", "excitation.f0", "parameters.slide_stifness",
        "stages[0].design", "stages[1].scorers[0].order"], got
    assert "x.toml (6 problem(s))" in str(info.value)
    assert "cannot convert '50 kg' to Hz" in dict(got)["excitation.f0"]
    # a value dropped to be checked again is not reported twice, nor what follows from it
    data = copy.deepcopy(QUICK)
    data["stages"][0]["select"]["threshold"] = 2
    data["stages"][0]["bogus"] = 1
    data["parameters"] = {"slide_stiffness": {"min": "5 kg"}}
    assert list(problems(data)) == ["stages[0].select.threshold", "stages[0].bogus",
                                    "parameters.slide_stiffness.min"]


def test_a_list_where_a_quantity_belongs_is_one_problem_at_its_key():
    """``f1 = [1]`` was three problems at ``excitation.f1.str``, ``.float`` and ``.int``
    (pydantic's union members, no keys of the file) and hid the unknown output channel."""
    data = copy.deepcopy(QUICK)
    data["excitation"]["f1"] = [1]
    data["model"]["output"] = "nope"
    assert problems(data) == {
        "excitation.f1": "expected a number or a quantity with its unit (\"1e6 N/mm\"), "
                         "got [1]",
        "model.output": "unknown channel 'nope'; the model has crank_axial, crank_radial, "
                        "drive_axial, drive_radial"}


def test_a_bad_group_does_not_hide_the_stages_problems():
    """An unknown group member stopped the checks: the unknown design went unreported."""
    data = copy.deepcopy(QUICK)
    data["groups"] = {"g": ["slide_stiffness", "nope"]}
    data["stages"][0]["design"] = "oatt"
    got = problems(data)
    assert list(got) == ["groups.g", "stages[0].design"], got
    assert got["groups.g"] == "unknown parameter 'nope'"
    assert got["stages[0].design"].startswith("unknown design 'oatt'; available:")
