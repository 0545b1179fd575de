"""armkit.jit: light calls run a kernel's Python function until a background thread has
compiled it, batches run compiled, and both tiers give the same results bit for bit."""

from __future__ import annotations

import copy
import json
import math
import multiprocessing
import os
import pickle
import subprocess
import sys
import threading

import numpy as np
import pytest

import armkit
from armkit import jit
from armkit.errors import InputError
from armkit.jit import Kernel, kernel, prange


@kernel(error_model="numpy")
def _twice(x):
    return 2.0 * x


def _sum_of_twice(a):
    total = 0.0
    for i in range(a.shape[0]):
        total += _twice(a[i])
    return total


def _acos(x):
    return math.acos(x)


def _exp(x):
    return math.exp(x)


def _log(x):
    return math.log(x)


def _ceil(x):
    return math.ceil(x)


def _squares(a, out):
    for i in prange(a.shape[0]):
        out[i] = a[i] * a[i] + 1.0


@pytest.fixture(autouse=True)
def _auto_mode(monkeypatch):
    """The default tiers, whatever ARMKIT_JIT the suite runs under, and a background compiler
    of the test's own that has not started."""
    monkeypatch.setattr(jit, "mode", "auto")
    monkeypatch.setattr(jit, "_compiler", jit._Compiler())
    monkeypatch.setattr(jit._Compiler, "python_seconds", 0.0)


def _fresh(function, **options) -> Kernel:
    """A kernel of its own per test, never compiled before."""
    return Kernel(function, options)


def test_a_light_call_runs_python_and_compiles_nothing():
    outer = _fresh(_sum_of_twice)
    inner_before = _twice.is_compiled
    assert outer.light(np.arange(4.0)) == 12.0
    assert not outer.is_compiled and not jit._compiler.started
    assert _twice.is_compiled == inner_before        # the kernel it calls ran as Python too
    assert outer.python_seconds > 0.0


def test_light_calls_past_the_start_compile_in_the_background(monkeypatch):
    monkeypatch.setattr(jit, "START_AFTER", 0.0)
    outer = _fresh(_sum_of_twice)
    assert outer.light(np.arange(4.0)) == 12.0       # answered as Python, queued
    assert jit._compiler.started
    assert outer.wait(timeout=600)
    assert outer.is_compiled
    assert outer.light is outer.dispatcher           # later calls go straight to numba
    assert outer.light(np.arange(3.0)) == 6.0
    assert outer(np.arange(3.0)) == 6.0


def test_the_background_thread_compiles_and_no_light_call_does(monkeypatch):
    """Every compilation runs on the background thread while light calls go on as Python."""
    monkeypatch.setattr(jit, "START_AFTER", 0.0)
    threads = []
    numba = jit._numba()
    original = numba.core.dispatcher.Dispatcher.compile

    def compile_and_note(self, sig):
        threads.append(threading.current_thread().name)
        return original(self, sig)

    monkeypatch.setattr(numba.core.dispatcher.Dispatcher, "compile", compile_and_note)
    outer = _fresh(_sum_of_twice)
    results = set()
    while not outer.is_compiled:
        results.add(outer.light(np.arange(4.0)))
    results.add(outer.light(np.arange(4.0)))
    assert results == {12.0}
    assert threads and set(threads) == {"armkit-jit"}


def _squares_numpy(a, out):
    out[:] = a * a + 1.0


def test_a_numpy_version_runs_the_light_calls_until_the_kernel_is_ready(monkeypatch):
    calls = []
    squares = Kernel(_squares, {}, lambda a, out: calls.append(len(a)) or _squares_numpy(a, out))
    a = np.linspace(-1.0, 1.0, 7)
    light, compiled = np.empty_like(a), np.empty_like(a)
    squares.light(a, light)
    assert calls == [7] and not squares.is_compiled and squares.python_seconds > 0.0
    squares.prepare(a, compiled)
    assert squares.wait(timeout=600)
    squares.light(a, compiled)
    assert calls == [7] and squares.is_compiled        # ready: compiled
    np.testing.assert_array_equal(light, compiled)


def test_a_call_compiles_and_sized_calls_choose_by_work():
    few = _fresh(_sum_of_twice)
    assert few.sized(3, np.arange(3.0), few=3) == 6.0
    assert not few.is_compiled
    many = _fresh(_sum_of_twice)
    assert many.sized(4, np.arange(4.0), few=3) == 12.0
    assert many.is_compiled


def test_a_math_error_in_python_is_answered_as_numba_answers_it():
    """math.acos(1.5) raises in Python; numba answers NaN, and so does the Python tier, without
    compiling; the same for an overflow (inf) and the logarithm of 0 (-inf)."""
    acos = _fresh(_acos, error_model="numpy")
    assert acos.light(0.5) == math.acos(0.5)
    assert math.isnan(acos.light(1.5))
    assert not acos.is_compiled
    exp, log = _fresh(_exp), _fresh(_log)
    assert exp.light(1e3) == math.inf and log.light(0.0) == -math.inf
    assert math.isnan(log.light(-1.0))
    assert not (exp.is_compiled or log.is_compiled)
    assert (acos(1.5), exp(1e3), log(0.0)) == (pytest.approx(math.nan, nan_ok=True), math.inf,
                                                -math.inf)


def test_an_error_numba_would_not_raise_either_is_answered_compiled():
    ceil = _fresh(_ceil)
    assert ceil.light(2.5) == 3
    assert not ceil.is_compiled
    ceil.light(math.inf)            # Python raises OverflowError; numba answers some integer
    assert ceil.is_compiled


def test_new_argument_types_after_compiling_run_as_python_and_are_queued(monkeypatch):
    monkeypatch.setattr(jit, "START_AFTER", 0.0)
    twice = _fresh(_sum_of_twice)
    twice.prepare(np.arange(3.0))
    assert twice.wait(timeout=600)
    assert len(twice.dispatcher.overloads) == 1
    assert twice.light(np.arange(3, dtype=np.float32)) == 6.0     # no version for float32 yet
    assert jit._compiler.wait(timeout=600)
    assert len(twice.dispatcher.overloads) == 2
    assert twice(np.arange(3, dtype=np.int32)) == 6.0            # a batch: compiled at once
    assert len(twice.dispatcher.overloads) == 3


_forked = Kernel(_sum_of_twice, {"cache": False})


def _sum_in_child() -> tuple[float, float]:
    return _forked.light(np.arange(4.0)), _forked(np.arange(3.0))


def test_a_child_forked_while_the_background_thread_works_answers(monkeypatch):
    """Forked in the middle of the background thread's work (importing numba or compiling),
    a child answers light and batch calls (as Python where it cannot compile), and the parent
    goes on to compile."""
    monkeypatch.setattr(jit, "START_AFTER", 0.0)
    assert _forked.light(np.arange(4.0)) == 12.0            # queued: the thread starts
    with multiprocessing.get_context("fork").Pool(1) as pool:
        assert pool.apply(_sum_in_child) == (12.0, 6.0)
    assert _forked.wait(timeout=600)


def test_a_kernel_pickles_by_name():
    solver = armkit.IKSolver(armkit.robot("ur5"))       # holds its closed form's kernel
    assert pickle.loads(pickle.dumps(_twice)) is _twice
    again = pickle.loads(pickle.dumps(solver))
    assert again.family.kernel is solver.family.kernel
    assert copy.deepcopy(_twice) is _twice


def test_a_parallel_kernel_is_the_same_loop_in_both_tiers():
    squares = _fresh(_squares, parallel=True)
    a = np.linspace(-1.0, 1.0, 5000)
    python, compiled = np.empty_like(a), np.empty_like(a)
    squares.light(a, python)
    squares(a, compiled)
    assert squares.is_compiled
    np.testing.assert_array_equal(python, compiled)


def test_modes_are_checked(tmp_path):
    with pytest.raises(InputError, match="mode: expected one of auto, compiled, python, "
                                         "found 'fast'"):
        jit.set_mode("fast")
    # From the environment: read at the first call that needs it, reported as bad input.
    cases = ((["fk", "ur5", "0", "0", "0", "0", "0", "0"], "ARMKIT_JIT", "fast",
              "armkit: ARMKIT_JIT: expected one of auto, compiled, python, found 'fast'"),
             (["workspace", "ur5", "-n", "1e5", "--out", str(tmp_path)], "ARMKIT_NUM_THREADS",
              "many", "armkit: ARMKIT_NUM_THREADS: expected a whole number of threads >= 1, "
                      "found 'many'"))
    for argv, variable, value, line in cases:
        result = subprocess.run([sys.executable, "-m", "armkit", *argv], capture_output=True,
                                text=True, env={**os.environ, variable: value})
        assert result.returncode == 2, result.stderr
        assert result.stderr.strip() == line


# One process computes every light entry point's results as Python (never importing numba),
# then again compiled; the parent compares them.
TIERS = r"""
import json, sys
import numpy as np
import armkit
from armkit import jit
from armkit.spatial import pose_from_xyz_rpy
sys.path.insert(0, sys.argv[1])
from tests.planning.scenes import SHELF_GOAL, SHELF_START, shelf

def results():
    out = {}
    rng = np.random.default_rng(12)
    for name in ("ur5", "inspection_6dof", "tool_changer_6dof"):
        robot = armkit.robot(name)
        lo, hi = robot.chain.sampling_limits
        out[f"fk batch {name}"] = armkit.fk(robot, rng.uniform(lo, hi, (300, robot.n)))
        for i, q in enumerate(rng.uniform(lo, hi, (8, robot.n))):
            out[f"fk {name} {i}"] = armkit.fk(robot, q)
            out[f"jacobian {name} {i}"] = armkit.jacobian(robot, q)
            target = armkit.fk(robot, rng.uniform(lo, hi))
            r = armkit.ik(robot, target, seed=i)
            out[f"ik {name} {i}"] = np.r_[r.q, r.success, r.position_error, r.rotation_error]
            r = armkit.ik(robot, target, q, seed=i, method="lm")
            out[f"ik lm from q0 {name} {i}"] = np.r_[r.q, r.success, r.iterations]
    ur5 = armkit.robot("ur5")
    for i, z in enumerate(np.linspace(0.1, 0.5, 5)):
        solutions = armkit.ik_solutions(ur5, pose_from_xyz_rpy([0.4, 0.1, z], [np.pi, 0.2, 0.0]))
        out[f"ik_solutions {i}"] = solutions.q
    for planner in ("rrtconnect", "rrt"):
        r = armkit.plan(armkit.robot("inspection_6dof"), SHELF_START, SHELF_GOAL, scene=shelf(),
                        planner=planner, seed=3, waypoints=10)
        out[f"plan {planner}"] = np.r_[r.path.ravel(), r.iterations, r.states_checked]
    q0, qf = np.zeros(6), np.array([1.0, -0.5, 0.3, 2.0, -1.0, 0.1])
    motion = armkit.jerk_limited(q0, qf, 1.0, 2.0, 10.0)
    out["jerk_limited"] = motion.evaluate(np.linspace(0.0, motion.duration, 50))
    points = np.deg2rad([[50.4, -180, 130], [43.2, -166, 123], [35, -152, 116], [27, -137, 108]])
    out["spline"] = armkit.spline([0, 2, 4, 5], points, "4-5-5").sample(
        np.linspace(0, 5, 100)).qdd
    robot = armkit.robot("inspection_6dof")
    waypoints = np.random.default_rng(0).uniform(-1.0, 1.0, (10, 6))
    r = armkit.retime(waypoints, robot.velocity_limits, robot.acceleration_limits)
    out["retime"] = r.trajectory.evaluate(np.linspace(0.0, r.trajectory.duration, 50))
    return {k: np.asarray(v, dtype=float).ravel().tolist() for k, v in out.items()}

jit.set_mode("python")
python = results()
numba_imported = "numba" in sys.modules
jit.set_mode("compiled")
compiled = results()
print(json.dumps({"python": python, "compiled": compiled, "numba_imported": numba_imported}))
"""


@pytest.mark.slow
def test_python_and_compiled_tiers_give_the_same_results():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    result = subprocess.run([sys.executable, "-c", TIERS, root], capture_output=True, text=True,
                            timeout=1800)
    assert result.returncode == 0, result.stderr[-3000:]
    found = json.loads(result.stdout)
    assert not found["numba_imported"]          # the Python tier compiled nothing
    assert found["python"].keys() == found["compiled"].keys()
    for key, python in found["python"].items():
        np.testing.assert_array_equal(python, found["compiled"][key], err_msg=key)


# A fresh process makes light calls in a loop until the background thread is idle, noting the
# thread of every compilation numba makes; it prints them and the calls' results compiled.
LOOP = r"""
import json, sys, threading
import numpy as np
import numba
import armkit
from armkit import jit

compiles = []
original = numba.core.dispatcher.Dispatcher.compile


def noted(self, sig):
    compiles.append(threading.current_thread().name)
    return original(self, sig)


numba.core.dispatcher.Dispatcher.compile = noted
jit.START_AFTER = 0.0
cases = sys.argv[1].split(",")
ur5 = armkit.robot("ur5")
panda = armkit.robot("panda")
rng = np.random.default_rng(0)
q = rng.uniform(*ur5.chain.sampling_limits, (50, 6))
T = armkit.fk(ur5, q)
Tp = armkit.fk(panda, rng.uniform(*panda.chain.sampling_limits, (50, 7)))
calls = {"fk": lambda i: armkit.fk(ur5, q[i]),
         "jacobian": lambda i: armkit.jacobian(ur5, q[i]),
         "ik": lambda i: (armkit.ik(ur5, T[i], q[i] + 0.01), armkit.ik(panda, Tp[i])),
         "ik_solutions": lambda i: armkit.ik_solutions(ur5, T[i]),
         "jerk_limited": lambda i: armkit.jerk_limited(q[i], q[i - 1], 1.0, 2.0, 10.0),
         "retime": lambda i: armkit.retime(q[i:i + 4], 1.0, 2.0)}
i = 0
while i < 20 or not jit.wait_for_background(timeout=0.0):
    for case in cases:
        calls[case](i % 40 + 1)
    i += 1
print(json.dumps({"compiles": compiles, "calls": i}))
"""


def _loop_in_a_fresh_process(cases: str) -> dict:
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    result = subprocess.run([sys.executable, "-c", LOOP, cases], capture_output=True,
                            text=True, timeout=1800, cwd=root)
    assert result.returncode == 0, result.stderr[-3000:]
    return json.loads(result.stdout)


@pytest.mark.slow
def test_no_light_call_compiles_in_the_foreground():
    """A loop of single calls of every kind reaches compiled code with every compilation (or
    cache load) on the background thread: none in the calls themselves."""
    found = _loop_in_a_fresh_process("fk,jacobian,ik,ik_solutions,jerk_limited,retime")
    assert found["compiles"] and set(found["compiles"]) == {"armkit-jit"}, found
