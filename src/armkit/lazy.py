"""A package's names loaded on first use (PEP 562): importing the package costs little more
than the modules it cannot do without.

A package lists its public names once, as imports: those it needs at once at the top, the rest
in an ``if TYPE_CHECKING:`` block (which type checkers and readers follow, and Python skips).
`lazy_names` reads that block from the package's source and loads each of its names from its
module at the first use; `public_names` gives ``__all__`` of a package without lazy names.
"""

from __future__ import annotations

import importlib
import re
import sys
from collections.abc import Callable


# ``from armkit.x import a, b`` or ``from armkit.x import (a,\n b)``, at `indent` spaces.
_IMPORT = r"^{indent}from (armkit[\w.]*) import (\([^)]*\)|[^\n]*)"


def _imports(text: str, indent: str) -> dict[str, str]:
    """The names that `text`'s ``from armkit... import ...`` statements at `indent` bind ->
    their modules (armkit.lazy's own left out)."""
    return {name.split(" as ")[-1].strip(): module
            for module, names in re.findall(_IMPORT.format(indent=indent), text, re.M)
            if module != __name__
            for name in names.strip("()").split(",") if name.strip()}


def _source(package: str) -> str:
    with open(sys.modules[package].__file__, encoding="utf-8") as file:
        return file.read()


def public_names(package: str) -> list[str]:
    """A package's ``__all__`` when it loads everything at once: the names its top-level
    ``from armkit... import ...`` statements bind."""
    return [name for name in _imports(_source(package), "") if not name.startswith("_")]


def lazy_names(package: str) -> tuple[Callable, Callable, list[str]]:
    """The package's ``__getattr__``, ``__dir__`` and ``__all__``.

    A name that the package's ``if TYPE_CHECKING:`` block imports is imported from its module
    at its first use and kept in the package's namespace, so that later look-ups are plain
    attribute reads. ``__all__`` holds the names the package imports at the top, then those.
    """
    text = _source(package)
    block = re.search(r"^if TYPE_CHECKING:.*\n((?:[ \t]+.*\n|\n)*)", text, re.M)
    homes = _imports(block.group(1), "    ") if block else {}
    eager = public_names(package)
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

    return __getattr__, __dir__, [*eager, *homes]
