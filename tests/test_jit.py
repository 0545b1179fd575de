"""armkit.jit: light calls run a kernel's Python function until compiling pays, batches run
compiled, and both tiers give the same results bit for bit."""

from __future__ import annotations

import copy
import json
import math
import os
import pickle
import subprocess
import sys

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


def _squares(a, out):
    for i in prange(a.shape[0]):
        out[i] = a[i] * a[i] + 1.0


@pytest.fixture(autouse=True)
def _auto_mode(monkeypatch):
    """The default tiers, whatever ARMKIT_JIT the suite runs under."""
    monkeypatch.setattr(jit, "mode", "auto")


def _fresh(function, **options) -> Kernel:
    """A kernel of its own per test, never compiled before."""
    return Kernel(function, options)


def test_a_light_call_runs_python_and_compiles_nothing():
    outer = _fresh(_sum_of_twice)
    inner_before = _twice.is_compiled
    assert outer.light(np.arange(4.0)) == 12.0
    assert not outer.is_compiled
    assert _twice.is_compiled == inner_before        # the kernel it calls ran as Python too
    assert outer.python_seconds > 0.0


def test_the_budget_spent_a_light_call_compiles(monkeypatch):
    monkeypatch.setattr(jit, "PYTHON_BUDGET", 0.0)
    outer = _fresh(_sum_of_twice)
    assert outer.light(np.arange(4.0)) == 12.0
    assert outer.is_compiled
    assert outer.light is outer.dispatcher           # later calls go straight to numba
    assert outer(np.arange(3.0)) == 6.0


def _squares_numpy(a, out):
    out[:] = a * a + 1.0


def test_a_numpy_version_runs_the_light_calls_under_the_same_budget(monkeypatch):
    calls = []
    squares = Kernel(_squares, {}, lambda a, out: calls.append(len(a)) or _squares_numpy(a, out))
    a = np.linspace(-1.0, 1.0, 7)
    light, compiled = np.empty_like(a), np.empty_like(a)
    squares.light(a, light)
    assert calls == [7] and not squares.is_compiled and squares.python_seconds > 0.0
    monkeypatch.setattr(jit, "PYTHON_BUDGET", 0.0)
    squares.light(a, compiled)
    assert calls == [7] and squares.is_compiled        # the budget spent: compiled
    np.testing.assert_array_equal(light, compiled)


def test_a_call_compiles_and_sized_calls_choose_by_work():
    few = _fresh(_sum_of_twice)
    assert few.sized(3, np.arange(3.0), few=3) == 6.0
    assert not few.is_compiled
    many = _fresh(_sum_of_twice)
    assert many.sized(4, np.arange(4.0), few=3) == 12.0
    assert many.is_compiled


def test_a_math_error_in_python_is_answered_compiled():
    """math.acos(1.5) raises in Python; numba answers NaN, and so does the light call."""
    acos = _fresh(_acos, error_model="numpy")
    assert acos.light(0.5) == math.acos(0.5)
    assert not acos.is_compiled
    assert math.isnan(acos.light(1.5))
    assert acos.is_compiled


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
