"""Physical effects (plugin group ``sensfw.effects``): physics added at a named place of any
model, through the hooks the model offers there (:mod:`sensfw.models.places`).

* :mod:`.base` — the :class:`Effect` contract and the signature classes;
* :mod:`.contact` — effects on a contact's law: ``clearance``, ``friction``,
  ``contact_hardening``;
* :mod:`.elements` — effects that add force elements, bodies or mass: ``damping``,
  ``preload``, ``added_mass``, ``flexible_mode``, ``limit_stop``;
* :mod:`.joint` — effects at a bolted joint: ``micro_slip`` (Iwan model of Jenkins
  elements), ``cubic_stiffness`` (``clearance`` and ``damping`` fit joints too);
* :mod:`.laws` — the wrapped contact and joint laws the effects put in place.
"""

from . import contact, elements, joint  # noqa: F401  (register the built-ins)
from .base import SIGNATURE_CLASSES, Effect, make_effect

__all__ = ["SIGNATURE_CLASSES", "Effect", "make_effect"]
