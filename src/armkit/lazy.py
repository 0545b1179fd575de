"""A package's names loaded on first use (PEP 562): importing the package costs little more
than the modules it cannot do without.

A package lists its public names once, as imports: those it needs at once at the top, the rest
in an ``if TYPE_CHECKING:`` block (which type checkers and readers follow, and Python skips).
`lazy_names` reads that block from the package's source and loads each of its names from its
module at the first use.
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


def lazy_names(package: str) -> tuple[Callable, Callable, list[str]]:
    """The package's ``__getattr__``, ``__dir__`` and ``__all__``.

    A name that the package's ``if TYPE_CHECKING:`` block imports is imported from its module
    at its first use and kept in the package's namespace, so that later look-ups are plain
    attribute reads. ``__all__`` holds the names the package imports at the top, then those.
    """
    module = sys.modules[package]
    with open(module.__file__, encoding="utf-8") as file:
        text = file.read()
    block = re.search(r"^if TYPE_CHECKING:.*\n((?:[ \t]+.*\n|\n)*)", text, re.M)
    homes = _imports(block.group(1), "    ") if block else {}
    eager = [name for name in _imports(text, "") if not name.startswith("_")]
    namespace = module.__dict__

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
