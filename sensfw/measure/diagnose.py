"""Find the physical effect the model lacks, and calibrate it.

For each candidate effect the model is extended by that effect and its few parameters are
calibrated against the measurement, surrogate-assisted because simulations are costly: a
small design over the effect's parameters (5 points for one parameter, 3x3 for two; log
spacing for ranges over a factor 10), a Gaussian-process surrogate of the discrepancy,
its minimiser confirmed by simulation (twice, refitting the surrogate with the new point).
Candidates are ranked by the Bayesian information criterion of the remaining discrepancy,
``BIC = n ln(RSS/n) + k ln n`` (n discrepancy entries, k added parameters), against the
model without any effect; the verdict is "none" when no candidate lowers the BIC clearly
(by more than ``min_delta_bic``) and the error by at least ``min_reduction`` — then nothing
explains more than noise.

The discrepancy of one level is a vector of dB differences: the FRF in one-third-octave
bands (H1 averaged coherently over each band, so noise averages down), and the THD ratio
model/measured in dB (weighted as ``THD_WEIGHT`` bands); over several levels the vectors
are stacked. Bands more than 35 dB (the dynamic range) below the strongest measured band are
left out (:attr:`~sensfw.measure.compare.LevelComparison.used_bands`): there the response
is weak and a shaker measurement is noise-limited (with 2 % noise the low-frequency bands
of the shipped model's axial FRF read 5-15 dB high).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import SensfwError
from ..models.places import fitting_places
from ..plugins import effects as effect_registry
from ..runs import Runner
from ..study import Study
from .compare import compare_level
from .io import Measurement
from .session import Variant, simulate
from .synthetic import model_with_effects

THD_WEIGHT = 3.0


def discrepancy(comparisons) -> np.ndarray:
    """Stacked dB differences of several :class:`~sensfw.measure.compare.LevelComparison`."""
    parts = []
    for c in comparisons:
        parts.append(np.array([b["mean_db"] for b in c.used_bands]))
        if c.thd_model and c.thd_measured:
            parts.append(np.array([20 * np.log10(c.thd_model / c.thd_measured)])
                         * math.sqrt(THD_WEIGHT))
    return np.concatenate(parts)


def rms(v: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(v))))


def bic(v: np.ndarray, k: int) -> float:
    n = len(v)
    return float(n * np.log(max(np.mean(np.square(v)), 1e-300)) + k * np.log(n))


@dataclass
class Evaluation:
    values: dict[str, float]
    vector: np.ndarray | None  # None: the simulation failed

    @property
    def error(self) -> float:
        return rms(self.vector) if self.vector is not None else math.inf


@dataclass
class Candidate:
    effect: str
    attach: str
    params: list[str]
    evaluations: list[Evaluation] = field(default_factory=list)

    def best(self) -> Evaluation:
        return min(self.evaluations, key=lambda e: e.error)


class Evaluator:
    """Discrepancy of model variants against the measurements (through the run store)."""

    def __init__(self, study: Study, measurements: Sequence[Measurement], runner: Runner,
                 band: tuple[float, float] | None = None):
        self.study, self.meas, self.runner = study, list(measurements), runner
        ex = study.excitation
        self.band = band or (ex.f0, ex.f1)
        self.levels = [m.level for m in self.meas]
        self.n_simulations = 0

    def comparisons(self, variants: Sequence[Variant], label: str):
        sims = simulate(self.study, self.runner, variants, self.meas, label)
        self.n_simulations += len(sims)
        out = []
        for v in variants:
            comps = []
            for i, m in enumerate(self.meas):
                sig = sims[(v, i)]
                if sig is None:
                    comps = None
                    break
                comps.append(compare_level(m.signals, sig, self.study.output, self.band,
                                           m.level, m.file))
            out.append(comps)
        return out

    def evaluate(self, variants: Sequence[Variant], label: str) -> list[np.ndarray | None]:
        return [None if c is None else discrepancy(c) for c in self.comparisons(variants,
                                                                                label)]


class Coding:
    """Map effect parameters to [-1, 1] (logarithmically for ranges of a factor 10 or more)."""

    def __init__(self, params):
        self.names = [p.name for p in params]
        self.lo = np.array([p.min for p in params], float)
        self.hi = np.array([p.max for p in params], float)
        self.log = (self.lo > 0) & (self.hi >= 10 * self.lo)

    def _t(self, x):
        return np.where(self.log, np.log10(np.where(self.log, x, 1.0)), x)

    def code(self, values) -> np.ndarray:
        x = np.array([values[n] for n in self.names] if isinstance(values, dict) else values,
                     float)
        a, b = self._t(self.lo), self._t(self.hi)
        return 2 * (self._t(x) - a) / (b - a) - 1

    def decode(self, z) -> dict[str, float]:
        a, b = self._t(self.lo), self._t(self.hi)
        t = a + (np.clip(np.asarray(z, float), -1, 1) + 1) / 2 * (b - a)
        x = t.copy()
        x[self.log] = 10.0 ** t[self.log]
        return dict(zip(self.names, map(float, x), strict=True))

    def grid(self, levels: dict, default: int) -> list[dict[str, float]]:
        axes = [np.linspace(-1, 1, levels.get(n, default)) for n in self.names]
        pts = np.array(np.meshgrid(*axes, indexing="ij")).reshape(len(axes), -1).T
        return [self.decode(z) for z in pts]


def calibrate(ev: Evaluator, effect: dict, params, label: str, refine: int = 2,
              points_1d: int = 5, points_2d: int = 3,
              seeds: Sequence[dict] = (), levels: dict | None = None) -> Candidate:
    """Surrogate-assisted calibration of one effect's parameters (see module docstring);
    ``seeds`` are extra design points suggested by the evidence."""
    import warnings

    from sklearn.exceptions import ConvergenceWarning
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    cod = Coding(params)
    base = Variant.of([effect])
    cand = Candidate(effect=effect["name"], attach=effect.get("attach", ""), params=cod.names)
    k = len(cod.names)

    def run(points: list[dict]) -> None:
        vecs = ev.evaluate([base.with_params(x) for x in points], label)
        cand.evaluations += [Evaluation(x, v) for x, v in zip(points, vecs, strict=True)]

    design = cod.grid(levels or {}, points_1d if k == 1 else points_2d)
    run(design + [sd for sd in seeds if set(sd) == set(cod.names)])
    dense = np.array(np.meshgrid(*[np.linspace(-1, 1, 201 if k == 1 else 41)] * k,
                                 indexing="ij")).reshape(k, -1).T
    for _ in range(refine):
        ok = [e for e in cand.evaluations if e.vector is not None]
        if len(ok) < 3:
            break
        Z = np.array([cod.code(e.values) for e in ok])
        y = np.log(np.array([e.error for e in ok]) + 1e-6)
        kernel = ConstantKernel(1.0) * RBF([0.5] * k, (0.05, 10.0)) + \
            WhiteKernel(1e-3, (1e-8, 1e-1))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)  # small designs, by design
            gp = GaussianProcessRegressor(kernel, normalize_y=True, n_restarts_optimizer=2,
                                          random_state=0).fit(Z, y)
        x_best = cod.decode(dense[int(np.argmin(gp.predict(dense)))])
        if any(np.allclose(cod.code(x_best), cod.code(e.values), atol=1e-6)
               for e in cand.evaluations):
            break
        run([x_best])
    return cand


def evidence(effect_cls, before, after) -> list[str]:
    """What the measurement shows that this effect explains (words for the report)."""
    out = []
    b0, a0 = before[0], after[0] if after else None
    thd_ratio = b0.thd_measured / b0.thd_model if b0.thd_model else float("nan")
    if np.isfinite(thd_ratio) and abs(np.log(thd_ratio)) > np.log(1.25):
        out.append(f"measured THD {b0.thd_measured:.2f} % vs model {b0.thd_model:.2f} % "
                   f"({thd_ratio:.2f}x)")
    shifts = [r for r in b0.resonances if r["shift_pct"] is not None and
              abs(r["shift_pct"]) > 1.0]
    if shifts:
        out.append("resonances shifted: " + ", ".join(
            f"{r['measured_hz']:.0f} Hz measured vs {r['model_hz']:.0f} Hz model"
            for r in shifts[:3]))
    missing = [r for r in b0.resonances if r["model_hz"] is None]
    if missing:
        out.append("measured peaks without a model mode: " + ", ".join(
            f"{r['measured_hz']:.0f} Hz" for r in missing[:3]))
    worst = sorted(b0.bands, key=lambda b: -abs(b["mean_db"]))[:2]
    if worst and abs(worst[0]["mean_db"]) > 1.0:
        out.append("largest FRF differences in the bands " + ", ".join(
            f"{b['centre_hz']:.0f} Hz ({b['mean_db']:+.1f} dB)" for b in worst))
    if a0 is not None:
        out.append(f"with the effect calibrated the FRF error falls from "
                   f"{b0.frf_rms_db:.2f} dB to {a0.frf_rms_db:.2f} dB and the THD gap from "
                   f"{b0.thd_model:.2f}/{b0.thd_measured:.2f} % to "
                   f"{a0.thd_model:.2f}/{a0.thd_measured:.2f} %")
    out.append("this effect typically shows: " + "; ".join(effect_cls.signatures))
    return out


def diagnose(study: Study, measurements: Sequence[Measurement], runner: Runner,
             candidates: Sequence[str] | None = None, min_delta_bic: float = 10.0,
             min_reduction: float = 0.3, refine_top: int = 3, refine_iterations: int = 5,
             log=lambda s: None) -> dict:
    """Rank the candidate effects (all registered ones by default); see module docstring.
    The ``refine_top`` best candidates after the surrogate stage get a local search of
    ``refine_iterations`` compass steps before the final ranking."""
    ev = Evaluator(study, measurements, runner)
    names = list(candidates) if candidates else effect_registry.names()
    places = model_with_effects(study, []).places()
    base_cmp = ev.comparisons([Variant()], "baseline")[0]
    if base_cmp is None:
        raise SensfwError("the study's model failed at the measured level(s); nothing to "
                          "compare")
    base_vec = discrepancy(base_cmp)
    bic0 = bic(base_vec, 0)
    cands: dict[tuple[str, str], tuple] = {}
    for name in names:
        cls = effect_registry.get(name)
        for attach in fitting_places(places, cls):
            log(f"candidate {name}@{attach}")
            eff = cls(attach=attach)
            cand = calibrate(ev, eff.spec(), eff.parameters(), f"{name}",
                             seeds=eff.seeds(base_cmp), levels=eff.design_levels)
            cands[(name, attach)] = (cls, eff, cand)
    # second round for the most promising: a local search on simulations, so that a
    # narrow valley missed by the small design does not decide the ranking
    ranked = sorted(cands.values(), key=lambda c: c[2].best().error)
    for _, eff, cand in ranked[:refine_top]:
        log(f"refining {eff.name}@{eff.attach}")
        refine_local(ev, cand, eff.spec(), eff.parameters(), f"{eff.name} refine",
                     max_iter=refine_iterations)
    rows = []
    for (name, attach), (cls, eff, cand) in cands.items():
        best = cand.best()
        if best.vector is None:
            continue
        spec = eff.spec()
        after_cmp = ev.comparisons([Variant.of([spec], best.values)], f"{name} confirm")[0]
        k = len(cand.params)
        score = bic(best.vector, k)
        rows.append({
            "effect": name, "attach": attach, "params": best.values,
            "error_before": rms(base_vec), "error_after": best.error,
            "reduction": 1 - best.error / rms(base_vec) if rms(base_vec) > 0 else 0.0,
            "score": score, "delta_bic": bic0 - score, "n_params": k,
            "n_evaluations": len(cand.evaluations),
            "evidence": evidence(cls, base_cmp, after_cmp),
        })
    rows.sort(key=lambda r: r["score"])
    top = rows[0] if rows else None
    verdict = "none"
    if top and top["delta_bic"] > min_delta_bic and top["reduction"] >= min_reduction:
        verdict = top["effect"]
    return {"verdict": verdict, "ranking": rows, "n_simulations": ev.n_simulations,
            "baseline": {"error": rms(base_vec), "bic": bic0,
                         "comparison": [c.to_dict() for c in base_cmp]},
            "criteria": {"min_delta_bic": min_delta_bic, "min_reduction": min_reduction,
                         "thd_weight": THD_WEIGHT,
                         "dynamic_range_db": base_cmp[0].dynamic_range}}


def refine_local(ev: Evaluator, cand: Candidate, effect: dict, params, label: str,
                 step: float = 0.25, min_step: float = 0.002, max_iter: int = 14) -> Candidate:
    """Compass search around the best point on actual simulations: the 2k neighbours at
    +-``step`` (coded units) are simulated together (in parallel); move to the best if it
    improves, else halve the step."""
    cod = Coding(params)
    base = Variant.of([effect])
    best = cand.best()
    z, err = cod.code(best.values), best.error
    for _ in range(max_iter):
        if step < min_step:
            break
        trials = []
        for i in range(len(z)):
            for s in (-step, step):
                zz = z.copy()
                zz[i] = np.clip(zz[i] + s, -1, 1)
                if not np.allclose(zz, z):
                    trials.append(zz)
        if not trials:
            break
        xs = [cod.decode(t) for t in trials]
        vecs = ev.evaluate([base.with_params(x) for x in xs], label)
        improved = False
        for t, x, vec in zip(trials, xs, vecs, strict=True):
            e = Evaluation(x, vec)
            cand.evaluations.append(e)
            if e.error < err - 1e-9:
                z, err, improved = t, e.error, True
        if not improved:
            step /= 2
    return cand


def refine_simplex(ev: Evaluator, cand: Candidate, effect: dict, params, label: str,
                   size: float = 0.05, max_evaluations: int = 30) -> Candidate:
    """Nelder-Mead on actual simulations from the best point (coded units, clipped to the
    bounds): follows curved valleys (e.g. frequency and damping of a light mode) where the
    compass search stalls."""
    from scipy.optimize import minimize

    cod = Coding(params)
    base = Variant.of([effect])

    def f(z):
        x = cod.decode(z)
        vec = ev.evaluate([base.with_params(x)], label)[0]
        e = Evaluation(x, vec)
        cand.evaluations.append(e)
        return e.error

    z0 = cod.code(cand.best().values)
    simplex = [z0] + [np.clip(z0 + size * np.eye(len(z0))[i], -1, 1) for i in range(len(z0))]
    minimize(f, z0, method="Nelder-Mead",
             options={"initial_simplex": np.array(simplex), "maxfev": max_evaluations,
                      "xatol": 1e-4, "fatol": 1e-4})
    return cand


def augment(study: Study, measurements: Sequence[Measurement], runner: Runner, effect: str,
            attach: str | None = None, start: Mapping[str, float] | None = None,
            log=lambda s: None) -> dict:
    """Add ``effect`` to the model and calibrate it: the error trajectory (baseline, effect
    added at its nominal values, calibrated) and the calibrated parameter values. ``start``
    (e.g. the values :func:`diagnose` found) replaces the surrogate-assisted design by a
    local search from that point."""
    ev = Evaluator(study, measurements, runner)
    cls = effect_registry.get(effect)
    eff = cls(attach=attach)
    model_with_effects(study, [eff])  # resolves (and checks) where the effect attaches
    spec = eff.spec()
    params = eff.parameters()
    base_cmp = ev.comparisons([Variant()], "baseline")[0]
    if base_cmp is None:
        raise SensfwError("the study's model failed at the measured level(s)")
    nominal = {p.name: p.nominal for p in params}
    added = ev.evaluate([Variant.of([spec], nominal)], f"{effect} added")[0]
    log(f"calibrating {effect}@{eff.attach}")
    if start is None:
        cand = calibrate(ev, spec, params, effect, refine=3, seeds=eff.seeds(base_cmp),
                         levels=cls.design_levels)
    else:
        names = [p.name for p in params]
        if set(start) != set(names):
            raise SensfwError(f"start values for {effect} must give exactly {names}, got "
                              f"{sorted(start)}")
        x0 = {n: float(start[n]) for n in names}
        cand = Candidate(effect=effect, attach=eff.attach, params=names, evaluations=[
            Evaluation(x0, ev.evaluate([Variant.of([spec], x0)], f"{effect} start")[0])])
    cand = refine_local(ev, cand, spec, params, f"{effect} refine")
    cand = refine_simplex(ev, cand, spec, params, f"{effect} refine")
    best = cand.best()
    after = ev.comparisons([Variant.of([spec], best.values)], f"{effect} calibrated")[0]
    trajectory = [
        {"step": "baseline", "error": rms(discrepancy(base_cmp)), "params": {}},
        {"step": "effect added", "error": rms(added) if added is not None else None,
         "params": nominal},
        {"step": "calibrated", "error": best.error, "params": best.values},
    ]
    return {"effect": effect, "attach": eff.attach, "params": best.values,
            "trajectory": trajectory, "n_simulations": ev.n_simulations,
            "evidence": evidence(cls, base_cmp, after),
            "comparison": {"baseline": [c.to_dict() for c in base_cmp],
                           "calibrated": [c.to_dict() for c in after] if after else None},
            "evaluations": [{"params": e.values, "error": e.error if e.vector is not None
                             else None} for e in cand.evaluations]}
