"""Parameters and design spaces: what a calibration ending on a bound writes as a nominal."""

from dataclasses import replace

import pytest

from sensfw.params import DesignSpace, Parameter, ParameterError, ParameterSet


def test_a_variable_on_its_bound_is_written_as_its_bound_and_run_as_decoded():
    """A calibration that ends on a bound (coded -1 or +1) writes the value as the study's
    nominal, which must lie inside [min, max]. Decoded through a member's linear map, -0.9
    on [-0.9, 2] comes back as -0.9000000000000001 by round-off (0.55 - 1.45); the BERT
    calibration on both kinds ended there and its study.toml was then rejected. The run
    itself keeps the decoded value (run keys and the stick-slip models' scores rest on it)."""
    params = ParameterSet([Parameter("exponent", "-", 0.0, -0.9, 2.0),
                           Parameter("force", "N", 500.0, 20.0, 2e4)])
    space = DesignSpace.from_parameters(params)
    off = 0
    for name, bound in (("exponent", -0.9), ("exponent", 2.0), ("force", 20.0),
                        ("force", 2e4)):
        var = space[name]
        decoded = var.member_values(var.decode(var.code(bound)))[name]
        assert space.to_parameters({name: var.decode(var.code(bound))})[name] == decoded
        off += decoded != bound
        value = params[name].clip(decoded)
        assert value == bound
        replace(params[name], nominal=value)  # a valid nominal: does not raise
    assert off >= 1  # the round-off this guards against happens here


def test_a_value_outside_its_bounds_by_more_than_round_off_is_an_error():
    p = Parameter("exponent", "-", 0.0, -0.9, 2.0)
    assert p.clip(-0.9 - 1e-12) == -0.9
    assert p.check(-0.9 - 1e-12) == -0.9 - 1e-12
    for f in (p.check, p.clip):
        with pytest.raises(ParameterError, match=r"exponent.*outside its bounds"):
            f(-0.9 - 1e-6)


def test_a_dimensionless_bound_message_has_no_trailing_blank():
    from sensfw.errors import ParameterError
    from sensfw.params import Parameter

    with pytest.raises(ParameterError) as info:
        Parameter("exponent", "", 1.3, 1.2, 1.46).check(1.5)
    assert str(info.value) == "parameter 'exponent' = 1.5 is outside its bounds [1.2, 1.46]"
    with pytest.raises(ParameterError, match=r"= 2e\+06 N/mm is outside its bounds "
                                             r"\[1e\+06, 1\.5e\+06\] N/mm$"):
        Parameter("k", "N/mm", 1.2e6, 1e6, 1.5e6).check(2e6)


def test_a_misspelt_parameter_is_answered_with_the_closest_name(tmp_path):
    """`sensfw simulate --set slide_stifness=...` or an effect's `flex_frequncy=...`: the
    list of every parameter alone left the user to find the typo in 21 names."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    proc = subprocess.run([sys.executable, "-m", "sensfw", "simulate",
                           str(root / "studies" / "quick.toml"), "--out",
                           str(tmp_path / "m.csv"), "--set", "slide_stifness=1e6",
                           "--effect", "flexible_mode@driveshaft:flex_frequncy=1800"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    assert "unknown parameter 'slide_stifness' (did you mean 'slide_stiffness'?)" in proc.stderr
    assert "Traceback" not in proc.stderr
