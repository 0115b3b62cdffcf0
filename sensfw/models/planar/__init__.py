"""Planar multibody assemblies (rigid bodies, point masses, force elements, contacts): the
description a model builds for one parameter set (:mod:`.mechanism`), its statics with numpy
(:mod:`.statics`) and its Exudyn build (:mod:`.exudyn`)."""

from .mechanism import Body, Contacts, CoordinateIndex, Link, Mechanism, plus

__all__ = ["Body", "Contacts", "CoordinateIndex", "Link", "Mechanism", "plus"]
