"""A package's names loaded on first use (PEP 562): importing the package costs little more
than the modules it cannot do without."""

from __future__ import annotations

import importlib
import sys


def lazy_names(package: str, homes: dict[str, str]):
    """The package's ``__getattr__`` and ``__dir__``: a name of `homes` (name -> the module that
    defines it) is imported at its first use and kept in the package's namespace, so that
    later look-ups are plain attribute reads."""
    namespace = sys.modules[package].__dict__

    def __getattr__(name: str):
        home = homes.get(name)
        if home is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(home), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(homes))

    return __getattr__, __dir__
