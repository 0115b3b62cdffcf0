"""The ``sensfw`` command line (typer + rich): :mod:`.common` (app, options, errors,
progress), :mod:`.study` (run, report, validate, compare-designs, plugins, places) and
:mod:`.measure` (simulate, compare, diagnose, augment). The work of every command is in the
library; these modules parse options and print results."""

import importlib
import sys

from .common import app

for _module in ("study", "measure"):  # registers the commands, in this order in the help
    importlib.import_module(f"{__name__}.{_module}")


def main() -> None:  # pragma: no cover
    sys.exit(app())


__all__ = ["app", "main"]
