"""One small plugin registry used by every plugin kind (designs, scorers, surrogates, models,
effects).

Built-ins register with the :meth:`Registry.register` decorator in the modules named by
``builtins`` (imported on first use, so importing sensfw stays cheap). Third-party plugins
declare an entry point in the registry's group (``sensfw.designs`` ...); entry points load
lazily on the first lookup that misses, and one that fails to load is a warning, not a crash
(as xarray does for its backends).

A name of the form ``"package.module:Class"`` (the form of an entry point's value) is imported
on first use and registered under that name, so a plugin in any importable module works
without packaging, also in worker processes (which import it again by the same name); the
test suite's fault-injection model is used this way.
"""

from __future__ import annotations

import importlib
import warnings
from collections.abc import Callable, Iterator
from importlib.metadata import entry_points
from typing import Generic, TypeVar

from .errors import UnknownPluginError

T = TypeVar("T")


class Registry(Generic[T]):
    """Name -> plugin mapping for one plugin kind."""

    def __init__(self, kind: str, group: str, builtins: tuple[str, ...] = ()):
        self.kind, self.group, self._builtin_modules = kind, group, builtins
        self._items: dict[str, T] = {}
        self._origin: dict[str, str] = {}
        self._builtins_loaded = self._entry_points_loaded = False

    def register(self, name: str | None = None) -> Callable[[T], T]:
        """Decorator registering a built-in plugin under ``name`` (default: its ``name``)."""

        def deco(obj: T) -> T:
            self.add(name or getattr(obj, "name", None) or obj.__name__, obj, origin="built-in")
            return obj

        return deco

    def add(self, name: str, obj: T, origin: str = "runtime") -> None:
        self._items[name] = obj
        self._origin[name] = origin

    def _load_builtins(self) -> None:
        if not self._builtins_loaded:
            self._builtins_loaded = True
            for module in self._builtin_modules:
                importlib.import_module(module)

    def _load_entry_points(self) -> None:
        if self._entry_points_loaded:
            return
        self._entry_points_loaded = True
        for ep in entry_points(group=self.group):
            if ep.name in self._items:
                continue
            try:
                self.add(ep.name, ep.load(), origin=f"entry point {ep.value}")
            except Exception as exc:  # a broken plugin must not break sensfw
                warnings.warn(
                    f"could not load {self.kind} plugin {ep.name!r} ({ep.value}): {exc}",
                    RuntimeWarning,
                    stacklevel=2,
                )

    def _load_reference(self, name: str) -> None:
        """Import ``"module:attr"`` and register it under that name."""
        module, _, attr = name.partition(":")
        try:
            obj = importlib.import_module(module.strip())
            for part in attr.strip().split("."):
                obj = getattr(obj, part)
        except Exception as err:  # ImportError, AttributeError, or the module's own error
            raise UnknownPluginError(self.kind, name, self.names(),
                                     reason=f"cannot import {name!r} ({err})") from None
        self.add(name, obj, origin=f"module {module.strip()}")

    def get(self, name: str) -> T:
        """The plugin registered as ``name`` (or importable as ``"module:attr"``);
        :class:`UnknownPluginError` lists the others."""
        self._load_builtins()
        if name not in self._items:
            self._load_entry_points()
        if name not in self._items and ":" in name:
            self._load_reference(name)
        if name not in self._items:
            raise UnknownPluginError(self.kind, name, self.names())
        return self._items[name]

    def names(self) -> list[str]:
        self._load_builtins()
        self._load_entry_points()
        return sorted(self._items)

    def origin(self, name: str) -> str:
        self.get(name)
        return self._origin[name]

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name in self.names()

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())
