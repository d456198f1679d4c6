"""``Registry``: named plug-ins (rewards, actors, losses, ...) found by the files that define them.

A plug-in package holds one module per plug-in; each module registers what it defines with
``@REGISTRY.register("name")``. The registry imports every module of its package the first time
a name is looked up, so adding a plug-in means adding its file (and its YAML), nothing else. A
name that is not registered raises a ``ValueError`` listing the valid ones.
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable
from typing import Any


class Registry:
    """Plug-ins of one kind; ``key`` names the config key that chooses them (for messages)."""

    def __init__(self, key: str, package: str):
        self.key = key
        self.package = package
        self._entries: dict[str, Any] = {}
        self._loaded = False

    def register(self, name: str) -> Callable[[Any], Any]:
        """Decorator: ``@REGISTRY.register("name")`` on a class or function."""

        def add(entry: Any) -> Any:
            if name in self._entries and self._entries[name] is not entry:
                raise ValueError(f"{self.key}: {name!r} is registered twice")
            self._entries[name] = entry
            return entry

        return add

    def get(self, name: str) -> Any:
        """The plug-in called ``name``; ``ValueError`` naming the valid ones if there is none."""
        self._load()
        if name not in self._entries:
            raise ValueError(
                f"{self.key}={name!r} is not available; choose one of {', '.join(self.names())}"
            )
        return self._entries[name]

    def names(self) -> tuple[str, ...]:
        self._load()
        return tuple(sorted(self._entries))

    def _load(self) -> None:
        if self._loaded:
            return
        self._loaded = True
        package = importlib.import_module(self.package)
        for module in pkgutil.iter_modules(package.__path__):
            if not module.name.startswith("_"):
                importlib.import_module(f"{self.package}.{module.name}")
