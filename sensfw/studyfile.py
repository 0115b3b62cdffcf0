"""Editing study files in place: moved to :mod:`sensfw.study.edit`; these names stay
importable from here because :mod:`sensfw.measure` and the command line use them."""

from .study.edit import add_effect, set_calibration, set_nominals

__all__ = ["add_effect", "set_calibration", "set_nominals"]
