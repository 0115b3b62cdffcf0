"""The second shipped model: the bolted lap-joint beam of the UNESP-BERT rig (Exudyn).

* :mod:`.parameters` — the parameters (E, density, damping, joint, clamp, shaker mass) and
  the fixed geometry;
* :mod:`.fe` — Euler-Bernoulli frame elements of the beams and their Craig-Bampton reduction;
* :mod:`.assembly` — the hooks effects act through, and the reduced structure with numpy
  (forces, statics, linearisation);
* :mod:`.mechanics` — the mechanics: beams, places (joint, clamp, beams), laws, force elements;
* :mod:`.simulation` — the Exudyn build and solve;
* :mod:`.model` — :class:`BoltedBeam`.
"""

from ...plugins import models
from .mechanics import places
from .model import BoltedBeam
from .parameters import PARAMETERS, Geometry

models.register("bolted_beam")(BoltedBeam)

__all__ = ["PARAMETERS", "BoltedBeam", "Geometry", "places"]
