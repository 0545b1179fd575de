"""How many threads a batch kernel runs on: chosen by the work's size and the machine's load.

A batch is split over threads only when each thread gets enough samples to pay for starting
it, and never over more threads than there are idle cores: on a machine whose cores are busy
with other work, a second thread waits for a core and makes the batch slower than one thread
(measured in benchmarks/fk.py). `set_num_threads` (or the environment variable
``ARMKIT_NUM_THREADS``, read at the first batch) sets an upper bound that the load no longer
lowers.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor

from armkit.errors import InputError

_ENV = "ARMKIT_NUM_THREADS"


def _from_environment() -> int | None:
    text = os.environ.get(_ENV, "").strip()
    if not text:
        return None
    if not text.isdigit() or int(text) < 1:
        raise InputError(f"{_ENV}: expected a whole number of threads >= 1, found {text!r}")
    return int(text)


_UNREAD = object()
# The environment is read at the first batch, where a bad value is reported as the call's
# InputError.
_chosen: int | None | object = _UNREAD


def set_num_threads(n: int | None) -> None:
    """Set the most threads a batch kernel may use; None returns to the automatic choice.

    Parameters
    ----------
    n : int or None
        1 .. the number of cores (numba's thread pool), or None: as many as there are idle
        cores (the one-minute load average subtracted from the core count), at most.

    Raises
    ------
    InputError
        If n is not None and not a whole number in 1 .. cores.

    Example
    -------
    >>> import armkit
    >>> armkit.set_num_threads(1)       # every batch on the calling thread
    >>> armkit.get_num_threads()
    1
    >>> armkit.set_num_threads(None)
    """
    global _chosen
    if n is not None:
        cores = os.cpu_count() or 1
        if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= cores:
            raise InputError(f"n: expected a whole number of threads 1 .. {cores} or None, "
                             f"found {n!r}")
    _chosen = n


def get_num_threads() -> int:
    """The bound set by `set_num_threads` or ``ARMKIT_NUM_THREADS``; else the idle cores now."""
    global _chosen
    if _chosen is _UNREAD:
        _chosen = _from_environment()
    return _chosen if _chosen is not None else idle_cores()


def idle_cores() -> int:
    """Cores not busy with other work: core count minus the one-minute load average, plus
    this process's own share of that load (it is running now), at least 1."""
    cores = os.cpu_count() or 1
    try:
        load = os.getloadavg()[0]
    except OSError:                     # no load average on this platform
        return cores
    return max(1, min(cores, int(cores - load + 1.0)))


def threads_for(samples: int, grain: int, most: int | None = None) -> int:
    """Threads for a batch of `samples`, each thread being worth its start-up from `grain`
    samples on, at most `most` (default: `get_num_threads`); 1 means the serial kernel."""
    if samples < 2 * grain:
        return 1
    return max(1, min(samples // grain, get_num_threads() if most is None else most))


def in_ranges(work: Callable[[int, int], object], count: int, threads: int) -> list:
    """``work(first, last)`` over [0, count): in one call on this thread if `threads` is 1,
    else over ranges of about count / (8 threads) items (so that a thread that finishes early
    takes more) on `threads` threads; the results in the ranges' order. `work` must release
    the GIL for the threads to run at once (numba kernels declared ``nogil``)."""
    if threads <= 1 or count <= 1:
        return [work(0, count)]
    size = max(1, -(-count // (8 * threads)))
    ranges = [(first, min(count, first + size)) for first in range(0, count, size)]
    with ThreadPoolExecutor(threads) as pool:
        return list(pool.map(lambda r: work(*r), ranges))
