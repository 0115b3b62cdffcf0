"""The registries of every plugin kind, in one place.

>>> from sensfw.plugins import designs
>>> design = designs.get("oat")
"""

from __future__ import annotations

from .registry import Registry

models: Registry = Registry("model", "sensfw.models", ("sensfw.models",))
designs: Registry = Registry("design", "sensfw.designs", ("sensfw.designs",))
scorers: Registry = Registry("scorer", "sensfw.scorers", ("sensfw.scorers",))
surrogates: Registry = Registry("surrogate", "sensfw.surrogates", ("sensfw.surrogates",))
effects: Registry = Registry("effect", "sensfw.effects", ("sensfw.effects",))

ALL: dict[str, Registry] = {
    "models": models,
    "designs": designs,
    "scorers": scorers,
    "surrogates": surrogates,
    "effects": effects,
}
