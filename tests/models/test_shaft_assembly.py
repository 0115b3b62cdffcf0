"""The shipped Exudyn model (issue 3): resonances, physical nonlinearity, linear limit,
time-step convergence, determinism, clear failures."""

from dataclasses import replace

import numpy as np
import pytest
from scipy.signal import find_peaks

from sensfw.errors import ParameterError, SimulationError
from sensfw.excitation import Chirp
from sensfw.models.base import SolverSettings
from sensfw.models.shaft_assembly import GROUPS, PARAMETERS, ShaftAssembly
from sensfw.signal import frf, thd

pytestmark = pytest.mark.slow  # Exudyn simulations of the shaft model

NOMINAL = PARAMETERS.nominal()
AMP_LOW, AMP_NOMINAL, AMP_HIGH = 0.05, 0.1, 0.2  # N; the study levels (studies/*.toml)


def axial_frf(sig, nperseg=None):
    f, H = frf(sig.force, sig.channels["crank_axial"], sig.fs, estimator="Hv",
               nperseg=nperseg)
    band = (f >= 50) & (f <= 5000)
    return f[band], H[band]


@pytest.fixture(scope="module")
def nominal_1s():
    return ShaftAssembly().simulate(NOMINAL, Chirp(50, 5000, 1.0, 20000, AMP_NOMINAL,
                                                   tail=0.05))


def test_parameters_are_table_1_plus_preload():
    assert len(PARAMETERS) == 21
    assert PARAMETERS["slide_stiffness"].unit == "N/mm"
    assert (PARAMETERS["slide_damping"].min, PARAMETERS["slide_damping"].nominal,
            PARAMETERS["slide_damping"].max) == (1.0, 234.0, 468.0)
    assert PARAMETERS["clutch_crank_exponent"].nominal == 0.99
    from sensfw.params import DesignSpace

    assert len(DesignSpace.from_parameters(PARAMETERS, GROUPS)) == 19  # Sect. 3.1
    with pytest.raises(ParameterError, match=r"slide_damping.*outside its bounds"):
        ShaftAssembly().simulate({"slide_damping": 1000.0}, Chirp(50, 5000, 0.01, 20000))
    # both inside their bounds, but Eq. 3 needs the stiction velocity below the friction one
    with pytest.raises(ParameterError, match=r"slide_v_stiction \(0.5 mm/s\) must be below "
                                             r"slide_v_friction \(0.5 mm/s\)"):
        ShaftAssembly().simulate({"slide_v_stiction": 0.5, "slide_v_friction": 0.5},
                                 Chirp(50, 5000, 0.01, 20000))


def test_nominal_run_has_three_resonances_in_band(nominal_1s):
    sig = nominal_1s
    for name, x in sig.channels.items():
        assert np.all(np.isfinite(x)), name
        assert np.std(x) > 0, name
    f, H = axial_frf(sig, nperseg=2048)
    db = 20 * np.log10(np.abs(H))
    peaks, _ = find_peaks(db, prominence=6.0)
    freqs = f[peaks]
    distinct = [freqs[0]] if len(freqs) else []
    for fr in freqs[1:]:
        if fr > 1.1 * distinct[-1]:
            distinct.append(fr)
    assert len(distinct) >= 3, freqs


def test_thd_grows_with_excitation_amplitude():
    m = ShaftAssembly()
    values = {}
    for amp in (AMP_LOW, AMP_HIGH):
        sig = m.simulate(NOMINAL, Chirp(50, 5000, 0.5, 20000, amp))
        values[amp] = thd(sig.channels["crank_axial"], sig.fs, sig.f_inst)
    assert values[AMP_HIGH] >= 2.0 * values[AMP_LOW], values


def test_linearised_model_is_linear_and_matches_its_eigenfrequencies():
    import exudyn as exu

    lin = ShaftAssembly(linearised=True)
    sig = lin.simulate(NOMINAL, Chirp(50, 5000, 1.0, 20000, AMP_NOMINAL, tail=0.3))
    assert thd(sig.channels["crank_axial"], sig.fs, sig.f_inst) < 1.0
    # eigenfrequencies of the linear mass and stiffness matrices, from Exudyn's linearisation
    built = lin.build(NOMINAL, None)
    M, K, _ = exu.solver.ComputeLinearizedSystem(built.mbs)
    built.mbs.Reset()
    built.SC.Reset()
    w2 = np.linalg.eigvals(np.linalg.solve(M, K)).real
    fn = np.sort(np.sqrt(w2[w2 > 0]) / (2 * np.pi))
    fn = fn[(fn > 60) & (fn < 4800)]
    # cross-check against the numpy model's own matrices
    M2, K2, _ = lin.linear_matrices(NOMINAL)
    w2b = np.linalg.eigvals(np.linalg.solve(M2, K2)).real
    fnb = np.sort(np.sqrt(w2b[w2b > 0]) / (2 * np.pi))
    fnb = fnb[(fnb > 60) & (fnb < 4800)]
    np.testing.assert_allclose(fn, fnb, rtol=1e-4)
    f, H = axial_frf(sig)
    mag = np.abs(H)
    matched = 0
    for fr in fn:
        win = (f > 0.97 * fr) & (f < 1.03 * fr)
        fpk = f[win][np.argmax(mag[win])]
        if abs(fpk / fr - 1) < 0.01:
            matched += 1
    assert len(fn) >= 3 and matched >= 3, (fn, matched)


CORNERS = {
    "nominal": NOMINAL,
    "all-min": {k: p.min for k, p in PARAMETERS.items()},
    "all-max": {k: p.max for k, p in PARAMETERS.items()},
    # the screen run with the stiffest stick-slip friction of Table 1
    "v-min": {**NOMINAL, "slide_v_stiction": 0.01, "slide_v_friction": 0.1},
}
SHORT = Chirp(50, 5000, 0.3, 20000, AMP_NOMINAL, tail=0.05)


def frf_db_and_thd(sig):
    _, H = axial_frf(sig, nperseg=1024)
    s = sig.sweep()
    return 20 * np.log10(np.abs(H)), thd(s.channels["crank_axial"], s.fs, s.f_inst)


def change(a, b):
    """FRF change (dB RMS) and relative THD change from run ``b`` to run ``a``."""
    (db_a, thd_a), (db_b, thd_b) = frf_db_and_thd(a), frf_db_and_thd(b)
    return float(np.sqrt(np.mean((db_a - db_b) ** 2))), abs(thd_a - thd_b) / thd_b


def step_change(params, solver):
    """FRF change (dB RMS) and relative THD change when the step a run used is halved, or
    its error tolerance where the model integrated it adaptively (the step or tolerance it
    used is returned)."""
    m = ShaftAssembly()
    sig = m.simulate(params, SHORT, solver)
    if "tolerance" in sig.meta:
        used = sig.meta["tolerance"]
        half = m.simulate(params, SHORT, replace(solver, tolerance=used / 2))
        assert half.meta["tolerance"] == used / 2
    else:  # the same integrator at half the step
        used = sig.meta["step"]
        half = m.simulate(params, SHORT, SolverSettings(method=sig.meta["integrator"],
                                                        step=used / 2, auto_step=False))
        assert half.meta["step"] == pytest.approx(used / 2)
    return (*change(sig, half), used)


@pytest.mark.parametrize("corner", list(CORNERS))
def test_halving_the_time_step_changes_little(corner):
    """Default settings (the step the model picks for the run) against half that step, or
    half the tolerance for the run it integrates adaptively (v-min). The full 1 s chirp is
    bench/convergence.py."""
    rms_db, d_thd, _ = step_change(CORNERS[corner], SolverSettings())
    assert rms_db < 0.5, rms_db
    assert d_thd < 0.05, d_thd


def test_the_stiff_friction_corner_is_integrated_adaptively():
    """At a fixed 10 us RK4 is unstable in the stick band of the friction at v-min
    (|lambda h| = 4.1) and chatters. The model integrates this run with error-controlled
    DOPRI5 steps instead, and agrees with RK4 at the 1.47 us step the linearisation asks of
    it (|lambda h| = 0.6; measured 0.02 dB and 0.01 % on this chirp) within the convergence
    bar, at over 5x RK4's mean step (measured 8 us). So does velocity Verlet
    (``stiff_method``), at |lambda h| <= 0.8 and with at most a quarter of RK4's right-hand
    sides, and at half its own step."""
    rms_db, d_thd, h = step_change(CORNERS["v-min"], SolverSettings(auto_step=False))
    assert h == 1e-5 and rms_db > 5.0 and d_thd > 1.0, (rms_db, d_thd)
    m = ShaftAssembly()
    sig = m.simulate(CORNERS["v-min"], SHORT)
    meta = sig.meta
    assert meta["integrator"] == "DOPRI5 adaptive" and meta["step_limited_by"] == "real eigenvalue"
    assert meta["real_lambda_h"] > 2.785  # beyond RK4's stability at the largest step
    rk4 = m.simulate(CORNERS["v-min"], SHORT, SolverSettings(step=1 / 34 / 20000,
                                                             auto_step=False))
    assert meta["mean_step"] > 5 * rk4.meta["step"]
    rms_db, d_thd = change(sig, rk4)
    assert rms_db < 0.5 and d_thd < 0.05, (rms_db, d_thd)
    verlet = SolverSettings(stiff_method="VelocityVerlet")
    fast = m.simulate(CORNERS["v-min"], SHORT, verlet)
    assert fast.meta["integrator"] == "VelocityVerlet" and fast.meta["real_lambda_h"] <= 0.8
    # one right-hand side per Verlet step (26 per sample), four per RK4 step (34 per sample)
    verlet_evaluations, rk4_evaluations = fast.meta["steps"], 4 * rk4.meta["steps"]
    assert verlet_evaluations <= rk4_evaluations / 4
    rms_db, d_thd = change(fast, rk4)
    assert rms_db < 0.5 and d_thd < 0.05, (rms_db, d_thd)
    rms_db, d_thd, _ = step_change(CORNERS["v-min"], verlet)
    assert rms_db < 0.5 and d_thd < 0.05, (rms_db, d_thd)


def test_deterministic_in_process_and_across_workers():
    from sensfw.runs import RunSpec
    from sensfw.runs.executor import run_processes

    m = ShaftAssembly()
    ex = Chirp(50, 5000, 0.05, 20000, AMP_NOMINAL)
    # nominal (10 us), all-min (a step the linearised eigenvalues choose) and v-min (adaptive
    # steps under error control)
    cases = [NOMINAL, CORNERS["all-min"], CORNERS["v-min"]]
    specs = [RunSpec.create(m, params, ex, SolverSettings()) for params in cases]
    got = {}
    run_processes(specs, lambda s, r: got.update({s.key(): r}), workers=1)
    for params, spec in zip(cases, specs, strict=True):
        a, b = m.simulate(params, ex), m.simulate(params, ex)
        c = got[spec.key()].signals
        assert a.meta["step"] == c.meta["step"]
        for ch in m.sensors:
            assert np.array_equal(a.channels[ch], b.channels[ch])
            assert np.array_equal(a.channels[ch], c.channels[ch])
    assert got[specs[1].key()].signals.meta["step"] < 1e-5
    assert got[specs[2].key()].signals.meta["integrator"] == "DOPRI5 adaptive"


def test_static_state_does_not_depend_on_what_the_process_solved_before():
    """Every run starts from the static equilibrium, so it must be bitwise the same whatever
    the process solved before it (in a study: the other runs of the design). The former
    solver chain reached the all-min corner through MINPACK ``lm``, which in scripts gave
    states a few ulps apart after other solves (10-20 of 80 repetitions), amplified to
    5e-10 m/s^2 in the first sample, and failed CI's determinism test once. The trigger
    depends on the process's history, so this test guards the property rather than
    reproducing that failure on demand."""
    m = ShaftAssembly()
    target = m.parameters().complete(CORNERS["all-min"])
    first = m.equilibrium(target)
    rng = np.random.default_rng(0)
    for _ in range(12):
        other = {k: float(rng.uniform(p.min, p.max)) for k, p in PARAMETERS.items()}
        other["slide_v_stiction"], other["slide_v_friction"] = 0.5, 1.0
        m.equilibrium(m.parameters().complete(other))
        assert np.array_equal(m.equilibrium(target), first)
    # and it is a static state: the residual forces vanish against gravity (mass * g, N)
    index = m.coordinates(target)
    weight = float(np.sum(index.masses()[index.y_index()])) * 9.81
    assert np.max(np.abs(m.generalized_forces(first, np.zeros(len(first)), target))) \
        < 1e-9 * weight


def test_divergence_is_one_clear_error_and_silent(capfd):
    m = ShaftAssembly()
    with pytest.raises(SimulationError) as info:
        # a fixed step far beyond RK4's stability (the automatic step would refuse it)
        m.simulate(NOMINAL, Chirp(50, 5000, 0.05, 20000, 1.0),
                   SolverSettings(step=5e-5, auto_step=False))
    msg = str(info.value)
    assert "shaft_assembly simulation failed" in msg and "slide_damping=234" in msg
    captured = capfd.readouterr()
    assert captured.out == "" and captured.err == ""


# A corner of Table 1 found by the fractional factorial of compare-designs on the paper
# study: both clutch contacts at their stiffest with the drive contact's softest exponent.
STIFF_CORNER = {
    "max": ["clutch_crank_stiffness", "clutch_drive_stiffness", "l1_clearance", "l1_damping",
            "slide_damping", "slide_exponent", "slide_mu_dynamic", "slide_mu_static",
            "slide_v_friction", "slide_v_stiction", "spring_damping", "spring_stiffness"],
    "min": ["bearing_preload", "clutch_crank_damping", "clutch_drive_damping",
            "clutch_drive_exponent", "l3_clearance", "l3_damping", "slide_clearance",
            "slide_stiffness"],
}


def test_a_stiff_corner_that_diverges_at_the_step_is_rerun_at_half_the_step(tmp_path):
    """With the step fixed, RK4 at 10 us is unstable at this corner (a contact mode at
    |lambda h| = 2.97, beyond RK4's 2.83); one halving cures it, the step used is recorded,
    and with no halving allowed the failure names the step. With the automatic step (the
    default) the linearisation predicts it and the first attempt succeeds."""
    import json

    from sensfw.runs import RunStore
    from sensfw.runs.spec import RunSpec, execute

    m = ShaftAssembly()
    params = {n: getattr(PARAMETERS[n], side) for side, names in STIFF_CORNER.items()
              for n in names}
    params = PARAMETERS.complete(params)
    ex = Chirp(50, 5000, 0.05, 20000, AMP_NOMINAL)
    fixed = {"step": 1e-5, "auto_step": False}
    strict = execute(RunSpec.create(m, params, ex, SolverSettings(**fixed, halvings=0)))
    assert not strict.ok and "diverged" in strict.error and "at step 1e-05 s" in strict.error
    spec = RunSpec.create(m, params, ex, SolverSettings(**fixed, halvings=1))
    res = execute(spec)
    assert res.ok, res.error
    assert res.signals.meta["step"] == 5e-6 and res.signals.meta["step_halvings"] == 1
    assert res.signals.meta["step_limited_by"] == "divergence"
    assert all(np.all(np.isfinite(x)) for x in res.signals.channels.values())
    RunStore(tmp_path).save(spec, res)
    assert json.loads((tmp_path / f"{spec.key()}.json").read_text())["step"] == 5e-6

    auto = execute(RunSpec.create(m, params, ex, SolverSettings(halvings=0)))
    assert auto.ok, auto.error
    meta = auto.signals.meta
    assert meta["step_halvings"] == 0 and meta["step"] < 5e-6
    assert meta["oscillatory_lambda_h"] <= 1.5 and meta["real_lambda_h"] <= 0.6
