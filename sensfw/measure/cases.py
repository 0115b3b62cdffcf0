"""Synthetic diagnosis cases with known answers, drawn at random: how often a diagnosis
finds the truth is a rate over such cases (``bench/recovery.py``), not a handful of chosen
examples.

A case (:func:`draw`) is an effect and a place drawn from all that fit the study's model
(or, in a quarter of the cases, no effect), its parameters in their calibration coding at
25-100 % of the way from the neutral value to the far bound (parameters without a neutral
value anywhere in their range), two or three of the study's calibration variables off
nominal by factors in 0.6-1.6 (log-uniform, inside their bounds), noise of 1-5 % of each
channel's RMS and one to three levels. :func:`measure` makes its records, :func:`outcome`
judges a verdict against it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..evaluate import model_with_effects
from ..models.places import fitting_places
from ..plugins import effects
from ..study import Study
from .calibration import Coordinates

#: the ranges :func:`draw` draws from by default (``bench/recovery.py``'s cases)
NOISE = (0.01, 0.05)
FACTORS = (0.6, 1.6)


def draw(study: Study, seed: int, levels: Sequence[float],
         noise: tuple[float, float] = NOISE, factors: tuple[float, float] = FACTORS) -> dict:
    """One random case (module docstring) from ``seed``; ``levels`` are the excitation
    levels a case draws one to three of. ``noise`` (fraction of each channel's RMS,
    uniform) and ``factors`` (of the base variables' nominal values, log-uniform) widen or
    move the defaults' ranges for cases unlike those a method was tuned on; with the
    defaults a seed draws the same case as ever (the draws keep their order)."""
    if not 0 < noise[0] <= noise[1]:
        raise ValueError(f"noise range {noise}: need 0 < low <= high")
    if not 0 < factors[0] <= factors[1]:
        raise ValueError(f"factor range {factors}: need 0 < low <= high")
    rng = np.random.default_rng(seed)
    model = model_with_effects(study, [])
    pairs = [(name, place) for name in effects.names()
             for place in fitting_places(model.places(), effects.get(name))]
    case: dict = {"seed": seed, "effect": None, "place": None, "params": {}}
    if rng.random() >= 0.25:
        name, place = pairs[int(rng.integers(len(pairs)))]
        eff = effects.get(name)(attach=place)
        values = {}
        for a in Coordinates.of(None, eff.parameters()).axes:
            if a.name in eff.neutral:
                zn = a.code(eff.neutral[a.name])
                far = 1.0 if zn <= 0 else -1.0
                values[a.name] = a.decode(zn + rng.uniform(0.25, 1.0) * (far - zn))
            else:
                values[a.name] = a.decode(rng.uniform(-1, 1))
        case.update(effect=name, place=place, params=values)
    space = study.calibration_space(list(study.spec.calibration.parameters))
    chosen = rng.choice(space.names, size=min(int(rng.integers(2, 4)), len(space)),
                        replace=False)
    base = {}
    for v in space.variables:
        if v.name in chosen:
            f = math.exp(rng.uniform(math.log(factors[0]), math.log(factors[1])))
            base[v.name] = float(np.clip(v.nominal * f, v.low, v.high))
    case["base"] = base
    case["sets"] = space.to_parameters({**space.nominal_row(), **base})
    case["noise"] = float(rng.uniform(*noise))
    n = int(rng.integers(1, 4))
    case["levels"] = sorted(float(x) for x in rng.choice(levels, size=n, replace=False))
    return case


def truth(case: dict) -> str:
    """The true hypothesis's name."""
    return f"{case['effect']}@{case['place']}" if case["effect"] else "parameters"


def true_values(study: Study, case: dict) -> tuple[list[dict] | None, dict[str, float]]:
    """The true hypothesis's effect specs and calibrated values (base variables, effect
    parameters)."""
    space = study.calibration_space(list(study.spec.calibration.parameters))
    values = {**space.nominal_row(), **case["base"], **case["params"]}
    spec = [{"name": case["effect"], "attach": case["place"]}] if case["effect"] else None
    return spec, values


def measure(study: Study, case: dict, folder: Path) -> list[str]:
    """The case's records (one CSV per level) in ``folder``."""
    from .io import write_csv
    from .synthetic import Rig, synthesize

    hidden = []
    if case["effect"]:
        hidden = [truth(case) + ":" + ",".join(f"{k}={v!r}"
                                               for k, v in case["params"].items())]
    files = []
    for i, level in enumerate(case["levels"]):
        sig, _ = synthesize(study, sets=case["sets"], effects=hidden, amplitude=level,
                            rig=Rig(noise=case["noise"], seed=case["seed"] * 10 + i))
        files.append(str(write_csv(Path(folder) / f"m{i}.csv", sig, level=level)))
    return files


def outcome(case: dict, named: Sequence[str], verdict: str, can_tell: bool) -> str:
    """The verdict against the case: ``"correct"`` / ``"false discovery"`` without an
    effect; where the data can tell, ``"right"`` (the effect and its place named; with the
    same effect at places the channels cannot tell apart), ``"right effect, wrong place"``,
    ``"wrong effect"`` or ``"missed"``; where they cannot, ``"correct (cannot tell)"``
    ("parameters" or "none") or ``"named (cannot tell)"`` / ``"wrong (cannot tell)"``."""
    if not case["effect"]:
        return "correct" if verdict in ("parameters", "none") else "false discovery"
    names = {n.split("@")[0] for n in named}
    if not can_tell:
        if verdict in ("parameters", "none"):
            return "correct (cannot tell)"
        return "named (cannot tell)" if truth(case) in named else "wrong (cannot tell)"
    if truth(case) in named and names == {case["effect"]}:
        return "right"
    if verdict in ("parameters", "none"):
        return "missed"
    return "right effect, wrong place" if case["effect"] in names else "wrong effect"
