"""Kernels: functions that numba compiles to machine code, compiled where no call waits for it.

Compiling a kernel into an empty numba cache costs from a second to over ten (the numeric IK
solver: about 13 s of CPU on the 2-core machines of BENCHMARKS.md), and even a warm cache costs
``import numba`` (about 1.1 s); running the same function as Python costs microseconds to
milliseconds for one configuration or one target. So a `Kernel` has two tiers, and a call with
little work never waits for the compiled one:

- ``kernel.light(*args)``, for a call with little work (one configuration, one target), runs
  the compiled kernel once it is ready, and until then the kernel's Python function (or its
  NumPy version, below), while a background thread imports numba and compiles the kernel (or
  loads it from numba's cache) for this call's argument types. The thread starts once light
  calls have spent `START_AFTER` seconds as Python in the process (a program that makes a
  handful of them, such as one command line, never imports numba); from then on every kernel
  that a light call meets is queued for it at once. When a kernel is ready the next light
  call runs it compiled; no light call compiles in the foreground, and a compiled kernel met
  with argument types it was not compiled for runs that call as Python and queues those types.
- ``kernel(*args)`` runs the compiled kernel, compiling it in the foreground (or waiting for
  the background thread) if it is not ready: batch work, where the Python tier would cost more
  than the compilation, calls this.
- ``kernel.sized(items, *args, few=FEW)`` is light for at most `few` items of work
  (configurations, targets, samples: the caller knows what one costs), compiled for more.
- A kernel whose loops would be slow as Python can name a vectorised NumPy function that does
  the same arithmetic in the same order (``kernel(python=...)``): its light calls run that
  while the kernel is not ready.
- `warm_up` (``armkit.warm_up``, ``armkit warm-up``) compiles the kernels of armkit's common
  calls up front, for a program that wants compiled speed from its first call;
  ``kernel.prepare(*args)`` queues one kernel and ``kernel.wait()`` waits for it.

Both tiers run the same source and give the same results bit for bit (tests/test_jit.py holds
them to it). In the Python tier, ``math``'s functions answer a domain error or an overflow as
numba's do, with NaN or inf rather than an exception; an error numba would not raise either
(``math.ceil(nan)``) ends the Python run, and that one call is made compiled. A kernel declared
``parallel=True`` writes its parallel loop as ``prange``, which is ``range`` in Python and
numba's ``prange`` when compiled.

The environment variable ``ARMKIT_JIT`` (read at the first light call) or `set_mode` chooses:
``auto`` (the default, as above), ``compiled`` (every call compiled in the foreground, numba's
own behaviour; benchmarks of compiled speed use it) or ``python`` (light calls always Python,
nothing compiled in the background; for debugging a kernel).

A forked child starts a background thread of its own when it needs one. A child forked while
the background thread was importing numba or compiling has inherited locks held by a thread it
does not have: it compiles nothing, and runs as Python every kernel it has no compiled code for
(correct, slower; a multiprocessing "spawn" or "forkserver" context, as Dask uses, has no such
limit).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import importlib
import math
import os
import queue
import sys
import threading
import time
import types
import weakref

import numpy as np

from armkit.errors import InputError

START_AFTER = 0.1       # s of light calls run as Python before the background thread starts
#                         (a command line that makes a few light calls never imports numba)
FEW = 16                # items (configurations, targets) a `Kernel.sized` call runs light
MODES = ("auto", "compiled", "python")
SWITCH_INTERVAL = 0.0005    # s: the GIL's switch interval while the background thread works,
#                             so a light call waits at most this long for its turn (Python's
#                             default, 5 ms, would let one call wait 5 ms or more)
_PYTHON_ERRORS = (ArithmeticError, ValueError)      # what ends a Python run (see above)

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
    """Whether this thread is inside a Python run of a kernel, or in a call that compiles in
    the foreground if it must."""

    python = False
    foreground = False


_tier = _Tier()


def _nan_on_error(function):
    """`function` of `math`, answering a domain error with NaN (-inf for the logarithm of 0)
    and an overflow with inf, as numba's compiled math does."""
    def safe(*args):
        try:
            return function(*args)
        except OverflowError:
            return math.inf
        except ValueError:
            return -math.inf if function in _LOGARITHMS and args[0] == 0.0 else math.nan
    return functools.update_wrapper(safe, function)


_LOGARITHMS = (math.log, math.log10, math.log2)


class _NumbaMath(types.ModuleType):
    """`math` as the Python tier sees it: the functions that raise where numba returns NaN or
    inf wrapped by `_nan_on_error`, the rest `math`'s own."""

    RAISING = ("sqrt", "acos", "asin", "acosh", "atanh", "log", "log10", "log1p", "log2",
               "exp", "expm1", "cos", "sin", "tan", "cosh", "sinh", "gamma", "lgamma", "pow")

    def __init__(self):
        super().__init__("math")
        for name in dir(math):
            if not name.startswith("_"):
                value = getattr(math, name)
                setattr(self, name, _nan_on_error(value) if name in self.RAISING else value)


_math = _NumbaMath()


def _with_numba_math(function):
    """`function` with `math` bound to `_math`, its other globals those of its module (read
    when this is called: the module is loaded by then)."""
    if not isinstance(function, types.FunctionType) or "math" not in function.__code__.co_names:
        return function
    copy = types.FunctionType(function.__code__, {**function.__globals__, "math": _math},
                              function.__name__, function.__defaults__, function.__closure__)
    copy.__qualname__ = function.__qualname__
    return copy


class Kernel:
    """A function numba compiles on demand (see the module's docstring).

    Attributes
    ----------
    py_func : function
        The function as written (what numba compiles).
    python : function
        What light calls run while the kernel is not ready: `py_func` (with numba's math), or
        the NumPy version given to `kernel` (which must not raise where numba would not).
    options : dict
        `numba.njit`'s options.
    python_seconds : float
        Time its light calls have spent in Python so far (s), until the background thread
        started.
    """

    def __init__(self, function, options: dict, python=None):
        functools.update_wrapper(self, function)
        self.py_func = function
        self.python = python or function
        self.options = options
        self.python_seconds = 0.0
        self._dispatcher = None
        self._compiled = False
        self._ready = threading.Event()
        self._queued = False
        self._broken = False        # the background compilation failed: light calls stay Python
        self._tier_func = None      # py_func with numba's math, on first use
        _all_kernels.add(self)

    def __repr__(self) -> str:
        return f"<kernel {self.py_func.__module__}.{self.py_func.__qualname__}>"

    def __reduce__(self):
        # By name, as a function pickles: a result or solver holding a kernel can be pickled
        # (Dask sends them to workers) and comes back holding the module's own kernel.
        return _named, (self.py_func.__module__, self.py_func.__qualname__)

    def __call__(self, *args):
        if _tier.python or (no_compiling and not self._compiled):
            return self._python_tier()(*args)
        if not self._compiled:
            self._switch()
        _tier.foreground = True             # a batch: compiled, types new or not
        try:
            return self._dispatcher(*args)
        finally:
            _tier.foreground = False

    @property
    def is_compiled(self) -> bool:
        """Whether calls from Python now go to the compiled kernel."""
        return self._compiled

    def light(self, *args):
        """Call with little work: compiled if ready, else as Python (see above)."""
        if _tier.python:                    # inside another kernel's Python run
            return self._python_tier()(*args)
        chosen = mode or _mode()
        if chosen == "compiled":
            return self(*args)
        if chosen == "auto" and not self._queued and (
                _compiler.started or _Compiler.python_seconds >= START_AFTER):
            self.prepare(*args)
        return self._run_python(args)

    def _run_python(self, args):
        """One call in the Python tier; an error numba would not raise either ends it, and
        the call is made compiled."""
        timed = not _compiler.started
        start = time.perf_counter() if timed else 0.0
        _tier.python = True
        try:
            with np.errstate(all="ignore"):
                return (self.python if self.python is not self.py_func
                        else self._python_tier())(*args)
        except _PYTHON_ERRORS:
            pass
        finally:
            _tier.python = False
            if timed:
                spent = time.perf_counter() - start
                self.python_seconds += spent
                _Compiler.python_seconds += spent
        return self(*args)

    def _python_tier(self):
        """py_func with numba's math (on first use, when its module is loaded)."""
        if self._tier_func is None:
            self._tier_func = _with_numba_math(self.py_func)
        return self._tier_func

    def sized(self, items: int, *args, few: int = FEW):
        """Call for `items` items of work: `light` for at most `few`, else compiled."""
        if items <= few:
            return self.light(*args)
        return self(*args)

    def prepare(self, *args) -> None:
        """Queue this kernel for the background thread, to be compiled for the types of
        `args` (a call's arguments); returns at once."""
        if not self._compiled:
            self._queued = True
            _compiler.request(self, args)

    def wait(self, timeout: float | None = None) -> bool:
        """Wait until the kernel is compiled (after `prepare`, or a light call that queued
        it); False if `timeout` (s) passed first."""
        return self._ready.wait(timeout)

    @property
    def dispatcher(self):
        """numba's dispatcher for this kernel, created (not compiled) on first use."""
        if self._dispatcher is None:
            with _dispatcher_lock:
                if self._dispatcher is None:
                    self._dispatcher = self._new_dispatcher()
        return self._dispatcher

    def _new_dispatcher(self):
        numba = _numba()
        function = self.py_func
        if self.options.get("parallel"):
            # The same code, seeing numba's prange where the module has `prange`.
            function = types.FunctionType(function.__code__,
                                          {**function.__globals__, "prange": numba.prange},
                                          function.__name__, function.__defaults__,
                                          function.__closure__)
            function.__qualname__ = self.py_func.__qualname__
        dispatcher = numba.njit(**self.options)(function)
        # numba calls this on a call whose argument types have no compiled version yet: in
        # the auto mode, a light call must not compile in the foreground (see above).
        compile_for_args = dispatcher._compile_for_args

        def unseen_types(*args, **kwargs):
            if no_compiling:
                return lambda *call: self._python_tier()(*call)
            if _tier.foreground or (mode or _mode()) != "auto" or _tier.python:
                with _compiler_lock():          # one compilation at a time, typing included
                    return compile_for_args(*args, **kwargs)
            if not self._broken:
                _compiler.request(self, args)
            return lambda *call: self._run_python(call)

        dispatcher._compile_for_args = unseen_types
        return dispatcher

    def _switch(self) -> None:
        """Send every later light call straight to the dispatcher."""
        self.light = self.dispatcher        # shadows the method: no Python frame either
        self._compiled = True
        self._ready.set()


_dispatcher_lock = threading.Lock()
_all_kernels: weakref.WeakSet = weakref.WeakSet()      # every kernel (for a forked child)


class _Compiler:
    """The background thread: imports numba, then compiles the queued kernels one by one."""

    python_seconds = 0.0        # light calls' Python time in the process before it started

    def __init__(self):
        self.queue: queue.SimpleQueue = queue.SimpleQueue()
        self.thread: threading.Thread | None = None
        self.started = False
        self.busy = threading.Event()       # set while there is work queued or running
        self.working = False                # importing numba or compiling, this moment
        self._lock = threading.Lock()
        self._switch_interval = None

    def request(self, kernel: Kernel, args: tuple) -> None:
        with self._lock:
            self.busy.set()
            self.queue.put((kernel, args))
            if self.thread is None:
                self.started = True
                self.thread = threading.Thread(target=self._run, name="armkit-jit",
                                               daemon=True)
                self.thread.start()

    def _run(self) -> None:
        self._quick_switches()
        self.working = True
        try:
            numba = _numba()
        except Exception:           # no numba: light calls stay Python, batches say why
            return
        finally:
            self.working = False
        while True:
            if self.queue.empty():
                with self._lock:
                    if self.queue.empty():
                        self.busy.clear()
                        self._default_switches()
            kernel, args = self.queue.get()
            self._quick_switches()
            self.working = True
            try:
                # The dispatcher first: making one takes numba's compiler lock inside
                # _dispatcher_lock, so taking them the other way round could deadlock with a
                # foreground call making the same dispatcher.
                dispatcher = kernel.dispatcher
                with _compiler_lock():
                    dispatcher.compile(tuple(numba.typeof(a) for a in args))
            except Exception:       # noqa: BLE001 (a batch call compiles it and says why)
                kernel._broken = True
                continue
            finally:
                self.working = False
            if not kernel._compiled:
                kernel._switch()

    def _quick_switches(self) -> None:
        if self._switch_interval is None:
            self._switch_interval = sys.getswitchinterval()
            sys.setswitchinterval(min(SWITCH_INTERVAL, self._switch_interval))

    def _default_switches(self) -> None:
        if self._switch_interval is not None:
            sys.setswitchinterval(self._switch_interval)
            self._switch_interval = None

    def wait(self, timeout: float | None = None) -> bool:
        """Wait until the queue is done; False if `timeout` (s) passed first."""
        end = None if timeout is None else time.monotonic() + timeout
        while self.busy.is_set():
            left = None if end is None else end - time.monotonic()
            if left is not None and left <= 0:
                return False
            time.sleep(0.005 if left is None else min(0.005, left))
        return True


_compiler = _Compiler()


def wait_for_background(timeout: float | None = None) -> bool:
    """Wait until the background thread has compiled every kernel queued for it; False if
    `timeout` (s) passed first."""
    return _compiler.wait(timeout)


def _compiler_lock():
    """numba's compiler lock (re-entrant), held around a compilation and the typing of its
    arguments, so that the background thread and a foreground call never compile at once."""
    from numba.core.compiler_lock import global_compiler_lock

    return global_compiler_lock


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
    calls run `python` (a NumPy version of the same arithmetic) if given, else the function,
    while the kernel is not ready."""
    return lambda function: Kernel(function, options, python)


def _typeof_kernel(value: Kernel, context):
    """numba's type of a kernel: its dispatcher's (so that a kernel calling another is compiled
    as numba compiles calls between its own dispatchers)."""
    from numba.core import types as numba_types

    return numba_types.Dispatcher(value.dispatcher)


_numba_lock = threading.Lock()


_forked_busy = False            # the background thread was importing numba or compiling
no_compiling = False            # in a child forked then: nothing is compiled (see the module)


def _before_fork() -> None:
    global _forked_busy
    _forked_busy = _compiler.working


def _after_fork_in_child() -> None:
    """A forked child has no background thread: it starts its own when its light calls need
    one, and queues again what the parent had queued and not compiled. Forked while the
    thread imported numba or compiled, it inherited locks that no thread of its own will
    release: it compiles nothing, and runs as Python every kernel it has no compiled code for."""
    global _compiler, no_compiling
    _compiler = _Compiler()
    no_compiling = no_compiling or _forked_busy
    for each in list(_all_kernels):
        if not each._compiled:
            each._queued = no_compiling


os.register_at_fork(before=_before_fork, after_in_child=_after_fork_in_child)


def _numba():
    """numba, imported on the first compilation, with `_typeof_kernel` and armkit's cache
    stamps (`_stamp_caches`) registered in it."""
    with _numba_lock:
        import numba
        from numba.extending import typeof_impl

        if Kernel not in typeof_impl.registry:
            # numba loads its extensions at a dispatcher's first compilation, unguarded: done
            # here, once, before two threads can compile.
            from numba.core import entrypoints

            entrypoints.init_all()
            typeof_impl.register(Kernel)(_typeof_kernel)
            _stamp_caches()
    return numba


def _stamp_caches() -> None:
    """Key every cached armkit kernel on all of armkit's source, not only its own file.

    numba keys a cached kernel on the file that defines it, but the kernels of one module call
    and inline kernels of others (every FK step of `armkit.kinematics.core`): after an edit to
    one of those, a cached caller would go on running the old code. armkit's kernels are looked
    up by locators (numba's own, in `__pycache__` or NUMBA_CACHE_DIR) whose stamp adds a hash
    of every armkit source file, so any change to armkit compiles its kernels again. Where
    numba's caching machinery is not as expected, its own locators stay.
    """
    from numba.core import caching

    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)
    bases = [getattr(caching, name, None) or getattr(caching, "_" + name, None)
             for name in ("UserProvidedCacheLocator", "InTreeCacheLocator")]
    if impl is None or None in bases or not hasattr(impl, "_locator_classes"):
        return
    package = os.path.dirname(os.path.abspath(__file__))
    digest = hashlib.sha256()
    for folder, subfolders, files in os.walk(package):
        subfolders.sort()
        for name in sorted(files):
            if name.endswith(".py"):
                path = os.path.join(folder, name)
                digest.update(os.path.relpath(path, package).encode())
                with open(path, "rb") as file:
                    digest.update(file.read())
    stamp = digest.hexdigest()

    def armkit_locator(base):
        class ArmkitLocator(base):
            def get_source_stamp(self):
                return super().get_source_stamp(), stamp

            @classmethod
            def from_function(cls, py_func, py_file):
                if not os.path.abspath(py_file).startswith(package + os.sep):
                    return None
                return super().from_function(py_func, py_file)

        ArmkitLocator.__name__ = f"Armkit{base.__name__.lstrip('_')}"
        return ArmkitLocator

    impl._locator_classes = [*map(armkit_locator, bases), *impl._locator_classes]
