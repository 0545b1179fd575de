"""pytest settings for the whole tree: the names every docstring example may use.

Docstring examples (``--doctest-modules`` over src/armkit, see pyproject.toml) run with
``np`` and ``armkit`` already imported, as the examples are written.
"""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(autouse=True)
def _doctest_names(doctest_namespace):
    import armkit

    doctest_namespace["np"] = np
    doctest_namespace["armkit"] = armkit
    np.set_printoptions(legacy=False)
