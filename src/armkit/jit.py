"""Kernels: functions that numba compiles to machine code, run as Python while that is cheaper.

Compiling a kernel into an empty numba cache costs from a second to over ten (the numeric IK
solver: about 13 s of CPU on the 2-core machines of BENCHMARKS.md); running the same function
as Python costs microseconds to milliseconds for one configuration or one target. So a
`Kernel` has two tiers, chosen by the caller, who knows how much work a call is:

- ``kernel(*args)`` runs the compiled kernel, compiling it (or loading it from numba's cache)
  on the first call. Batch work calls this.
- ``kernel.light(*args)``, for a call with little work (one configuration, one target), runs
  the kernel's Python function until the kernel is compiled or its Python runs have taken
  `PYTHON_BUDGET` seconds in all; from then on, the compiled kernel. The kernels it calls run
  as Python too. A math error that numba would answer with NaN (``math.acos(1.5)``, a
  division by zero, the sine of infinity) ends the Python run, and the call is made again
  compiled.
- ``kernel.sized(items, *args, few=FEW)`` is light for at most `few` items of work
  (configurations, targets, samples: the caller knows what one costs), compiled for more.
- A kernel whose loops would be slow as Python can name a vectorised NumPy function that does
  the same arithmetic in the same order (``kernel(python=...)``): its light calls run that
  instead, under the same budget.

A process whose light calls never add up to the budget compiles none of them and never imports
numba; one that makes many of them pays at most the budget before compiling, as it would have
from the first call. Both tiers run the same source: tests/test_jit.py holds them to the same
results. A kernel declared ``parallel=True`` writes its parallel loop as ``prange``, which is
``range`` in Python and numba's ``prange`` when compiled.

The environment variable ``ARMKIT_JIT`` (read at the first light call) or `set_mode` chooses:
``auto`` (the default, as above), ``compiled`` (every call compiled, numba's own behaviour;
benchmarks of compiled speed use it) or ``python`` (light calls always Python; for debugging
a kernel).
"""

from __future__ import annotations

import contextlib
import functools
import importlib
import os
import threading
import time
import types

import numpy as np

from armkit.errors import InputError

PYTHON_BUDGET = 1.0     # s of Python runs per kernel before a light call compiles it
FEW = 16                # items (configurations, targets) a `Kernel.sized` call runs light
MODES = ("auto", "compiled", "python")
_PYTHON_ERRORS = (ArithmeticError, ValueError)      # where numba's math returns inf or NaN

prange = range


mode: str | None = None     # from ARMKIT_JIT at the first light call (where a bad value is
#                             reported as that call's InputError), or `set_mode`


def _mode() -> str:
    """The mode, read from ``ARMKIT_JIT`` if not set yet."""
    global mode
    if mode is None:
        text = os.environ.get("ARMKIT_JIT", "").strip() or "auto"
        if text not in MODES:
            raise InputError(f"ARMKIT_JIT: expected one of {', '.join(MODES)}, found {text!r}")
        mode = text
    return mode


def set_mode(new_mode: str) -> None:
    """Choose the tiers of light calls from now on: "auto", "compiled" or "python" (see the
    module's docstring); a kernel already compiled stays compiled."""
    global mode
    if new_mode not in MODES:
        raise InputError(f"mode: expected one of {', '.join(MODES)}, found {new_mode!r}")
    mode = new_mode


class _Tier(threading.local):
    """Whether this thread is inside a Python run of a kernel."""

    python = False


_tier = _Tier()


class Kernel:
    """A function numba compiles on demand (see the module's docstring).

    Attributes
    ----------
    py_func : function
        The function as written, run by the Python tier inside another kernel's Python run.
    python : function
        What light calls run as Python: `py_func`, or the NumPy version given to `kernel`.
    options : dict
        `numba.njit`'s options.
    python_seconds : float
        Time its light calls have spent in Python so far (s).
    """

    def __init__(self, function, options: dict, python=None):
        functools.update_wrapper(self, function)
        self.py_func = function
        self.python = python or function
        self.options = options
        self.python_seconds = 0.0
        self._dispatcher = None
        self._compiled = False
        # A class of its own, whose __call__ becomes the dispatcher itself once compiled: a
        # compiled call then costs what numba's dispatch costs and nothing more.
        self.__class__ = type(f"Kernel.{function.__name__}", (Kernel,), {})

    def __repr__(self) -> str:
        return f"<kernel {self.py_func.__module__}.{self.py_func.__qualname__}>"

    def __reduce__(self):
        # By name, as a function pickles: a result or solver holding a kernel can be pickled
        # (Dask sends them to workers) and comes back holding the module's own kernel.
        return _named, (self.py_func.__module__, self.py_func.__qualname__)

    def __call__(self, *args):
        if _tier.python:
            return self.py_func(*args)
        return self.compiled()(*args)

    @property
    def is_compiled(self) -> bool:
        """Whether calls from Python now go to the compiled kernel."""
        return self._compiled

    def light(self, *args):
        """Call with little work: as Python while that is cheaper than compiling (see above)."""
        if _tier.python:                    # inside another kernel's Python run
            return self.py_func(*args)
        chosen = mode or _mode()
        if chosen == "compiled" or (chosen == "auto" and self.python_seconds >= PYTHON_BUDGET):
            return self.compiled()(*args)
        start = time.perf_counter()
        _tier.python = True
        try:
            with np.errstate(all="ignore"):
                return self.python(*args)
        except _PYTHON_ERRORS:
            pass
        finally:
            _tier.python = False
            self.python_seconds += time.perf_counter() - start
        return self.compiled()(*args)

    def sized(self, items: int, *args, few: int = FEW):
        """Call for `items` items of work: `light` for at most `few`, else compiled."""
        if items <= few:
            return self.light(*args)
        return self(*args)

    @property
    def dispatcher(self):
        """numba's dispatcher for this kernel, created (not compiled) on first use."""
        if self._dispatcher is None:
            numba = _numba()
            function = self.py_func
            if self.options.get("parallel"):
                # The same code, seeing numba's prange where the module has `prange`.
                function = types.FunctionType(function.__code__,
                                              {**function.__globals__, "prange": numba.prange},
                                              function.__name__, function.__defaults__,
                                              function.__closure__)
                function.__qualname__ = self.py_func.__qualname__
            self._dispatcher = numba.njit(**self.options)(function)
        return self._dispatcher

    def compiled(self):
        """The dispatcher, which every later call of this kernel goes to directly."""
        if not self._compiled:
            dispatcher = self.dispatcher
            type(self).__call__ = staticmethod(dispatcher)
            self.light = dispatcher         # shadows the method: no Python frame either
            self._compiled = True
        return self._dispatcher


@contextlib.contextmanager
def numba_threads(count: int):
    """Within the block, parallel kernels called from this thread run on `count` threads (at
    most numba's pool); the setting is numba's per thread, restored on leaving."""
    numba = _numba()
    before = numba.get_num_threads()
    numba.set_num_threads(min(count, numba.config.NUMBA_NUM_THREADS))
    try:
        yield
    finally:
        numba.set_num_threads(before)


def _named(module: str, qualname: str) -> Kernel:
    return getattr(importlib.import_module(module), qualname)


def kernel(python=None, **options):
    """Decorator: a `Kernel` of the function, compiled with ``numba.njit(**options)``; light
    calls run `python` (a NumPy version of the same arithmetic) if given, else the function."""
    return lambda function: Kernel(function, options, python)


def _typeof_kernel(value: Kernel, context):
    """numba's type of a kernel: its dispatcher's (so that a kernel calling another is compiled
    as numba compiles calls between its own dispatchers)."""
    from numba.core import types as numba_types

    return numba_types.Dispatcher(value.dispatcher)


def _numba():
    """numba, imported on the first compilation, with `_typeof_kernel` registered in it."""
    import numba
    from numba.extending import typeof_impl

    if Kernel not in typeof_impl.registry:
        typeof_impl.register(Kernel)(_typeof_kernel)
    return numba
