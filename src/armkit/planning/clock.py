"""The clock a planning kernel reads to keep its deadline, compiled or run as Python.

numba has no clock, so the kernels read the operating system's monotonic clock through
``clock_gettime`` (ctypes), which nopython code can call. The function is passed to the kernels
as an argument, not read as a global: numba then takes its address at each call instead of
baking it into the machine code, and the kernels stay in numba's cache. In the Python tier the
same call runs through ctypes. A deadline travels as a `timer` array (int64: the seconds and
nanoseconds last read, the deadline, and a pause no later than it, in nanoseconds of the clock
of `time.monotonic`). A loop that can stop between iterations and be called again (a planner's)
returns at the pause; the checks inside an iteration keep the deadline.
"""

from __future__ import annotations

import ctypes
import math
import time

import numpy as np

from armkit.jit import kernel

_inline = kernel(inline="always")

CLOCK = time.CLOCK_MONOTONIC            # the clock of time.monotonic on POSIX systems

clock_gettime = ctypes.CDLL(None, use_errno=True).clock_gettime
clock_gettime.argtypes = [ctypes.c_int, ctypes.c_void_p]
clock_gettime.restype = ctypes.c_int


def timer(time_limit: float) -> np.ndarray:
    """A timer whose deadline (and pause) is `time_limit` s from now (inf: none)."""
    limit = float(time_limit)
    if not math.isfinite(limit):
        return timer_until(_NEVER)
    return timer_until(time.monotonic_ns() + int(max(limit, 0.0) * 1e9))


_NEVER = np.iinfo(np.int64).max


def timer_until(deadline_ns: int, pause_ns: int | None = None) -> np.ndarray:
    """A timer for a deadline (and a pause, by default the deadline) in `time.monotonic_ns`'s
    nanoseconds."""
    deadline_ns = min(int(deadline_ns), _NEVER)
    pause_ns = deadline_ns if pause_ns is None else min(int(pause_ns), deadline_ns)
    return np.array([0, 0, deadline_ns, pause_ns], dtype=np.int64)


def paused_after(deadline: np.ndarray, seconds: float) -> np.ndarray:
    """The same deadline, with a pause `seconds` from now."""
    return timer_until(int(deadline[2]), time.monotonic_ns() + int(seconds * 1e9))


@_inline
def expired(clock, timer):
    """Whether the deadline of `timer` has passed; `clock` is `clock_gettime`."""
    clock(CLOCK, timer.ctypes.data)
    return timer[0] * 1_000_000_000 + timer[1] >= timer[2]


@_inline
def paused(clock, timer):
    """Whether the pause of `timer` (never later than its deadline) has come."""
    clock(CLOCK, timer.ctypes.data)
    return timer[0] * 1_000_000_000 + timer[1] >= timer[3]


def left(timer: np.ndarray) -> float:
    """Seconds left before the timer's deadline (negative once it has passed)."""
    return (int(timer[2]) - time.monotonic_ns()) * 1e-9
