"""The hypotheses a diagnosis compares: "parameters only" (H0: the study's calibration
variables recalibrated) and every candidate effect at every place of the model it fits,
pruned by the signature classes of the measured amplitude dependence
(:mod:`sensfw.measure.signatures`) and by the effects the model already has."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

from ..errors import SensfwError
from ..evaluate import model_with_effects
from ..models.places import fitting_places
from ..params import DesignSpace
from ..plugins import effects as effect_registry
from ..runs import Runner
from ..study import Study
from . import discrepancy, signatures
from .calibration import Coordinates, Fit
from .io import Measurement
from .residuals import Residuals

Log = Callable[[str], None]


def calibration_variables(study: Study, runner: Runner, log: Log = lambda s: None
                          ) -> tuple[list[str], str]:
    """The base variables to calibrate and where they come from: ``[calibration]
    parameters``, else every variable the first stage's screen ranks above its threshold
    (the screen runs through the run store, so it is reused when it exists)."""
    cal = study.spec.calibration
    if cal is not None and cal.parameters:
        return list(cal.parameters), "[calibration] parameters"
    stage = study.stages[0]
    if stage.select is None:
        raise SensfwError("diagnosis needs the base parameters to calibrate: add "
                          "[calibration] parameters = [...] to the study, or a screening "
                          "first stage with a [select]")
    from ..pipeline import run_stage

    log(f"screen {stage.name!r} for the calibration variables")
    res = run_stage(study, stage, runner, {})
    imp = res.screening.importance
    names = [n for n in imp.sort_values(ascending=False).index
             if imp[n] >= stage.select.threshold]
    return names, f"screen {stage.name!r} above {stage.select.threshold:.0%}"


def calibration_residuals(study: Study, measurements: Sequence[Measurement], runner: Runner,
                          log: Log = lambda s: None
                          ) -> tuple[list[str], str, DesignSpace, Residuals]:
    """Where H0 is calibrated: the :func:`calibration_variables` and where they come from,
    their design space, and the residuals of ``measurements`` over it."""
    names, source = calibration_variables(study, runner, log)
    space = study.calibration_space(names)
    return names, source, space, Residuals(study, measurements, runner, space)


def neutral_values(effect) -> dict[str, float]:
    """Effect parameters at their nominal values overridden by the neutral ones (where the
    effect vanishes exactly)."""
    return {**{p.name: p.nominal for p in effect.parameters()}, **effect.neutral}


@dataclass
class Hypothesis:
    """H0 (``effect is None``) or an effect at a place, with its calibration."""

    effect: object | None
    place: str
    coords: Coordinates
    fit: Fit | None = None
    heldout: float | None = None
    notes: list[str] = field(default_factory=list)
    #: the screen's estimate: the surrogate's predicted optimum and its lower bound
    screen: dict = field(default_factory=dict)

    @property
    def name(self) -> str:
        return "parameters" if self.effect is None else f"{self.effect.name}@{self.place}"

    @property
    def effects(self) -> list[dict]:
        """The effect specs of this hypothesis's model variant."""
        return [] if self.effect is None else [self.effect.spec()]

    @property
    def neutral(self) -> dict[str, float]:
        return {} if self.effect is None else neutral_values(self.effect)

    @property
    def own(self) -> list[str]:
        """The effect's parameter names."""
        return [] if self.effect is None else [p.name for p in self.effect.parameters()]

    @property
    def k(self) -> int:
        return len(self.coords)

    def bic(self, n: int) -> float:
        return self.fit.chi2 + self.k * math.log(n)

    def row(self, n: int, h0: Hypothesis | None) -> dict:
        fit = self.fit
        out = {"hypothesis": self.name,
               "effect": None if self.effect is None else self.effect.name,
               "place": self.place or None, "k": self.k, "chi2": fit.chi2,
               "chi2_per_entry": fit.chi2 / n, "bic": self.bic(n),
               "fits_noise": discrepancy.fits(fit.best.w, self.k),
               "heldout_chi2_per_entry": self.heldout,
               "params": fit.values, "calibration": fit.summary(),
               "trades": fit.trades(), "n_points": fit.n_points,
               "surrogate": fit.info.get("surrogate"), "screen": self.screen,
               "notes": self.notes}
        if h0 is not None and h0.fit is not None:
            out["delta_bic"] = h0.bic(n) - out["bic"]
        return out


def candidate_names(study: Study, names: Sequence[str] | None, log: Log = lambda s: None
                    ) -> list[tuple[str, str | None]]:
    """``names`` (``NAME`` or ``NAME@PLACE``; default every registered effect) as (effect,
    place or None), checked before anything runs: an empty item, an unknown effect, a
    place the effect does not fit are errors; a candidate given twice (or at a place its
    own ``NAME`` already covers) is raced once, with a note."""
    places = model_with_effects(study, []).places()
    wanted: list[tuple[str, str | None]] = []
    for c in names or effect_registry.names():
        name, _, place = c.partition("@")
        name, place = name.strip(), place.strip() or None
        if not name:
            raise SensfwError(f"candidate {c!r}: an empty effect name (the list is "
                              "NAME or NAME@PLACE, separated by commas)")
        fits = fitting_places(places, effect_registry.get(name))  # raises for unknown
        if not fits and names is None:  # every registered effect: those that fit here
            continue
        if not fits:
            raise SensfwError(f"candidate {name}: it fits no place of the model "
                              f"{study.model_ref()['name']}")
        if place is not None and place not in fits:
            raise SensfwError(f"candidate {name}@{place}: the model has no place {place!r} "
                              f"that {name} fits ({', '.join(fits)})")
        if (name, place) in wanted or (name, None) in wanted:
            log(f"  {c.strip()}: given twice; raced once")
            continue
        if place is None and any(n == name for n, _ in wanted):
            log(f"  {name}: every place it fits, besides those given with it")
            wanted = [(n, p) for n, p in wanted if n != name]
        wanted.append((name, place))
    return wanted


def candidates(study: Study, names: Sequence[str] | None, found: Mapping,
               base: Coordinates, log: Log = lambda s: None, prune: bool = True
               ) -> list[Hypothesis]:
    """Every candidate effect at every place it fits (``names``: ``NAME`` or
    ``NAME@PLACE``; default every registered effect; :func:`candidate_names`), less the
    effects the study's model already has (an augmented study: their parameters are the
    model's) and, with ``prune``, the effects whose signature classes the levels do not
    show (``found``)."""
    model = model_with_effects(study, [])
    places = model.places()
    owned = {p.name: f"{e.name}@{e.attach}" for e in getattr(model, "effects", ())
             for p in e.parameters()}
    out = []
    for name, place in candidate_names(study, names):
        cls = effect_registry.get(name)
        fits = fitting_places(places, cls)
        clash = sorted({owned[p.name] for p in cls().parameters() if p.name in owned})
        if clash:
            log(f"  {name}: the model has it already ({', '.join(clash)}); left out")
            continue
        if found and not signatures.allows(cls, found):
            log(f"  {name}: its signature {sorted(cls.signature_classes)} is not in the "
                f"measurement's; {'left out' if prune else 'kept (no pruning)'}")
            if prune:
                continue
        for pl in [place] if place else fits:
            eff = cls(attach=pl)
            out.append(Hypothesis(eff, pl, base + Coordinates.of(None, eff.parameters())))
    return out


def pruned(study: Study, names: Sequence[str] | None, kept: Sequence[Hypothesis],
           base: Coordinates) -> list[Hypothesis]:
    """The candidates :func:`candidates` left out by their signature classes (those the
    model has already stay out)."""
    have = {h.name for h in kept}
    return [h for h in candidates(study, names, {}, base) if h.name not in have]
