"""The shipped benchmark model: a nested output-shaft assembly with contacts (Exudyn).

* :mod:`.table1` — the parameters (Table 1 + preload), their grouping and the fixed geometry;
* :mod:`.mechanics` — the mechanics: bodies, places (contacts and bodies) and force elements;
* :mod:`.model` — :class:`ShaftAssembly`: effects at places, statics, Exudyn build, simulation
  (the generic planar machinery is in :mod:`sensfw.models.planar`).
"""

from ...plugins import models
from .mechanics import HOUSING, places
from .model import ShaftAssembly
from .table1 import GROUPS, PARAMETERS, Geometry

models.register("shaft_assembly")(ShaftAssembly)

__all__ = ["GROUPS", "HOUSING", "PARAMETERS", "Geometry", "ShaftAssembly", "places"]
